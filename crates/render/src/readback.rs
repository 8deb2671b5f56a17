//! Getting frames back from the GPU: where each view's images go in the staging buffer (rows
//! padded to `COPY_BYTES_PER_ROW_ALIGNMENT`), the copies, the mapping, and the unpadding.

use crate::error::{RenderError, Result};
use crate::frame::Frame;
use crate::targets::Targets;

/// Where one view's images lie in the staging buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Slot {
    pub width: u32,
    pub height: u32,
    /// Bytes per row of the RGBA copy, padded.
    pub color_row: u32,
    /// Bytes per row of the depth copy (f32 bits in R32Uint), padded.
    pub depth_row: u32,
    pub color_offset: u64,
    pub depth_offset: u64,
}

/// `bytes` rounded up to the copy row alignment (256).
pub(crate) fn padded_row(bytes: u32) -> u32 {
    bytes.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// Staging bytes one view of this size needs.
pub(crate) fn slot_bytes(width: u32, height: u32) -> u64 {
    (u64::from(padded_row(4 * width)) + u64::from(padded_row(4 * width))) * u64::from(height)
}

/// Lays out views of the given sizes one after the other; returns the slots and total bytes.
pub(crate) fn plan(sizes: impl IntoIterator<Item = (u32, u32)>) -> (Vec<Slot>, u64) {
    let mut offset = 0u64;
    let slots = sizes
        .into_iter()
        .map(|(width, height)| {
            let (color_row, depth_row) = (padded_row(4 * width), padded_row(4 * width));
            let color_offset = offset;
            let depth_offset = color_offset + u64::from(color_row) * u64::from(height);
            offset = depth_offset + u64::from(depth_row) * u64::from(height);
            Slot {
                width,
                height,
                color_row,
                depth_row,
                color_offset,
                depth_offset,
            }
        })
        .collect();
    (slots, offset)
}

/// Records the copies of one view's colour and depth targets into the staging buffer.
pub(crate) fn encode_copies(
    encoder: &mut wgpu::CommandEncoder,
    targets: &Targets,
    staging: &wgpu::Buffer,
    slot: &Slot,
) {
    let extent = wgpu::Extent3d {
        width: slot.width,
        height: slot.height,
        depth_or_array_layers: 1,
    };
    for (texture, offset, row) in [
        (&targets.color, slot.color_offset, slot.color_row),
        (&targets.depth_out, slot.depth_offset, slot.depth_row),
    ] {
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset,
                    bytes_per_row: Some(row),
                    rows_per_image: Some(slot.height),
                },
            },
            extent,
        );
    }
}

/// Maps the first `total` bytes of `staging` (after the copies were submitted), waits, and
/// unpads every slot into a frame.
pub(crate) fn read_frames(
    device: &wgpu::Device,
    staging: &wgpu::Buffer,
    total: u64,
    slots: &[Slot],
) -> Result<Vec<Frame>> {
    let map_error = |message: String| RenderError::BufferMap {
        op: "render",
        message,
    };
    let slice = staging.slice(0..total);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        // The receiver outlives the wait below; a send error cannot happen while it is alive.
        let _ = sender.send(result);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| map_error(e.to_string()))?;
    match receiver.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(map_error(e.to_string())),
        Err(_) => return Err(map_error("the map callback never ran".into())),
    }
    let frames = {
        let data = slice
            .get_mapped_range()
            .map_err(|e| map_error(e.to_string()))?;
        unpad_all(slots, &data)
    };
    staging.unmap();
    frames
}

/// Unpads every slot, spread over the CPU's threads (the GPU is idle meanwhile; on a CPU
/// rasteriser this copy is a fifth of the time of a call). Each frame is independent, so the
/// result does not depend on the thread count.
fn unpad_all(slots: &[Slot], data: &[u8]) -> Result<Vec<Frame>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let per_thread = slots.len().div_ceil(threads.clamp(1, slots.len().max(1)));
    if slots.len() < 2 || per_thread == slots.len() {
        return slots.iter().map(|slot| unpad(slot, data)).collect();
    }
    let parts: Vec<Result<Vec<Frame>>> = std::thread::scope(|scope| {
        let handles: Vec<_> = slots
            .chunks(per_thread)
            .map(|chunk| scope.spawn(move || chunk.iter().map(|s| unpad(s, data)).collect()))
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join().unwrap_or_else(|_| {
                    Err(RenderError::Backend {
                        op: "read back",
                        message: "a read-back thread failed".into(),
                    })
                })
            })
            .collect()
    });
    let mut frames = Vec::with_capacity(slots.len());
    for part in parts {
        frames.extend(part?);
    }
    Ok(frames)
}

/// Cuts one view's padded rows out of the mapped bytes into a frame.
pub(crate) fn unpad(slot: &Slot, data: &[u8]) -> Result<Frame> {
    let (w, h) = (slot.width as usize, slot.height as usize);
    // The last depth row ends last; colour rows end before the depth block starts.
    let end = slot.depth_offset as usize + slot.depth_row as usize * h.saturating_sub(1) + 4 * w;
    let colour_fits = slot.color_offset as usize + slot.color_row as usize * h <= end;
    if w == 0 || h == 0 || data.len() < end || !colour_fits {
        return Err(RenderError::ImageSize {
            op: "read back",
            got: data.len(),
            expected: end,
            width: slot.width,
            height: slot.height,
        });
    }
    let mut rgb = vec![0u8; 3 * w * h];
    let mut mask = vec![0u8; w * h];
    let mut depth_m = vec![0f32; w * h];
    let rows = rgb
        .chunks_exact_mut(3 * w)
        .zip(mask.chunks_exact_mut(w))
        .zip(depth_m.chunks_exact_mut(w));
    for (v, ((rgb_row, mask_row), depth_row)) in rows.enumerate() {
        let start = slot.color_offset as usize + v * slot.color_row as usize;
        let src = &data[start..start + 4 * w];
        for ((dst, m), px) in rgb_row
            .chunks_exact_mut(3)
            .zip(mask_row.iter_mut())
            .zip(src.chunks_exact(4))
        {
            dst.copy_from_slice(&px[..3]);
            *m = px[3];
        }
        let start = slot.depth_offset as usize + v * slot.depth_row as usize;
        let src = &data[start..start + 4 * w];
        for (z, b) in depth_row.iter_mut().zip(src.chunks_exact(4)) {
            *z = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
        }
    }
    Ok(Frame {
        width: slot.width,
        height: slot.height,
        rgb,
        depth_m,
        mask,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_padded_to_256_bytes() {
        assert_eq!(padded_row(4 * 516), 2304);
        assert_eq!(padded_row(256), 256);
        assert_eq!(padded_row(4), 256);
        assert_eq!(slot_bytes(516, 386), 2 * 2304 * 386);
    }

    #[test]
    fn slots_follow_each_other() {
        let (slots, total) = plan([(3, 2), (70, 1)]);
        assert_eq!(slots[0].color_offset, 0);
        assert_eq!(slots[0].depth_offset, 512);
        assert_eq!(slots[1].color_offset, 1024);
        assert_eq!(slots[1].depth_offset, 1024 + 512);
        assert_eq!(total, 1024 + 1024);
    }

    #[test]
    fn unpadding_drops_the_padding_and_splits_alpha_into_the_mask() {
        let (slots, total) = plan([(2, 2)]);
        let mut data = vec![0xEEu8; total as usize];
        let s = slots[0];
        for v in 0..2usize {
            for u in 0..2usize {
                let c = s.color_offset as usize + v * 256 + 4 * u;
                data[c..c + 4].copy_from_slice(&[u as u8, v as u8, 7, 10 * v as u8 + u as u8]);
                let d = s.depth_offset as usize + v * 256 + 4 * u;
                data[d..d + 4].copy_from_slice(&(0.5 + v as f32 + 0.25 * u as f32).to_ne_bytes());
            }
        }
        let f = unpad(&s, &data).unwrap();
        assert_eq!(f.rgb, vec![0, 0, 7, 1, 0, 7, 0, 1, 7, 1, 1, 7]);
        assert_eq!(f.mask, vec![0, 1, 10, 11]);
        assert_eq!(f.depth_m, vec![0.5, 0.75, 1.5, 1.75]);
        assert!(unpad(&s, &data[..600]).is_err());
    }
}
