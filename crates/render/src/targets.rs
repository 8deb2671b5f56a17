//! GPU resources reused from call to call: render targets cached by image size, and buffers
//! (per-view uniforms, read-back staging) that only grow.
//!
//! Depth leaves the GPU through a colour target, not the z-buffer: wgpu's GL backend cannot copy
//! depth textures to buffers, and the z-buffer holds a non-linear value anyway. The target is
//! R32Uint holding the bits of the f32 z, not R32Float: wgpu's GL backend does not offer
//! R32Float as a render target on desktop GL contexts (Mesa's EGL gives one, with no
//! `GL_ARB_color_buffer_float` in its extension string), while R32Uint renders everywhere and
//! the bits come back exactly.

use std::collections::HashMap;

/// RGB plus the instance id in alpha.
pub(crate) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Bits of the camera-frame z in metres (f32), 0 (= 0.0) where nothing was drawn.
pub(crate) const DEPTH_OUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The z-buffer for the depth test only; never read back.
pub(crate) const ZBUFFER_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// At most this many image sizes keep their targets; more sizes flush the cache.
const MAX_CACHED_SIZES: usize = 8;

/// The three attachments of one image size.
pub(crate) struct Targets {
    pub color: wgpu::Texture,
    pub color_view: wgpu::TextureView,
    pub depth_out: wgpu::Texture,
    pub depth_out_view: wgpu::TextureView,
    pub zbuffer_view: wgpu::TextureView,
}

impl Targets {
    fn new(device: &wgpu::Device, width: u32, height: u32) -> Self {
        let make = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        use wgpu::TextureUsages as U;
        let color = make(
            "mvgrasp-render rgb+id",
            COLOR_FORMAT,
            U::RENDER_ATTACHMENT | U::COPY_SRC,
        );
        let depth_out = make(
            "mvgrasp-render depth",
            DEPTH_OUT_FORMAT,
            U::RENDER_ATTACHMENT | U::COPY_SRC,
        );
        let zbuffer = make(
            "mvgrasp-render z-buffer",
            ZBUFFER_FORMAT,
            U::RENDER_ATTACHMENT,
        );
        Self {
            color_view: color.create_view(&Default::default()),
            depth_out_view: depth_out.create_view(&Default::default()),
            zbuffer_view: zbuffer.create_view(&Default::default()),
            color,
            depth_out,
        }
    }
}

/// Targets by `(width, height)`.
#[derive(Default)]
pub(crate) struct TargetCache {
    by_size: HashMap<(u32, u32), Targets>,
}

impl TargetCache {
    /// Makes sure targets exist for every size in `sizes` (creating only the missing ones).
    pub(crate) fn prepare(&mut self, device: &wgpu::Device, sizes: &[(u32, u32)]) {
        let missing = sizes
            .iter()
            .filter(|s| !self.by_size.contains_key(s))
            .count();
        if self.by_size.len() + missing > MAX_CACHED_SIZES {
            self.by_size.retain(|s, _| sizes.contains(s));
        }
        for &(w, h) in sizes {
            self.by_size
                .entry((w, h))
                .or_insert_with(|| Targets::new(device, w, h));
        }
    }

    /// The targets of one size, if prepared.
    pub(crate) fn get(&self, width: u32, height: u32) -> Option<&Targets> {
        self.by_size.get(&(width, height))
    }

    /// How many sizes hold targets now.
    pub(crate) fn len(&self) -> usize {
        self.by_size.len()
    }
}

/// A buffer that is replaced by a larger one when too small, and otherwise kept.
pub(crate) struct GrowBuffer {
    label: &'static str,
    usage: wgpu::BufferUsages,
    buffer: Option<wgpu::Buffer>,
}

impl GrowBuffer {
    pub(crate) fn new(label: &'static str, usage: wgpu::BufferUsages) -> Self {
        Self {
            label,
            usage,
            buffer: None,
        }
    }

    /// A buffer of at least `size` bytes (rounded up to a power of two, but not past
    /// `max_bytes`), and whether it was (re)created by this call.
    pub(crate) fn ensure(
        &mut self,
        device: &wgpu::Device,
        size: u64,
        max_bytes: u64,
    ) -> (&wgpu::Buffer, bool) {
        let fits = self.buffer.as_ref().is_some_and(|b| b.size() >= size);
        if !fits && let Some(old) = self.buffer.take() {
            old.destroy();
        }
        let created = !fits;
        let (label, usage) = (self.label, self.usage);
        let buffer = self.buffer.get_or_insert_with(|| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                // Round up so that a slowly growing batch does not reallocate every call.
                size: size.max(256).next_power_of_two().min(max_bytes).max(size),
                usage,
                mapped_at_creation: false,
            })
        });
        (buffer, created)
    }
}
