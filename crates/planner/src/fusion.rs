//! Every view's depth fused into one model of the scene around the object, in the table frame
//! (z up, the table at `table_z_m`): a voxel grid that says, for each cell, whether some view
//! observed a surface in it ([`Occupancy::Occupied`]), saw through it to a surface behind
//! ([`Occupancy::Free`]), or neither ([`Occupancy::Unknown`]: behind every view's surface or
//! outside every view). Built once per plan and shared by every check of every candidate; it
//! also keeps the observed points near the object, from which [`crate::virtual_view`] draws the
//! object as a camera on any approach axis would see it.
//!
//! Space carving with a projective test: a cell is free when its centre, seen from some view,
//! lies more than `surface_band_m` in front of the depth that view measured at the centre's
//! pixel. A pixel without depth says nothing. A cell holding an observed point of any view is
//! occupied whatever the others say (a conservative union, as sensor noise and calibration
//! error make views disagree near surfaces).

use mvgrasp_geometry::{Pose3, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::depth_image::View;
use mvgrasp_geometry::rounding::{round, rounded_index};

/// A box's lower and upper corners, world.
type Bounds = (Vec3, Vec3);

/// What the fused views say about a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Occupancy {
    /// Some view saw through the cell to a surface behind it.
    Free,
    /// No view saw into the cell.
    Unknown,
    /// Some view observed a surface point in the cell.
    Occupied,
}

/// How the views are fused.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FusionParams {
    /// Edge of a cell, metres.
    pub voxel_m: f32,
    /// The grid covers the object's observed points grown by this on every side (and down to
    /// the table), metres: where the hand can meet space the object hides.
    pub margin_m: f32,
    /// The points kept for virtual views cover the object grown by this, metres (a GQ-CNN's
    /// crop spans 6 cm each side of a grasp at 0.7 m).
    pub points_margin_m: f32,
    /// The points kept for virtual views are thinned to one (their mean) per cube of this
    /// edge, metres (a crop pixel spans 3.8 mm at 0.7 m).
    pub point_cell_m: f32,
    /// Observed points this far above the table are the object (within its mask where the
    /// view has one), metres.
    pub min_height_m: f32,
    /// Height of the table in the world frame (z up), metres.
    pub table_z_m: f32,
    /// A cell's centre must lie this far in front of a view's measured depth (along the
    /// optical axis) for the view to see through it, metres.
    pub surface_band_m: f32,
    /// The most cells: a bigger object gets coarser cells.
    pub max_cells: usize,
    /// The hand check lets the open hand into space that no view has seen (false: a hand
    /// there is rejected, the conservative default).
    pub allow_unknown: bool,
}

impl Default for FusionParams {
    fn default() -> Self {
        Self {
            voxel_m: 0.003,
            margin_m: 0.05,
            points_margin_m: 0.08,
            point_cell_m: 0.0015,
            min_height_m: 0.005,
            table_z_m: 0.0,
            // A cell's half diagonal: a surface that crosses the cell lies within it of the
            // centre.
            surface_band_m: 0.003 * 0.87,
            max_cells: 4_000_000,
            allow_unknown: false,
        }
    }
}

/// Edge of the cubes the kept points are grouped in, metres.
pub const POINT_BUCKET_M: f32 = 0.01;

/// A run of [`Fusion::points`] that lies in one cube of [`POINT_BUCKET_M`].
#[derive(Clone, Debug, PartialEq)]
pub struct PointBucket {
    /// The cube's centre, world: every point of the run lies within half the cube's diagonal
    /// of it.
    pub centre: Vec3,
    /// The run, as indices into [`Fusion::points`].
    pub range: std::ops::Range<usize>,
}

/// The fused model: a grid of cells over the object and its surroundings, and the observed
/// points near the object.
#[derive(Clone, Debug)]
pub struct Fusion {
    /// Centre of cell (0, 0, 0), world.
    origin: Vec3,
    voxel_m: f32,
    dims: [usize; 3],
    cells: Vec<Occupancy>,
    table_z_m: f32,
    /// Observed points (world) within `points_margin_m` of the object, grouped by bucket.
    points: Vec<Vec3>,
    /// The points' buckets: cubes of [`POINT_BUCKET_M`], each its centre and its run of
    /// `points`, so that a virtual view draws only the buckets its frustum can reach.
    buckets: Vec<PointBucket>,
    /// Per cell count: free, unknown, occupied.
    counts: [usize; 3],
    allow_unknown: bool,
    /// The bounds of the object's observed points above the table (within the views' masks,
    /// where they have them), world.
    object_bounds: Bounds,
}

impl Fusion {
    /// Fuses `views` (cameras posed in the table frame). `None` when no view observed a point
    /// above the table (within its mask, where it has one): there is no object to fuse around.
    pub fn build(views: &[View], params: &FusionParams) -> Option<Self> {
        let table_z = params.table_z_m;
        // Every observed point, world frame; and the object's bounds.
        let per_view: Vec<(Vec<Vec3>, Option<Bounds>)> = views
            .par_iter()
            .map(|view| {
                let k = view.depth.intrinsics();
                let w = k.width as usize;
                let mut points = Vec::new();
                let mut bounds: Option<Bounds> = None;
                for (i, &d) in view.depth.as_slice().iter().enumerate() {
                    if d <= 0.0 {
                        continue;
                    }
                    let (u, v) = (i % w, i / w);
                    let p = view.camera.unproject(u as f32, v as f32, d);
                    let on_object = view.mask.as_ref().is_none_or(|m| m.at(u as i64, v as i64));
                    if on_object && p.z > table_z + params.min_height_m {
                        bounds = Some(match bounds {
                            None => (p, p),
                            Some((lo, hi)) => (lo.min(p), hi.max(p)),
                        });
                    }
                    points.push(p);
                }
                (points, bounds)
            })
            .collect();
        let (lo, hi) = per_view
            .iter()
            .filter_map(|(_, b)| *b)
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))?;
        // The grid: the object grown by the margin, down to the table (one layer of cells
        // centred on it), cells aligned so that one layer's centres lie on the table.
        let grid_lo = Vec3::new(lo.x - params.margin_m, lo.y - params.margin_m, table_z);
        let grid_hi = hi + Vec3::splat(params.margin_m);
        let extent = grid_hi - grid_lo;
        let mut voxel = params.voxel_m.max(1e-4);
        let dims_for = |voxel: f32| {
            [
                (extent.x / voxel).ceil() as usize + 1,
                (extent.y / voxel).ceil() as usize + 1,
                (extent.z / voxel).ceil() as usize + 1,
            ]
        };
        let mut dims = dims_for(voxel);
        while dims.iter().product::<usize>() > params.max_cells.max(1) {
            voxel *= 1.25;
            dims = dims_for(voxel);
        }
        let band = params.surface_band_m * voxel / params.voxel_m.max(1e-4);
        let mut fusion = Self {
            origin: grid_lo,
            voxel_m: voxel,
            dims,
            cells: vec![Occupancy::Unknown; dims.iter().product()],
            table_z_m: table_z,
            points: Vec::new(),
            buckets: Vec::new(),
            counts: [0; 3],
            allow_unknown: params.allow_unknown,
            object_bounds: (lo, hi),
        };
        // Space carving, a z-slice of cells per task; each view's pose inverted once.
        let carvers: Vec<(Pose3, &View)> = views
            .iter()
            .map(|view| (view.camera.camera_from_world(), view))
            .collect();
        let plane = dims[0] * dims[1];
        let origin = fusion.origin;
        fusion
            .cells
            .par_chunks_mut(plane)
            .enumerate()
            .for_each(|(z, slice)| {
                for (i, cell) in slice.iter_mut().enumerate() {
                    let centre = origin
                        + Vec3::new((i % dims[0]) as f32, (i / dims[0]) as f32, z as f32) * voxel;
                    if carvers.iter().any(|(camera_from_world, view)| {
                        sees_through(view, camera_from_world, centre, band)
                    }) {
                        *cell = Occupancy::Free;
                    }
                }
            });
        // Observed points mark their cells; those near the object are kept, one mean point per
        // `point_cell_m` cube (views overlap: the same surface seen five times is drawn once).
        let (keep_lo, keep_hi) = (
            lo - Vec3::splat(params.points_margin_m),
            hi + Vec3::splat(params.points_margin_m),
        );
        let point_cell = params.point_cell_m.max(1e-4);
        let key_dims = ((keep_hi - keep_lo) / point_cell).ceil() + Vec3::ONE;
        // Fx hashing: the keys are cube indices, and SipHash's cost was half the thinning's.
        let mut slot_of = rustc_hash::FxHashMap::<u64, usize>::default();
        let mut sums: Vec<(Vec3, u32)> = Vec::new();
        for (points, _) in per_view {
            for p in points {
                if let Some(i) = fusion.index_of(p) {
                    fusion.cells[i] = Occupancy::Occupied;
                }
                if p.cmpge(keep_lo).all() && p.cmple(keep_hi).all() {
                    let c = ((p - keep_lo) / point_cell).floor();
                    let key = ((c.z as u64 * key_dims.y as u64) + c.y as u64) * key_dims.x as u64
                        + c.x as u64;
                    let slot = *slot_of.entry(key).or_insert_with(|| {
                        sums.push((Vec3::ZERO, 0));
                        sums.len() - 1
                    });
                    sums[slot].0 += p;
                    sums[slot].1 += 1;
                }
            }
        }
        let points: Vec<Vec3> = sums.into_iter().map(|(s, n)| s / n as f32).collect();
        (fusion.points, fusion.buckets) = bucketed(points, keep_lo);
        for cell in &fusion.cells {
            fusion.counts[*cell as usize] += 1;
        }
        Some(fusion)
    }

    /// Edge of a cell, metres (the asked-for size, or coarser for a big object).
    pub fn voxel_m(&self) -> f32 {
        self.voxel_m
    }

    /// Cells along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The box around the object's observed points above the table (within the views'
    /// masks, where they have them), world: lower and upper corners. Other observed points
    /// (a neighbour off the mask, a bin's wall) are obstacles, not the object.
    pub fn object_bounds(&self) -> (Vec3, Vec3) {
        self.object_bounds
    }

    /// Height of the table, metres.
    pub fn table_z_m(&self) -> f32 {
        self.table_z_m
    }

    /// Centre of cell (0, 0, 0), world; cell `(x, y, z)` is centred `voxel_m` times that
    /// further, and stored at `(z * ny + y) * nx + x`.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Whether the hand check lets the hand into unknown space ([`FusionParams::allow_unknown`]).
    pub fn allows_unknown(&self) -> bool {
        self.allow_unknown
    }

    /// How many cells are free, unknown and occupied.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }

    /// The observed points near the object, world frame, grouped by [`Fusion::buckets`].
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// The points' buckets, in the order of [`Fusion::points`].
    pub fn buckets(&self) -> &[PointBucket] {
        &self.buckets
    }

    /// The cell holding `p`, if the grid covers it.
    fn index_of(&self, p: Vec3) -> Option<usize> {
        let g = (p - self.origin) / self.voxel_m;
        // The nearest cell along each axis, if the grid has it.
        let [x, y, z] = [
            rounded_index(g.x, self.dims[0])?,
            rounded_index(g.y, self.dims[1])?,
            rounded_index(g.z, self.dims[2])?,
        ];
        Some((z * self.dims[1] + y) * self.dims[0] + x)
    }

    /// What the views say about the cell holding `p`: `None` outside the grid (more than the
    /// margin from the object, or below the table's layer).
    pub fn at(&self, p: Vec3) -> Option<Occupancy> {
        self.index_of(p).map(|i| self.cells[i])
    }

    /// How many cells whose centres lie in the box of half extents `half` at `world_from_box`
    /// are free, unknown and occupied.
    pub fn count_in_box(&self, world_from_box: &Pose3, half: Vec3) -> [usize; 3] {
        let mut counts = [0; 3];
        // The box's cells: its world bounds, clipped to the grid.
        let (lo, hi) = world_bounds(world_from_box, half);
        let range = |axis: usize, lo: f32, hi: f32| {
            let o = self.origin[axis];
            let a = ((lo - o) / self.voxel_m).ceil().max(0.0);
            let b = ((hi - o) / self.voxel_m)
                .floor()
                .min(self.dims[axis] as f32 - 1.0);
            (a <= b).then_some(a as usize..=b as usize)
        };
        let (Some(xs), Some(ys), Some(zs)) = (
            range(0, lo.x, hi.x),
            range(1, lo.y, hi.y),
            range(2, lo.z, hi.z),
        ) else {
            return counts;
        };
        let box_from_world = world_from_box.inverse();
        for z in zs {
            for y in ys.clone() {
                for x in xs.clone() {
                    let centre =
                        self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.voxel_m;
                    let q = box_from_world.transform_point(centre);
                    if q.x.abs() <= half.x && q.y.abs() <= half.y && q.z.abs() <= half.z {
                        counts[self.cells[(z * self.dims[1] + y) * self.dims[0] + x] as usize] += 1;
                    }
                }
            }
        }
        counts
    }

    /// Whether an observed point of any view can lie in the box of half extents `half` at
    /// `world_from_box`: false only when the box lies inside the grid and no occupied cell
    /// comes within a cell's half diagonal of it (every observed point in the grid lies in an
    /// occupied cell, within that of the cell's centre).
    pub fn may_hold_observed(&self, world_from_box: &Pose3, half: Vec3) -> bool {
        let grown = half + Vec3::splat(self.voxel_m * 0.87);
        let (lo, hi) = world_bounds(world_from_box, grown);
        let grid_lo = self.origin - Vec3::splat(self.voxel_m / 2.0);
        let grid_hi = self.origin
            + (Vec3::new(
                self.dims[0] as f32,
                self.dims[1] as f32,
                self.dims[2] as f32,
            ) - Vec3::splat(0.5))
                * self.voxel_m;
        if !(lo.cmpge(grid_lo).all() && hi.cmple(grid_hi).all()) {
            return true;
        }
        let [_, _, occupied] = self.count_in_box(world_from_box, grown);
        occupied > 0
    }

    /// The worst cell whose centre lies in the box of half extents `half` at `world_from_box`
    /// (occupied over unknown over free); `None` when no cell centre lies in it.
    pub fn worst_in_box(&self, world_from_box: &Pose3, half: Vec3) -> Option<Occupancy> {
        let [free, unknown, occupied] = self.count_in_box(world_from_box, half);
        [
            (occupied, Occupancy::Occupied),
            (unknown, Occupancy::Unknown),
            (free, Occupancy::Free),
        ]
        .into_iter()
        .find_map(|(n, kind)| (n > 0).then_some(kind))
    }
}

/// `points` grouped by cubes of [`POINT_BUCKET_M`] from `lo` (a stable sort: each cube's
/// points keep their order), and the cubes' runs.
fn bucketed(points: Vec<Vec3>, lo: Vec3) -> (Vec<Vec3>, Vec<PointBucket>) {
    let cube = |p: Vec3| {
        let c = ((p - lo) / POINT_BUCKET_M).floor().max(Vec3::ZERO);
        [c.z as u32, c.y as u32, c.x as u32]
    };
    let mut keyed: Vec<([u32; 3], Vec3)> = points.into_iter().map(|p| (cube(p), p)).collect();
    keyed.sort_by_key(|&(key, _)| key);
    let mut buckets: Vec<PointBucket> = Vec::new();
    for (i, &([z, y, x], _)) in keyed.iter().enumerate() {
        match buckets.last_mut() {
            Some(b) if i > 0 && keyed[i - 1].0 == [z, y, x] => b.range.end = i + 1,
            _ => buckets.push(PointBucket {
                centre: lo + (Vec3::new(x as f32, y as f32, z as f32) + 0.5) * POINT_BUCKET_M,
                range: i..i + 1,
            }),
        }
    }
    (keyed.into_iter().map(|(_, p)| p).collect(), buckets)
}

/// The world bounds of the box of half extents `half` at `world_from_box`.
fn world_bounds(world_from_box: &Pose3, half: Vec3) -> Bounds {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for corner in 0..8 {
        let sign = |bit: u32| if corner >> bit & 1 == 1 { 1.0 } else { -1.0 };
        let p = world_from_box.transform_point(Vec3::new(
            sign(0) * half.x,
            sign(1) * half.y,
            sign(2) * half.z,
        ));
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (lo, hi)
}

/// Whether `view` sees through the point `p` (world) to a surface more than `band` behind it.
fn sees_through(view: &View, camera_from_world: &Pose3, p: Vec3, band: f32) -> bool {
    let q = camera_from_world.transform_point(p);
    let Some([u, v]) = view.depth.intrinsics().project(q) else {
        return false;
    };
    let d = view.depth.at(round(u), round(v));
    d > 0.0 && q.z < d - band
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_scenes::{box_view, seen_box};

    #[test]
    fn a_box_seen_from_above_is_free_above_unknown_inside_and_occupied_on_its_top() {
        // 4 x 12 cm, 5 cm tall, seen from 0.7 m straight above.
        let fusion = Fusion::build(&[box_view(false)], &FusionParams::default()).unwrap();
        let at = |x, y, z| fusion.at(Vec3::new(x, y, z));
        assert_eq!(at(0.0, 0.0, 0.08), Some(Occupancy::Free));
        assert_eq!(at(0.0, 0.0, 0.05), Some(Occupancy::Occupied));
        assert_eq!(at(0.0, 0.0, 0.025), Some(Occupancy::Unknown));
        assert_eq!(at(0.01, -0.05, 0.04), Some(Occupancy::Unknown));
        // Beside it, down to the table: seen.
        assert_eq!(at(0.03, 0.0, 0.02), Some(Occupancy::Free));
        assert_eq!(at(0.03, 0.0, 0.003), Some(Occupancy::Free));
        assert_eq!(at(0.03, 0.0, 0.0), Some(Occupancy::Occupied));
        // The grid: the box grown by 5 cm.
        assert_eq!(at(0.0, 0.0, 0.13), None);
        assert_eq!(at(0.08, 0.0, 0.02), None);
        assert_eq!(at(0.06, 0.0, 0.02), Some(Occupancy::Free));
    }

    #[test]
    fn a_second_view_sees_into_the_first_ones_shadow() {
        // A 4 cm cube seen from 45 degrees on -x: the table behind it (+x) is in its shadow.
        let left = seen_box(-1.0);
        let shadow = Vec3::new(0.035, 0.0, 0.01);
        let one = Fusion::build(std::slice::from_ref(&left), &FusionParams::default()).unwrap();
        assert_eq!(one.at(shadow), Some(Occupancy::Unknown));
        assert_eq!(one.at(Vec3::new(-0.035, 0.0, 0.01)), Some(Occupancy::Free));
        // From the other side as well: seen free; the box's inside still unknown.
        let both = Fusion::build(&[left, seen_box(1.0)], &FusionParams::default()).unwrap();
        assert_eq!(both.at(shadow), Some(Occupancy::Free));
        assert_eq!(both.at(Vec3::new(0.0, 0.0, 0.02)), Some(Occupancy::Unknown));
        let [free, unknown, occupied] = both.counts();
        assert!(
            free > unknown && unknown > 0 && occupied > 0,
            "{:?}",
            both.counts()
        );
    }

    #[test]
    fn boxes_report_their_worst_cell() {
        let fusion = Fusion::build(&[box_view(false)], &FusionParams::default()).unwrap();
        let at = |x, y, z| Pose3::from_translation(Vec3::new(x, y, z));
        let half = Vec3::splat(0.005);
        assert_eq!(
            fusion.worst_in_box(&at(0.0, 0.0, 0.09), half),
            Some(Occupancy::Free)
        );
        assert_eq!(
            fusion.worst_in_box(&at(0.0, 0.0, 0.03), half),
            Some(Occupancy::Unknown)
        );
        assert_eq!(
            fusion.worst_in_box(&at(0.0, 0.0, 0.05), half),
            Some(Occupancy::Occupied)
        );
        // Beside the box, clear of its side by 2 mm: free.
        assert_eq!(
            fusion.worst_in_box(&at(0.027, 0.0, 0.03), half),
            Some(Occupancy::Free)
        );
        assert_eq!(fusion.worst_in_box(&at(0.5, 0.0, 0.03), half), None);
    }

    #[test]
    fn a_box_clear_of_every_occupied_cell_holds_no_observed_point() {
        let fusion = Fusion::build(&[box_view(false)], &FusionParams::default()).unwrap();
        let at = |x, y, z| Pose3::from_translation(Vec3::new(x, y, z));
        let half = Vec3::splat(0.005);
        // Above the box's top (z 5 cm) by 1 cm: clear; touching it, or reaching out of the
        // grid: maybe.
        assert!(!fusion.may_hold_observed(&at(0.0, 0.0, 0.065), half));
        assert!(fusion.may_hold_observed(&at(0.0, 0.0, 0.054), half));
        assert!(fusion.may_hold_observed(&at(0.0, 0.0, 0.098), half));
        // Beside the box: reaching 1 mm into the table, maybe; 3 mm above it, clear.
        assert!(fusion.may_hold_observed(&at(0.04, 0.0, 0.004), half));
        assert!(!fusion.may_hold_observed(&at(0.04, 0.0, 0.008), half));
    }

    #[test]
    fn nothing_on_the_table_is_nothing_to_fuse() {
        let mut view = box_view(false);
        for d in view.depth.as_mut_slice() {
            *d = 0.7;
        }
        assert!(Fusion::build(&[view], &FusionParams::default()).is_none());
    }
}
