//! Every candidate seen as a GQ-CNN saw its training crops: a virtual camera on the candidate's
//! approach axis, looking along it with the closing axis along its rows, draws the fused views'
//! points ([`Fusion::points`]) straight into the network's crop. One network then scores the
//! candidates of every view on the same footing, whichever view found them.
//!
//! Each crop pixel takes the mean depth of the points in its footprint that lie within
//! `front_tolerance_m` of the nearest (the surface facing the camera, as the training crops'
//! area filter averages it); a pixel no point reaches takes the mean of its filled neighbours
//! (sampling gaps), else the table plane where its ray meets it, else the farthest depth in the
//! crop.

use mvgrasp_geometry::{Mat3, Pose3, Vec3};
use mvgrasp_grasp::Grasp;
use mvgrasp_infer::{Gqcnn, GqcnnWorkspace, Tensor};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloud_sampler::{CloudSamplerParams, sample_cloud_grasps};
use crate::contract::InputContract;
use crate::crop::CropParams;
use crate::depth_image::View;
use crate::error::{PlannerError, Result};
use crate::fusion::{Fusion, POINT_BUCKET_M};
use crate::plan::Plan;
use crate::policy::GqcnnPolicy;
use crate::ranker::Ranker;
use crate::scored::ScoredGrasp;
use crate::seed::splitmix;
use mvgrasp_geometry::rounding::rounded_index;

/// Salts the scorer's own proposals' seed apart from the planner's.
const PROPOSE_SALT: u64 = 0x70d0_5eed;
/// ... and the fused model's candidates' seed.
const CLOUD_SALT: u64 = 0xc10d_5eed;

/// How candidates are re-scored on virtual views.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VirtualViewParams {
    /// The virtual camera stands this far above the table's height at the grasp, along the
    /// approach (the top-down GQ-CNN's training cameras: 0.65 to 0.75 m), metres.
    pub camera_height_m: f32,
    /// ... but never nearer the grasp than this, metres.
    pub min_distance_m: f32,
    /// Points within this of a pixel's nearest are its surface, metres.
    pub front_tolerance_m: f32,
    /// The best this many candidates of each view (after the hand check) are re-scored.
    pub candidates_per_view: usize,
    /// Grasp axes the proposing policy samples in each view (each at its sampler's depths)
    /// once it proposes for this scorer ([`crate::MultiViewPlanner::new`]).
    pub grasps_per_view: usize,
    /// Each candidate's score is the mean over itself and this many perturbed copies (0: its
    /// own score): a robust score that a lucky crop cannot win.
    pub perturbations: usize,
    /// A perturbed copy's centre moves up to this along each axis, metres.
    pub perturb_translation_m: f32,
    /// ... and its orientation up to this about each axis, radians.
    pub perturb_rotation_rad: f32,
    /// The scorer also proposes candidates of its own in the views that look within
    /// `top_down_tolerance_rad` of straight down (a top-down GQ-CNN plans there as it was
    /// trained); they are checked and re-scored like the others.
    pub propose_top_down: bool,
    /// See `propose_top_down`, radians.
    pub top_down_tolerance_rad: f32,
    /// Candidates sampled on the fused model's points in any reachable direction
    /// ([`crate::cloud_sampler`]; `num_grasps` 0: none), checked and re-scored like the others
    /// in a quota of their own.
    pub cloud: CloudSamplerParams,
}

/// A hash of `grasp`'s pose and width (its floats' bits).
fn grasp_key(grasp: &Grasp) -> u64 {
    let pose = &grasp.world_from_gripper;
    let q = pose.rotation;
    [
        pose.translation.x,
        pose.translation.y,
        pose.translation.z,
        q.x,
        q.y,
        q.z,
        q.w,
        grasp.width_m,
    ]
    .iter()
    .fold(0u64, |h, v| splitmix(h ^ u64::from(v.to_bits())))
}

impl Default for VirtualViewParams {
    fn default() -> Self {
        Self {
            camera_height_m: 0.7,
            min_distance_m: 0.4,
            front_tolerance_m: 0.003,
            candidates_per_view: 10,
            // 70 axes and 4 perturbed copies: on the development set (plan_eval --first-index
            // 50) they held as often as 200 and 8 (40 against 37 of 47) in 0.58 s an object
            // instead of 0.95.
            grasps_per_view: 70,
            perturbations: 4,
            perturb_translation_m: 0.002,
            perturb_rotation_rad: 5f32.to_radians(),
            propose_top_down: true,
            top_down_tolerance_rad: 10f32.to_radians(),
            cloud: CloudSamplerParams::default(),
        }
    }
}

/// The virtual camera's distance from `grasp`'s centre along its approach.
fn distance_for(grasp: &Grasp, table_z_m: f32, params: &VirtualViewParams) -> f32 {
    let height = grasp.world_from_gripper.translation.z - table_z_m;
    (params.camera_height_m - height).max(params.min_distance_m)
}

/// The crop `crop` (the network's, for a camera of focal length `focal_px`) of `fusion`'s
/// points as a camera `distance_m` back along `grasp`'s approach sees them (see the module
/// docs); `size_px^2` depths, row-major.
pub fn virtual_crop(
    fusion: &Fusion,
    grasp: &Grasp,
    crop: &CropParams,
    focal_px: f32,
    distance_m: f32,
    front_tolerance_m: f32,
) -> Vec<f32> {
    draw_crop(
        fusion,
        grasp,
        crop,
        focal_px,
        distance_m,
        front_tolerance_m,
        true,
    )
    .0
}

/// [`virtual_crop`], drawing only the buckets that can reach the frustum when `cull` (else
/// every point: the reference the culled crop is tested against), and how many buckets it drew.
fn draw_crop(
    fusion: &Fusion,
    grasp: &Grasp,
    crop: &CropParams,
    focal_px: f32,
    distance_m: f32,
    front_tolerance_m: f32,
    cull: bool,
) -> (Vec<f32>, usize) {
    let size = crop.size_px as usize;
    let half = size as f32 / 2.0;
    // Crop pixels are window/size image pixels.
    let focal = focal_px * crop.size_px as f32 / crop.window_px.max(1) as f32;
    let world_from_camera =
        grasp.world_from_gripper * Pose3::from_translation(Vec3::new(0.0, 0.0, -distance_m));
    let camera_from_world = world_from_camera.inverse();
    let pixel_of = |q: Vec3| -> Option<usize> {
        if q.z <= 1e-3 {
            return None;
        }
        let j = rounded_index(focal * q.x / q.z + half, size)?;
        let i = rounded_index(focal * q.y / q.z + half, size)?;
        Some(i * size + j)
    };
    // The rotation as a matrix, formed once: three products a coordinate per point.
    let r = Mat3::from_quat(camera_from_world.rotation);
    let t = camera_from_world.translation;
    // Only the buckets whose cube can reach the crop's frustum (|x|, |y| < k z, z > 0): the
    // crop sees a few centimetres around the grasp, the fused points span 20 or so. A cube is
    // skipped when its bounding sphere (grown by a millimetre against rounding) lies wholly
    // beyond one of the frustum's planes; the points drawn, and so the crop, are the same.
    let k = (half + 0.5) / focal;
    let reach = (0.5 * 3f32.sqrt() * POINT_BUCKET_M + 1e-3) * (1.0 + k * k).sqrt();
    let points = fusion.points();
    let mut camera_points: Vec<(usize, f32)> = Vec::new();
    let mut drawn = 0;
    for bucket in fusion.buckets() {
        let c = r * bucket.centre + t;
        let beyond = c.z < -reach || c.x.abs() - k * c.z > reach || c.y.abs() - k * c.z > reach;
        if cull && beyond {
            continue;
        }
        drawn += 1;
        camera_points.extend(points[bucket.range.clone()].iter().filter_map(|&p| {
            let q = r * p + t;
            pixel_of(q).map(|i| (i, q.z))
        }));
    }
    let mut nearest = vec![f32::INFINITY; size * size];
    for &(i, z) in &camera_points {
        nearest[i] = nearest[i].min(z);
    }
    let mut sum = vec![0.0f64; size * size];
    let mut count = vec![0u32; size * size];
    for &(i, z) in &camera_points {
        if z <= nearest[i] + front_tolerance_m {
            sum[i] += f64::from(z);
            count[i] += 1;
        }
    }
    let mut depth: Vec<f32> = sum
        .iter()
        .zip(&count)
        .map(|(&s, &n)| {
            if n == 0 {
                0.0
            } else {
                (s / f64::from(n)) as f32
            }
        })
        .collect();
    // Sampling gaps: two rounds of neighbours' means.
    for _ in 0..2 {
        let before = depth.clone();
        for i in 0..size {
            for j in 0..size {
                if before[i * size + j] > 0.0 {
                    continue;
                }
                let (mut s, mut n) = (0.0f32, 0u32);
                for (di, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (y, x) = (i as i64 + di, j as i64 + dj);
                    if (0..size as i64).contains(&y) && (0..size as i64).contains(&x) {
                        let d = before[y as usize * size + x as usize];
                        if d > 0.0 {
                            s += d;
                            n += 1;
                        }
                    }
                }
                if n >= 2 {
                    depth[i * size + j] = s / n as f32;
                }
            }
        }
    }
    // The rest: the table, else the farthest surface.
    let origin = world_from_camera.translation;
    let farthest = depth.iter().copied().fold(0.0f32, f32::max);
    for i in 0..size {
        for j in 0..size {
            let d = &mut depth[i * size + j];
            if *d > 0.0 {
                continue;
            }
            let ray = world_from_camera.rotation
                * Vec3::new((j as f32 - half) / focal, (i as f32 - half) / focal, 1.0);
            let t = (fusion.table_z_m() - origin.z) / ray.z;
            *d = if ray.z < 0.0 && t > 0.0 { t } else { farthest };
        }
    }
    (depth, drawn)
}

/// A network that re-scores candidates on virtual views of the fused scene.
#[derive(Debug)]
pub struct VirtualScorer {
    /// The network, with its sampler and contract, for the candidates it proposes itself.
    pub policy: GqcnnPolicy,
    /// A second network that scores the same virtual crops ([`VirtualScorer::set_second`]).
    second: Option<Gqcnn>,
    /// The views, the candidates re-scored and the perturbations.
    pub params: VirtualViewParams,
    /// Ranks the re-scored candidates by their modelled chance to hold ([`Ranker`]); `None`:
    /// by the re-score.
    pub ranker: Option<Ranker>,
}

impl VirtualScorer {
    /// A scorer with `net` and the default parameters, for a gripper opening `max_width_m`.
    ///
    /// # Errors
    /// See [`GqcnnPolicy::new`].
    pub fn new(net: Gqcnn, max_width_m: f32) -> Result<Self> {
        Ok(Self {
            policy: GqcnnPolicy::new(net, max_width_m)?,
            second: None,
            params: VirtualViewParams::default(),
            ranker: None,
        })
    }

    /// The multi-view planner's scorer (`plan --fuse`): the shipped top-down GQ-CNN
    /// ([`crate::models::GQCNN_TOPDOWN`]) with the default parameters, and the shipped
    /// [`Ranker`].
    ///
    /// # Errors
    /// As [`VirtualScorer::new`].
    pub fn shipped(max_width_m: f32) -> Result<Self> {
        let mut scorer = Self::new(crate::models::GQCNN_TOPDOWN.load()?, max_width_m)?;
        scorer.ranker = Some(Ranker::shipped()?);
        Ok(scorer)
    }

    /// A second network that scores the same virtual crops, the score then being the geometric
    /// mean of the two (a candidate must please both); `None`: the scorer's network alone.
    ///
    /// # Errors
    /// [`PlannerError::Network`] when the second network takes other crops.
    pub fn set_second(&mut self, net: Option<Gqcnn>) -> Result<()> {
        if let Some(net) = &net
            && InputContract::of(net) != self.policy.contract
        {
            let arch = net.architecture();
            return Err(PlannerError::Network {
                image_px: arch.image_size_px,
                pose_inputs: arch.pose_inputs,
                crop_px: self.policy.contract.crop.size_px,
            });
        }
        self.second = net;
        Ok(())
    }

    /// The candidates the scorer's network finds itself in the views that look (nearly)
    /// straight down ([`VirtualViewParams::propose_top_down`]), scored on those views, with
    /// their indices in `views`; none when not asked for.
    ///
    /// # Errors
    /// See [`GqcnnPolicy::plan`].
    pub fn propose(&self, views: &[View], seed: u64) -> Result<Vec<ScoredGrasp>> {
        if !self.params.propose_top_down {
            return Ok(Vec::new());
        }
        let (indices, top): (Vec<usize>, Vec<View>) = views
            .iter()
            .enumerate()
            .filter(|(_, v)| {
                (-v.camera.optical_axis().z).clamp(-1.0, 1.0).acos()
                    <= self.params.top_down_tolerance_rad
            })
            .map(|(i, v)| (i, v.clone()))
            .unzip();
        let plan = self.policy.plan(&top, splitmix(seed ^ PROPOSE_SALT))?;
        Ok(plan
            .candidates
            .into_iter()
            .map(|c| ScoredGrasp {
                view: indices[c.view],
                by_scorer: true,
                from_cloud: false,
                ..c
            })
            .collect())
    }

    /// Candidates sampled on `fusion`'s points ([`VirtualViewParams::cloud`]), scored on their
    /// virtual views, each credited to the view of `views` that looks most nearly along its
    /// approach; none when not asked for.
    ///
    /// # Errors
    /// A network error.
    pub fn propose_on_cloud(
        &self,
        fusion: &Fusion,
        views: &[View],
        seed: u64,
    ) -> Result<Vec<ScoredGrasp>> {
        if self.params.cloud.num_grasps == 0 || views.is_empty() {
            return Ok(Vec::new());
        }
        let seed = splitmix(seed ^ CLOUD_SALT);
        let grasps = sample_cloud_grasps(fusion, self.policy.max_width_m, &self.params.cloud, seed);
        let quality = self.score(fusion, &grasps, seed)?;
        Ok(grasps
            .into_iter()
            .zip(quality)
            .filter_map(|(grasp, q)| {
                let approach = grasp.approach();
                let (index, view) = views.iter().enumerate().max_by(|a, b| {
                    let along = |v: &View| v.camera.optical_axis().dot(approach);
                    along(a.1).total_cmp(&along(b.1))
                })?;
                let image = grasp.to_image(&view.camera, std::f32::consts::FRAC_PI_2)?;
                Some(ScoredGrasp {
                    view: index,
                    image,
                    grasp,
                    theta_rad: view.theta_rad(),
                    quality: q,
                    view_quality: Some(q),
                    virtual_quality: None,
                    by_scorer: false,
                    from_cloud: true,
                })
            })
            .collect())
    }

    /// The network's probability that each grasp is robust, seen on its virtual view of
    /// `fusion` (the mean over the perturbed copies, where asked for; deterministic from `seed`
    /// and the grasp itself, so that a grasp's score does not depend on the others scored with
    /// it).
    ///
    /// # Errors
    /// A network error.
    pub fn score(&self, fusion: &Fusion, grasps: &[Grasp], seed: u64) -> Result<Vec<f32>> {
        let p = &self.params;
        let copies = p.perturbations + 1;
        let mut posed = Vec::with_capacity(grasps.len() * copies);
        for grasp in grasps {
            let mut rng = ChaCha8Rng::seed_from_u64(splitmix(seed ^ grasp_key(grasp)));
            let mut jitter = |r: f32| {
                if r > 0.0 {
                    rng.random_range(-r..=r)
                } else {
                    0.0
                }
            };
            posed.push(*grasp);
            for _ in 0..p.perturbations {
                let (t, r) = (p.perturb_translation_m, p.perturb_rotation_rad);
                let shift = Vec3::new(jitter(t), jitter(t), jitter(t));
                let turn = mvgrasp_geometry::Rot3::from_scaled_axis(Vec3::new(
                    jitter(r),
                    jitter(r),
                    jitter(r),
                ));
                posed.push(Grasp {
                    world_from_gripper: grasp.world_from_gripper * Pose3::from_parts(shift, turn),
                    width_m: grasp.width_m,
                });
            }
        }
        let contract = self.policy.contract;
        let crop = contract.crop;
        let side = crop.size_px as usize;
        let nets: Vec<&Gqcnn> = std::iter::once(self.policy.net())
            .chain(self.second.as_ref())
            .collect();
        let mut workspace = GqcnnWorkspace::default();
        let mut quality = Vec::with_capacity(posed.len());
        for chunk in posed.chunks(256) {
            let distances: Vec<f32> = chunk
                .iter()
                .map(|g| distance_for(g, fusion.table_z_m(), p))
                .collect();
            let mut crops = Vec::with_capacity(chunk.len() * side * side);
            crops.par_extend(chunk.par_iter().zip(&distances).flat_map_iter(|(g, &d)| {
                virtual_crop(fusion, g, &crop, contract.focal_px, d, p.front_tolerance_m)
            }));
            let depth = Tensor::new(&[chunk.len(), 1, side, side], crops)?;
            // Each network's score; with two, their geometric mean (both must like it).
            let mut combined = vec![1.0f32; chunk.len()];
            for net in &nets {
                let pose_inputs = net.architecture().pose_inputs;
                let mut poses = Vec::with_capacity(chunk.len() * pose_inputs);
                for (g, &d) in chunk.iter().zip(&distances) {
                    poses.push(d);
                    if pose_inputs == 2 {
                        // The virtual camera's angle to the table: the approach's.
                        poses.push((-g.approach().z).clamp(-1.0, 1.0).asin());
                    }
                }
                let pose = Tensor::new(&[chunk.len(), pose_inputs], poses)?;
                for (c, q) in combined
                    .iter_mut()
                    .zip(net.predict(&depth, &pose, &mut workspace)?)
                {
                    *c *= q;
                }
            }
            let root = 1.0 / nets.len() as f32;
            quality.extend(combined.into_iter().map(|q| q.powf(root)));
        }
        Ok(quality
            .chunks(copies)
            .map(|c| c.iter().sum::<f32>() / c.len() as f32)
            .collect())
    }

    /// Re-scores the best `params.candidates_per_view` of each view in `plan` (and as many of
    /// the scorer's own candidates in each view, apart: [`ScoredGrasp::quota`]) on their virtual
    /// views and ranks them by that score (with a [`Ranker`], by its probability built on that
    /// score, which then stays in [`ScoredGrasp::virtual_quality`]) ahead of the rest (which
    /// keep their order); each keeps the score it was planned with in
    /// [`ScoredGrasp::view_quality`].
    ///
    /// # Errors
    /// A network error.
    pub fn rescore(&self, plan: &mut Plan, fusion: &Fusion, seed: u64) -> Result<()> {
        let mut per_view = std::collections::HashMap::<(usize, bool), usize>::new();
        let (mut head, mut rest): (Vec<ScoredGrasp>, Vec<ScoredGrasp>) = (Vec::new(), Vec::new());
        for c in std::mem::take(&mut plan.candidates) {
            let n = per_view.entry(c.quota()).or_default();
            if *n < self.params.candidates_per_view {
                *n += 1;
                head.push(c);
            } else {
                rest.push(c);
            }
        }
        let grasps: Vec<Grasp> = head.iter().map(|c| c.grasp).collect();
        let quality = self.score(fusion, &grasps, seed)?;
        for (c, q) in head.iter_mut().zip(quality) {
            c.view_quality = Some(c.quality);
            c.quality = q;
            if let Some(ranker) = &self.ranker {
                c.virtual_quality = Some(q);
                c.quality = ranker.probability(c, fusion.table_z_m());
            }
        }
        // Stable: ties keep the planner's order.
        head.sort_by(|a, b| b.quality.total_cmp(&a.quality));
        head.extend(rest);
        plan.candidates = head;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::crop::crop_depth;
    use crate::fusion::FusionParams;
    use crate::test_scenes::{box_view, seen_box};
    use mvgrasp_grasp::ImageGrasp;

    #[test]
    fn culled_virtual_crops_are_the_whole_cloud_s_to_the_bit() {
        // Two oblique views of a cube and the top-down view of a box, fused; grasps all
        // around, near and far, tilted every way: the crop drawn from the buckets that reach
        // its frustum is the crop drawn from every point.
        let views = [seen_box(-1.0), seen_box(1.0)];
        let fusion = Fusion::build(&views, &FusionParams::default()).unwrap();
        let top = box_view(false);
        let top_fusion =
            Fusion::build(std::slice::from_ref(&top), &FusionParams::default()).unwrap();
        let crop = CropParams::default();
        let focal = views[0].depth.intrinsics().fx;
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        // Buckets the culled crops skipped, and all they could have drawn, over all grasps.
        let (mut skipped, mut total) = (0, 0);
        for fusion in [&fusion, &top_fusion] {
            assert!(fusion.buckets().len() > 10, "{}", fusion.buckets().len());
            for _ in 0..200 {
                let centre = Vec3::new(
                    rng.random_range(-0.1..0.1),
                    rng.random_range(-0.1..0.1),
                    rng.random_range(0.0..0.08),
                );
                let turn = mvgrasp_geometry::Rot3::from_scaled_axis(Vec3::new(
                    std::f32::consts::PI + rng.random_range(-1.2..1.2),
                    rng.random_range(-1.2..1.2),
                    rng.random_range(-3.0..3.0),
                ));
                let grasp = Grasp {
                    world_from_gripper: Pose3::from_parts(centre, turn),
                    width_m: 0.04,
                };
                let distance = rng.random_range(0.3..0.8);
                let (culled, drawn) =
                    draw_crop(fusion, &grasp, &crop, focal, distance, 0.003, true);
                let (all, every) = draw_crop(fusion, &grasp, &crop, focal, distance, 0.003, false);
                assert_eq!(every, fusion.buckets().len());
                skipped += every - drawn;
                total += every;
                assert_eq!(
                    culled.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
                    all.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
                    "{grasp:?} at {distance} m"
                );
            }
        }
        // The culling is at work: a frustum a few centimetres across skips most buckets.
        assert!(2 * skipped > total, "{skipped} of {total} buckets skipped");
    }

    #[test]
    fn the_ranker_orders_the_re_scored_candidates_by_its_probability() {
        let view = box_view(false);
        let views = std::slice::from_ref(&view);
        let fusion = Fusion::build(views, &FusionParams::default()).unwrap();
        let mut scorer = VirtualScorer::shipped(0.08).unwrap();
        scorer.params.candidates_per_view = 4;
        scorer.params.perturbations = 1;
        let planned = scorer.policy.plan(views, 3).unwrap();
        assert!(planned.candidates.len() > 4);
        // With the ranker: the first 4 re-scored, their re-score kept beside the probability
        // they are ranked by.
        let mut ranked = planned.clone();
        scorer.rescore(&mut ranked, &fusion, 1).unwrap();
        let ranker = scorer.ranker.clone().unwrap();
        let head = &ranked.candidates[..4];
        for c in head {
            let rescore = c.virtual_quality.unwrap();
            assert!((0.0..=1.0).contains(&rescore));
            assert_eq!(c.quality, ranker.probability(c, fusion.table_z_m()));
            assert!(c.view_quality.is_some());
        }
        assert!(head.windows(2).all(|w| w[0].quality >= w[1].quality));
        // Without it: ranked by the re-score itself, which is the ranker's input above.
        scorer.ranker = None;
        let mut plain = planned.clone();
        scorer.rescore(&mut plain, &fusion, 1).unwrap();
        let mut rescores: Vec<f32> = head.iter().map(|c| c.virtual_quality.unwrap()).collect();
        rescores.sort_by(|a, b| b.total_cmp(a));
        let plain_head: Vec<f32> = plain.candidates[..4].iter().map(|c| c.quality).collect();
        assert_eq!(plain_head, rescores);
        assert!(
            plain.candidates[..4]
                .iter()
                .all(|c| c.virtual_quality.is_none())
        );
    }

    #[test]
    fn a_virtual_top_down_view_draws_the_crop_the_camera_saw() {
        // The top-down camera 0.7 m above the table: its own crop of a grasp across the box
        // and the virtual camera's crop of the same grasp agree.
        let view = box_view(false);
        let fusion = Fusion::build(std::slice::from_ref(&view), &FusionParams::default()).unwrap();
        let k = view.depth.intrinsics();
        let image = ImageGrasp {
            center_px: [k.cx, k.cy],
            angle_rad: 0.3,
            depth_m: 0.67,
            width_m: 0.04,
        };
        let grasp = image.to_world(&view.camera);
        let crop = CropParams::default();
        let seen = crop_depth(&view.depth, image.center_px, image.angle_rad, &crop);
        let distance = distance_for(&grasp, 0.0, &VirtualViewParams::default());
        assert!((distance - 0.67).abs() < 1e-4, "{distance}");
        let drawn = virtual_crop(&fusion, &grasp, &crop, k.fx, distance, 0.003);
        assert_eq!(drawn.len(), seen.len());
        // Away from the box's edges (where the area filter blends the two depths), to the
        // float; at them, within the step.
        let mut off = 0;
        for (a, b) in drawn.iter().zip(&seen) {
            assert!((a - b).abs() <= 0.05 + 1e-4, "{a} {b}");
            if (a - b).abs() > 1e-3 {
                off += 1;
            }
        }
        assert!(off < 32 * 3, "{off} pixels differ");
        // The test tells orientations apart: the grasp turned the other way differs far more.
        let mirrored = ImageGrasp {
            angle_rad: -0.3,
            ..image
        }
        .to_world(&view.camera);
        let wrong = virtual_crop(&fusion, &mirrored, &crop, k.fx, distance, 0.003);
        let wrong_off = wrong
            .iter()
            .zip(&seen)
            .filter(|(a, b)| (*a - *b).abs() > 1e-3)
            .count();
        assert!(wrong_off > 3 * off, "{wrong_off} against {off}");
        // The box's top (0.65 m) at the centre, the table (0.7 m) at the crop's ends.
        assert!((drawn[16 * 32 + 16] - 0.65).abs() < 1e-3);
        assert!((drawn[16 * 32] - 0.7).abs() < 1e-3);
    }

    #[test]
    fn a_tilted_virtual_view_sees_the_table_tilted() {
        // No points at all near the grasp: a 45-degree view of the bare table, its depth
        // rising along the tilt.
        let view = box_view(false);
        let fusion = Fusion::build(std::slice::from_ref(&view), &FusionParams::default()).unwrap();
        let tilted = Grasp {
            world_from_gripper: Pose3::from_parts(
                Vec3::new(0.5, 0.0, 0.02),
                mvgrasp_geometry::Rot3::from_rotation_y(std::f32::consts::PI * 0.75),
            ),
            width_m: 0.04,
        };
        let drawn = virtual_crop(&fusion, &tilted, &CropParams::default(), 552.5, 0.6, 0.003);
        // The centre ray meets the table 2 cm / sin(45 deg) past the grasp.
        let centre = drawn[16 * 32 + 16];
        assert!(
            (centre - (0.6 + 0.02 * 2f32.sqrt())).abs() < 2e-3,
            "{centre}"
        );
        // Along the closing axis (rows) the depth changes; across it, not.
        assert!((drawn[16 * 32 + 20] - centre).abs() > 5e-3);
        assert!((drawn[20 * 32 + 16] - centre).abs() < 1e-3);
    }
}
