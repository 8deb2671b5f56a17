//! Stable resting poses of a rigid object on a horizontal plane, with their probabilities.
//!
//! The quasi-static estimate of Dex-Net (Goldberg et al. 1999; meshpy): the object is dropped
//! with a uniformly random orientation; it lands on the convex-hull face hit by the downward ray
//! from its centre of mass, so a face is first touched with probability equal to the solid angle
//! it subtends at the centre of mass over 4 pi. A face whose support polygon does not contain the
//! centre of mass's projection topples over the edge between them onto the next face, until a
//! face that does; that face collects the probability of every face that drains into it.
//!
//! A curved surface makes faces that only look stable: a can on its side, a lemon, rests on a
//! thin strip of hull facets and rolls at a touch. Each resting face gets a tipping angle: the
//! smallest rotation that carries the centre of mass over an edge of the face's basin (the faces
//! that drain into it) into another pose's basin. Tipping onto a neighbour that rolls straight
//! back (a bulge on a scanned box's base) does not count. Faces below
//! [`StablePoseParams::min_tipping_angle_rad`] are `marginal`. Neighbouring marginal faces (a
//! can's side) are reported as one pose carrying their summed probability.

use std::collections::HashMap;

use parry3d::math::{Pose3, Rot3, Vec3};

use crate::error::{GeometryError, Result};
use crate::mesh::TriangleMesh;

/// Marginal resting faces are one rolling family only if their normals are within 30 degrees.
const ROLLING_NEIGHBOUR_COS: f32 = 0.866;

/// How to compute and select stable poses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StablePoseParams {
    /// Keep at most this many poses, most probable first.
    pub max_poses: usize,
    /// Drop poses less probable than this.
    pub min_probability: f32,
    /// Hull facets whose normals differ from a face's first facet by less than this are one
    /// face (absorbs scanning noise on flat sides), radians.
    pub coplanar_tolerance_rad: f32,
    /// A resting face with a smaller tipping angle is marginal: it rolls or topples at a touch.
    /// The default, 10 degrees, errs on the safe side. On the real meshes the soup can's side
    /// (1.7 degrees), the low-poly lemon's facets (up to 7.3) and a mug's bare side (2.3) are
    /// marginal and a mug resting on its handle (12 to 15) is not; the cracker box standing on
    /// its warped scanned base (6.8) is flagged too, wrongly but harmlessly: a pose lost, not a
    /// bad label.
    pub min_tipping_angle_rad: f32,
}

impl Default for StablePoseParams {
    fn default() -> Self {
        Self {
            max_poses: 10,
            min_probability: 0.01,
            coplanar_tolerance_rad: 5f32.to_radians(),
            min_tipping_angle_rad: 10f32.to_radians(),
        }
    }
}

/// One way the object rests on a table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StablePose {
    /// Probability of coming to rest in this pose when dropped at random.
    pub probability: f32,
    /// Places the object on the table: the face on the plane z = 0, the centre of mass above the
    /// table origin. Any rotation about the table's z axis is an equally valid pose.
    pub table_from_object: Pose3,
    /// Outward normal of the resting face in the object frame (it points down at the table).
    pub face_normal: Vec3,
    /// Area of the resting face, square metres (the convex support polygon).
    pub face_area_m2: f32,
    /// Smallest rotation that tips the object into another pose, radians (see the module docs).
    pub tipping_angle_rad: f32,
    /// True when the pose only looks stable: a curved face that rolls, or a narrow base that
    /// topples at a touch. [`crate::RestingPoses`] offers such poses only for an object that
    /// has no other.
    pub marginal: bool,
}

/// The stable poses of `mesh`, most probable first (see the module docs).
///
/// # Errors
/// [`GeometryError::InvalidParameter`] for parameters out of range;
/// [`GeometryError::Degenerate`] for a flat mesh.
pub fn stable_poses(mesh: &TriangleMesh, params: &StablePoseParams) -> Result<Vec<StablePose>> {
    check_params(params)?;
    let com = mesh.mass_facts(1.0)?.center_of_mass;
    let hull = mesh.convex_hull()?;
    let faces = HullFaces::new(&hull, params.coplanar_tolerance_rad);
    let n = faces.normal.len();

    // Where each face drains to; a cycle (numerically flat ground) ends on the face that closes it.
    let mut next: Vec<Option<usize>> = (0..n).map(|f| faces.topples_to(f, com)).collect();
    let mut sinks = vec![usize::MAX; n];
    for start in 0..n {
        let mut path = Vec::new();
        let mut f = start;
        while sinks[f] == usize::MAX {
            if path.contains(&f) {
                next[f] = None;
                sinks[f] = f;
                break;
            }
            path.push(f);
            match next[f] {
                Some(g) => f = g,
                None => sinks[f] = f,
            }
        }
        let sink = sinks[f];
        for g in path {
            sinks[g] = sink;
        }
    }
    let solid_angle: Vec<f64> = (0..n).map(|f| faces.solid_angle(f, com)).collect();
    let total: f64 = solid_angle.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(GeometryError::Degenerate {
            op: "stable poses",
            detail: "the centre of mass sees no hull face".into(),
            path: mesh.origin().to_path_buf(),
        });
    }
    let mut probability = vec![0f64; n];
    for f in 0..n {
        probability[sinks[f]] += solid_angle[f] / total;
    }

    // Marginal resting faces that touch (through the faces draining into them) are one family.
    let tipping: Vec<f32> = (0..n)
        .map(|f| {
            if sinks[f] == f {
                faces.escape_angle(f, com, &sinks)
            } else {
                0.0
            }
        })
        .collect();
    let marginal = |f: usize| tipping[f] < params.min_tipping_angle_rad;
    let mut family: Vec<usize> = (0..n).collect();
    fn root(family: &mut [usize], mut f: usize) -> usize {
        while family[f] != f {
            family[f] = family[family[f]];
            f = family[f];
        }
        f
    }
    for (f, g) in faces.adjacent_pairs() {
        let (a, b) = (sinks[f], sinks[g]);
        // Neighbours on one curved surface face nearly the same way; a lens's two sides do not.
        let same_surface = faces.normal[a].dot(faces.normal[b]) > ROLLING_NEIGHBOUR_COS;
        if a != b && marginal(a) && marginal(b) && same_surface {
            let (ra, rb) = (root(&mut family, a), root(&mut family, b));
            family[ra] = rb;
        }
    }
    let mut by_family: HashMap<usize, (usize, f64)> = HashMap::new();
    for f in (0..n).filter(|&f| sinks[f] == f) {
        let r = root(&mut family, f);
        let entry = by_family.entry(r).or_insert((f, 0.0));
        entry.1 += probability[f];
        if probability[f] > probability[entry.0] {
            entry.0 = f;
        }
    }

    let mut poses: Vec<StablePose> = by_family
        .into_values()
        .map(|(f, p)| StablePose {
            probability: p as f32,
            table_from_object: faces.table_from_object(f, com),
            face_normal: faces.normal[f],
            face_area_m2: faces.area(f),
            tipping_angle_rad: tipping[f],
            marginal: marginal(f),
        })
        .filter(|pose| pose.probability >= params.min_probability)
        .collect();
    poses.sort_by(|a, b| {
        b.probability
            .total_cmp(&a.probability)
            .then(a.face_normal.x.total_cmp(&b.face_normal.x))
    });
    poses.truncate(params.max_poses);
    Ok(poses)
}

fn check_params(params: &StablePoseParams) -> Result<()> {
    let invalid = |name, value: f32, expected| {
        Err(GeometryError::InvalidParameter {
            op: "stable poses",
            name,
            value: value.to_string(),
            expected,
        })
    };
    if !(0.0..=1.0).contains(&params.min_probability) {
        return invalid("min_probability", params.min_probability, "between 0 and 1");
    }
    if !(0.0..0.5).contains(&params.coplanar_tolerance_rad) {
        return invalid(
            "coplanar_tolerance_rad",
            params.coplanar_tolerance_rad,
            "in [0, 0.5)",
        );
    }
    if !(0.0..1.5).contains(&params.min_tipping_angle_rad) {
        return invalid(
            "min_tipping_angle_rad",
            params.min_tipping_angle_rad,
            "in [0, 1.5)",
        );
    }
    Ok(())
}

/// Hull facets grouped into planar faces, with the boundary edges between faces.
struct HullFaces<'a> {
    hull: &'a TriangleMesh,
    /// Facets of each face.
    facets: Vec<Vec<usize>>,
    /// Outward unit normal of each face (its first facet's).
    normal: Vec<Vec3>,
    /// Boundary edges of each face: (a, b, face on the other side).
    boundary: Vec<Vec<(Vec3, Vec3, usize)>>,
}

impl<'a> HullFaces<'a> {
    fn new(hull: &'a TriangleMesh, tolerance_rad: f32) -> Self {
        let triangles = hull.triangles();
        let normals = hull.triangle_normals();
        let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (t, tri) in triangles.iter().enumerate() {
            for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
                by_edge.entry((a.min(b), a.max(b))).or_default().push(t);
            }
        }
        let neighbours = |t: usize| {
            let tri = triangles[t];
            [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])].map(|(a, b)| {
                let across = by_edge.get(&(a.min(b), a.max(b)));
                (
                    a,
                    b,
                    across.and_then(|ts| ts.iter().copied().find(|&o| o != t)),
                )
            })
        };
        // Region growing from the largest facets, each against its seed's normal (no drift).
        let area = |t: usize| {
            let [a, b, c] = hull.triangle_corners(triangles[t]);
            (b - a).cross(c - a).length()
        };
        let mut order: Vec<usize> = (0..triangles.len()).collect();
        order.sort_by(|&a, &b| area(b).total_cmp(&area(a)).then(a.cmp(&b)));
        let cos_tol = tolerance_rad.cos();
        let mut face_of = vec![usize::MAX; triangles.len()];
        let mut facets = Vec::new();
        let mut normal = Vec::new();
        for &seed in &order {
            if face_of[seed] != usize::MAX {
                continue;
            }
            let id = facets.len();
            let (seed_normal, mut members, mut stack) = (normals[seed], Vec::new(), vec![seed]);
            face_of[seed] = id;
            while let Some(t) = stack.pop() {
                members.push(t);
                for (_, _, across) in neighbours(t) {
                    if let Some(o) = across
                        && face_of[o] == usize::MAX
                        && normals[o].dot(seed_normal) >= cos_tol
                    {
                        face_of[o] = id;
                        stack.push(o);
                    }
                }
            }
            members.sort_unstable();
            facets.push(members);
            normal.push(seed_normal);
        }
        let vertex = |i: u32| hull.vertices()[i as usize];
        let boundary = facets
            .iter()
            .enumerate()
            .map(|(id, members)| {
                members
                    .iter()
                    .flat_map(|&t| neighbours(t))
                    .filter_map(|(a, b, across)| {
                        let other = face_of[across?];
                        (other != id).then(|| (vertex(a), vertex(b), other))
                    })
                    .collect()
            })
            .collect();
        Self {
            hull,
            facets,
            normal,
            boundary,
        }
    }

    fn corners(&self, t: usize) -> [Vec3; 3] {
        self.hull.triangle_corners(self.hull.triangles()[t])
    }

    fn area(&self, f: usize) -> f32 {
        self.facets[f]
            .iter()
            .map(|&t| {
                let [a, b, c] = self.corners(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Pairs of faces that share an edge.
    fn adjacent_pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.boundary
            .iter()
            .enumerate()
            .flat_map(|(f, edges)| edges.iter().map(move |e| (f, e.2)))
    }

    /// The centre of mass projected onto face `f`'s plane, and its height above that plane.
    fn projection(&self, f: usize, com: Vec3) -> (Vec3, f32) {
        let n = self.normal[f];
        let on_plane = self.corners(self.facets[f][0])[0];
        let height = (on_plane - com).dot(n);
        (com + n * height, height)
    }

    /// The support polygon of face `f`: the convex hull of its vertices in the face plane, in
    /// plane coordinates (u, v) with the plane basis.
    fn support_polygon(&self, f: usize) -> (Vec<[f32; 2]>, Vec3, Vec3) {
        let n = self.normal[f];
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let mut points: Vec<[f32; 2]> = self.facets[f]
            .iter()
            .flat_map(|&t| self.corners(t))
            .map(|p| [p.dot(u), p.dot(v)])
            .collect();
        (convex_hull_2d(&mut points), u, v)
    }

    /// Whether the support polygon of `f` holds `p` (a point on its plane).
    fn holds(&self, f: usize, p: Vec3) -> bool {
        let (polygon, u, v) = self.support_polygon(f);
        let q = [p.dot(u), p.dot(v)];
        polygon.len() >= 3
            && polygon
                .iter()
                .zip(polygon.iter().cycle().skip(1))
                .all(|(a, b)| (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]) >= 0.0)
    }

    /// The face `f` topples onto, or `None` when it holds the centre of mass's projection.
    fn topples_to(&self, f: usize, com: Vec3) -> Option<usize> {
        let (p, _) = self.projection(f, com);
        if self.holds(f, p) {
            return None;
        }
        // Leave the face through the boundary edge closest to the projection: on a convex
        // support polygon that is the edge the centre of mass passes over.
        self.boundary[f]
            .iter()
            .map(|&(a, b, other)| (distance_to_segment(p, a, b), other))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, other)| other)
    }

    /// Smallest rotation, resting on sink `f`, that carries the centre of mass over an edge
    /// between `f`'s basin and another sink's: the edges are projected onto `f`'s plane and the
    /// angle is atan(distance from the centre of mass's projection / its height).
    fn escape_angle(&self, f: usize, com: Vec3, sinks: &[usize]) -> f32 {
        let (p, height) = self.projection(f, com);
        let n = self.normal[f];
        let flatten = |q: Vec3| q - n * n.dot(q - p);
        (0..self.boundary.len())
            .filter(|&g| sinks[g] == f)
            .flat_map(|g| self.boundary[g].iter())
            .filter(|&&(_, _, other)| sinks[other] != f)
            .map(|&(a, b, _)| {
                distance_to_segment(p, flatten(a), flatten(b)).atan2(height.max(1e-9))
            })
            .fold(std::f32::consts::FRAC_PI_2, f32::min)
    }

    /// Solid angle of face `f` seen from `com` (Van Oosterom and Strackee), steradians.
    fn solid_angle(&self, f: usize, com: Vec3) -> f64 {
        self.facets[f]
            .iter()
            .map(|&t| {
                let [a, b, c] = self.corners(t).map(|v| (v - com).as_dvec3());
                let (la, lb, lc) = (a.length(), b.length(), c.length());
                let numerator = a.dot(b.cross(c)).abs();
                let denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
                2.0 * numerator.atan2(denominator)
            })
            .sum()
    }

    /// Rotates face `f`'s outward normal onto -z, puts the lowest point on z = 0 and the centre of mass
    /// above the origin.
    fn table_from_object(&self, f: usize, com: Vec3) -> Pose3 {
        let rotation = Rot3::from_rotation_arc(self.normal[f], -Vec3::Z);
        // The lowest hull vertex touches the table (a merged face is only nearly planar).
        let lowest = self
            .hull
            .vertices()
            .iter()
            .map(|v| (rotation * *v).z)
            .fold(f32::INFINITY, f32::min);
        let com_rotated = rotation * com;
        Pose3::from_parts(Vec3::new(-com_rotated.x, -com_rotated.y, -lowest), rotation)
    }
}

/// Andrew's monotone chain: the convex hull of `points`, counter-clockwise, no repeated ends.
fn convex_hull_2d(points: &mut [[f32; 2]]) -> Vec<[f32; 2]> {
    points.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    let cross = |o: [f32; 2], a: [f32; 2], b: [f32; 2]| {
        (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
    };
    let mut hull: Vec<[f32; 2]> = Vec::with_capacity(points.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &[f32; 2]>> = if pass == 0 {
            Box::new(points.iter())
        } else {
            Box::new(points.iter().rev())
        };
        for &p in ordered {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

fn distance_to_segment(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
    (a + ab * t - p).length()
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d::shape::{Cuboid, Cylinder};

    fn mesh((v, t): (Vec<Vec3>, Vec<[u32; 3]>)) -> TriangleMesh {
        TriangleMesh::new(v, t).unwrap()
    }

    #[test]
    fn a_box_has_six_poses_summing_to_one_with_larger_faces_likelier() {
        let half = Vec3::new(0.06, 0.04, 0.02);
        let all = StablePoseParams {
            min_probability: 0.0,
            ..Default::default()
        };
        let poses = stable_poses(&mesh(Cuboid::new(half).to_trimesh()), &all).unwrap();
        assert_eq!(poses.len(), 6);
        let sum: f32 = poses.iter().map(|p| p.probability).sum();
        assert!((sum - 1.0).abs() < 1e-4, "{sum}");
        // The two largest faces (normals along z) come first, the two smallest (x) last.
        assert!(poses[0].face_normal.z.abs() > 0.99 && poses[1].face_normal.z.abs() > 0.99);
        assert!(poses[4].face_normal.x.abs() > 0.99 && poses[5].face_normal.x.abs() > 0.99);
        assert!(poses.iter().all(|p| !p.marginal));
        // Lying flat: the centre of mass is 2 cm above the table, over its origin.
        let com_on_table = poses[0].table_from_object.transform_point(Vec3::ZERO);
        assert!(
            (com_on_table - Vec3::new(0.0, 0.0, 0.02)).length() < 1e-5,
            "{com_on_table}"
        );
        // Tipping a 12 x 8 x 4 cm box lying flat over its long edge: atan(4 cm / 2 cm).
        assert!((poses[0].tipping_angle_rad - 2f32.atan()).abs() < 1e-3);
    }

    #[test]
    fn a_can_stands_or_lies_on_its_side_and_the_side_pose_rolls() {
        // A 6.6 cm x 10 cm can, 64 facets around: the side is one rolling family.
        let (v, t) = Cylinder::new(0.05, 0.033).to_trimesh(64);
        let poses = stable_poses(&mesh((v, t)), &StablePoseParams::default()).unwrap();
        assert_eq!(poses.len(), 3, "{poses:#?}");
        let side = poses.iter().find(|p| p.face_normal.y.abs() < 0.1).unwrap();
        assert!(side.marginal, "lying on its side must roll");
        let ends: Vec<_> = poses
            .iter()
            .filter(|p| p.face_normal.y.abs() > 0.99)
            .collect();
        assert_eq!(ends.len(), 2);
        assert!(ends.iter().all(|p| !p.marginal));
        let sum: f32 = poses.iter().map(|p| p.probability).sum();
        assert!((sum - 1.0).abs() < 1e-3);
        assert!(
            side.probability > 0.5,
            "a can this long mostly lands on its side"
        );
    }

    #[test]
    fn a_thin_plate_on_its_edge_is_marginal() {
        let half = Vec3::new(0.05, 0.05, 0.003);
        let all = StablePoseParams {
            min_probability: 0.0,
            ..Default::default()
        };
        let poses = stable_poses(&mesh(Cuboid::new(half).to_trimesh()), &all).unwrap();
        let on_edge: Vec<_> = poses
            .iter()
            .filter(|p| p.face_normal.z.abs() < 0.1)
            .collect();
        assert!(!on_edge.is_empty() && on_edge.iter().all(|p| p.marginal));
    }

    #[test]
    fn top_k_and_min_probability_select() {
        let half = Vec3::new(0.06, 0.04, 0.02);
        let m = mesh(Cuboid::new(half).to_trimesh());
        let two = StablePoseParams {
            max_poses: 2,
            ..Default::default()
        };
        assert_eq!(stable_poses(&m, &two).unwrap().len(), 2);
        let likely = StablePoseParams {
            min_probability: 0.2,
            ..Default::default()
        };
        assert!(
            stable_poses(&m, &likely)
                .unwrap()
                .iter()
                .all(|p| p.probability >= 0.2)
        );
        let bad = StablePoseParams {
            min_probability: 2.0,
            ..Default::default()
        };
        assert!(matches!(
            stable_poses(&m, &bad),
            Err(GeometryError::InvalidParameter { .. })
        ));
    }
}
