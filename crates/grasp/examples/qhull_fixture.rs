//! Writes the reference fixture of Ferrari-Canny epsilons computed by qhull, the general 6-D
//! hull that grasp quality used as its fallback until it was replaced by an exact method of
//! our own (qhull's Rust binding runs bindgen, which needs libclang at build time).
//!
//! cargo run --release -p mvgrasp-grasp --example qhull_fixture -- OUT.json
//!
//! Each case is a real contact pair (jaws closed on a box, a ball and the built-in mug along
//! random lines), a friction coefficient and wrench parameters, with qhull's epsilon of the
//! wrenches of `contact_wrenches`. Half the cases are drawn so that the closing line lies
//! between the inscribed and the circumscribed friction polygon at some contact: the sets on
//! which the structured polar enumeration used to fall back to qhull.

use std::process::ExitCode;

use mvgrasp_geometry::objects::default_object;
use mvgrasp_geometry::{Mat3, Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::quality::{
    ContactPair, TorsionModel, WrenchParams, contact_wrenches, find_contacts, wrench_set_epsilon,
};
use mvgrasp_grasp::{GraspObject, Gripper};
use parry3d::shape::{Ball, Cuboid};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

/// One fixture case.
#[derive(Serialize)]
struct Case {
    center_of_mass: Vec3,
    torque_scale_m: f32,
    contacts: ContactPair,
    friction_coef: f32,
    params: WrenchParams,
    /// Whether the closing line was drawn near the cone's edge (the old fallback's sets).
    near_cone_edge: bool,
    qhull_epsilon: f64,
}

const CASES_PER_KIND: usize = 200;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}

fn object(mesh: Result<TriangleMesh, String>) -> Result<GraspObject, String> {
    GraspObject::new(mesh?).map_err(|e| e.to_string())
}

fn run() -> Result<(), String> {
    let out = std::env::args()
        .nth(1)
        .ok_or("usage: qhull_fixture OUT.json")?;
    let objects = [
        object({
            let (v, t) = Cuboid::new(Vec3::new(0.02, 0.03, 0.025)).to_trimesh();
            TriangleMesh::new(v, t).map_err(|e| e.to_string())
        })?,
        object({
            let (v, t) = Ball::new(0.03).to_trimesh(16, 16);
            TriangleMesh::new(v, t).map_err(|e| e.to_string())
        })?,
        object(default_object().map(|o| o.mesh).map_err(|e| e.to_string()))?,
    ];
    let gripper = Gripper::default();
    let mut rng = ChaCha8Rng::seed_from_u64(20261202);
    let mut cases = Vec::new();
    let (mut near, mut general) = (0, 0);
    let mut tries = 0;
    while (near < CASES_PER_KIND || general < CASES_PER_KIND) && tries < 200_000 {
        tries += 1;
        let object = &objects[tries % objects.len()];
        let axis = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-0.5..0.5),
            rng.random_range(-0.5..0.5),
        )
        .normalize();
        let (y, z) = axis.any_orthonormal_pair();
        let offset = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * 0.015;
        let pose = Pose3::from_parts(
            object.center_of_mass() + offset,
            Rot3::from_mat3(&Mat3::from_cols(axis, y, z)),
        );
        let Some(contacts) = find_contacts(object, &pose, &gripper) else {
            continue;
        };
        let params = WrenchParams {
            num_cone_faces: [4, 6, 8, 8][tries % 4],
            torsion_model: [TorsionModel::UniformPatch, TorsionModel::DexNet][(tries / 4) % 2],
            finger_radius_m: rng.random_range(0.002..0.01),
            ..WrenchParams::default()
        };
        // The tangent of the push's angle to the inward normal, at the worse contact.
        let mut slope = 0.0f32;
        for (contact, push) in contacts.contacts.iter().zip(contacts.push_directions()) {
            let normal = push.dot(contact.inward_normal());
            if normal <= 1e-3 {
                slope = f32::INFINITY;
                break;
            }
            let tangential = (push - normal * contact.inward_normal()).length();
            slope = slope.max(tangential / normal);
        }
        if !slope.is_finite() {
            continue;
        }
        let near_cone_edge = near < CASES_PER_KIND && (general >= CASES_PER_KIND || tries % 2 == 0);
        let friction_coef = if near_cone_edge {
            let inradius = (std::f32::consts::PI / params.num_cone_faces as f32).cos();
            slope / rng.random_range(inradius..1.0)
        } else {
            rng.random_range(0.2..1.2)
        };
        if !(0.05..=2.0).contains(&friction_coef) {
            continue;
        }
        let wrenches = contact_wrenches(object, &contacts, friction_coef, &params)
            .map_err(|e| e.to_string())?;
        let qhull_epsilon = wrench_set_epsilon(&wrenches);
        if near_cone_edge {
            near += 1;
        } else {
            general += 1;
        }
        cases.push(Case {
            center_of_mass: object.center_of_mass(),
            torque_scale_m: object.torque_scale_m(),
            contacts,
            friction_coef,
            params,
            near_cone_edge,
            qhull_epsilon,
        });
    }
    let positive = cases.iter().filter(|c| c.qhull_epsilon > 0.0).count();
    let text = serde_json::to_string(&cases).map_err(|e| e.to_string())?;
    std::fs::write(&out, text + "\n").map_err(|e| format!("{out}: {e}"))?;
    println!(
        "{out}: {} cases ({near} near the cone edge, {general} general), {positive} with epsilon > 0",
        cases.len()
    );
    Ok(())
}
