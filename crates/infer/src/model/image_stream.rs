//! The GQ-CNN's image stream (normalisation, then per layer convolution, ReLU, LRN and max
//! pooling, then flattening) run image by image: each task takes a run of the batch through
//! every layer in buffers of its own, a few hundred kilobytes that stay in cache, where whole
//! batch-sized intermediates would not. The ops and their order are the layer-by-layer pass's,
//! and each image is computed alone, so every value is the same whatever the batch split.

use rayon::prelude::*;

use crate::error::{InferError, Result};
use crate::model::description::ConvSpec;
use crate::model::gqcnn::Dense;
use crate::ops::{
    Conv2dParams, LocalResponseNorm, Pool2dParams, conv2d_into, local_response_norm_into,
    max_pool2d_into, relu,
};
use crate::parallel::Parallelism;
use crate::tensor::Tensor;

/// One task's intermediates, kept between calls.
#[derive(Debug, Default)]
pub(super) struct StreamBuffers {
    a: Tensor,
    b: Tensor,
    scratch: Vec<f32>,
}

/// The layers of an image stream, borrowed from the network.
pub(super) struct ImageStream<'n> {
    /// Each convolution's spec, weight `[out, in, k, k]` and bias `[out]`.
    pub convs: &'n [(ConvSpec, Dense)],
    pub lrn: LocalResponseNorm,
    pub image_mean: f32,
    pub image_std: f32,
}

impl ImageStream<'_> {
    /// The flattened features `[N, C * h * w]` of `depth` `[N, 1, S, S]` (checked by the
    /// caller) into `out`. With [`Parallelism::Rayon`] a batch is split into one contiguous run
    /// of images per thread; a lone image runs on the calling thread and lets its
    /// convolutions' matrix products use the threads.
    pub(super) fn features(
        &self,
        depth: &Tensor,
        out: &mut Tensor,
        buffers: &mut Vec<StreamBuffers>,
        par: Parallelism,
    ) -> Result<()> {
        let n = depth.shape().first().copied().unwrap_or(0);
        let pixels = depth.len() / n.max(1);
        let side = depth.shape().last().copied().unwrap_or(0);
        let features = self.feature_len(side);
        out.resize(&[n, features]);
        if n == 0 || features == 0 {
            return Ok(());
        }
        let tasks = par.threads().min(n);
        let images = depth.data().chunks_exact(pixels);
        if tasks <= 1 {
            buffers.resize_with(1, Default::default);
            let inner = if n == 1 { par } else { Parallelism::Sequential };
            let buf = &mut buffers[0];
            for (image, row) in images.zip(out.data_mut().chunks_exact_mut(features)) {
                self.image(image, side, row, buf, inner)?;
            }
            return Ok(());
        }
        let per_task = n.div_ceil(tasks);
        let tasks = n.div_ceil(per_task);
        buffers.resize_with(tasks, Default::default);
        out.data_mut()
            .par_chunks_mut(per_task * features)
            .zip(depth.data().par_chunks(per_task * pixels))
            .zip(buffers.par_iter_mut())
            .try_for_each(|((rows, images), buf)| {
                let images = images.chunks_exact(pixels);
                for (image, row) in images.zip(rows.chunks_exact_mut(features)) {
                    self.image(image, side, row, buf, Parallelism::Sequential)?;
                }
                Ok(())
            })
    }

    /// The flattened length of one image's features, for images `side` pixels square.
    fn feature_len(&self, side: usize) -> usize {
        let (channels, side) = self.convs.iter().fold((1, side), |(_, side), (spec, _)| {
            (spec.filters, side / spec.pool)
        });
        channels * side * side
    }

    /// One image (`pixels`, `side` square) through every layer into `row`.
    fn image(
        &self,
        pixels: &[f32],
        side: usize,
        row: &mut [f32],
        buf: &mut StreamBuffers,
        par: Parallelism,
    ) -> Result<()> {
        let StreamBuffers { a, b, scratch } = buf;
        a.resize(&[1, 1, side, side]);
        for (x, &d) in a.data_mut().iter_mut().zip(pixels) {
            *x = (d - self.image_mean) / self.image_std;
        }
        for (spec, layer) in self.convs {
            let pad = spec.kernel / 2;
            let params = Conv2dParams {
                padding: [pad, pad],
                ..Conv2dParams::default()
            };
            conv2d_into(a, &layer.weight, Some(&layer.bias), params, b, scratch, par)?;
            relu(b);
            std::mem::swap(a, b);
            if spec.lrn {
                local_response_norm_into(a, self.lrn, b)?;
                std::mem::swap(a, b);
            }
            if spec.pool > 1 {
                let p = spec.pool;
                max_pool2d_into(a, Pool2dParams::new([p, p]).with_stride([p, p]), b)?;
                std::mem::swap(a, b);
            }
        }
        if a.len() != row.len() {
            return Err(InferError::ShapeMismatch {
                op: "gqcnn image stream",
                expected: format!("{} features per image", row.len()),
                got: a.shape().to_vec(),
            });
        }
        row.copy_from_slice(a.data());
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use std::path::Path;

    use crate::model::{Gqcnn, GqcnnWorkspace};
    use crate::parallel::Parallelism;
    use crate::testing::{Rng, assert_same_bits};

    #[test]
    fn the_batch_split_does_not_change_a_bit() {
        let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
        let net = Gqcnn::load(&fixtures.join("gqcnn_tiny_pose2.json")).unwrap();
        let s = net.architecture().image_size_px;
        let mut rng = Rng::new(31);
        let mut workspace = GqcnnWorkspace::default();
        // A lone image (the products split instead), and batches that split unevenly.
        for n in [1, 2, 5, 9] {
            let depth = rng.tensor_in(&[n, 1, s, s], 0.6, 0.75);
            let pose = rng.tensor_in(&[n, 2], 0.0, 1.5);
            let one = net.logits(&depth, &pose, &mut workspace).unwrap().clone();
            for threads in [2, 3, 4, 0] {
                let par = Parallelism::Rayon { threads };
                let net = Gqcnn::load(&fixtures.join("gqcnn_tiny_pose2.json"))
                    .unwrap()
                    .with_parallelism(par);
                let got = net.logits(&depth, &pose, &mut workspace).unwrap();
                assert_same_bits(got, &one, &format!("batch {n}, {par:?}"));
            }
        }
    }
}
