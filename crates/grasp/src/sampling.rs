//! Antipodal grasp sampling on a mesh (Dex-Net's `AntipodalGraspSampler`, with parry ray casts).
//!
//! One try: a point on the surface (area-weighted), a closing direction inside the friction
//! cone about the inward normal there, the far surface found by casting back along that line
//! from the gripper's reach; the jaws closed on that line ([`crate::quality::find_contacts`]);
//! kept when the width fits and both contacts lie inside their friction cones (force closure).
//! Each kept axis is tried with several approach directions about it, and a grasp is kept when
//! the hand, swept along its approach, misses the object (and the table when the object rests
//! on one). Tries run in parallel batches, each from its own seed, and are accepted in order:
//! the same seed gives the same grasps for any thread count.

use std::f32::consts::TAU;

use mvgrasp_geometry::{Mat3, Pose3, Rot3, Vec3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::collision::{CollisionParams, check_collision};
use crate::error::{GraspError, Result};
use crate::grasp::Grasp;
use crate::gripper::Gripper;
use crate::object::GraspObject;
use crate::quality::{ContactPair, find_contacts, force_closure, grasp_seed};

/// How grasps are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SamplingParams {
    /// Stop once this many grasps are kept.
    pub target_grasps: usize,
    /// Give up after this many surface points.
    pub max_tries: usize,
    /// Friction coefficient of the antipodality check (Dex-Net 2.0: 0.5).
    pub friction_coef: f32,
    /// Approach directions tried about each kept closing axis, evenly spaced from a random
    /// start.
    pub approaches_per_axis: usize,
    /// A grasp closer than this to a kept one (centres) is a duplicate, metres...
    pub min_center_distance_m: f32,
    /// ...when its closing axis and approach are also within this angle of the kept one's.
    pub min_angle_rad: f32,
    /// Collision checks of the hand (approach sweep, clearance, table margin).
    pub collision: CollisionParams,
}

impl Default for SamplingParams {
    fn default() -> Self {
        Self {
            target_grasps: 100,
            max_tries: 4000,
            friction_coef: 0.5,
            approaches_per_axis: 8,
            min_center_distance_m: 0.0025,
            min_angle_rad: 0.2,
            collision: CollisionParams::default(),
        }
    }
}

impl SamplingParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`GraspError::InvalidParameter`] naming the first bad field.
    pub fn validate(&self) -> Result<()> {
        let bad = |name, value: String, expected| {
            Err(GraspError::InvalidParameter {
                op: "antipodal sampling",
                name,
                value,
                expected,
            })
        };
        if self.target_grasps == 0 {
            return bad("target_grasps", "0".into(), "at least 1");
        }
        if self.max_tries == 0 {
            return bad("max_tries", "0".into(), "at least 1");
        }
        if self.approaches_per_axis == 0 {
            return bad("approaches_per_axis", "0".into(), "at least 1");
        }
        if !(self.friction_coef.is_finite() && self.friction_coef > 0.0) {
            return bad(
                "friction_coef",
                self.friction_coef.to_string(),
                "a finite number > 0 (mu <= 0 has no friction cone)",
            );
        }
        for (name, value) in [
            ("min_center_distance_m", self.min_center_distance_m),
            ("min_angle_rad", self.min_angle_rad),
            ("collision.table_margin_m", self.collision.table_margin_m),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(name, value.to_string(), "a finite number >= 0");
            }
        }
        Ok(())
    }
}

/// A collision-free antipodal grasp on the object.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampledGrasp {
    /// The grasp in the object frame (`world_from_gripper` is `object_from_gripper` here).
    pub grasp: Grasp,
    /// Where the jaws touch, object frame.
    pub contacts: ContactPair,
}

/// Why tries were turned down.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Rejections {
    /// The line met no far surface, or a jaw would start inside the object.
    pub no_contacts: usize,
    /// The contacts were farther apart than the gripper opens (or closer than it closes).
    pub width: usize,
    /// A contact lies outside its friction cone: no force closure.
    pub friction: usize,
    /// Every approach about the axis hit the object or the table.
    pub collision: usize,
    /// Approaches that hit the object or the table (counted one by one).
    pub colliding_approaches: usize,
    /// Too close to a grasp already kept.
    pub duplicate: usize,
}

/// The grasps found and what it took.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SamplingReport {
    /// Kept grasps, in the order found.
    pub grasps: Vec<SampledGrasp>,
    /// Surface points tried.
    pub tries: usize,
    /// Antipodal axes found (before collision checks and duplicates).
    pub antipodal_axes: usize,
    /// Why the other tries failed.
    pub rejected: Rejections,
}

impl SamplingReport {
    /// A one-line account, e.g. for an object with no feasible grasp.
    pub fn summary(&self) -> String {
        let r = &self.rejected;
        format!(
            "{} grasps from {} tries ({} antipodal axes); turned down: {} no contacts, {} too wide or narrow, \
             {} outside the friction cone, {} every approach in collision, {} duplicates",
            self.grasps.len(),
            self.tries,
            self.antipodal_axes,
            r.no_contacts,
            r.width,
            r.friction,
            r.collision,
            r.duplicate
        )
    }
}

/// Tries evaluated together (in parallel) before their results are accepted in order.
const BATCH: usize = 64;

/// Samples up to `params.target_grasps` collision-free antipodal grasps on `object`.
///
/// With `table_from_object` (the object resting on the table, z = 0) grasps whose hand reaches
/// below the table are rejected too. An object with no feasible grasp gives an empty
/// `grasps` and a report that says why ([`SamplingReport::summary`]).
///
/// # Errors
/// [`GraspError::InvalidParameter`] for bad parameters or an invalid gripper.
pub fn sample_antipodal(
    object: &GraspObject,
    gripper: &Gripper,
    params: &SamplingParams,
    table_from_object: Option<&Pose3>,
    seed: u64,
) -> Result<SamplingReport> {
    params.validate()?;
    gripper.validate()?;
    let surface = SurfaceSampler::new(object);
    let mut report = SamplingReport {
        grasps: Vec::new(),
        tries: 0,
        antipodal_axes: 0,
        rejected: Rejections::default(),
    };
    let mut start = 0;
    while start < params.max_tries && report.grasps.len() < params.target_grasps {
        let end = (start + BATCH).min(params.max_tries);
        let outcomes: Vec<TryOutcome> = (start..end)
            .into_par_iter()
            .map(|i| {
                let mut rng = ChaCha8Rng::seed_from_u64(grasp_seed(seed, i));
                try_axis(
                    object,
                    gripper,
                    params,
                    table_from_object,
                    &surface,
                    &mut rng,
                )
            })
            .collect();
        for outcome in outcomes {
            if report.grasps.len() >= params.target_grasps {
                break;
            }
            report.tries += 1;
            accept(outcome, params, &mut report);
        }
        start = end;
    }
    Ok(report)
}

/// What one try found.
enum TryOutcome {
    NoContacts,
    Width,
    Friction,
    /// An antipodal axis: the grasps of its collision-free approaches, and how many collided.
    Axis {
        free: Vec<SampledGrasp>,
        colliding: usize,
    },
}

fn accept(outcome: TryOutcome, params: &SamplingParams, report: &mut SamplingReport) {
    let r = &mut report.rejected;
    match outcome {
        TryOutcome::NoContacts => r.no_contacts += 1,
        TryOutcome::Width => r.width += 1,
        TryOutcome::Friction => r.friction += 1,
        TryOutcome::Axis { free, colliding } => {
            report.antipodal_axes += 1;
            r.colliding_approaches += colliding;
            if free.is_empty() {
                r.collision += 1;
            }
            for candidate in free {
                if report.grasps.len() >= params.target_grasps {
                    break;
                }
                if report
                    .grasps
                    .iter()
                    .any(|kept| is_duplicate(&kept.grasp, &candidate.grasp, params))
                {
                    report.rejected.duplicate += 1;
                } else {
                    report.grasps.push(candidate);
                }
            }
        }
    }
}

/// Same place, same axis (either way round) and same approach, within the tolerances.
fn is_duplicate(a: &Grasp, b: &Grasp, params: &SamplingParams) -> bool {
    let cos = params.min_angle_rad.cos();
    a.center().distance(b.center()) < params.min_center_distance_m
        && a.closing_axis().dot(b.closing_axis()).abs() > cos
        && a.approach().dot(b.approach()) > cos
}

/// An antipodal closing line on the object, before any approach is chosen: what Dex-Net calls a
/// 3-D grasp (centre and axis).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AntipodalAxis {
    /// Midway between the contacts, object frame.
    pub center: Vec3,
    /// Where the jaws touch (its `closing_axis` is the grasp's axis), object frame.
    pub contacts: ContactPair,
}

impl AntipodalAxis {
    /// The closing axis, object frame (unit).
    pub fn axis(&self) -> Vec3 {
        self.contacts.closing_axis
    }

    /// The gripper frame at this axis approaching at `angle_rad` about it, measured from the
    /// canonical approach ([`canonical_frame`]); object frame.
    pub fn object_from_gripper(&self, angle_rad: f32) -> Pose3 {
        canonical_frame(self.center, self.axis(), angle_rad)
    }
}

/// The gripper frame at `center` closing along `axis`, its approach turned `angle_rad` about
/// the axis from a canonical one that depends only on the axis (so that grasps stored as a
/// centre and an axis can be rebuilt exactly).
pub fn canonical_frame(center: Vec3, axis: Vec3, angle_rad: f32) -> Pose3 {
    let [y0, z0] = perpendiculars(axis);
    let (s, c) = angle_rad.sin_cos();
    let z = z0 * c + y0 * s;
    let y = z.cross(axis);
    Pose3::from_parts(center, Rot3::from_mat3(&Mat3::from_cols(axis, y, z)))
}

/// Samples up to `target_axes` distinct antipodal axes on `object`, with no approach chosen and
/// no collision check (a caller that fixes the approach, such as a camera looking along it,
/// checks collisions then). Two axes are distinct unless their centres are within
/// `params.min_center_distance_m` and their axes within `params.min_angle_rad`. Seeded like
/// [`sample_antipodal`]: the same axes for any thread count.
///
/// # Errors
/// [`GraspError::InvalidParameter`] for bad parameters or an invalid gripper.
pub fn sample_antipodal_axes(
    object: &GraspObject,
    gripper: &Gripper,
    params: &SamplingParams,
    target_axes: usize,
    seed: u64,
) -> Result<Vec<AntipodalAxis>> {
    params.validate()?;
    gripper.validate()?;
    let surface = SurfaceSampler::new(object);
    let cos = params.min_angle_rad.cos();
    let mut axes: Vec<AntipodalAxis> = Vec::new();
    let mut start = 0;
    while start < params.max_tries && axes.len() < target_axes {
        let end = (start + BATCH).min(params.max_tries);
        let found: Vec<Option<AntipodalAxis>> = (start..end)
            .into_par_iter()
            .map(|i| {
                let mut rng = ChaCha8Rng::seed_from_u64(grasp_seed(seed, i));
                find_axis(object, gripper, params, &surface, &mut rng).ok()
            })
            .collect();
        for candidate in found.into_iter().flatten() {
            if axes.len() >= target_axes {
                break;
            }
            let duplicate = axes.iter().any(|kept| {
                kept.center.distance(candidate.center) < params.min_center_distance_m
                    && kept.axis().dot(candidate.axis()).abs() > cos
            });
            if !duplicate {
                axes.push(candidate);
            }
        }
        start = end;
    }
    Ok(axes)
}

/// One try's antipodal axis, or why there is none.
fn find_axis(
    object: &GraspObject,
    gripper: &Gripper,
    params: &SamplingParams,
    surface: &SurfaceSampler,
    rng: &mut ChaCha8Rng,
) -> std::result::Result<AntipodalAxis, TryOutcome> {
    let (p1, outward) = surface.sample(object, rng);
    let axis = sample_in_cone(-outward, params.friction_coef.atan(), rng);
    // The far jaw's start: as far along the axis as the gripper reaches.
    let reach = gripper.max_opening_m;
    // (A little past p1, so that p1 itself is met when nothing else is.)
    let Some(far) = object.caster().cast(p1 + axis * reach, -axis, reach + 1e-3) else {
        return Err(TryOutcome::NoContacts);
    };
    let width = p1.distance(far.point);
    // Meeting the start point again: the object is wider than the reach along this line.
    if width < 1e-4 || !gripper.fits(width) {
        return Err(TryOutcome::Width);
    }
    let frame = canonical_frame((p1 + far.point) / 2.0, axis, 0.0);
    let Some(contacts) = find_contacts(object, &frame, gripper) else {
        return Err(TryOutcome::NoContacts);
    };
    // `find_contacts` refuses mu <= 0, which `validate` already did.
    if !force_closure(&contacts, params.friction_coef).unwrap_or(false) {
        return Err(TryOutcome::Friction);
    }
    // Centre the gripper between the contacts it actually makes.
    let [c0, c1] = contacts.contacts.map(|c| c.point);
    Ok(AntipodalAxis {
        center: (c0 + c1) / 2.0,
        contacts,
    })
}

fn try_axis(
    object: &GraspObject,
    gripper: &Gripper,
    params: &SamplingParams,
    table_from_object: Option<&Pose3>,
    surface: &SurfaceSampler,
    rng: &mut ChaCha8Rng,
) -> TryOutcome {
    let found = match find_axis(object, gripper, params, surface, rng) {
        Ok(found) => found,
        Err(outcome) => return outcome,
    };
    let offset: f32 = rng.random_range(0.0..TAU);
    let k = params.approaches_per_axis;
    let mut free = Vec::with_capacity(k);
    let mut colliding = 0;
    for i in 0..k {
        let pose = found.object_from_gripper(offset + TAU * i as f32 / k as f32);
        let collision = check_collision(
            object,
            gripper,
            &pose,
            found.contacts.width_m,
            table_from_object,
            &params.collision,
        );
        if collision.is_free() {
            free.push(SampledGrasp {
                grasp: Grasp {
                    world_from_gripper: pose,
                    width_m: found.contacts.width_m,
                },
                contacts: found.contacts,
            });
        } else {
            colliding += 1;
        }
    }
    TryOutcome::Axis { free, colliding }
}

/// Two unit vectors that make a right-handed frame (`axis`, first, second).
fn perpendiculars(axis: Vec3) -> [Vec3; 2] {
    let helper = if axis.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    let y = axis.cross(helper).normalize();
    let z = axis.cross(y);
    [y, z]
}

/// A direction uniformly distributed (by solid angle) in the cone of `half_angle` about `axis`.
fn sample_in_cone(axis: Vec3, half_angle: f32, rng: &mut ChaCha8Rng) -> Vec3 {
    let cos_max = half_angle.cos();
    let cos_t: f32 = rng.random_range(cos_max..=1.0);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi: f32 = rng.random_range(0.0..TAU);
    let [u, v] = perpendiculars(axis);
    (axis * cos_t + (u * phi.cos() + v * phi.sin()) * sin_t).normalize()
}

/// Area-weighted points on the surface with their outward normals.
struct SurfaceSampler {
    /// Running sum of triangle areas.
    cumulative: Vec<f32>,
}

impl SurfaceSampler {
    fn new(object: &GraspObject) -> Self {
        let mesh = object.mesh();
        let mut total = 0.0;
        let cumulative = mesh
            .triangles()
            .iter()
            .map(|&t| {
                let [a, b, c] = mesh.triangle_corners(t);
                total += (b - a).cross(c - a).length() / 2.0;
                total
            })
            .collect();
        Self { cumulative }
    }

    fn sample(&self, object: &GraspObject, rng: &mut ChaCha8Rng) -> (Vec3, Vec3) {
        let mesh = object.mesh();
        let total = self.cumulative.last().copied().unwrap_or(0.0);
        let pick: f32 = rng.random_range(0.0..=total);
        let index = self
            .cumulative
            .partition_point(|&c| c < pick)
            .min(self.cumulative.len().saturating_sub(1));
        let [a, b, c] = mesh.triangle_corners(mesh.triangles()[index]);
        let (mut u, mut v): (f32, f32) = (rng.random(), rng.random());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let point = a + (b - a) * u + (c - a) * v;
        let normal = (b - a).cross(c - a).normalize_or_zero();
        (point, normal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mvgrasp_geometry::TriangleMesh;
    use parry3d::shape::Cuboid;

    fn cube(half: f32) -> GraspObject {
        let (v, t) = Cuboid::new(Vec3::splat(half)).to_trimesh();
        GraspObject::new(TriangleMesh::new(v, t).unwrap()).unwrap()
    }

    #[test]
    fn a_cube_gives_grasps_across_parallel_faces() {
        let params = SamplingParams {
            target_grasps: 30,
            ..SamplingParams::default()
        };
        let report = sample_antipodal(&cube(0.02), &Gripper::default(), &params, None, 7).unwrap();
        assert_eq!(report.grasps.len(), 30, "{}", report.summary());
        for g in &report.grasps {
            // The closing axis is (nearly) a face normal: within the friction cone.
            let axis = g.grasp.closing_axis();
            let largest = axis.abs().max_element();
            assert!(largest > 0.5f32.atan().cos() - 1e-3, "{axis:?}");
            assert!((g.grasp.width_m - 0.04).abs() < 0.02, "{}", g.grasp.width_m);
        }
    }

    #[test]
    fn the_same_seed_gives_the_same_grasps_on_any_thread_count() {
        let object = cube(0.02);
        let params = SamplingParams {
            target_grasps: 20,
            ..SamplingParams::default()
        };
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| sample_antipodal(&object, &Gripper::default(), &params, None, 3))
                .unwrap()
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn an_object_wider_than_the_gripper_has_no_grasp_and_says_why() {
        let yumi = Gripper::preset(crate::GripperPreset::Yumi);
        let params = SamplingParams {
            max_tries: 200,
            ..SamplingParams::default()
        };
        let report = sample_antipodal(&cube(0.04), &yumi, &params, None, 1).unwrap();
        assert!(report.grasps.is_empty());
        assert_eq!(report.tries, 200);
        assert!(report.rejected.width > 100, "{}", report.summary());
        assert!(report.summary().starts_with("0 grasps from 200 tries"));
    }

    #[test]
    fn bad_parameters_are_errors() {
        let object = cube(0.02);
        for params in [
            SamplingParams {
                friction_coef: 0.0,
                ..SamplingParams::default()
            },
            SamplingParams {
                target_grasps: 0,
                ..SamplingParams::default()
            },
        ] {
            assert!(sample_antipodal(&object, &Gripper::default(), &params, None, 0).is_err());
        }
    }
}
