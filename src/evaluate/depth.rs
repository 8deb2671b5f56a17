//! The depth suite: depth predicted from RGB views against the rendered depth, over the
//! object's pixels, per method and number of views (the seed paper's Table 1: the top-down
//! view and every view scored).
//!
//! Each object rests in its most probable pose and is seen by the paper's 10 test views (the
//! first top-down) at the suite's distance, in random colours with its masks (or with the
//! photographic look, [`crate::scene::photoreal`]); depth is predicted from the first N views.
//! Methods: `lsm` (the shipped Learnt Stereo Machine, the only one that takes one view), `mvs`
//! (the shipped multi-view stereo network, every pixel kept), `refined` (the plane sweep
//! sharpened by the shipped refiner, every pixel kept), `sweep` (the plane sweep as `plan
//! --rgb` and `predict_depth` use it: unconfirmed pixels missing), `sweep-hull` (as the
//! default run's one-view planner gets it: unconfirmed pixels at the visual hull's depth) and
//! `hull` (the visual hull alone). The two networks that give a confidence (`mvs`, `refined`)
//! are also tallied by it: per tenth of confidence, the object pixels and those within 5 mm.

use std::path::Path;
use std::sync::Arc;

use mvgrasp_geometry::{HemisphereLayout, Intrinsics, IntrinsicsPreset};
use mvgrasp_infer::Parallelism;
use mvgrasp_render::Renderer;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::lsm::lsm_depths;
use crate::mvs::mvs_depths;
use crate::planner::{DepthPredictor, RgbInput, models, render_rgb};
use crate::scene::photoreal::render_photoreal;
use crate::stereo::{RgbView, SweepParams, sweep_depths};
use crate::sweep_refiner::{RefinedSweep, Unsure};

/// The methods, in the report's order.
pub const METHODS: [&str; 6] = ["lsm", "mvs", "refined", "sweep", "sweep-hull", "hull"];

/// The set name of the depth records of real photographs.
pub const REAL_PHOTOS: &str = "real photographs";

/// Confidence bins of the reliability tally: tenths.
pub const CONFIDENCE_BINS: usize = 10;

/// Error bins of the median, metres (0.1 mm), and their count (the last: 50 mm and more).
const BIN_M: f64 = 1e-4;
const BINS: usize = 501;

/// One method's errors over the object pixels of some views.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DepthErrors {
    /// Object pixels with a true depth.
    pub object_pixels: u64,
    /// Those the method predicted.
    pub predicted: u64,
    /// Sum of the predicted pixels' absolute errors, metres.
    pub abs_error_m: f64,
    /// Sum of the object pixels' true depths, metres (the paper's normalisation).
    pub true_depth_m: f64,
    /// Object pixels predicted within 2 mm.
    pub within_2mm: u64,
    /// Object pixels predicted within 5 mm.
    pub within_5mm: u64,
    /// Predicted pixels by error in 0.1 mm bins (the last: 50 mm and more), trailing zeros cut.
    pub histogram: Vec<u32>,
}

impl DepthErrors {
    /// Adds `predicted` against `truth` over the pixels of `mask`.
    pub fn add(&mut self, predicted: &[f32], truth: &[f32], mask: &[bool]) {
        let mut histogram = std::mem::take(&mut self.histogram);
        histogram.resize(BINS, 0);
        for ((&p, &t), &m) in predicted.iter().zip(truth).zip(mask) {
            if !m || t <= 0.0 {
                continue;
            }
            self.object_pixels += 1;
            self.true_depth_m += f64::from(t);
            if p > 0.0 {
                let e = f64::from((p - t).abs());
                self.predicted += 1;
                self.abs_error_m += e;
                self.within_2mm += u64::from(e <= 2e-3);
                self.within_5mm += u64::from(e <= 5e-3);
                histogram[((e / BIN_M) as usize).min(BINS - 1)] += 1;
            }
        }
        let used = histogram.iter().rposition(|&c| c > 0).map_or(0, |i| i + 1);
        histogram.truncate(used);
        self.histogram = histogram;
    }

    /// Adds another tally.
    pub fn merge(&mut self, other: &Self) {
        self.object_pixels += other.object_pixels;
        self.predicted += other.predicted;
        self.abs_error_m += other.abs_error_m;
        self.true_depth_m += other.true_depth_m;
        self.within_2mm += other.within_2mm;
        self.within_5mm += other.within_5mm;
        if self.histogram.len() < other.histogram.len() {
            self.histogram.resize(other.histogram.len(), 0);
        }
        for (a, b) in self.histogram.iter_mut().zip(&other.histogram) {
            *a += b;
        }
    }

    /// The median error of the predicted pixels, millimetres (to 0.1 mm; infinite when it is
    /// 50 mm or more, past the histogram; NaN when none).
    pub fn median_mm(&self) -> f64 {
        let half = self.predicted.div_ceil(2);
        let mut seen = 0u64;
        for (bin, &count) in self.histogram.iter().enumerate() {
            seen += u64::from(count);
            if seen >= half && count > 0 {
                if bin == BINS - 1 {
                    return f64::INFINITY;
                }
                return (bin as f64 + 0.5) * BIN_M * 1e3;
            }
        }
        f64::NAN
    }

    /// The mean error of the predicted pixels, millimetres.
    pub fn mean_mm(&self) -> f64 {
        1e3 * self.abs_error_m / self.predicted.max(1) as f64
    }

    /// The share of object pixels predicted.
    pub fn predicted_share(&self) -> f64 {
        self.predicted as f64 / self.object_pixels.max(1) as f64
    }

    /// The share of object pixels predicted within 5 mm (a missing pixel is not within).
    pub fn within_5mm_share(&self) -> f64 {
        self.within_5mm as f64 / self.object_pixels.max(1) as f64
    }

    /// The paper's normalised error: the mean error over the mean true depth.
    pub fn normalised(&self) -> f64 {
        let mean_depth = self.true_depth_m / self.object_pixels.max(1) as f64;
        self.abs_error_m / self.predicted.max(1) as f64 / mean_depth.max(f64::MIN_POSITIVE)
    }
}

/// One object's depth errors for one number of views: per method, over the top-down view and
/// over all the input views.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DepthRecord {
    /// The object's name in its set.
    pub object: String,
    /// The set's name.
    pub set: String,
    /// Input views.
    pub views: usize,
    /// Per method of [`METHODS`] that takes this many views: (method, top-down, all views).
    pub methods: Vec<(String, DepthErrors, DepthErrors)>,
    /// Per method that gives a confidence: per tenth of confidence, the object pixels of all
    /// views with a true depth and those predicted within 5 mm.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reliability: Vec<(String, Vec<[u64; 2]>)>,
}

/// Adds each object pixel of `depth` to its confidence tenth of `bins`: [pixels, within 5 mm].
fn tally_confidence(
    bins: &mut [[u64; 2]],
    (depth, confidence): (&[f32], &[f32]),
    truth: &[f32],
    mask: &[bool],
) {
    for (((&d, &c), &t), &on) in depth.iter().zip(confidence).zip(truth).zip(mask) {
        if on && t > 0.0 {
            let bin = ((c * CONFIDENCE_BINS as f32) as usize).min(CONFIDENCE_BINS - 1);
            bins[bin][0] += 1;
            bins[bin][1] += u64::from(d > 0.0 && (d - t).abs() <= 5e-3);
        }
    }
}

/// The suite's prepared networks and settings.
pub struct DepthSuite {
    lsm: mvgrasp_infer::Lsm,
    mvs: mvgrasp_infer::Mvs,
    refined: RefinedSweep,
    layout: HemisphereLayout,
    input: RgbInput,
}

impl DepthSuite {
    /// The shipped networks and the paper's test views at `distance_m`, in random colours or
    /// (`photo`) with the photographic look.
    ///
    /// # Errors
    /// Shipped weights that cannot be loaded.
    pub fn new(distance_m: f32, photo: bool) -> Result<Self> {
        Ok(Self {
            lsm: models::LSM
                .load()?
                .with_parallelism(Parallelism::all_threads()),
            mvs: models::MVS
                .load()?
                .with_parallelism(Parallelism::all_threads()),
            // Every pixel kept, as for the MVS network.
            refined: RefinedSweep {
                net: Arc::new(
                    models::SWEEP_REFINER
                        .load()?
                        .with_parallelism(Parallelism::all_threads()),
                ),
                min_confidence: 0.0,
                unsure: Unsure::Missing,
            },
            layout: HemisphereLayout {
                radius_m: distance_m,
                ..HemisphereLayout::paper_test()
            },
            input: RgbInput {
                depth: DepthPredictor::Baseline(SweepParams::default()),
                per_face: false,
                photo,
            },
        })
    }

    /// The records of `mesh` (named `object` in `set`), one per number of `views`; the
    /// cameras and colours seeded by `seed`.
    ///
    /// # Errors
    /// A mesh with no stable pose, or a renderer or network error.
    pub fn run(
        &self,
        renderer: &Renderer,
        (set, object): (&str, &str),
        mesh: &mvgrasp_geometry::TriangleMesh,
        views: &[usize],
        (seed, picture): (u64, Option<(&Path, usize)>),
    ) -> Result<Vec<DepthRecord>> {
        let rest = mvgrasp_geometry::RestingPoses::of(mesh)?;
        let (_, pose) = rest.get(0)?;
        let com = mesh.mass_facts(1000.0)?.center_of_mass;
        let target = pose.table_from_object.transform_point(com);
        let intrinsics = Intrinsics::preset(IntrinsicsPreset::PhoxiS);
        let cameras = self.layout.cameras(intrinsics, target, seed)?;
        let rendered = if self.input.photo {
            render_photoreal(renderer, mesh, &pose.table_from_object, &cameras, seed)?.views
        } else {
            render_rgb(
                renderer,
                mesh,
                &pose.table_from_object,
                &cameras,
                &self.input,
                seed,
            )?
        };
        let (inputs, truths): (Vec<RgbView>, Vec<Vec<f32>>) = rendered.into_iter().unzip();
        views
            .iter()
            .map(|&n| self.score((set, object), &inputs, &truths, (n, picture)))
            .collect()
    }

    /// The records of a folder of calibrated photographs with a depth sensor's images and
    /// object masks (`plan --rgb`'s and `plan --views-dir`'s layout in one folder), named
    /// `object` in the set [`REAL_PHOTOS`]: per number of `views` (at most the folder's), every
    /// method against the sensor's depth over the masked pixels where the sensor has depth,
    /// the folder's first view in the top-down view's place.
    ///
    /// # Errors
    /// A folder that cannot be read (naming the file), views without masks, or a network
    /// error.
    pub fn run_photographs(
        &self,
        object: &str,
        dir: &Path,
        views: &[usize],
        picture: Option<(&Path, usize)>,
    ) -> Result<Vec<DepthRecord>> {
        let inputs = crate::planner::read_rgb_dir(dir)?;
        let sensor = crate::planner::read_views_dir(dir)?;
        if inputs.iter().any(|v| v.mask.is_none()) {
            return Err(crate::Error::Evaluate {
                problem: format!("{}: the photographs need masks", dir.display()),
            });
        }
        // The folder's readers check each file against its camera; the two against each other:
        let sizes = |k: &mvgrasp_geometry::Intrinsics| (k.width, k.height);
        if sensor.len() != inputs.len()
            || inputs
                .iter()
                .zip(&sensor)
                .any(|(c, d)| sizes(&c.camera.intrinsics) != sizes(&d.camera.intrinsics))
        {
            return Err(crate::Error::Evaluate {
                problem: format!(
                    "{}: {} colour views and {} depth images of other sizes",
                    dir.display(),
                    inputs.len(),
                    sensor.len()
                ),
            });
        }
        let truths: Vec<Vec<f32>> = sensor.iter().map(|v| v.depth.as_slice().to_vec()).collect();
        let mut counts: Vec<usize> = views.iter().map(|&n| n.clamp(1, inputs.len())).collect();
        counts.dedup();
        counts
            .into_iter()
            .map(|n| self.score((REAL_PHOTOS, object), &inputs, &truths, (n, picture)))
            .collect()
    }

    /// Every method's depth from the first `n` of `inputs`, scored against `truths` over the
    /// inputs' masks: the first view, and all `n`. With `picture` `(path, m)` and `n` equal to
    /// `m`, the first view's error sheet ([`write_error_sheet`]) too.
    fn score(
        &self,
        (set, object): (&str, &str),
        inputs: &[RgbView],
        truths: &[Vec<f32>],
        (n, picture): (usize, Option<(&Path, usize)>),
    ) -> Result<DepthRecord> {
        let wanted = picture.filter(|&(_, m)| m.clamp(1, inputs.len()) == n.clamp(1, inputs.len()));
        let n = n.clamp(1, inputs.len());
        let input = &inputs[..n];
        let mask = |i: usize| inputs[i].mask.as_deref().unwrap_or(&[]);
        // (method, each view's depth). The LSM cannot place its grid from one camera that
        // does not look down at the table (photographs from the side): it has no row there.
        let mut predicted: Vec<(&str, Vec<Vec<f32>>)> = match lsm_depths(&self.lsm, input) {
            Ok(depths) => vec![("lsm", depths)],
            Err(crate::RuntimeError::Stereo { .. }) if n == 1 => Vec::new(),
            Err(e) => return Err(e.into()),
        };
        let mut reliability = Vec::new();
        if n >= 2 {
            let mvs: Vec<(Vec<f32>, Vec<f32>)> = mvs_depths(&self.mvs, input, 0.0)?
                .into_iter()
                .map(|v| (v.depth_m, v.confidence))
                .collect();
            let refined: Vec<(Vec<f32>, Vec<f32>)> = self
                .refined
                .depths(input)?
                .into_iter()
                .map(|v| (v.depth_m, v.confidence))
                .collect();
            for (method, views) in [("mvs", mvs), ("refined", refined)] {
                let mut bins = vec![[0u64; 2]; CONFIDENCE_BINS];
                for (i, ((depth, confidence), truth)) in views.iter().zip(truths).enumerate() {
                    tally_confidence(&mut bins, (depth, confidence), truth, mask(i));
                }
                reliability.push((method.to_string(), bins));
                predicted.push((method, views.into_iter().map(|(d, _)| d).collect()));
            }
            let hull_fill = SweepParams {
                hull_where_unconfirmed: true,
                ..SweepParams::default()
            };
            let swept = sweep_depths(input, &SweepParams::default())?;
            let filled = sweep_depths(input, &hull_fill)?;
            predicted.push(("sweep", swept.iter().map(|s| s.depth_m.clone()).collect()));
            predicted.push((
                "sweep-hull",
                filled.into_iter().map(|s| s.depth_m).collect(),
            ));
            predicted.push(("hull", swept.into_iter().map(|s| s.hull_m).collect()));
        }
        if let Some((path, _)) = wanted.filter(|_| !predicted.is_empty()) {
            let first: Vec<(&str, &[f32])> = predicted
                .iter()
                .map(|(m, depths)| (*m, depths[0].as_slice()))
                .collect();
            write_error_sheet(path, &inputs[0], &truths[0], &first)?;
        }
        let methods = predicted
            .into_iter()
            .map(|(method, depths)| {
                let (mut top, mut all) = (DepthErrors::default(), DepthErrors::default());
                for (i, (depth, truth)) in depths.iter().zip(truths).enumerate() {
                    if i == 0 {
                        top.add(depth, truth, mask(i));
                    }
                    all.add(depth, truth, mask(i));
                }
                (method.to_string(), top, all)
            })
            .collect();
        Ok(DepthRecord {
            object: object.to_string(),
            set: set.to_string(),
            views: n,
            methods,
            reliability,
        })
    }
}

/// The file name of the error sheet of `object` in `set` from `views` views.
pub fn sheet_name(set: &str, object: &str, views: usize) -> String {
    super::report::png_name(&format!("depth_{set}_{object}_{views}views"))
}

/// The number of views the error sheets are drawn from, of a run's `views`: 5 (the planner's)
/// when it is one, else the most.
pub fn sheet_views(views: &[usize]) -> usize {
    if views.contains(&5) {
        5
    } else {
        views.iter().copied().max().unwrap_or(1)
    }
}

/// Errors drawn up to this, millimetres (red); more is the same red.
pub const SHEET_ERROR_MM: f32 = 20.0;

/// The seed paper's Fig. 5 for one view: a PNG of columns, each the object's box in the view
/// (half again as large, at least 64 pixels, at full resolution; the whole view at half
/// resolution when there is no mask): the colour image and the true depth, then each method's
/// predicted depth (top, on the truth's grey scale over the object) above its error over the
/// object (bottom: black within 1 mm to red at [`SHEET_ERROR_MM`] and more; blue where the
/// method predicted nothing; the rest dim).
///
/// # Errors
/// A PNG that cannot be written.
pub fn write_error_sheet(
    path: &Path,
    view: &RgbView,
    truth: &[f32],
    methods: &[(&str, &[f32])],
) -> Result<()> {
    let k = view.camera.intrinsics;
    let (w, h) = (k.width as usize, k.height as usize);
    let (x0, y0, tw, th, step) = object_box(view.mask.as_deref(), w, h);
    let columns = 2 + methods.len();
    let (sheet_w, sheet_h) = (tw * columns, 2 * th);
    let mut sheet = vec![0u8; 3 * sheet_w * sheet_h];
    let mask = view.mask.as_deref().unwrap_or(&[]);
    let on = |i: usize| mask.get(i).copied().unwrap_or(false) && truth[i] > 0.0;
    // The truth's grey scale, over the object.
    let object = view
        .mask
        .clone()
        .and_then(|pixels| mvgrasp_planner::Mask::new(k.width, k.height, pixels).ok());
    let (near, far) = crate::grasps_file::depth_span(truth, object.as_ref());
    let grey = |d: f32| -> [u8; 3] {
        if d <= 0.0 {
            return [0, 0, 0];
        }
        let g = (250.0 - 200.0 * ((d - near) / (far - near)).clamp(0.0, 1.0)) as u8;
        [g, g, g]
    };
    let mut put = |col: usize, row: usize, x: usize, y: usize, c: [u8; 3]| {
        let i = 3 * ((row * th + y) * sheet_w + col * tw + x);
        sheet[i..i + 3].copy_from_slice(&c);
    };
    for y in 0..th {
        for x in 0..tw {
            let i = (y0 + step * y) * w + x0 + step * x;
            let dim = |c: [u8; 3]| c.map(|v| v / 3);
            put(0, 0, x, y, view.rgb[i]);
            put(
                0,
                1,
                x,
                y,
                if on(i) { view.rgb[i] } else { dim(view.rgb[i]) },
            );
            let true_grey = grey(truth[i]);
            put(1, 0, x, y, true_grey);
            put(1, 1, x, y, if on(i) { true_grey } else { dim(true_grey) });
            for (m, (_, depth)) in methods.iter().enumerate() {
                let d = depth[i];
                put(2 + m, 0, x, y, if on(i) { grey(d) } else { dim(grey(d)) });
                let error = if !on(i) {
                    [0, 0, 0]
                } else if d <= 0.0 {
                    [40, 80, 220]
                } else {
                    let mm = (1e3 * (d - truth[i]).abs() - 1.0).max(0.0);
                    [(255.0 * (mm / (SHEET_ERROR_MM - 1.0)).min(1.0)) as u8, 0, 0]
                };
                put(2 + m, 1, x, y, error);
            }
        }
    }
    Ok(crate::images::write_png8(
        path,
        sheet_w as u32,
        sheet_h as u32,
        3,
        &sheet,
    )?)
}

/// The tile of an error sheet in a `w` x `h` view: `(x0, y0, width, height, step)`, the box of
/// the mask's pixels half again as large (at least 64 pixels a side, inside the view) at full
/// resolution, or the whole view at half resolution without a mask or object pixels.
fn object_box(mask: Option<&[bool]>, w: usize, h: usize) -> (usize, usize, usize, usize, usize) {
    let whole = (0, 0, w / 2, h / 2, 2);
    let Some(mask) = mask else {
        return whole;
    };
    let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = (i % w, i / w);
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    if lo[0] > hi[0] {
        return whole;
    }
    let side = |a: usize, b: usize, n: usize| {
        let size = ((b - a + 1) * 3 / 2).max(64).min(n);
        let start = ((a + b) / 2).saturating_sub(size / 2).min(n - size);
        (start, size)
    };
    let ((x0, tw), (y0, th)) = (side(lo[0], hi[0], w), side(lo[1], hi[1], h));
    (x0, y0, tw, th, 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_count_missing_pixels_against_the_share_and_merge_into_one_median() {
        let truth = [0.5f32, 0.5, 0.5, 0.5, 0.0];
        let mask = [true, true, true, true, true];
        let mut a = DepthErrors::default();
        // 1 mm, 3 mm, 10 mm off, and one missing; the last pixel has no true depth.
        a.add(&[0.501, 0.503, 0.51, 0.0, 0.4], &truth, &mask);
        assert_eq!((a.object_pixels, a.predicted), (4, 3));
        assert_eq!((a.within_2mm, a.within_5mm), (1, 2));
        assert!((a.median_mm() - 3.05).abs() < 0.06, "{}", a.median_mm());
        assert!((a.within_5mm_share() - 0.5).abs() < 1e-9);
        let mut b = DepthErrors::default();
        b.add(&[0.5001, 0.5001, 0.5001, 0.5001, 0.0], &truth, &mask);
        a.merge(&b);
        assert_eq!(a.predicted, 7);
        assert!(a.median_mm() < 1.0, "{}", a.median_mm());
        let mut far = DepthErrors::default();
        far.add(&[0.6, 0.6, 0.501, 0.0, 0.0], &truth, &mask);
        assert_eq!(
            far.median_mm(),
            f64::INFINITY,
            "100 mm off: past the histogram"
        );
    }
}
