//! Clutter: each object of a dataset rendered among neighbours drawn from the same object list,
//! packed on the table around it, so that its crops show what a pile or a bin shows around a
//! grasp, and its labels count the hand meeting any neighbour.
//!
//! The object's own grasps are sampled and scored on it alone (robust Ferrari-Canny does not
//! depend on the neighbours); a grasp is collision-free only when the open hand, swept along
//! its approach, meets neither the object, nor the table, nor any neighbour. The neighbours
//! rest in one of their stable poses (drawn by probability), turned about the vertical at
//! random, each placed where its footprint (the box its vertices cover on the table) keeps a
//! gap from every footprint placed before it. Grasps are made on the object only, never on a
//! neighbour, so that an object-wise split of the dataset stays object-wise for the grasps.

use std::borrow::Borrow;

use mvgrasp_geometry::{Pose3, RestingPoses, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::physics::{PhysicsObject, ShapeParams};
use mvgrasp_grasp::{GraspObject, Gripper, HandShapes};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, RuntimeError};

/// How the neighbours are chosen and placed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClutterParams {
    /// Neighbours per stable pose of the object, drawn uniformly from this inclusive range.
    pub neighbours: [usize; 2],
    /// A neighbour's centre lies within this of the object's (a square's half side), metres.
    pub spread_m: f32,
    /// Footprints keep at least this apart, metres (0: they may touch).
    pub gap_m: f32,
    /// Places tried for each neighbour before it is left out.
    pub tries: usize,
}

impl Default for ClutterParams {
    fn default() -> Self {
        Self {
            neighbours: [2, 8],
            spread_m: 0.15,
            gap_m: 0.003,
            tries: 30,
        }
    }
}

impl ClutterParams {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`Error::ConfigValue`] naming the key.
    pub fn validate(&self) -> Result<()> {
        let [lo, hi] = self.neighbours;
        if lo > hi || hi == 0 {
            return Err(Error::from(RuntimeError::ConfigValue {
                key: "clutter.neighbours",
                value: format!("{:?}", self.neighbours),
                expected: "[min, max] with min <= max and max >= 1",
            }));
        }
        if !(self.spread_m.is_finite() && self.spread_m > 0.0 && self.spread_m <= 1.0) {
            return Err(Error::from(RuntimeError::ConfigValue {
                key: "clutter.spread_m",
                value: format!("{}", self.spread_m),
                expected: "in (0, 1] metres",
            }));
        }
        if !(self.gap_m.is_finite() && self.gap_m >= 0.0) {
            return Err(Error::from(RuntimeError::ConfigValue {
                key: "clutter.gap_m",
                value: format!("{}", self.gap_m),
                expected: "at least 0 metres",
            }));
        }
        if self.tries == 0 {
            return Err(Error::from(RuntimeError::ConfigValue {
                key: "clutter.tries",
                value: "0".into(),
                expected: "at least 1",
            }));
        }
        Ok(())
    }
}

/// A neighbour as loaded once for an object: its mesh, the shape the hand check meets, and
/// its steady resting poses with their probabilities (and, built when the physics labels ask,
/// its shapes for the trial).
pub struct Neighbour {
    mesh: TriangleMesh,
    object: GraspObject,
    poses: Vec<(f32, Pose3)>,
    physics: std::sync::OnceLock<PhysicsObject>,
}

impl Neighbour {
    /// Its mesh, in its own frame.
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// The shape the hand check meets.
    pub fn object(&self) -> &GraspObject {
        &self.object
    }

    /// Its shapes for the trial, built with `shape` on first use (one dataset, one `shape`).
    ///
    /// # Errors
    /// A mesh the trial's shapes cannot be built from (tried again on the next call).
    pub fn physics(&self, shape: &ShapeParams) -> Result<&PhysicsObject> {
        if let Some(built) = self.physics.get() {
            return Ok(built);
        }
        let built = PhysicsObject::from_grasp_object(&self.object, shape)?;
        Ok(self.physics.get_or_init(|| built))
    }

    /// Its most probable steady resting pose.
    pub fn most_probable_pose(&self) -> Pose3 {
        self.poses[0].1
    }

    /// `mesh` as a neighbour.
    ///
    /// # Errors
    /// A mesh with no stable pose (an empty list of them included) or that the hand check
    /// cannot use.
    pub fn new(mesh: TriangleMesh) -> Result<Self> {
        let resting = RestingPoses::of(&mesh)?;
        // At least one pose: the first is the most probable.
        resting.get(0)?;
        let poses = resting
            .iter()
            .map(|(_, p)| (p.probability, p.table_from_object))
            .collect();
        Ok(Self {
            object: GraspObject::new(mesh.clone())?,
            mesh,
            poses,
            physics: std::sync::OnceLock::new(),
        })
    }
}

/// A neighbour placed on the table.
#[derive(Clone, Copy, Debug)]
pub struct Placed {
    /// Index into the neighbours.
    pub index: usize,
    /// Where it rests.
    pub table_from_neighbour: Pose3,
}

/// The box a mesh's vertices cover on the table, `[min x, min y, max x, max y]`.
fn footprint(mesh: &TriangleMesh, table_from_mesh: &Pose3) -> [f32; 4] {
    mesh.vertices().iter().fold(
        [
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        ],
        |[x0, y0, x1, y1], v| {
            let p = table_from_mesh.transform_point(*v);
            [x0.min(p.x), y0.min(p.y), x1.max(p.x), y1.max(p.y)]
        },
    )
}

fn apart(a: [f32; 4], b: [f32; 4], gap: f32) -> bool {
    a[2] + gap <= b[0] || b[2] + gap <= a[0] || a[3] + gap <= b[1] || b[3] + gap <= a[1]
}

/// `wanted` of `items`, drawn without repeats in a random order (the first `wanted` of a
/// Fisher-Yates shuffle).
pub(crate) fn draw_without_repeats(
    mut items: Vec<usize>,
    wanted: usize,
    rng: &mut impl Rng,
) -> Vec<usize> {
    let wanted = wanted.min(items.len());
    for i in 0..wanted {
        let j = rng.random_range(i..items.len());
        items.swap(i, j);
    }
    items.truncate(wanted);
    items
}

/// Places a random number of `neighbours` (each at most once, in a random order) around the
/// object `mesh` resting at `table_from_object`.
pub fn place(
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    neighbours: &[impl Borrow<Neighbour>],
    params: &ClutterParams,
    rng: &mut impl Rng,
) -> Vec<Placed> {
    let [lo, hi] = params.neighbours;
    let wanted = rng.random_range(lo..=hi);
    let order = draw_without_repeats((0..neighbours.len()).collect(), wanted, rng);
    let mut footprints = vec![footprint(mesh, table_from_object)];
    let mut placed = Vec::new();
    for index in order {
        let neighbour: &Neighbour = neighbours[index].borrow();
        let total: f32 = neighbour.poses.iter().map(|(p, _)| p).sum();
        for _ in 0..params.tries {
            let mut pick = rng.random_range(0.0..total.max(f32::MIN_POSITIVE));
            let pose = neighbour
                .poses
                .iter()
                .find(|(p, _)| {
                    pick -= p;
                    pick <= 0.0
                })
                .map_or(neighbour.poses[0].1, |(_, pose)| *pose);
            let yaw = rng.random_range(0.0..std::f32::consts::TAU);
            let s = params.spread_m;
            let at = Vec3::new(rng.random_range(-s..s), rng.random_range(-s..s), 0.0);
            let table_from_neighbour = Pose3::from_parts(at, Rot3::from_rotation_z(yaw)) * pose;
            let area = footprint(&neighbour.mesh, &table_from_neighbour);
            if footprints.iter().all(|f| apart(*f, area, params.gap_m)) {
                footprints.push(area);
                placed.push(Placed {
                    index,
                    table_from_neighbour,
                });
                break;
            }
        }
    }
    placed
}

/// The object and its placed neighbours as one mesh in the table frame.
///
/// # Errors
/// A mesh that cannot be joined (no triangles).
pub fn scene_mesh(
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    neighbours: &[impl Borrow<Neighbour>],
    placed: &[Placed],
) -> Result<TriangleMesh> {
    let mut parts = vec![mesh.transformed(table_from_object)];
    parts.extend(placed.iter().map(|p| {
        neighbours[p.index]
            .borrow()
            .mesh
            .transformed(&p.table_from_neighbour)
    }));
    Ok(TriangleMesh::concatenate(&parts, mesh.origin())?)
}

/// Whether the open hand of a grasp `width_m` wide at `table_from_gripper`, swept along its
/// approach, meets a placed neighbour.
pub fn hits_a_neighbour(
    gripper: &Gripper,
    table_from_gripper: &Pose3,
    width_m: f32,
    neighbours: &[impl Borrow<Neighbour>],
    placed: &[Placed],
) -> bool {
    if placed.is_empty() {
        return false;
    }
    let hand = HandShapes::new(
        gripper,
        gripper.opening_for(width_m),
        gripper.approach_distance_m,
    );
    placed.iter().any(|p| {
        let neighbour_from_gripper = p.table_from_neighbour.inverse() * *table_from_gripper;
        hand.hits_object(
            &neighbours[p.index].borrow().object,
            &neighbour_from_gripper,
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn cube(half: f32) -> TriangleMesh {
        let (v, t) = parry3d::shape::Cuboid::new(Vec3::splat(half)).to_trimesh();
        TriangleMesh::new(v, t).unwrap()
    }

    fn resting(half: f32) -> Pose3 {
        Pose3::from_parts(Vec3::new(0.0, 0.0, half), Rot3::IDENTITY)
    }

    #[test]
    fn neighbours_are_placed_apart_and_deterministically() {
        let neighbours: Vec<Neighbour> = (0..6)
            .map(|i| Neighbour::new(cube(0.01 + 0.002 * i as f32)).unwrap())
            .collect();
        let params = ClutterParams {
            neighbours: [6, 6],
            ..ClutterParams::default()
        };
        let object = cube(0.03);
        let placed_with = |seed| {
            place(
                &object,
                &resting(0.03),
                &neighbours,
                &params,
                &mut ChaCha8Rng::seed_from_u64(seed),
            )
        };
        let placed = placed_with(1);
        assert!(placed.len() >= 4, "{}", placed.len());
        let mut areas = vec![footprint(&object, &resting(0.03))];
        for p in &placed {
            let area = footprint(&neighbours[p.index].mesh, &p.table_from_neighbour);
            assert!(areas.iter().all(|a| apart(*a, area, params.gap_m)));
            // On the table: the lowest vertex at z = 0.
            let lowest = neighbours[p.index]
                .mesh
                .vertices()
                .iter()
                .map(|v| p.table_from_neighbour.transform_point(*v).z)
                .fold(f32::INFINITY, f32::min);
            assert!(lowest.abs() < 1e-4, "{lowest}");
            areas.push(area);
        }
        let again = placed_with(1);
        assert_eq!(placed.len(), again.len());
        for (a, b) in placed.iter().zip(&again) {
            assert_eq!(a.index, b.index);
            assert_eq!(a.table_from_neighbour, b.table_from_neighbour);
        }
        let mesh = scene_mesh(&object, &resting(0.03), &neighbours, &placed).unwrap();
        assert_eq!(mesh.triangles().len(), 12 * (1 + placed.len()));
    }

    #[test]
    fn a_hand_coming_down_on_a_neighbour_meets_it() {
        let neighbours = vec![Neighbour::new(cube(0.02)).unwrap()];
        let gripper = Gripper::default();
        // A neighbour 4 cm to the side of a grasp closing along x at 3 cm above the table.
        let placed = [Placed {
            index: 0,
            table_from_neighbour: Pose3::from_parts(Vec3::new(0.05, 0.0, 0.02), Rot3::IDENTITY),
        }];
        let down = |x: f32| {
            Pose3::from_parts(
                Vec3::new(x, 0.0, 0.03),
                Rot3::from_rotation_x(std::f32::consts::PI),
            )
        };
        assert!(hits_a_neighbour(
            &gripper,
            &down(0.0),
            0.04,
            &neighbours,
            &placed
        ));
        assert!(!hits_a_neighbour(
            &gripper,
            &down(-0.2),
            0.04,
            &neighbours,
            &placed
        ));
        assert!(!hits_a_neighbour(
            &gripper,
            &down(0.0),
            0.04,
            &neighbours,
            &[]
        ));
    }

    #[test]
    fn bad_ranges_are_refused_by_name() {
        let bad = ClutterParams {
            neighbours: [3, 1],
            ..ClutterParams::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("neighbours")
        );
        let bad = ClutterParams {
            spread_m: 0.0,
            ..ClutterParams::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("spread_m"));
        assert!(ClutterParams::default().validate().is_ok());
    }
}
