//! The clutter suite: VGN and GIGA's clutter-removal rounds, in mvgrasp's own trial.
//!
//! Each round sets up a scene of [`EvalConfig::clutter_objects`] objects drawn at random (with
//! repeats, as VGN draws) from the evaluation's object sets, and grasps until the table is
//! empty, two grasps in a row fail, or the planner finds no grasp:
//!
//! - **packed**: the first object in its most probable resting pose at the origin, the rest
//!   around it in steady poses (by probability), turned at random, footprints 5 mm apart within
//!   10 cm of the first ([`crate::grasp_dataset::clutter::place`]); a scene holds fewer objects
//!   when the packing finds no room for one.
//! - **pile**: the objects dropped one by one at random orientations over the middle of a 20 cm
//!   box, the box taken away, and what leaves the 30 cm workspace taken away with it
//!   ([`mvgrasp_grasp::physics::drop_pile`]).
//!
//! Each grasp is planned on depth rendered from the scene's cameras, without a mask (the
//! objects are what stands on the fitted table): 1 view is the top-down PhoXi S 0.7 m above
//! the table, planned by the top-down GQ-CNN alone (`plan --no-fuse` on a depth image); more
//! views add cameras 50 degrees up around the scene, 0.7 m away, fused by the multi-view
//! planner (`plan --views-dir`). With a depth-from-RGB method (`--clutter-depth-from`) each
//! view's depth is predicted from colour views instead, as `plan --rgb` predicts it: the
//! objects in random colours on the grey table (in a plain blue bin), the method given the
//! foreground (what is not the table, as a picker that knows its empty workspace tells apart)
//! as its masks, the planner still none; the bin's walls keep their known depth (a fixture,
//! like the table). Depth from RGB needs 2 views or more. The grasp is tried in rapier among
//! the others ([`mvgrasp_grasp::physics::simulate_grasp_among`]) on the object nearest its
//! centre; it must come out alone. A held object is taken away and the rest settle (and what
//! leaves the workspace goes, uncleared), as VGN's simulator does; after a failure the scene
//! is as it was (VGN carries the failed grasp's pushes to the next) and the next attempt
//! samples with the next seed. When the object does not stay at rest before the hand comes
//! (the trial's settle) the scene is settled again and the attempt repeated, uncounted; after
//! two such repeats the object is taken away uncounted: it tests the scene, not the grasp.
//!
//! Success rate: held of grasps tried; cleared: held of the objects the scene held (less those
//! taken away uncounted), as VGN and GIGA report them.

use std::cell::OnceCell;
use std::rc::Rc;

use mvgrasp_geometry::{Camera, IntrinsicsPreset, Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::LabelSettings;
use mvgrasp_grasp::physics::{
    Drop, FailureStage, PhysicsObject, PileParams, box_walls, drop_pile, settle_objects,
    simulate_grasp_in_scene,
};
use mvgrasp_render::Renderer;
use parry3d::query::PointQuery;
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::objects::ObjectRef;
use crate::error::{Error, ErrorKind, Result};
use crate::grasp_dataset::clutter::{ClutterParams, Neighbour, place};
use crate::planner::{
    DepthFrom, DepthPredictor, GqcnnPolicy, PlanOptions, Planner, SensorPlanParams, View, models,
    plan_on_view, plan_on_views,
};
use crate::scene::render_depths;
use mvgrasp_planner::seed::splitmix;

mod record;
mod views;

pub use record::{Attempt, Outcome, RoundRecord};
pub use views::cameras;
use views::{BIN_MARGIN_M, bin_mask};

/// The scenes the suite knows.
pub const SCENES: [&str; 3] = ["packed", "pile", "bin"];

/// How a round's objects are set on the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClutterScene {
    /// Standing in steady poses, packed side by side.
    Packed,
    /// Dropped into a box that is then taken away.
    Pile,
    /// Dropped into a bin that stays: its walls are seen and are obstacles of the trial.
    Bin,
}

impl ClutterScene {
    /// Its name in configs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::Packed => "packed",
            Self::Pile => "pile",
            Self::Bin => "bin",
        }
    }

    /// How its objects are dropped and settle (the packed scene settles as a pile does).
    fn pile_params(self) -> PileParams {
        match self {
            Self::Packed | Self::Pile => PileParams::default(),
            // A tote 30 cm square inside, 8 cm deep.
            Self::Bin => PileParams {
                box_half_side_m: 0.15,
                box_height_m: 0.08,
                workspace_half_side_m: 0.2,
                keep_box: true,
                ..PileParams::default()
            },
        }
    }
}

impl std::str::FromStr for ClutterScene {
    type Err = String;

    fn from_str(name: &str) -> std::result::Result<Self, String> {
        match name {
            "packed" => Ok(Self::Packed),
            "pile" => Ok(Self::Pile),
            "bin" => Ok(Self::Bin),
            _ => Err(format!("{name:?}: expected one of {}", SCENES.join(", "))),
        }
    }
}

/// The depths of the shipped top-down GQ-CNN's training cameras (its dataset's
/// `radius_m`, `training/configs/datasets/topdown.toml`), metres.
pub const TRAINING_DEPTHS_M: [f32; 2] = [0.65, 0.75];

/// The rounds' cameras by default: a PhoXi S 0.7 m from the table's centre.
pub const DEFAULT_CAMERA: (IntrinsicsPreset, f32) = (IntrinsicsPreset::PhoxiS, 0.7);

/// Times a round settles its scene again for an object that would not stay at rest before one
/// is taken away uncounted.
const MAX_RESETTLES: usize = 2;

/// An object of the pool, built on first use: its mesh, hand-check shape, poses and trial
/// shapes.
struct PoolObject {
    name: String,
    built: OnceCell<Result<Rc<Neighbour>>>,
}

/// An object drawn for a round: its name, its mesh, hand-check and trial shapes.
type Drawn = (String, Rc<Neighbour>);

/// One object on the table.
struct OnTable {
    name: String,
    shape: Rc<Neighbour>,
    pose: Pose3,
}

impl OnTable {
    /// Its trial shapes (built, and checked, when it was drawn).
    fn physics(&self, labels: &LabelSettings) -> Result<&PhysicsObject> {
        self.shape.physics(&labels.physics_shape)
    }
}

/// The suite's planners, cameras and object pool, built once per evaluation.
pub struct ClutterSuite {
    pool: Vec<(ObjectRef, PoolObject)>,
    labels: LabelSettings,
    topdown: Planner,
    fused: Option<(Planner, SensorPlanParams)>,
    /// The depth-from-RGB method that predicts the views' depth instead of rendering it.
    rgb: Option<DepthPredictor>,
    /// The bin's walls: each one's trial shape (centred) and where it stands.
    walls: Vec<(PhysicsObject, Pose3)>,
    /// The walls' meshes where they stand, as one mesh (what the cameras see).
    bin: TriangleMesh,
}

impl ClutterSuite {
    /// The suite over `objects`, loading the shipped top-down GQ-CNN (its crops shown as from
    /// `depth_range_m`, see [`GqcnnPolicy::depth_range_m`]), when some view count is above
    /// 1 the multi-view one, and with `depth_from` that depth-from-RGB method (its views'
    /// depth predicted from colour views, as the fused planner of `plan --rgb` takes it).
    ///
    /// # Errors
    /// No objects, or a network that cannot load.
    pub fn new(
        objects: &[ObjectRef],
        views: &[usize],
        depth_range_m: Option<[f32; 2]>,
        depth_from: Option<DepthFrom>,
    ) -> Result<Self> {
        if objects.is_empty() {
            return Err(Error::Evaluate {
                problem: "the clutter suite has no objects to draw from".into(),
            });
        }
        let labels = LabelSettings::default();
        let mut policy =
            GqcnnPolicy::new(models::GQCNN_TOPDOWN.load()?, labels.gripper.max_opening_m)?;
        policy.depth_range_m = depth_range_m;
        let topdown = Planner::from(policy);
        let fused = if views.iter().any(|&n| n > 1) {
            let options = PlanOptions {
                fuse: true,
                ..PlanOptions::default()
            };
            let (planner, _, params) = options.on_depth(models::MVGQCNN.load()?)?;
            Some((planner, params))
        } else {
            None
        };
        let mut walls = Vec::new();
        let mut wall_meshes = Vec::new();
        for (half, centre) in box_walls(&ClutterScene::Bin.pile_params()) {
            let (vertices, triangles) = parry3d::shape::Cuboid::new(half).to_trimesh();
            let mesh = TriangleMesh::new(vertices, triangles)?;
            let pose = Pose3::from_translation(centre);
            walls.push((PhysicsObject::new(&mesh, &labels.physics_shape)?, pose));
            wall_meshes.push(mesh.transformed(&pose));
        }
        let bin = TriangleMesh::concatenate(&wall_meshes, std::path::Path::new("bin walls"))?;
        Ok(Self {
            walls,
            bin,
            pool: objects
                .iter()
                .map(|o| {
                    let entry = PoolObject {
                        name: format!("{}|{}", o.set, o.name),
                        built: OnceCell::new(),
                    };
                    (o.clone(), entry)
                })
                .collect(),
            labels,
            topdown,
            fused,
            rgb: depth_from.map(DepthPredictor::shipped).transpose()?,
        })
    }

    /// The pool's object `i`, built on first use; `None` when it cannot be (a mesh the grasp
    /// analysis refuses: it is never drawn).
    fn object(&self, i: usize) -> Option<Drawn> {
        let (object, entry) = &self.pool[i];
        let built = entry.built.get_or_init(|| {
            let neighbour = Neighbour::new(object.load()?)?;
            neighbour.physics(&self.labels.physics_shape)?;
            Ok(Rc::new(neighbour))
        });
        let shape = built.as_ref().ok()?;
        Some((entry.name.clone(), Rc::clone(shape)))
    }

    /// The objects of the pool that could not be built so far, and why.
    pub fn unusable(&self) -> Vec<(String, String)> {
        self.pool
            .iter()
            .filter_map(|(_, entry)| match entry.built.get() {
                Some(Err(e)) => Some((entry.name.clone(), e.to_string())),
                _ => None,
            })
            .collect()
    }

    /// `count` objects drawn at random with repeats; one that cannot be built is drawn again.
    fn draw(&self, count: usize, rng: &mut ChaCha8Rng) -> Result<Vec<Drawn>> {
        let mut drawn = Vec::with_capacity(count);
        while drawn.len() < count {
            if self
                .pool
                .iter()
                .all(|(_, e)| matches!(e.built.get(), Some(Err(_))))
            {
                return Err(Error::Evaluate {
                    problem: "no object of the clutter suite's sets can be used".into(),
                });
            }
            if let Some(object) = self.object(rng.random_range(0..self.pool.len())) {
                drawn.push(object);
            }
        }
        Ok(drawn)
    }

    /// Runs round `round` of `scene` with `count` objects, planned on `views` depth views of
    /// `camera` cameras `distance_m` from the table's centre.
    ///
    /// # Errors
    /// An object that cannot be built, a render or a trial that fails.
    pub fn round(
        &self,
        renderer: &Renderer,
        (scene, views, count, round): (ClutterScene, usize, usize, usize),
        (camera, distance_m): (IntrinsicsPreset, f32),
    ) -> Result<RoundRecord> {
        let salt = match scene {
            ClutterScene::Packed => 0,
            ClutterScene::Pile => 0x5eed,
            ClutterScene::Bin => 0xb1,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(salt ^ (round as u64).wrapping_mul(0x9e37));
        let drawn = self.draw(count, &mut rng)?;
        let mut table = match scene {
            ClutterScene::Packed => self.pack(&drawn, &mut rng)?,
            ClutterScene::Pile | ClutterScene::Bin => self.pile(&drawn, scene, &mut rng)?,
        };
        let cameras = cameras(views, camera, distance_m)?;
        let pile = scene.pile_params();
        let fixed: Vec<(&PhysicsObject, Pose3)> = if scene == ClutterScene::Bin {
            self.walls
                .iter()
                .map(|(physics, pose)| (physics, *pose))
                .collect()
        } else {
            Vec::new()
        };
        let physics = &self.labels.physics;
        let gripper = &self.labels.gripper;
        let mut record = RoundRecord {
            scene,
            views,
            round,
            camera: camera.name().to_string(),
            distance_m,
            depth_from: self.rgb.as_ref().map(|rgb| rgb.kind().name().to_string()),
            objects: table.len(),
            fell_out: 0,
            attempts: Vec::new(),
        };
        let (mut failures_in_a_row, mut seed, mut resettles) = (0, 0u64, 0);
        while !table.is_empty() && failures_in_a_row < 2 {
            let objects_left = table.len();
            let Some((quality, grasp)) =
                self.plan(renderer, &table, !fixed.is_empty(), &cameras, (round, seed))?
            else {
                record.attempts.push(Attempt {
                    object: None,
                    objects_left,
                    quality: None,
                    outcome: Outcome::NoGrasp,
                    lift_m: None,
                });
                break;
            };
            // Each attempt samples anew (after a failure the scene is as before).
            seed += 1;
            let target = nearest(&table, grasp.center());
            let others: Vec<(&PhysicsObject, Pose3)> = table
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != target)
                .map(|(_, o)| Ok((o.physics(&self.labels)?, o.pose)))
                .collect::<Result<_>>()?;
            let trial = simulate_grasp_in_scene(
                table[target].physics(&self.labels)?,
                &table[target].pose,
                &others,
                &fixed,
                &grasp,
                gripper,
                physics,
            )?;
            let mut attempt = Attempt {
                object: Some(table[target].name.clone()),
                objects_left,
                quality: Some(quality),
                outcome: Outcome::Held,
                lift_m: Some(trial.object_lift_m),
            };
            match trial.failed_at {
                Some(FailureStage::Settle) if resettles < MAX_RESETTLES => {
                    // Settle the scene and try again, uncounted.
                    resettles += 1;
                    record.fell_out += self.settle(&mut table, &pile)?;
                    continue;
                }
                Some(FailureStage::Settle) => {
                    attempt.outcome = Outcome::Unsettled;
                    resettles = 0;
                    table.remove(target);
                    record.fell_out += self.settle(&mut table, &pile)?;
                }
                Some(stage) => {
                    attempt.outcome = Outcome::Failed(stage.name().to_string());
                    failures_in_a_row += 1;
                }
                None => {
                    table.remove(target);
                    record.fell_out += self.settle(&mut table, &pile)?;
                    failures_in_a_row = 0;
                }
            }
            record.attempts.push(attempt);
        }
        Ok(record)
    }

    /// The best grasp planned on `table` (in the bin, with `walls`) seen from `cameras` with
    /// `seed` in round `round` (which, with the seed, colours the objects for depth from RGB),
    /// and its quality.
    fn plan(
        &self,
        renderer: &Renderer,
        table: &[OnTable],
        walls: bool,
        cameras: &[Camera],
        (round, seed): (usize, u64),
    ) -> Result<Option<(f32, mvgrasp_grasp::Grasp)>> {
        let mut parts: Vec<TriangleMesh> = table
            .iter()
            .map(|o| o.shape.mesh().transformed(&o.pose))
            .collect();
        let depths = match &self.rgb {
            None => {
                if walls {
                    parts.push(self.bin.clone());
                }
                let merged = TriangleMesh::concatenate(&parts, parts[0].origin())?;
                render_depths(renderer, &merged, &Pose3::IDENTITY, cameras)?
            }
            Some(rgb) => {
                let objects = TriangleMesh::concatenate(&parts, parts[0].origin())?;
                let colours = splitmix(((round as u64) << 32) ^ seed);
                views::predicted_depths(
                    renderer,
                    rgb,
                    &objects,
                    walls.then_some(&self.bin),
                    cameras,
                    colours,
                )?
            }
        };
        let inside = ClutterScene::Bin.pile_params().box_half_side_m - BIN_MARGIN_M;
        let mut views = Vec::with_capacity(cameras.len());
        for (camera, depth) in cameras.iter().zip(depths) {
            // In the bin, the workspace is its inside: what stands over its floor, as a bin
            // picker is told where its bin is. Elsewhere no mask.
            let mask = if walls {
                match bin_mask(camera, &depth, inside) {
                    Some(mask) => Some(mask),
                    None => return Ok(None),
                }
            } else {
                None
            };
            views.push(View {
                camera: *camera,
                depth,
                mask,
            });
        }
        let gripper = &self.labels.gripper;
        let planned = match (&self.fused, views.len()) {
            (Some((planner, params)), n) if n > 1 => {
                let params = SensorPlanParams {
                    seed,
                    ..params.clone()
                };
                plan_on_views(planner, gripper, views, &params).map(|r| r.best)
            }
            _ => {
                let params = SensorPlanParams {
                    seed,
                    ..SensorPlanParams::default()
                };
                let view = views.into_iter().next().ok_or(Error::Evaluate {
                    problem: "a clutter round with no view".into(),
                })?;
                plan_on_view(&self.topdown, gripper, view, true, &params).map(|r| r.best)
            }
        };
        // A plan that finds nothing (no table, nothing on it, no candidate left) ends the
        // round, as VGN's "no grasp detected"; any other error (a network, a render) is the
        // evaluation's.
        match planned {
            Ok(best) => Ok(best.map(|b| (b.quality, b.grasp))),
            Err(e) if e.kind() == ErrorKind::Planning => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// `drawn` packed on the table: the first at the origin in its most probable resting pose,
    /// the rest around it.
    fn pack(&self, objects: &[Drawn], rng: &mut ChaCha8Rng) -> Result<Vec<OnTable>> {
        let shapes: Vec<Rc<Neighbour>> = objects.iter().map(|(_, s)| Rc::clone(s)).collect();
        let first_pose = shapes[0].most_probable_pose();
        let others = objects.len() - 1;
        let params = ClutterParams {
            neighbours: [others, others],
            spread_m: 0.1,
            gap_m: 0.005,
            tries: 50,
        };
        let mut poses = vec![(0, first_pose)];
        for p in place(shapes[0].mesh(), &first_pose, &shapes[1..], &params, rng) {
            poses.push((p.index + 1, p.table_from_neighbour));
        }
        Ok(poses
            .into_iter()
            .map(|(i, pose)| on_table(&objects[i], pose))
            .collect())
    }

    /// `drawn` dropped into `scene`'s box at random orientations, over its middle 10 cm.
    fn pile(
        &self,
        objects: &[Drawn],
        scene: ClutterScene,
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<OnTable>> {
        let drops: Vec<Drop<'_>> = objects
            .iter()
            .map(|(_, shape)| {
                Ok(Drop {
                    object: shape.physics(&self.labels.physics_shape)?,
                    rotation: random_rotation(rng),
                    xy: [rng.random_range(-0.05..0.05), rng.random_range(-0.05..0.05)],
                })
            })
            .collect::<Result<_>>()?;
        let rested = drop_pile(&drops, &scene.pile_params(), &self.labels.physics)?;
        Ok(objects
            .iter()
            .zip(rested)
            .filter_map(|(object, pose)| Some(on_table(object, pose?)))
            .collect())
    }

    /// Lets `table` rest (after an object was taken away); the number that left the workspace.
    fn settle(&self, table: &mut Vec<OnTable>, pile: &PileParams) -> Result<usize> {
        let objects: Vec<(&PhysicsObject, Pose3)> = table
            .iter()
            .map(|o| Ok((o.physics(&self.labels)?, o.pose)))
            .collect::<Result<_>>()?;
        let rested = settle_objects(&objects, pile, &self.labels.physics)?;
        let before = table.len();
        let mut kept = Vec::with_capacity(before);
        for (object, pose) in table.drain(..).zip(rested) {
            if let Some(pose) = pose {
                kept.push(OnTable { pose, ..object });
            }
        }
        *table = kept;
        Ok(before - table.len())
    }
}

fn on_table(object: &Drawn, pose: Pose3) -> OnTable {
    OnTable {
        name: object.0.clone(),
        shape: Rc::clone(&object.1),
        pose,
    }
}

/// A rotation drawn uniformly (Shoemake's subgroup algorithm).
fn random_rotation(rng: &mut impl Rng) -> Rot3 {
    let (u1, u2, u3): (f32, f32, f32) = (
        rng.random_range(0.0..1.0),
        rng.random_range(0.0..std::f32::consts::TAU),
        rng.random_range(0.0..std::f32::consts::TAU),
    );
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    Rot3::from_xyzw(a * u2.sin(), a * u2.cos(), b * u3.sin(), b * u3.cos()).normalize()
}

/// The object of `table` whose surface is nearest `point` (world frame).
fn nearest(table: &[OnTable], point: Vec3) -> usize {
    let distance = |o: &OnTable| {
        let local = o.pose.inverse_transform_point(point);
        o.shape
            .object()
            .caster()
            .trimesh()
            .distance_to_local_point(local, true)
    };
    (0..table.len())
        .min_by(|&a, &b| distance(&table[a]).total_cmp(&distance(&table[b])))
        .unwrap_or(0)
}
