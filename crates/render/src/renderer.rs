//! The renderer: a device, the pipeline, cached resources; scenes uploaded once and drawn from
//! many views per call, in one submission per batch.

use std::num::NonZeroU64;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

use crate::adapter::{self, Backend, Gpu};
use crate::camera::{View, clip_from_camera, column_major, validate_view};
use crate::error::{RenderError, Result};
use crate::frame::Frame;
use crate::look::Lighting;
use crate::mesh::{MeshInput, expand};
use crate::pipeline::{Pipeline, VIEW_UNIFORM_BYTES};
use crate::readback::{encode_copies, plan, read_frames, slot_bytes};
use crate::shadow::{Bounds, SHADOW_MAP_PX, ShadowMaps};
use crate::targets::{GrowBuffer, TargetCache};

/// Read-back bytes one batch may hold; more views are rendered in several submissions.
const STAGING_BUDGET_BYTES: u64 = 256 << 20;

/// Views one batch may hold (bounds the per-view uniform buffer).
const MAX_VIEWS_PER_BATCH: usize = 1024;

/// Distinguishes renderers so that a scene is never drawn by a device it does not live on.
static NEXT_RENDERER_ID: AtomicU64 = AtomicU64::new(1);

/// A headless renderer on one graphics device. Create it once and keep it: opening a device
/// costs far more than rendering a frame.
pub struct Renderer {
    id: u64,
    gpu: Gpu,
    pipeline: Pipeline,
    /// 1-pixel shadow maps bound under the headlight, which never samples them.
    no_shadows: ShadowMaps,
    state: Mutex<State>,
}

/// Resources reused from call to call; locked for the length of a render.
struct State {
    targets: TargetCache,
    uniforms: GrowBuffer,
    uniforms_bind_group: Option<wgpu::BindGroup>,
    staging: GrowBuffer,
    /// The world lights' shadow maps, made on the first [`Lighting::World`] render.
    shadows: Option<ShadowMaps>,
}

/// Meshes uploaded to a renderer's device, ready to draw from any number of views.
pub struct Scene {
    renderer_id: u64,
    pub(crate) vertices: wgpu::Buffer,
    /// The front-only meshes' vertices come first in `vertices`.
    front_vertex_count: u32,
    pub(crate) vertex_count: u32,
    mesh_count: usize,
    /// A sphere holding the scene (the shadow maps cover it).
    pub(crate) bounds: Bounds,
}

impl Scene {
    /// Number of meshes uploaded.
    pub fn mesh_count(&self) -> usize {
        self.mesh_count
    }

    /// Number of triangles drawn per view.
    pub fn triangle_count(&self) -> usize {
        self.vertex_count as usize / 3
    }
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("renderer_id", &self.renderer_id)
            .field("mesh_count", &self.mesh_count)
            .field("triangle_count", &self.triangle_count())
            .finish()
    }
}

impl std::fmt::Debug for Renderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Renderer")
            .field("id", &self.id)
            .field("adapter", &self.adapter_info())
            .finish()
    }
}

impl Renderer {
    /// Opens a device on the chosen backend ([`Backend::Auto`]: `MVGRASP_RENDER_BACKEND`, else
    /// the best adapter found) and builds the pipeline.
    ///
    /// # Errors
    /// [`RenderError::NoAdapter`] (with what to install) when no adapter is usable,
    /// [`RenderError::RequestDevice`] when the adapter refuses a device,
    /// [`RenderError::InvalidParameter`] for a bad `MVGRASP_RENDER_BACKEND`.
    pub fn new(backend: Backend) -> Result<Self> {
        let gpu = adapter::open(backend)?;
        let pipeline = Pipeline::new(&gpu.device);
        let no_shadows = ShadowMaps::new(&gpu.device, &pipeline.shadow, 1);
        let renderer = Self {
            id: NEXT_RENDERER_ID.fetch_add(1, Ordering::Relaxed),
            pipeline,
            no_shadows,
            state: Mutex::new(State {
                targets: TargetCache::default(),
                uniforms: GrowBuffer::new(
                    "mvgrasp-render view uniforms",
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                ),
                uniforms_bind_group: None,
                staging: GrowBuffer::new(
                    "mvgrasp-render read-back",
                    wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                ),
                shadows: None,
            }),
            gpu,
        };
        renderer.take_errors("create the pipeline")?;
        Ok(renderer)
    }

    /// The adapter: name, backend and driver, e.g. `llvmpipe (LLVM 19.1.7, 256 bits) (Gl, ...)`.
    pub fn adapter_info(&self) -> String {
        adapter::describe(&self.gpu.info)
    }

    /// The backend in use.
    pub fn backend(&self) -> Backend {
        match self.gpu.info.backend {
            wgpu::Backend::Vulkan => Backend::Vulkan,
            wgpu::Backend::Gl => Backend::Gl,
            wgpu::Backend::Metal => Backend::Metal,
            wgpu::Backend::Dx12 => Backend::Dx12,
            _ => Backend::Auto,
        }
    }

    /// Whether the adapter is a CPU rasteriser (llvmpipe, lavapipe, WARP).
    pub fn is_software(&self) -> bool {
        self.gpu.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Largest image side, pixels, this device renders.
    pub fn max_image_size_px(&self) -> u32 {
        self.gpu.limits.max_texture_dimension_2d
    }

    /// Checks the meshes and uploads them once, flat-shaded (three vertices a triangle, placed
    /// in the world by each mesh's `world_from_mesh`).
    ///
    /// # Errors
    /// [`RenderError::InvalidMesh`] naming the mesh and what is wrong (empty, non-finite
    /// position, index out of range, colour count, transform, instance id 0),
    /// [`RenderError::InvalidParameter`] for no meshes, [`RenderError::TooLarge`] past the
    /// device's buffer size.
    pub fn upload(&self, meshes: &[MeshInput<'_>]) -> Result<Scene> {
        let expanded = expand(meshes)?;
        let bounds = expanded.bounds;
        let (bytes, vertex_count) = (expanded.bytes, expanded.vertices);
        let limit = self.gpu.limits.max_buffer_size;
        let too_large = |what, needed: u64, limit: u64| RenderError::TooLarge {
            op: "upload",
            what,
            needed,
            limit,
        };
        if bytes.len() as u64 > limit {
            return Err(too_large(
                "the vertex buffer (bytes)",
                bytes.len() as u64,
                limit,
            ));
        }
        let vertex_count = u32::try_from(vertex_count)
            .map_err(|_| too_large("vertices", vertex_count as u64, u64::from(u32::MAX)))?;
        let vertices = self.gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("mvgrasp-render vertices"),
            size: bytes.len() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        self.gpu.queue.write_buffer(&vertices, 0, &bytes);
        self.take_errors("upload")?;
        Ok(Scene {
            renderer_id: self.id,
            vertices,
            // Fits: no more than `vertex_count`.
            front_vertex_count: u32::try_from(expanded.front_vertices).unwrap_or(vertex_count),
            vertex_count,
            mesh_count: meshes.len(),
            bounds,
        })
    }

    /// Renders `scene` from every view and reads back RGB, depth and mask, one frame per view
    /// in order. Views share one submission (or a few, past 1024 views or 256 MiB of
    /// read-back); render targets and buffers are kept for the next call.
    ///
    /// # Errors
    /// [`RenderError::InvalidView`] for bad intrinsics or a non-rigid `camera_from_world`,
    /// [`RenderError::ForeignScene`] for a scene of another renderer,
    /// [`RenderError::BufferMap`] / [`RenderError::Backend`] when the device fails.
    pub fn render(&self, scene: &Scene, views: &[View]) -> Result<Vec<Frame>> {
        self.render_lit(scene, views, &Lighting::Headlight)
    }

    /// [`Renderer::render`] under `lighting` ([`Lighting::World`]: lights fixed in the world,
    /// the meshes' materials drawn, the background in its colour).
    ///
    /// # Errors
    /// As [`Renderer::render`], and [`RenderError::InvalidParameter`] for bad lighting.
    pub fn render_lit(
        &self,
        scene: &Scene,
        views: &[View],
        lighting: &Lighting,
    ) -> Result<Vec<Frame>> {
        lighting.validate()?;
        if scene.renderer_id != self.id {
            return Err(RenderError::ForeignScene {
                scene_renderer: scene.renderer_id,
                renderer: self.id,
            });
        }
        let max_side = self.gpu.limits.max_texture_dimension_2d;
        for (i, view) in views.iter().enumerate() {
            validate_view(view, i, max_side)?;
        }
        let budget = STAGING_BUDGET_BYTES.min(self.gpu.limits.max_buffer_size);
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        let mut frames = Vec::with_capacity(views.len());
        let mut start = 0;
        while start < views.len() {
            let mut end = start;
            let mut bytes = 0u64;
            while end < views.len() {
                let k = &views[end].intrinsics;
                let need = slot_bytes(k.width, k.height);
                if end > start && (bytes + need > budget || end - start >= MAX_VIEWS_PER_BATCH) {
                    break;
                }
                if need > self.gpu.limits.max_buffer_size {
                    return Err(RenderError::TooLarge {
                        op: "render",
                        what: "one view's read-back buffer (bytes)",
                        needed: need,
                        limit: self.gpu.limits.max_buffer_size,
                    });
                }
                bytes += need;
                end += 1;
            }
            frames.extend(self.render_batch(&mut state, scene, &views[start..end], lighting)?);
            start = end;
        }
        Ok(frames)
    }

    /// Renders one view; see [`Renderer::render`].
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn render_one(&self, scene: &Scene, view: &View) -> Result<Frame> {
        self.render(scene, std::slice::from_ref(view))?
            .pop()
            .ok_or(RenderError::Backend {
                op: "render",
                message: "no frame came back".into(),
            })
    }

    /// How many image sizes hold cached render targets now (at most 8 are kept).
    pub fn cached_target_sizes(&self) -> usize {
        self.state
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .targets
            .len()
    }

    /// One submission: a render pass and two copies per view, then one map of the staging
    /// buffer.
    fn render_batch(
        &self,
        state: &mut State,
        scene: &Scene,
        views: &[View],
        lighting: &Lighting,
    ) -> Result<Vec<Frame>> {
        let device = &self.gpu.device;
        let limits = &self.gpu.limits;
        let State {
            targets,
            uniforms,
            uniforms_bind_group,
            staging,
            shadows,
        } = state;

        let mut sizes: Vec<(u32, u32)> = views
            .iter()
            .map(|v| (v.intrinsics.width, v.intrinsics.height))
            .collect();
        sizes.sort_unstable();
        sizes.dedup();
        targets.prepare(device, &sizes);

        // Per-view uniforms at dynamic offsets.
        let align = u64::from(limits.min_uniform_buffer_offset_alignment.max(1));
        let stride = VIEW_UNIFORM_BYTES.div_ceil(align) * align;
        let mut data = vec![0u8; (stride * views.len() as u64) as usize];
        for (view, chunk) in views.iter().zip(data.chunks_exact_mut(stride as usize)) {
            let matrices = [
                column_major(&view.camera_from_world),
                column_major(&clip_from_camera(&view.intrinsics)),
            ];
            let lights = lighting.uniform_floats(&view.camera_from_world);
            let floats = matrices.iter().flatten().chain(&lights);
            for (x, out) in floats.zip(chunk.chunks_exact_mut(4)) {
                out.copy_from_slice(&x.to_ne_bytes());
            }
        }
        let (uniform_buffer, created) =
            uniforms.ensure(device, data.len() as u64, limits.max_buffer_size);
        if created || uniforms_bind_group.is_none() {
            *uniforms_bind_group = Some(device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("mvgrasp-render view uniforms"),
                layout: &self.pipeline.view_layout,
                entries: &[wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: uniform_buffer,
                        offset: 0,
                        size: NonZeroU64::new(VIEW_UNIFORM_BYTES),
                    }),
                }],
            }));
        }
        self.gpu.queue.write_buffer(uniform_buffer, 0, &data);
        let Some(bind_group) = uniforms_bind_group.as_ref() else {
            return Err(internal("the uniform bind group is missing"));
        };

        let (slots, total) = plan(sizes_in_order(views));
        let (staging_buffer, _) = staging.ensure(device, total, limits.max_buffer_size);

        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("mvgrasp-render views"),
        });
        let shadow_maps = match lighting {
            Lighting::Headlight => &self.no_shadows,
            Lighting::World { .. } => shadows.get_or_insert_with(|| {
                ShadowMaps::new(device, &self.pipeline.shadow, SHADOW_MAP_PX)
            }),
        };
        shadow_maps.encode(
            &self.gpu.queue,
            &mut encoder,
            &self.pipeline.shadow,
            scene,
            lighting,
        );
        for (i, slot) in slots.iter().enumerate() {
            let Some(t) = targets.get(slot.width, slot.height) else {
                return Err(internal("render targets were not prepared"));
            };
            let offset = u32::try_from(i as u64 * stride)
                .map_err(|_| internal("too many views for one uniform buffer"))?;
            let clear = wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                store: wgpu::StoreOp::Store,
            };
            let clear_color = wgpu::Operations {
                load: wgpu::LoadOp::Clear(lighting.clear_color()),
                store: wgpu::StoreOp::Store,
            };
            {
                let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some("mvgrasp-render view"),
                    color_attachments: &[
                        Some(wgpu::RenderPassColorAttachment {
                            view: &t.color_view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: clear_color,
                        }),
                        Some(wgpu::RenderPassColorAttachment {
                            view: &t.depth_out_view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: clear,
                        }),
                    ],
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &t.zbuffer_view,
                        depth_ops: Some(wgpu::Operations {
                            load: wgpu::LoadOp::Clear(1.0),
                            store: wgpu::StoreOp::Discard,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: None,
                    occlusion_query_set: None,
                    multiview_mask: None,
                });
                pass.set_bind_group(0, bind_group, &[offset]);
                pass.set_bind_group(1, &shadow_maps.lookup_group, &[]);
                pass.set_vertex_buffer(0, scene.vertices.slice(..));
                if scene.front_vertex_count > 0 {
                    pass.set_pipeline(&self.pipeline.front_only);
                    pass.draw(0..scene.front_vertex_count, 0..1);
                }
                if scene.vertex_count > scene.front_vertex_count {
                    pass.set_pipeline(&self.pipeline.two_sided);
                    pass.draw(scene.front_vertex_count..scene.vertex_count, 0..1);
                }
            }
            encode_copies(&mut encoder, t, staging_buffer, slot);
        }
        self.gpu.queue.submit([encoder.finish()]);
        self.take_errors("render")?;
        let frames = read_frames(device, staging_buffer, total, &slots)?;
        self.take_errors("read back")?;
        Ok(frames)
    }

    /// Turns errors the backend raised since the last check into a [`RenderError::Backend`].
    fn take_errors(&self, op: &'static str) -> Result<()> {
        let mut errors = self.gpu.errors.lock().unwrap_or_else(|p| p.into_inner());
        if errors.is_empty() {
            return Ok(());
        }
        let message = errors.join("; ");
        errors.clear();
        Err(RenderError::Backend { op, message })
    }
}

/// Image sizes of the views, in order.
fn sizes_in_order(views: &[View]) -> impl Iterator<Item = (u32, u32)> + '_ {
    views
        .iter()
        .map(|v| (v.intrinsics.width, v.intrinsics.height))
}

/// An error that means a bug in this crate rather than bad input.
fn internal(message: &str) -> RenderError {
    RenderError::Backend {
        op: "render (internal)",
        message: message.into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renderers_and_scenes_can_be_shared_between_threads() {
        fn shareable<T: Send + Sync>() {}
        shareable::<Renderer>();
        shareable::<Scene>();
    }
}
