//! A plan as an MCAP log for robot tooling (Foxglove Studio opens it): each view's depth image
//! (`foxglove.RawImage`, 32-bit float metres) and calibration (`foxglove.CameraCalibration`),
//! the cameras' poses in the world (`foxglove.FrameTransforms` on `/tf`), the fitted table
//! (`foxglove.PoseInFrame`, in the first camera's frame: origin where the optical axis meets
//! it, z along its normal) and the ranked grasps (`foxglove.PosesInFrame`, world frame, best
//! first). JSON messages with JSON Schemas; no compression (no C library); every timestamp is
//! 0, so the same plan writes the same bytes.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use base64::Engine;
use mvgrasp_geometry::Pose3;
use mvgrasp_planner::{ScoredGrasp, TableFit, View};
use serde_json::{Value, json};

use crate::error::{Error, Result};

/// The topics, for readers and tests.
pub const GRASPS_TOPIC: &str = "/grasps";
/// See [`GRASPS_TOPIC`].
pub const TF_TOPIC: &str = "/tf";
/// See [`GRASPS_TOPIC`].
pub const TABLE_TOPIC: &str = "/table";

/// Every message's timestamp: 0 (a plan has no clock; the same plan, the same bytes).
fn time() -> Value {
    json!({"sec": 0, "nsec": 0})
}

fn schema(properties: Value) -> Vec<u8> {
    json!({"type": "object", "properties": properties})
        .to_string()
        .into_bytes()
}

fn vec3_schema() -> Value {
    json!({"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}})
}

fn quat_schema() -> Value {
    json!({"type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}})
}

fn time_schema() -> Value {
    json!({"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}})
}

fn pose_schema() -> Value {
    json!({"type": "object", "properties": {"position": vec3_schema(), "orientation": quat_schema()}})
}

fn pose_json(pose: &Pose3) -> Value {
    let t = pose.translation;
    let q = pose.rotation;
    json!({
        "position": {"x": t.x, "y": t.y, "z": t.z},
        "orientation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w},
    })
}

/// Writes the log of a plan over `views` (their cameras posed in the world) at `path`.
///
/// # Errors
/// [`Error::Io`] naming the file when it cannot be written.
pub fn write_plan_log(
    path: &Path,
    views: &[View],
    table: Option<&TableFit>,
    grasps: &[ScoredGrasp],
) -> Result<()> {
    let io = |e: mcap::McapError| Error::Io {
        op: "write",
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    };
    let mut buffer = Cursor::new(Vec::new());
    {
        let options = mcap::WriteOptions::new()
            .compression(None)
            .profile("")
            .library("mvgrasp");
        let mut writer = options.create(&mut buffer).map_err(io)?;
        let channel = |writer: &mut mcap::Writer<_>, topic: &str, name: &str, properties: Value| {
            let schema = writer.add_schema(name, "jsonschema", &schema(properties))?;
            writer.add_channel(schema, topic, "json", &BTreeMap::new())
        };
        let write = |writer: &mut mcap::Writer<_>, channel: u16, sequence: u32, message: Value| {
            writer.write_to_known_channel(
                &mcap::records::MessageHeader {
                    channel_id: channel,
                    sequence,
                    log_time: 0,
                    publish_time: 0,
                },
                message.to_string().as_bytes(),
            )
        };
        let image_schema = json!({
            "timestamp": time_schema(), "frame_id": {"type": "string"},
            "width": {"type": "integer"}, "height": {"type": "integer"},
            "encoding": {"type": "string"}, "step": {"type": "integer"},
            "data": {"type": "string", "contentEncoding": "base64"},
        });
        let calibration_schema = json!({
            "timestamp": time_schema(), "frame_id": {"type": "string"},
            "width": {"type": "integer"}, "height": {"type": "integer"},
            "distortion_model": {"type": "string"},
            "D": {"type": "array", "items": {"type": "number"}},
            "K": {"type": "array", "items": {"type": "number"}},
            "R": {"type": "array", "items": {"type": "number"}},
            "P": {"type": "array", "items": {"type": "number"}},
        });
        let mut transforms = Vec::new();
        for (i, view) in views.iter().enumerate() {
            let frame = format!("camera_{i}");
            let k = view.depth.intrinsics();
            let depth = channel(
                &mut writer,
                &format!("/{frame}/depth"),
                "foxglove.RawImage",
                image_schema.clone(),
            )
            .map_err(io)?;
            let bytes: Vec<u8> = view
                .depth
                .as_slice()
                .iter()
                .flat_map(|d| d.to_le_bytes())
                .collect();
            write(
                &mut writer,
                depth,
                0,
                json!({
                    "timestamp": time(), "frame_id": frame, "width": k.width, "height": k.height,
                    "encoding": "32FC1", "step": 4 * k.width,
                    "data": base64::engine::general_purpose::STANDARD.encode(&bytes),
                }),
            )
            .map_err(io)?;
            let calibration = channel(
                &mut writer,
                &format!("/{frame}/calibration"),
                "foxglove.CameraCalibration",
                calibration_schema.clone(),
            )
            .map_err(io)?;
            write(
                &mut writer,
                calibration,
                0,
                json!({
                    "timestamp": time(), "frame_id": frame, "width": k.width, "height": k.height,
                    "distortion_model": "plumb_bob", "D": [0.0, 0.0, 0.0, 0.0, 0.0],
                    "K": [k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0],
                    "R": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
                    "P": [k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0],
                }),
            )
            .map_err(io)?;
            let p = pose_json(&view.camera.world_from_camera);
            transforms.push(json!({
                "timestamp": time(), "parent_frame_id": "world", "child_frame_id": frame,
                "translation": p["position"], "rotation": p["orientation"],
            }));
        }
        let tf = channel(
            &mut writer,
            TF_TOPIC,
            "foxglove.FrameTransforms",
            json!({
                "transforms": {"type": "array", "items": {"type": "object", "properties": {
                    "timestamp": time_schema(), "parent_frame_id": {"type": "string"},
                    "child_frame_id": {"type": "string"}, "translation": vec3_schema(),
                    "rotation": quat_schema(),
                }}},
            }),
        )
        .map_err(io)?;
        write(&mut writer, tf, 0, json!({"transforms": transforms})).map_err(io)?;
        if let Some(table) = table {
            let on_table = table.world_from_camera().ok().map(|w| w.inverse());
            if let Some(camera_from_table) = on_table {
                let channel_id = channel(&mut writer, TABLE_TOPIC, "foxglove.PoseInFrame", json!({
                    "timestamp": time_schema(), "frame_id": {"type": "string"}, "pose": pose_schema(),
                }))
                .map_err(io)?;
                write(&mut writer, channel_id, 0, json!({
                    "timestamp": time(), "frame_id": "camera_0", "pose": pose_json(&camera_from_table),
                }))
                .map_err(io)?;
            }
        }
        let poses = channel(
            &mut writer,
            GRASPS_TOPIC,
            "foxglove.PosesInFrame",
            json!({
                "timestamp": time_schema(), "frame_id": {"type": "string"},
                "poses": {"type": "array", "items": pose_schema()},
            }),
        )
        .map_err(io)?;
        let grasp_poses: Vec<Value> = grasps
            .iter()
            .map(|g| pose_json(&g.grasp.world_from_gripper))
            .collect();
        write(
            &mut writer,
            poses,
            0,
            json!({
                "timestamp": time(), "frame_id": "world", "poses": grasp_poses,
            }),
        )
        .map_err(io)?;
        writer.finish().map_err(io)?;
    }
    std::fs::write(path, buffer.into_inner()).map_err(Error::io("write", path))
}
