//! The checks every mesh passes on construction.

use std::path::Path;

use parry3d::math::Vec3;

use crate::error::{GeometryError, Result};

/// Twice the area below which a triangle counts as degenerate (1e-12 m^2: a 1 um sliver).
const MIN_DOUBLE_AREA_M2: f32 = 2e-12;

/// Checks vertices and indices; returns the triangles with degenerate ones removed.
pub(super) fn checked_triangles(
    vertices: &[Vec3],
    triangles: Vec<[u32; 3]>,
    path: &Path,
) -> Result<Vec<[u32; 3]>> {
    if triangles.is_empty() {
        return Err(GeometryError::NoTriangles {
            path: path.to_path_buf(),
        });
    }
    let bad: Vec<usize> = (0..vertices.len())
        .filter(|&i| !vertices[i].is_finite())
        .collect();
    if let Some(&first) = bad.first() {
        return Err(GeometryError::NonFiniteVertices {
            count: bad.len(),
            total: vertices.len(),
            first,
            path: path.to_path_buf(),
        });
    }
    for (triangle, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(GeometryError::IndexOutOfRange {
                triangle,
                index: u64::from(index),
                vertex_count: vertices.len(),
                path: path.to_path_buf(),
            });
        }
    }
    let total = triangles.len();
    let kept: Vec<[u32; 3]> = triangles
        .into_iter()
        .filter(|t| {
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            t[0] != t[1]
                && t[1] != t[2]
                && t[0] != t[2]
                && (b - a).cross(c - a).length() > MIN_DOUBLE_AREA_M2
        })
        .collect();
    if kept.is_empty() {
        return Err(GeometryError::DegenerateOnly {
            triangles: total,
            path: path.to_path_buf(),
        });
    }
    Ok(kept)
}

/// Checks that the largest extent of `vertices` is plausible for a graspable object, in metres.
pub(super) fn check_size(vertices: &[Vec3], min_m: f32, max_m: f32, path: &Path) -> Result<()> {
    let (lo, hi) = vertices.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(*v), hi.max(*v)),
    );
    let extent = (hi - lo).max_element();
    if (min_m..=max_m).contains(&extent) {
        return Ok(());
    }
    // Of the usual unit mistakes, suggest the one that makes the object closest to a typical
    // graspable 10 cm (in log scale) among those that make it plausible at all.
    let typical_m = 0.1f32;
    let hint = [
        (0.001, "millimetres"),
        (0.01, "centimetres"),
        (1000.0, "kilometres"),
    ]
    .into_iter()
    .filter(|(scale, _)| (min_m..=max_m).contains(&(extent * scale)))
    .min_by(|a, b| {
        let off = |s: f32| (extent * s / typical_m).ln().abs();
        off(a.0).total_cmp(&off(b.0))
    })
    .map_or(
        "; set LoadOptions::scale to convert to metres".to_string(),
        |(scale, unit)| format!("; looks like {unit}: load with scale {scale}"),
    );
    Err(GeometryError::AbsurdSize {
        extent,
        min_m,
        max_m,
        hint,
        path: path.to_path_buf(),
    })
}
