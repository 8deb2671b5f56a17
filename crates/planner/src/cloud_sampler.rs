//! Antipodal grasp candidates on the fused model of the views ([`Fusion`]), in any direction
//! the arm can reach: not tied to a camera's optical axis, so a bowl's sloping wall can be
//! pinched along its normal, a tall object from the side and a mug by its rim.
//!
//! A contact is drawn among the object's observed points; its normal is the direction of least
//! spread of the points around it (principal components), turned to the side the views saw
//! free (both sides of a thin wall can be free: then both are tried). The closing axis enters
//! the surface within half the friction cone of the normal and is followed through the model
//! until it comes out into free space: the last observed points before that, near the axis,
//! are the second contact, which must lie within the friction cone too. A pair whose axis runs
//! into the table, into space no view has seen or past the hand's widest opening is dropped.
//! The approach is the direction across the closing axis nearest straight down, and that
//! turned about the axis by [`CloudSamplerParams::approach_turns_rad`], within the reachable
//! cone; the fingertips go [`CloudSamplerParams::depth_offsets_m`] past the contacts' midpoint.
//! The hand check and the virtual views' network decide which are good grasps.

use mvgrasp_geometry::{Mat3, Pose3, Rot3, Vec3};
use mvgrasp_grasp::Grasp;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

use crate::fusion::{Fusion, Occupancy};

/// Parameters of [`sample_cloud_grasps`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CloudSamplerParams {
    /// Grasps wanted (contact pairs times approaches times depths).
    pub num_grasps: usize,
    /// Contacts drawn at most.
    pub max_tries: usize,
    /// Coulomb friction coefficient: the cone's half-angle is atan(mu).
    pub friction_coef: f32,
    /// Narrowest grasp, metres.
    pub min_width_m: f32,
    /// Points within this of a contact give its normal, metres.
    pub normal_radius_m: f32,
    /// Points within this of the closing axis can be the second contact, metres.
    pub axis_radius_m: f32,
    /// Contacts at least this far above the table, metres.
    pub min_height_m: f32,
    /// The approach stays within this of straight down (the arm's reachable cone), radians.
    pub max_tilt_rad: f32,
    /// The approaches tried per pair: the one nearest straight down turned about the closing
    /// axis by these, radians.
    pub approach_turns_rad: Vec<f32>,
    /// How far past the contacts' midpoint, along the approach, the fingertips go, metres.
    pub depth_offsets_m: Vec<f32>,
    /// A pair whose centre lies within this of an earlier pair's, with its axis within
    /// `min_angle_rad`, is dropped, metres.
    pub min_distance_m: f32,
    /// See `min_distance_m`, radians.
    pub min_angle_rad: f32,
}

impl Default for CloudSamplerParams {
    fn default() -> Self {
        Self {
            num_grasps: 120,
            max_tries: 3000,
            friction_coef: 0.5,
            min_width_m: 0.002,
            normal_radius_m: 0.005,
            axis_radius_m: 0.002,
            min_height_m: 0.005,
            max_tilt_rad: 75f32.to_radians(),
            approach_turns_rad: vec![0.0, 0.5, -0.5],
            depth_offsets_m: vec![0.005, 0.02],
            min_distance_m: 0.003,
            min_angle_rad: 0.2,
        }
    }
}

/// The fused model's observed points in cubes of a side, for neighbour queries.
struct PointGrid<'a> {
    points: &'a [Vec3],
    side: f32,
    cells: FxHashMap<[i32; 3], Vec<u32>>,
}

impl<'a> PointGrid<'a> {
    fn new(points: &'a [Vec3], side: f32) -> Self {
        let mut cells = FxHashMap::<[i32; 3], Vec<u32>>::default();
        for (i, p) in points.iter().enumerate() {
            cells.entry(key(*p, side)).or_default().push(i as u32);
        }
        Self {
            points,
            side,
            cells,
        }
    }

    /// The points within `radius` (at most the grid's side) of `p`.
    fn near(&self, p: Vec3, radius: f32) -> impl Iterator<Item = Vec3> + '_ {
        let [x, y, z] = key(p, self.side);
        let r2 = radius * radius;
        (-1..=1)
            .flat_map(move |dz| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| [dx, dy, dz])))
            .filter_map(move |[dx, dy, dz]| self.cells.get(&[x + dx, y + dy, z + dz]))
            .flatten()
            .map(|&i| self.points[i as usize])
            .filter(move |q| q.distance_squared(p) <= r2)
    }

    /// The unit normal (unoriented) of the surface at `p`: the least principal direction of
    /// its neighbours, when there are enough of them and they spread over a surface.
    fn normal(&self, p: Vec3, radius: f32) -> Option<Vec3> {
        let near: Vec<Vec3> = self.near(p, radius).collect();
        if near.len() < 6 {
            return None;
        }
        let mean = near.iter().copied().sum::<Vec3>() / near.len() as f32;
        let mut cov = Mat3::ZERO;
        for q in &near {
            let d = *q - mean;
            cov += Mat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        let (values, vectors) = symmetric_eigen(cov);
        // A surface: two directions spread, the third much less.
        (values[0] < 0.3 * values[1]).then(|| vectors[0].normalize())
    }
}

fn key(p: Vec3, side: f32) -> [i32; 3] {
    let c = (p / side).floor();
    [c.x as i32, c.y as i32, c.z as i32]
}

/// Eigenvalues (ascending) and unit eigenvectors of a symmetric 3x3 matrix, by Jacobi
/// rotations.
fn symmetric_eigen(m: Mat3) -> ([f32; 3], [Vec3; 3]) {
    let mut a = [
        [m.x_axis.x, m.y_axis.x, m.z_axis.x],
        [m.x_axis.y, m.y_axis.y, m.z_axis.y],
        [m.x_axis.z, m.y_axis.z, m.z_axis.z],
    ];
    let mut v = [[1.0f32, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-12 * (a[0][0].abs() + a[1][1].abs() + a[2][2].abs()).max(1e-30) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-30 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (row_p, row_q) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * row_p[k] - s * row_q[k];
                a[q][k] = s * row_p[k] + c * row_q[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[i][i].total_cmp(&a[j][j]));
    let column = |j: usize| Vec3::new(v[0][j], v[1][j], v[2][j]);
    (order.map(|i| a[i][i]), order.map(column))
}

/// How far past the object's box its points may lie, metres (a few point cubes).
const OBJECT_BOX_SLACK_M: f32 = 0.005;

/// Antipodal grasps on `fusion`'s observed points of the object (see the module docs), at most
/// `max_width_m` wide; deterministic from `seed`.
pub fn sample_cloud_grasps(
    fusion: &Fusion,
    max_width_m: f32,
    params: &CloudSamplerParams,
    seed: u64,
) -> Vec<Grasp> {
    let floor = fusion.table_z_m() + params.min_height_m;
    // The object's points: above the table and within the object's box (grown by one point
    // cube: a kept point is the mean of those in its cube), so that a neighbour outside the
    // views' masks or a bin's wall is not grasped.
    let (lo, hi) = fusion.object_bounds();
    let (lo, hi) = (
        lo - Vec3::splat(OBJECT_BOX_SLACK_M),
        hi + Vec3::splat(OBJECT_BOX_SLACK_M),
    );
    let object: Vec<Vec3> = fusion
        .points()
        .iter()
        .copied()
        .filter(|p| p.z > floor && p.cmpge(lo).all() && p.cmple(hi).all())
        .collect();
    if object.is_empty() || params.num_grasps == 0 {
        return Vec::new();
    }
    let grid = PointGrid::new(&object, params.normal_radius_m.max(params.axis_radius_m));
    let cone = params.friction_coef.atan();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut pairs: Vec<(Vec3, Vec3)> = Vec::new();
    let mut grasps = Vec::new();
    for _ in 0..params.max_tries {
        if grasps.len() >= params.num_grasps {
            break;
        }
        let p1 = object[rng.random_range(0..object.len())];
        let Some(normal) = grid.normal(p1, params.normal_radius_m) else {
            continue;
        };
        // A random axis within half the cone of the inward normal, for each side seen free.
        let jitter = random_in_cone(&mut rng, 0.5 * cone);
        for inward in outward_sides(fusion, p1, normal).map(|n| -n) {
            let axis = turn_within(inward, jitter);
            let Some((width, p2)) = far_contact(fusion, &grid, p1, axis, max_width_m, params)
            else {
                continue;
            };
            let Some(n2) = grid.normal(p2, params.normal_radius_m) else {
                continue;
            };
            if n2.dot(axis).abs() < cone.cos() {
                continue;
            }
            let centre = 0.5 * (p1 + p2);
            if pairs.iter().any(|(c, a)| {
                c.distance(centre) < params.min_distance_m
                    && a.dot(axis).abs() > params.min_angle_rad.cos()
            }) {
                continue;
            }
            pairs.push((centre, axis));
            let table = fusion.table_z_m();
            grasps.extend(approaches(axis, params).into_iter().flat_map(|approach| {
                params.depth_offsets_m.iter().filter_map(move |&depth| {
                    // Fingertips below the table: the hand check would drop it.
                    let tips = centre + approach * depth;
                    (tips.z > table).then(|| Grasp {
                        world_from_gripper: Pose3::from_parts(
                            tips,
                            Rot3::from_mat3(&Mat3::from_cols(axis, approach.cross(axis), approach)),
                        ),
                        width_m: width,
                    })
                })
            }));
        }
    }
    grasps.truncate(params.num_grasps);
    grasps
}

/// The outward normals at `p`: `normal` or its reverse, whichever side the views saw free
/// just off the surface (both for a thin wall seen from both sides).
fn outward_sides(fusion: &Fusion, p: Vec3, normal: Vec3) -> impl Iterator<Item = Vec3> {
    let step = 1.5 * fusion.voxel_m();
    let free = move |n: Vec3| fusion.at(p + n * step) == Some(Occupancy::Free);
    [normal, -normal].into_iter().filter(move |&n| free(n))
}

/// A direction within `half_angle` of +z: (polar angle, azimuth).
fn random_in_cone(rng: &mut ChaCha8Rng, half_angle: f32) -> (f32, f32) {
    let cos = rng.random_range(half_angle.cos()..=1.0);
    (
        cos.clamp(-1.0, 1.0).acos(),
        rng.random_range(0.0..std::f32::consts::TAU),
    )
}

/// `direction` tilted by the polar angle of `turn` towards its azimuth.
fn turn_within(direction: Vec3, (polar, azimuth): (f32, f32)) -> Vec3 {
    let side = direction.any_orthonormal_vector();
    let side = Rot3::from_axis_angle(direction, azimuth) * side;
    (Rot3::from_axis_angle(side, polar) * direction).normalize()
}

/// Where the closing axis from `p1` along `axis` comes out of the object: (width, the second
/// contact), if it comes out into free space within the hand's opening, above the table,
/// having met no unseen space on the way past the object's far surface.
fn far_contact(
    fusion: &Fusion,
    grid: &PointGrid,
    p1: Vec3,
    axis: Vec3,
    max_width_m: f32,
    params: &CloudSamplerParams,
) -> Option<(f32, Vec3)> {
    let step = 0.5 * fusion.voxel_m();
    let floor = fusion.table_z_m() + params.min_height_m;
    let mut t = step;
    let exit = loop {
        if t > max_width_m + fusion.voxel_m() {
            return None;
        }
        let p = p1 + axis * t;
        if p.z < floor {
            return None;
        }
        match fusion.at(p)? {
            Occupancy::Free => break t,
            Occupancy::Unknown | Occupancy::Occupied => {}
        }
        t += step;
    };
    // The farthest observed point near the axis before the free space.
    let r2 = params.axis_radius_m * params.axis_radius_m;
    let mut far: Option<f32> = None;
    let mut s = 0.0;
    while s <= exit + step {
        for q in grid.near(p1 + axis * s, grid.side) {
            let along = (q - p1).dot(axis);
            let off = (q - p1) - axis * along;
            if off.length_squared() <= r2 && along <= exit + step {
                far = Some(far.map_or(along, |f: f32| f.max(along)));
            }
        }
        s += grid.side;
    }
    let width = far?;
    (width >= params.min_width_m && width <= max_width_m).then(|| (width, p1 + axis * width))
}

/// The approach directions across `axis`: the one nearest straight down, turned about the
/// axis by each of the parameters' turns, those within the reachable cone.
fn approaches(axis: Vec3, params: &CloudSamplerParams) -> Vec<Vec3> {
    let down = Vec3::NEG_Z;
    let across = down - axis * down.dot(axis);
    if across.length() < 1e-3 {
        return Vec::new();
    }
    let nearest = across.normalize();
    params
        .approach_turns_rad
        .iter()
        .map(|&turn| Rot3::from_axis_angle(axis, turn) * nearest)
        .filter(|a| a.dot(down).clamp(-1.0, 1.0).acos() <= params.max_tilt_rad)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fusion::FusionParams;
    use crate::scored::tilt_rad;
    use crate::test_scenes::{box_view, seen_box};

    #[test]
    fn eigenvectors_of_a_symmetric_matrix() {
        let r = Rot3::from_scaled_axis(Vec3::new(0.3, -0.5, 0.9));
        let d = Mat3::from_diagonal(Vec3::new(3.0, 1.0, 0.01));
        let m = Mat3::from_quat(r) * d * Mat3::from_quat(r).transpose();
        let (values, vectors) = symmetric_eigen(m);
        assert!(
            (values[0] - 0.01).abs() < 1e-4 && (values[2] - 3.0).abs() < 1e-4,
            "{values:?}"
        );
        let least = r * Vec3::Z;
        assert!(vectors[0].dot(least).abs() > 0.9999, "{vectors:?}");
    }

    #[test]
    fn a_cube_seen_from_both_sides_is_pinched_across_the_faces_the_views_saw() {
        // Two oblique views from -x and +x of a 4 cm cube: its +-x faces and its top are seen,
        // the +-y faces are not. Pairs across x come out into the free space the other view
        // saw; pairs across y meet unseen space; the top's axis runs into the table.
        let views = [seen_box(-1.0), seen_box(1.0)];
        let fusion = Fusion::build(&views, &FusionParams::default()).unwrap();
        let params = CloudSamplerParams::default();
        let grasps = sample_cloud_grasps(&fusion, 0.08, &params, 7);
        assert!(grasps.len() >= 30, "{} grasps", grasps.len());
        for g in &grasps {
            let axis = g.closing_axis();
            // Within half the friction cone of the faces' normal (and the normals' error).
            assert!(axis.x.abs() > 0.26f32.cos(), "axis {axis:?}");
            assert!((g.width_m - 0.04).abs() < 0.004, "width {}", g.width_m);
            assert!(tilt_rad(g) <= params.max_tilt_rad + 1e-4);
            // The contacts on the faces; the fingertips up to 2 cm past them along the approach.
            let c = g.center();
            assert!(
                c.x.abs() < 0.01 && c.y.abs() < 0.032 && c.z > 0.0,
                "centre {c:?}"
            );
            // A right-handed frame.
            let m = Mat3::from_quat(g.world_from_gripper.rotation);
            assert!((m.determinant() - 1.0).abs() < 1e-4);
        }
        // Straight down is among them, and tilted ones: not only the camera's axes.
        assert!(grasps.iter().any(|g| tilt_rad(g) < 0.05));
        assert!(grasps.iter().any(|g| tilt_rad(g) > 0.4));
        // Deterministic.
        assert_eq!(grasps, sample_cloud_grasps(&fusion, 0.08, &params, 7));
    }

    #[test]
    fn only_the_masked_object_is_pinched() {
        // The cube seen from both sides, each view's mask the half with y < 0 (as if the other
        // half were a neighbour, or a bin's wall): the pairs lie on the masked half.
        let views = [seen_box(-1.0), seen_box(1.0)].map(|view| {
            let k = *view.depth.intrinsics();
            let pixels = (0..k.width * k.height)
                .map(|i| {
                    let (u, v) = (i % k.width, i / k.width);
                    let d = view.depth.at(i64::from(u), i64::from(v));
                    d > 0.0 && view.camera.unproject(u as f32, v as f32, d).y < 0.0
                })
                .collect();
            let mask = crate::depth_image::Mask::new(k.width, k.height, pixels).unwrap();
            view.with_mask(mask).unwrap()
        });
        let fusion = Fusion::build(&views, &FusionParams::default()).unwrap();
        let grasps = sample_cloud_grasps(&fusion, 0.08, &CloudSamplerParams::default(), 7);
        assert!(grasps.len() >= 10, "{} grasps", grasps.len());
        let max_y = grasps.iter().map(|g| g.center().y).fold(f32::MIN, f32::max);
        let whole = Fusion::build(&[seen_box(-1.0), seen_box(1.0)], &FusionParams::default());
        let all = sample_cloud_grasps(&whole.unwrap(), 0.08, &CloudSamplerParams::default(), 7);
        let all_max_y = all.iter().map(|g| g.center().y).fold(f32::MIN, f32::max);
        // The masked points end at y = 0 (5 mm of slack; a centre lies up to 2 cm along a
        // tilted approach from the contacts): unmasked, the pairs reach the far face.
        assert!(max_y < 0.015 && all_max_y > 0.02, "{max_y} {all_max_y}");
    }

    #[test]
    fn no_pair_wider_than_the_hand_or_through_unseen_space() {
        // The 4 x 12 cm box seen from straight above only: its sides are unseen, so no axis
        // comes out of it into free space; and a 3 cm hand is narrower than the cube.
        let top = [box_view(false)];
        let fusion = Fusion::build(&top, &FusionParams::default()).unwrap();
        assert!(sample_cloud_grasps(&fusion, 0.08, &CloudSamplerParams::default(), 1).is_empty());
        let views = [seen_box(-1.0), seen_box(1.0)];
        let fusion = Fusion::build(&views, &FusionParams::default()).unwrap();
        assert!(sample_cloud_grasps(&fusion, 0.03, &CloudSamplerParams::default(), 1).is_empty());
    }
}
