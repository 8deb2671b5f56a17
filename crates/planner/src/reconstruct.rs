//! The object as the fused views allow it to be: a closed mesh of every cell above the table
//! that some view observed a surface in, or that no view saw into, connected to the object's
//! observed surface ([`Fusion`]). Hidden space counts as solid, so the mesh is the largest
//! object the views are consistent with (a visual hull carved by depth). `plan_eval
//! --dump-recon` tries each candidate in the physics trial on it; choosing by that trial did
//! not pick grasps that held more often (docs/planning.md, the fused multi-view planner), so the planner
//! does not use it.

use std::collections::VecDeque;

use mvgrasp_geometry::objects::mesh_sdf;
use mvgrasp_geometry::{TriangleMesh, Vec3};

use crate::fusion::{Fusion, Occupancy};

/// The grid's lowest layers of cells that are the table's, not the object's (the lowest is
/// centred on the table).
const TABLE_LAYERS: usize = 1;

/// The surface's level in the field (-1 at a solid cell's centre, +1 at an empty one's): -0.5
/// puts it a quarter of a cell outside the outermost solid centres, where 0 would put it half
/// a cell out (a surface point lies within half a cell of its cell's centre).
const ISO: f32 = -0.5;

impl Fusion {
    /// The solid cells (see the module docs): a flag per cell, in the grid's order. Occupied
    /// cells above the table seed a flood through occupied and unknown cells (faces shared);
    /// the table's layer and whatever the flood does not reach stay empty.
    pub fn solid_cells(&self) -> Vec<bool> {
        let [nx, ny, nz] = self.dims();
        let index = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        let mut solid = vec![false; nx * ny * nz];
        let mut queue = VecDeque::new();
        for z in TABLE_LAYERS..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = index(x, y, z);
                    if self.cell(i) == Occupancy::Occupied {
                        solid[i] = true;
                        queue.push_back((x, y, z));
                    }
                }
            }
        }
        while let Some((x, y, z)) = queue.pop_front() {
            let neighbours = [
                (x.wrapping_sub(1), y, z),
                (x + 1, y, z),
                (x, y.wrapping_sub(1), z),
                (x, y + 1, z),
                (x, y, z.wrapping_sub(1)),
                (x, y, z + 1),
            ];
            for (a, b, c) in neighbours {
                if a >= nx || b >= ny || c >= nz || c < TABLE_LAYERS {
                    continue;
                }
                let i = index(a, b, c);
                if !solid[i] && self.cell(i) == Occupancy::Unknown {
                    solid[i] = true;
                    queue.push_back((a, b, c));
                }
            }
        }
        solid
    }

    /// The solid cells' surface, meshed (closed, outward normals): the boundary runs a quarter
    /// of a cell outside the outermost solid cells' centres. `None` when no cell is
    /// solid or the mesher fails.
    pub fn solid_mesh(&self) -> Option<TriangleMesh> {
        let solid = self.solid_cells();
        if !solid.contains(&true) {
            return None;
        }
        let [nx, ny, nz] = self.dims();
        let voxel = self.voxel_m();
        let origin = self.origin();
        // -1 at a solid cell's centre, +1 elsewhere and outside the grid, trilinear between.
        let value = |x: i64, y: i64, z: i64| -> f32 {
            let inside = (0..nx as i64).contains(&x)
                && (0..ny as i64).contains(&y)
                && (0..nz as i64).contains(&z);
            if inside && solid[(z as usize * ny + y as usize) * nx + x as usize] {
                -1.0
            } else {
                1.0
            }
        };
        let field = |p: Vec3| -> f32 {
            let g = (p - origin) / voxel;
            let (x0, y0, z0) = (g.x.floor(), g.y.floor(), g.z.floor());
            let (fx, fy, fz) = (g.x - x0, g.y - y0, g.z - z0);
            let (x0, y0, z0) = (x0 as i64, y0 as i64, z0 as i64);
            let mut sum = 0.0;
            for (dz, wz) in [(0, 1.0 - fz), (1, fz)] {
                for (dy, wy) in [(0, 1.0 - fy), (1, fy)] {
                    for (dx, wx) in [(0, 1.0 - fx), (1, fx)] {
                        sum += wx * wy * wz * value(x0 + dx, y0 + dy, z0 + dz);
                    }
                }
            }
            // The level where the field is ISO (and never exactly zero at a grid corner of the
            // mesher's).
            sum - ISO + 1e-4
        };
        let lo = origin - Vec3::splat(voxel);
        let hi = origin + Vec3::new(nx as f32, ny as f32, nz as f32) * voxel;
        mesh_sdf(&field, lo, hi, voxel).ok()
    }
}

#[cfg(test)]
mod tests {
    use crate::fusion::FusionParams;
    use crate::test_scenes::box_view;

    use super::*;

    #[test]
    fn one_top_down_view_of_a_box_reconstructs_a_solid_down_to_the_table() {
        // One camera sees the box's top: everything under it is hidden, so the solid is the
        // box's footprint extruded from its top down to the table.
        let view = box_view(false);
        let fusion = Fusion::build(std::slice::from_ref(&view), &FusionParams::default()).unwrap();
        let mesh = fusion.solid_mesh().unwrap();
        let aabb = mesh.aabb();
        let (lo, hi) = (aabb.mins, aabb.maxs);
        let voxel = fusion.voxel_m();
        for (got, want) in [
            (lo.x, -0.02),
            (hi.x, 0.02),
            (lo.y, -0.06),
            (hi.y, 0.06),
            (lo.z, 0.5 * voxel),
            (hi.z, 0.05),
        ] {
            // A cell holding a surface point is solid: the boundary stands up to a cell and a
            // half outside the surface.
            assert!((got - want).abs() <= 1.5 * voxel, "{lo:?} {hi:?}");
        }
        let volume = mesh.mass_facts(1000.0).unwrap().volume_m3;
        let expected = 0.04 * 0.12 * (0.05 - 0.5 * voxel);
        assert!(
            (volume / expected - 1.0).abs() < 0.15,
            "{volume} vs {expected}"
        );
        assert!(mesh.is_watertight());
    }
}
