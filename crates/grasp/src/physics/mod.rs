//! Physics validation of parallel-jaw grasps with rapier: close, lift, shake.
//!
//! [`PhysicsObject`] holds an object's convex parts and mass, built once; [`simulate_grasp`] runs
//! one deterministic trial of a [`crate::Grasp`] on it; [`success_probability`] runs many under
//! pose noise.
//!
//! # The scene
//!
//! World = table frame: +z up, the table's top is the plane z = 0 (a fixed slab). The object is
//! one dynamic body placed at `table_from_object`, colliding through its convex parts, with the
//! mesh's own mass, centre of mass and inertia at [`PhysicsParams::object_density_kg_m3`]. The
//! gripper is a kinematic palm box (the gripper's `palm_size_m`, behind the fingers) driven by
//! position, and two dynamic fingers on prismatic joints along the closing axis. Each joint has a
//! velocity motor (target: the closing speed) whose force is capped at the gripper's
//! `force_limit_n`: a finger moves at the closing speed until the object stops it, then squeezes
//! with the force limit. The two fingers are driven independently, as a coupled gripper behaves
//! while the object slides freely: the first finger to touch pushes the object until the other
//! one arrives. Fingers feel no gravity (the palm carries them) and do not collide with each
//! other or with the palm. The hand opens to the grasp's width plus the gripper's
//! `open_margin_m` ([`crate::Gripper::opening_for`]), as the collision checks do.
//!
//! # Pads and friction
//!
//! Each finger grips through a round pad of the gripper's `pad_radius_m` at its tip end: a ring
//! of small balls standing 3 mm proud of the finger's box, so an object pressed against the
//! finger touches the pad. Friction is Coulomb's, one cone per contact point, at the gripper's
//! `pad_friction` between the hand and the object and [`PhysicsParams::table_friction`] between
//! the object and the table. A round pad pressed with F resists a twist about its normal with
//! up to (2/3) mu F r: on a flat face the ring's contacts give exactly that (each has the lever
//! arm (2/3) r), and where fewer of them touch (a curved surface) a brake about the closing
//! axis makes up the rest, so the pad behaves as a patch, not a point; the brake reads the
//! solver's (clustered) contacts. Contacts are recycled only while a pair moves less than
//! 0.3 mm (rapier's default let the fingers squeeze through a can on stale contacts).
//!
//! `tests/mechanics.rs` checks the trial against answers from mechanics at 0.9 and 1.1 times
//! each threshold: a squeezed box sliding out (m g = 2 mu F), a bar turning in the grip (its
//! weight's torque = the pads' 2 (2/3) mu F r), a cylinder squeezed out on a chord (the contact
//! normal past atan(mu)), and an approach meeting the object or clearing it by 1 mm.

//! # The phases
//!
//! 1. Settle: the object alone on the table for [`PhysicsParams::settle_time_s`]. If it moves
//!    more than the settle tolerances the pose is not stable: [`FailureStage::Settle`].
//! 2. Approach: the open gripper (fingers open for the grasp) moves along its approach from
//!    the gripper's `approach_distance_m` back to the grasp pose. It is checked by a
//!    swept-volume test (conservative advancement on lower bounds of the distances from both
//!    fingers and the palm to the table and to the settled object's own triangles, by
//!    separating axes: not its collision shape, which may bulge past the surface), not
//!    stepped: coming within 0.1 mm of anything on the way, or at either end, is
//!    [`FailureStage::Approach`]. A kinematic hand stepped
//!    along the same path would feel the same contacts later and more coarsely, and could
//!    tunnel through a thin part; the sweep needs no simulated time.
//! 3. Close: the fingers close until both stop (three steps slower than a tenth of the closing
//!    speed), then squeeze for [`PhysicsParams::close_hold_s`]. Unless both fingers touch the
//!    object (closer than [`PhysicsParams::contact_tolerance_m`]) and the opening is wider than
//!    the gripper's narrowest: [`FailureStage::Close`].
//! 4. Lift: the palm rises [`PhysicsParams::lift_height_m`] straight up over
//!    [`PhysicsParams::lift_duration_s`] on a minimum-jerk profile, then holds still for
//!    [`PhysicsParams::lift_hold_s`]. Not held (below): [`FailureStage::Lift`].
//! 5. Shake: for [`PhysicsParams::shake_duration_s`] the palm moves up and down by
//!    [`PhysicsParams::shake_amplitude_m`] and turns about the closing axis by
//!    [`PhysicsParams::shake_angle_rad`] at [`PhysicsParams::shake_frequency_hz`], faded in and
//!    out by a half sine so it starts and ends at rest; then holds still for
//!    [`PhysicsParams::final_hold_s`]. Not held: [`FailureStage::Shake`].
//!
//! # Success
//!
//! The object is held when, at the end of a phase: both fingers are within
//! [`PhysicsParams::contact_tolerance_m`] of it (exact distances, not contact caches), it is
//! farther than that from the table, the fingers have not shut (their opening is wider than
//! the gripper's narrowest by more than a millimetre, as after the close), its centre of mass
//! has risen at least [`PhysicsParams::min_lift_fraction`] of the lift height above where it
//! rested, and, if [`PhysicsParams::max_slip_m`] is set, its centre of mass has moved at most
//! that much in the gripper frame since the fingers closed. A trial succeeds when the object is
//! held after the shake.
//!
//! rapier runs single-threaded here (the crate does not enable its `parallel` feature), so a
//! trial is deterministic: the same inputs give the same outcome and the same final pose bits.

mod object;
mod params;
mod pile;
mod robust;
mod scene;
pub mod shell;
mod trial;

pub use object::{PhysicsObject, shape_error};
pub use params::{PhysicsNoise, PhysicsParams};
pub use pile::{Drop, PileParams, box_walls, drop_pile, settle_objects};
pub use robust::{StageCounts, SuccessEstimate, success_probability, success_probability_among};
pub use scene::{PAD_BALL_RADIUS_M, PAD_BALLS, pad_ring_radius};
pub use shell::{ShapeError, ShapeParams};
pub use trial::{
    FailureStage, PhysicsOutcome, simulate_grasp, simulate_grasp_among, simulate_grasp_in_scene,
};
