//! Grasp planning with a GQ-CNN: candidates from each view's depth image, scored by the
//! network, lifted to the world, best first (the seed paper's multi-view policy; with one
//! top-down view, Dex-Net 2.0's).

use mvgrasp_grasp::{Gripper, ImageGrasp};
use mvgrasp_infer::{Gqcnn, GqcnnWorkspace, Tensor};
use rayon::prelude::*;

use crate::cem::{self, CemParams, Mixture};
use crate::contract::InputContract;
use crate::crop::crop_depth;
use crate::depth_image::{DepthImage, View};
use crate::error::{PlannerError, Result};
use crate::fusion::Fusion;
use crate::plan::Plan;
use crate::sampler::{ImageSamplerParams, sample_image_grasps};
use crate::scored::{Rejections, ScoredGrasp};
use crate::seed::splitmix;

/// Salts the cross-entropy method's seed apart from the sampler's.
const CEM_SALT: u64 = 0xce3_5eed;

/// A GQ-CNN and how candidates are made for it.
#[derive(Debug)]
pub struct GqcnnPolicy {
    net: Gqcnn,
    /// The depth-image sampler's parameters.
    pub sampler: ImageSamplerParams,
    /// What the network expects: its crops are cut to it for each view's camera.
    pub contract: InputContract,
    /// The gripper's widest opening, metres.
    pub max_width_m: f32,
    /// Crops scored per network call.
    pub batch: usize,
    /// Refine each view's candidates by Dex-Net 2.0's cross-entropy method; `None`: score the
    /// sampler's candidates only.
    pub cem: Option<CemParams>,
    /// The depths of the network's training views, metres (nearest, farthest): a grasp axis
    /// whose surface lies outside them is shown to the network as from the nearest depth
    /// inside (its window scaled by the depth ratio so that it spans the metres it would
    /// there, its depths and the grasp depth shifted by the difference). `None`: crops as
    /// the camera sees them.
    pub depth_range_m: Option<[f32; 2]>,
}

impl GqcnnPolicy {
    /// A policy with the default sampler and crops, for a gripper opening `max_width_m`.
    ///
    /// # Errors
    /// [`PlannerError::Network`] for a network whose crops are not its contract's size, or
    /// whose pose stream takes something other than the grasp depth (1 input) or the depth and
    /// theta (2).
    pub fn new(net: Gqcnn, max_width_m: f32) -> Result<Self> {
        let contract = InputContract::of(&net);
        let arch = net.architecture();
        if arch.image_size_px != contract.crop.size_px as usize
            || !(1..=2).contains(&arch.pose_inputs)
        {
            return Err(PlannerError::Network {
                image_px: arch.image_size_px,
                pose_inputs: arch.pose_inputs,
                crop_px: contract.crop.size_px,
            });
        }
        Ok(Self {
            net,
            sampler: ImageSamplerParams::default(),
            contract,
            max_width_m,
            batch: 256,
            cem: None,
            depth_range_m: None,
        })
    }

    /// The network.
    pub fn net(&self) -> &Gqcnn {
        &self.net
    }

    /// Plans in every view (in parallel) and ranks all candidates together; deterministic
    /// from `seed` whatever the thread count.
    ///
    /// # Errors
    /// [`PlannerError::Camera`] for a view whose camera the network cannot be fed (see
    /// [`InputContract::crop_for`]), or a network error.
    pub fn plan(&self, views: &[View], seed: u64) -> Result<Plan> {
        let per_view = views
            .par_iter()
            .enumerate()
            .map(|(i, view)| self.score_view(i, view, splitmix(seed ^ i as u64)))
            .collect::<Result<Vec<_>>>()?;
        let candidates_per_view = per_view.iter().map(Vec::len).collect();
        let mut candidates: Vec<ScoredGrasp> = per_view.into_iter().flatten().collect();
        // A stable sort: equal scores keep view order, then sampling order.
        candidates.sort_by(|a, b| b.quality.total_cmp(&a.quality));
        Ok(Plan {
            candidates,
            candidates_per_view,
            rejections: Rejections::default(),
        })
    }

    /// The whole plan over `views`: [`GqcnnPolicy::plan`], then the hand check (unless
    /// `hand_check` is false) against the views and, where given, the views fused, until `keep`
    /// survive.
    ///
    /// # Errors
    /// See [`GqcnnPolicy::plan`].
    pub fn plan_checked(
        &self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        hand_check: bool,
        keep: usize,
        seed: u64,
    ) -> Result<Plan> {
        let mut plan = self.plan(views, seed)?;
        if hand_check {
            plan.reject_colliding(views, fusion, gripper, keep);
        }
        Ok(plan)
    }

    /// The scored candidates of one view, in sampling order (then the cross-entropy method's,
    /// round by round).
    fn score_view(&self, index: usize, view: &View, seed: u64) -> Result<Vec<ScoredGrasp>> {
        let mut sampler = self.sampler.clone();
        if let Some(cem) = &self.cem {
            sampler.num_grasps = cem
                .initial_samples
                .div_ceil(sampler.depths_per_grasp.max(1));
        }
        let grasps = sample_image_grasps(
            &view.depth,
            view.mask.as_ref(),
            self.max_width_m,
            &sampler,
            seed,
        );
        let filled = view.depth.with_holes_filled();
        let quality = self.score_on(view, &filled, &grasps)?;
        let mut scored: Vec<(ImageGrasp, f32)> = grasps.into_iter().zip(quality).collect();
        if let Some(cem) = &self.cem {
            self.cross_entropy(view, &filled, &mut scored, cem, splitmix(seed ^ CEM_SALT))?;
        }
        let theta = view.theta_rad();
        Ok(scored
            .into_iter()
            .map(|(g, q)| ScoredGrasp {
                view: index,
                image: g,
                grasp: g.to_world(&view.camera),
                theta_rad: theta,
                quality: q,
                view_quality: None,
                virtual_quality: None,
                by_scorer: false,
                from_cloud: false,
            })
            .collect())
    }

    /// Dex-Net 2.0's cross-entropy method on `scored` (the sampler's candidates): each round
    /// fits a mixture to the best of the previous round's and scores new candidates drawn from
    /// it, appended to `scored` (the planner then takes the best of all of them).
    fn cross_entropy(
        &self,
        view: &View,
        filled: &DepthImage,
        scored: &mut Vec<(ImageGrasp, f32)>,
        cem: &CemParams,
        seed: u64,
    ) -> Result<()> {
        let k = view.depth.intrinsics();
        let focal = k.fx;
        let mut rng = cem::rng(seed);
        let mut round: Vec<(ImageGrasp, f32)> = scored.clone();
        for _ in 0..cem.iterations {
            round.sort_by(|a, b| b.1.total_cmp(&a.1));
            let elite =
                ((round.len() as f32 * cem.elite_fraction).ceil() as usize).min(round.len());
            let points: Vec<_> = round[..elite]
                .iter()
                .map(|(g, _)| cem::features(g, focal))
                .collect();
            let components = ((elite as f32 * cem.components_fraction).round() as usize).max(1);
            let Some(mixture) = Mixture::fit(
                &points,
                components,
                cem.variance_floor,
                cem.em_steps,
                &mut rng,
            ) else {
                break;
            };
            let mut drawn = Vec::with_capacity(cem.samples_per_iteration);
            for _ in 0..20 * cem.samples_per_iteration {
                if drawn.len() >= cem.samples_per_iteration {
                    break;
                }
                let g = cem::grasp_of(&mixture.sample(&mut rng), focal);
                let [u, v] = g.center_px;
                let inside =
                    (0.0..k.width as f32).contains(&u) && (0.0..k.height as f32).contains(&v);
                if inside
                    && g.depth_m > 0.0
                    && (self.sampler.min_width_m..=self.max_width_m).contains(&g.width_m)
                    && view.depth.at(u.round() as i64, v.round() as i64) > 0.0
                {
                    drawn.push(g);
                }
            }
            let quality = self.score_on(view, filled, &drawn)?;
            round = drawn.into_iter().zip(quality).collect();
            scored.extend(round.iter().copied());
        }
        Ok(())
    }

    /// The network's probability that each grasp, in `view`'s image, is robust: its crop cut to
    /// the contract for the view's camera from the image with its holes filled
    /// ([`DepthImage::with_holes_filled`]), with the grasp's depth (and the view's theta for a
    /// multi-view network) as the pose input.
    ///
    /// # Errors
    /// [`PlannerError::Camera`] for a view whose camera the network cannot be fed, or a network
    /// error.
    pub fn score(&self, view: &View, grasps: &[ImageGrasp]) -> Result<Vec<f32>> {
        self.score_on(view, &view.depth.with_holes_filled(), grasps)
    }

    /// [`GqcnnPolicy::score`] with the crops cut from `filled`, `view`'s depth with its holes
    /// filled.
    fn score_on(
        &self,
        view: &View,
        filled: &DepthImage,
        grasps: &[ImageGrasp],
    ) -> Result<Vec<f32>> {
        let crop = self.contract.crop_for(&view.camera.intrinsics)?;
        let theta = view.theta_rad();
        let pose_inputs = self.net.architecture().pose_inputs;
        let side = crop.size_px as usize;
        let mut workspace = GqcnnWorkspace::default();
        let mut quality = Vec::with_capacity(grasps.len());
        for chunk in grasps.chunks(self.batch.max(1)) {
            // A crop shows the image around the grasp axis, whatever the grasp's depth: one crop
            // (and one pass of the image stream) for each run of grasps on the same axis.
            let mut axes: Vec<&ImageGrasp> = Vec::with_capacity(chunk.len());
            let mut image_of = Vec::with_capacity(chunk.len());
            for g in chunk {
                if !axes.last().is_some_and(|a| same_axis(a, g)) {
                    axes.push(g);
                }
                image_of.push(axes.len() - 1);
            }
            let mut crops = Vec::with_capacity(axes.len() * side * side);
            let mut poses = Vec::with_capacity(chunk.len() * pose_inputs);
            // Each axis's shift into the training depths (0 without a range, or inside it).
            let shifts: Vec<f32> = axes.iter().map(|g| self.depth_shift(filled, g)).collect();
            // The crops in parallel (in order: the same bytes whatever the thread count).
            crops.par_extend(axes.par_iter().zip(&shifts).flat_map_iter(|(g, &shift)| {
                if shift == 0.0 {
                    return crop_depth(filled, g.center_px, g.angle_rad, &crop);
                }
                let surface = filled.at(g.center_px[0] as i64, g.center_px[1] as i64);
                // The window that spans at the surface's depth what the training window
                // spans at the shifted one.
                let scaled = crate::crop::CropParams {
                    window_px: ((crop.window_px as f32 * (surface + shift) / surface).round()
                        as u32)
                        .max(crop.size_px),
                    ..crop
                };
                let mut cut = crop_depth(filled, g.center_px, g.angle_rad, &scaled);
                for d in cut.iter_mut().filter(|d| **d > 0.0) {
                    *d += shift;
                }
                cut
            }));
            for (g, &axis) in chunk.iter().zip(&image_of) {
                poses.push(g.depth_m + shifts[axis]);
                if pose_inputs == 2 {
                    poses.push(theta);
                }
            }
            let depth = Tensor::new(&[axes.len(), 1, side, side], crops)?;
            let pose = Tensor::new(&[chunk.len(), pose_inputs], poses)?;
            quality.extend(
                self.net
                    .predict_shared(&depth, &image_of, &pose, &mut workspace)?,
            );
        }
        Ok(quality)
    }
}

impl GqcnnPolicy {
    /// How far `g`'s axis must be moved along the optical axis for its surface to lie in
    /// [`GqcnnPolicy::depth_range_m`], metres (0 without a range, inside it, or with no depth
    /// at its centre).
    fn depth_shift(&self, filled: &DepthImage, g: &ImageGrasp) -> f32 {
        let Some([near, far]) = self.depth_range_m else {
            return 0.0;
        };
        let surface = filled.at(g.center_px[0] as i64, g.center_px[1] as i64);
        if surface > 0.0 {
            surface.clamp(near, far) - surface
        } else {
            0.0
        }
    }
}

/// Whether two grasps share a crop: the same centre and in-image angle, to the bit.
fn same_axis(a: &ImageGrasp, b: &ImageGrasp) -> bool {
    a.center_px.map(f32::to_bits) == b.center_px.map(f32::to_bits)
        && a.angle_rad.to_bits() == b.angle_rad.to_bits()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::GQCNN_TOPDOWN;
    use crate::test_scenes::box_view;

    #[test]
    fn an_axis_tried_at_several_depths_is_cropped_once_and_scored_as_if_alone() {
        let policy = GqcnnPolicy::new(GQCNN_TOPDOWN.load().unwrap(), 0.08).unwrap();
        let view = box_view(false);
        let grasps = sample_image_grasps(&view.depth, None, 0.08, &policy.sampler, 3);
        assert!(
            grasps.len() >= 30 && grasps.len().is_multiple_of(3),
            "{}",
            grasps.len()
        );
        assert!(grasps.chunks(3).all(|t| same_axis(&t[0], &t[2])));
        let crop = policy.contract.crop_for(&view.camera.intrinsics).unwrap();
        let side = crop.size_px as usize;
        let crops: Vec<f32> = grasps
            .iter()
            .flat_map(|g| crop_depth(&view.depth, g.center_px, g.angle_rad, &crop))
            .collect();
        let depth = Tensor::new(&[grasps.len(), 1, side, side], crops).unwrap();
        let poses = grasps.iter().map(|g| g.depth_m).collect();
        let pose = Tensor::new(&[grasps.len(), 1], poses).unwrap();
        let alone = policy
            .net
            .predict(&depth, &pose, &mut GqcnnWorkspace::default())
            .unwrap();
        let shared = policy.score(&view, &grasps).unwrap();
        assert_eq!(
            shared.iter().map(|q| q.to_bits()).collect::<Vec<_>>(),
            alone.iter().map(|q| q.to_bits()).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_depth_range_moves_only_the_axes_outside_it() {
        let mut policy = GqcnnPolicy::new(GQCNN_TOPDOWN.load().unwrap(), 0.08).unwrap();
        let view = box_view(false);
        let grasps = sample_image_grasps(&view.depth, None, 0.08, &policy.sampler, 3);
        let filled = view.depth.with_holes_filled();
        let plain = policy.score_on(&view, &filled, &grasps).unwrap();
        // The box's top is 0.65 m from the camera and the table 0.7 m: a range holding both
        // changes nothing, to the bit.
        policy.depth_range_m = Some([0.6, 0.75]);
        assert!(grasps.iter().all(|g| policy.depth_shift(&filled, g) == 0.0));
        assert_eq!(policy.score_on(&view, &filled, &grasps).unwrap(), plain);
        // One beyond them moves each axis to its near end, and the scores change.
        policy.depth_range_m = Some([0.4, 0.5]);
        for g in &grasps {
            let surface = filled.at(g.center_px[0] as i64, g.center_px[1] as i64);
            assert!((policy.depth_shift(&filled, g) - (0.5 - surface)).abs() < 1e-6);
        }
        assert_ne!(policy.score_on(&view, &filled, &grasps).unwrap(), plain);
    }

    #[test]
    fn the_cross_entropy_method_adds_its_rounds_and_is_deterministic() {
        let mut policy = GqcnnPolicy::new(GQCNN_TOPDOWN.load().unwrap(), 0.08).unwrap();
        let views = [box_view(false)];
        let cem = CemParams::default();
        policy.cem = Some(cem.clone());
        let plan = policy.plan(&views, 4).unwrap();
        // The sampler's 250 (rounded up to whole depth triples), then up to 3 rounds of 50.
        let sampled = cem.initial_samples.div_ceil(3) * 3;
        let n = plan.candidates.len();
        assert!(n > sampled && n <= sampled + 3 * 50, "{n} candidates");
        assert_eq!(plan.candidates, policy.plan(&views, 4).unwrap().candidates);
        // Every drawn grasp fits the gripper and lies in the image; the best closes across the
        // box's 4 cm side, centred on it.
        let k = views[0].depth.intrinsics();
        for c in &plan.candidates {
            assert!(c.image.width_m <= 0.08 && c.image.width_m >= 0.005, "{c:?}");
            assert!(c.image.center_px[0] >= 0.0 && c.image.center_px[0] < k.width as f32);
        }
        let best = plan.best().unwrap();
        assert!((0.03..0.055).contains(&best.image.width_m), "{best:?}");
        assert!((best.image.center_px[0] - k.cx).abs() < 10.0, "{best:?}");
    }
}
