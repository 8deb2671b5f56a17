//! Piles: objects dropped one by one into a box on the table, left to rest, and the box taken
//! away (VGN and GIGA's "pile" scenes), in the trial's rapier settings.

use mvgrasp_geometry::{Pose3, Rot3, Vec3};
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use crate::error::{GraspError, Result};
use crate::physics::object::PhysicsObject;
use crate::physics::params::PhysicsParams;
use crate::physics::scene::{insert_object, table_world};

/// How a pile is dropped and where it must stay.
///
/// | field | default | |
/// |---|---|---|
/// | `box_half_side_m` | 0.1 m | the box's inside is 20 cm square, centred on the origin |
/// | `box_height_m` | 0.15 m | its walls' height |
/// | `drop_gap_m` | 0.02 m | an object starts this far above the highest point so far |
/// | `rest_speed_m_s` | 0.01 m/s | at rest: every object's speed, linear and angular (rad/s) together, below this |
/// | `object_wait_s` | 1 s | at most this long for the pile to rest after each drop |
/// | `final_wait_s` | 2 s | and after the box is taken away |
/// | `workspace_half_side_m` | 0.15 m | an object whose centre of mass leaves the 30 cm square is taken away |
/// | `keep_box` | false | the box stays: a bin |
///
/// VGN drops each object from 20 cm; here it starts just above the pile, so that nothing
/// moves faster than the trial's contacts see coming (the trial's world has no continuous
/// collision detection).
#[derive(Clone, Debug, PartialEq)]
pub struct PileParams {
    /// Half the side of the box's square inside, metres.
    pub box_half_side_m: f32,
    /// Height of the box's walls, metres.
    pub box_height_m: f32,
    /// Gap between a dropped object's lowest point and the highest point below, metres.
    pub drop_gap_m: f32,
    /// Speed below which an object rests (its linear and angular velocities' joint norm).
    pub rest_speed_m_s: f32,
    /// The longest wait for rest after each drop, seconds.
    pub object_wait_s: f32,
    /// The longest wait for rest once the box is gone, seconds.
    pub final_wait_s: f32,
    /// Half the side of the square an object's centre of mass must stay in, metres.
    pub workspace_half_side_m: f32,
    /// The box stays on the table (a bin): [`drop_pile`] does not take it away and
    /// [`settle_objects`] settles the objects in it.
    pub keep_box: bool,
}

impl Default for PileParams {
    fn default() -> Self {
        Self {
            box_half_side_m: 0.1,
            box_height_m: 0.15,
            drop_gap_m: 0.02,
            rest_speed_m_s: 0.01,
            object_wait_s: 1.0,
            final_wait_s: 2.0,
            workspace_half_side_m: 0.15,
            keep_box: false,
        }
    }
}

impl PileParams {
    /// Checks every length and time is positive and finite, and the box inside the workspace.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let fields = [
            ("box_half_side_m", self.box_half_side_m),
            ("box_height_m", self.box_height_m),
            ("drop_gap_m", self.drop_gap_m),
            ("rest_speed_m_s", self.rest_speed_m_s),
            ("object_wait_s", self.object_wait_s),
            ("final_wait_s", self.final_wait_s),
            ("workspace_half_side_m", self.workspace_half_side_m),
        ];
        for (name, value) in fields {
            if !(value.is_finite() && value > 0.0) {
                return Err(GraspError::InvalidParameter {
                    op: "pile",
                    name,
                    value: value.to_string(),
                    expected: "a positive finite number",
                });
            }
        }
        if self.workspace_half_side_m < self.box_half_side_m {
            return Err(GraspError::InvalidParameter {
                op: "pile",
                name: "workspace_half_side_m",
                value: self.workspace_half_side_m.to_string(),
                expected: "at least box_half_side_m",
            });
        }
        Ok(())
    }
}

/// One object to drop: its shapes, its turn, and where over the table its centre of mass
/// comes down (table frame, metres; the height is the pile's).
#[derive(Clone, Copy, Debug)]
pub struct Drop<'a> {
    /// Its shapes and mass.
    pub object: &'a PhysicsObject,
    /// The object's orientation in the table frame as it is let go.
    pub rotation: Rot3,
    /// Where, in x and y, its centre of mass is let go.
    pub xy: [f32; 2],
}

/// Drops `drops` one by one into a box on the table, each just above everything dropped
/// before (moved in from a wall it would cross), waits after each for the pile to rest, takes the box away and waits again; then
/// takes away (repeatedly, waiting each time) any object whose centre of mass has left the
/// workspace square. Each object's resting pose (table frame, the pose to give
/// [`crate::physics::simulate_grasp_among`]), or `None` where it was taken away.
/// Deterministic: the same drops give the same pose bits.
///
/// # Errors
/// Invalid `pile` or `physics` settings, a non-finite rotation or position.
pub fn drop_pile(
    drops: &[Drop<'_>],
    pile: &PileParams,
    physics: &PhysicsParams,
) -> Result<Vec<Option<Pose3>>> {
    pile.validate()?;
    physics.validate()?;
    if let Some(bad) = drops
        .iter()
        .find(|d| !(d.rotation.is_finite() && d.xy.iter().all(|v| v.is_finite())))
    {
        return Err(GraspError::InvalidParameter {
            op: "pile",
            name: "drop",
            value: format!("{:?} at {:?}", bad.rotation, bad.xy),
            expected: "a finite rotation and position",
        });
    }
    let (mut world, _table) = table_world(physics);
    let walls = insert_box(&mut world, pile, physics);
    let mut bodies: Vec<Option<RigidBodyHandle>> = Vec::with_capacity(drops.len());
    for drop in drops {
        let turned = Pose3::from_rotation(drop.rotation);
        let extent = drop.object.shape().compute_aabb(&turned);
        let com = turned.transform_point(drop.object.center_of_mass());
        let top = highest_point(&world, &bodies, drops);
        // Centre of mass over (x, y), moved in as far as it takes to clear the walls (an
        // object let go across a wall would be thrown out of it); the lowest point
        // `drop_gap_m` above the pile.
        let inside = pile.box_half_side_m - 1.0e-3;
        let clamp = |want: f32, lo: f32, hi: f32, c: f32| {
            // Translation t puts the extent at [lo + t, hi + t]; keep it in [-inside, inside].
            let (min_t, max_t) = (-inside - lo, inside - hi);
            if min_t > max_t {
                (min_t + max_t) / 2.0
            } else {
                (want - c).clamp(min_t, max_t)
            }
        };
        let offset = Vec3::new(
            clamp(drop.xy[0], extent.mins.x, extent.maxs.x, com.x),
            clamp(drop.xy[1], extent.mins.y, extent.maxs.y, com.y),
            top + pile.drop_gap_m - extent.mins.z,
        );
        let pose = Pose3::from_parts(offset, drop.rotation);
        bodies.push(Some(insert_object(&mut world, drop.object, &pose, physics)));
        wait_for_rest(&mut world, &bodies, pile, pile.object_wait_s);
    }
    if !pile.keep_box {
        world.remove_body(walls);
    }
    Ok(rest_and_clear(&mut world, bodies, pile))
}

/// Lets `objects` (each at its pose on the table, as after a grasp took one of them away)
/// come to rest, and takes away what leaves the workspace square, as [`drop_pile`] ends; each
/// object's resting pose, or `None` where it was taken away.
///
/// # Errors
/// Invalid `pile` or `physics` settings, a non-finite pose.
pub fn settle_objects(
    objects: &[(&PhysicsObject, Pose3)],
    pile: &PileParams,
    physics: &PhysicsParams,
) -> Result<Vec<Option<Pose3>>> {
    pile.validate()?;
    physics.validate()?;
    if let Some((_, pose)) = objects.iter().find(|(_, pose)| !pose.is_finite()) {
        return Err(GraspError::InvalidParameter {
            op: "pile",
            name: "object pose",
            value: format!("{pose:?}"),
            expected: "a finite pose",
        });
    }
    let (mut world, _table) = table_world(physics);
    if pile.keep_box {
        insert_box(&mut world, pile, physics);
    }
    let bodies = objects
        .iter()
        .map(|(object, pose)| Some(insert_object(&mut world, object, pose, physics)))
        .collect();
    Ok(rest_and_clear(&mut world, bodies, pile))
}

/// Waits for rest, takes away what left the workspace, and again until nothing does; each
/// body's pose, `None` where taken away.
fn rest_and_clear(
    world: &mut PhysicsWorld,
    mut bodies: Vec<Option<RigidBodyHandle>>,
    pile: &PileParams,
) -> Vec<Option<Pose3>> {
    loop {
        wait_for_rest(world, &bodies, pile, pile.final_wait_s);
        let mut removed = false;
        for slot in &mut bodies {
            let Some(handle) = *slot else { continue };
            let outside = world.bodies.get(handle).is_none_or(|b| {
                let c = b.center_of_mass();
                c.x.abs() > pile.workspace_half_side_m
                    || c.y.abs() > pile.workspace_half_side_m
                    || c.z < 0.0
            });
            if outside {
                world.remove_body(handle);
                *slot = None;
                removed = true;
            }
        }
        if !removed {
            break;
        }
    }
    bodies
        .iter()
        .map(|slot| slot.and_then(|h| world.bodies.get(h).map(|b| *b.position())))
        .collect()
}

/// Half the thickness of the box's walls, metres.
const WALL_HALF_THICKNESS_M: f32 = 0.005;

/// The box's four walls standing on the table around the origin: each wall's half extents
/// and its centre (table frame, metres).
pub fn box_walls(pile: &PileParams) -> [(Vec3, Vec3); 4] {
    let (h, t, z) = (
        pile.box_half_side_m,
        WALL_HALF_THICKNESS_M,
        pile.box_height_m / 2.0,
    );
    let long = h + 2.0 * t;
    [
        (Vec3::new(t, long, z), Vec3::new(h + t, 0.0, z)),
        (Vec3::new(t, long, z), Vec3::new(-h - t, 0.0, z)),
        (Vec3::new(long, t, z), Vec3::new(0.0, h + t, z)),
        (Vec3::new(long, t, z), Vec3::new(0.0, -h - t, z)),
    ]
}

/// The box: a fixed body of its four walls, gripping like the table.
fn insert_box(
    world: &mut PhysicsWorld,
    pile: &PileParams,
    physics: &PhysicsParams,
) -> RigidBodyHandle {
    let body = world.insert_body(RigidBodyBuilder::fixed());
    for (half, centre) in box_walls(pile) {
        world.insert_collider(
            ColliderBuilder::cuboid(half.x, half.y, half.z)
                .translation(centre)
                .friction(physics.table_friction),
            Some(body),
        );
    }
    body
}

/// The highest point of the objects dropped so far (0: the table).
fn highest_point(
    world: &PhysicsWorld,
    bodies: &[Option<RigidBodyHandle>],
    drops: &[Drop<'_>],
) -> f32 {
    bodies
        .iter()
        .zip(drops)
        .filter_map(|(slot, drop)| {
            let body = world.bodies.get((*slot)?)?;
            Some(drop.object.shape().compute_aabb(body.position()).maxs.z)
        })
        .fold(0.0, f32::max)
}

/// Steps until every object rests (checked every quarter second, as VGN does) or `timeout_s`.
fn wait_for_rest(
    world: &mut PhysicsWorld,
    bodies: &[Option<RigidBodyHandle>],
    pile: &PileParams,
    timeout_s: f32,
) {
    let dt = world.integration_parameters.dt;
    let per_check = (0.25 / dt).round().max(1.0) as u32;
    let checks = (timeout_s / 0.25).ceil().max(1.0) as u32;
    for _ in 0..checks {
        for _ in 0..per_check {
            world.step();
        }
        let resting = bodies.iter().flatten().all(|&h| {
            world.bodies.get(h).is_none_or(|b| {
                let v = b.linvel();
                let w = b.angvel();
                (v.length_squared() + w.length_squared()).sqrt() <= pile.rest_speed_m_s
            })
        });
        if resting {
            return;
        }
    }
}
