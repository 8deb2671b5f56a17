//! Cast shadows of [`crate::Lighting::World`]'s lights: one shadow map per light (an
//! orthographic depth image of the scene seen from the light, a layer of one texture array),
//! drawn once per render call before the views and compared against in the views' fragment
//! shader (2 x 2 percentage-closer filtering by the comparison sampler).

use std::num::NonZeroU64;

use crate::camera::column_major;
use crate::look::{Lighting, MAX_LIGHTS};
use crate::mesh::VERTEX_BYTES;
use crate::renderer::Scene;

/// Side of a light's shadow map, pixels (a 1.2 m scene: about 1.2 mm a texel).
pub(crate) const SHADOW_MAP_PX: u32 = 1024;
/// The shadow maps' format.
const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Bytes of the fragment shader's block: one 4x4 f32 matrix per light.
const LIGHTS_UNIFORM_BYTES: u64 = 64 * MAX_LIGHTS as u64;
/// Bytes between two lights' matrices in the shadow pass's buffer (dynamic offsets).
const PASS_STRIDE: u64 = 256;

/// The shadow pass's pipeline and layouts, and the views' layout of the shadow bindings.
pub(crate) struct ShadowPipeline {
    pipeline: wgpu::RenderPipeline,
    pass_layout: wgpu::BindGroupLayout,
    /// Group 1 of the views' pipelines: the light matrices, the maps, the sampler.
    pub lookup_layout: wgpu::BindGroupLayout,
}

/// Shadow maps of one size with their buffers and bind groups.
pub(crate) struct ShadowMaps {
    layers: Vec<wgpu::TextureView>,
    pass_uniforms: wgpu::Buffer,
    pass_group: wgpu::BindGroup,
    lookup_uniforms: wgpu::Buffer,
    /// Group 1 of the views' pipelines.
    pub lookup_group: wgpu::BindGroup,
}

impl ShadowPipeline {
    pub(crate) fn new(device: &wgpu::Device, shader: &wgpu::ShaderModule) -> Self {
        let uniform = |visibility, dynamic, size| wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: NonZeroU64::new(size),
            },
            count: None,
        };
        let pass_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mvgrasp-render shadow pass"),
            entries: &[uniform(wgpu::ShaderStages::VERTEX, true, 64)],
        });
        let lookup_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mvgrasp-render shadow lookup"),
            entries: &[
                uniform(wgpu::ShaderStages::FRAGMENT, false, LIGHTS_UNIFORM_BYTES),
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Depth,
                        view_dimension: wgpu::TextureViewDimension::D2Array,
                        multisampled: false,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mvgrasp-render shadow layout"),
            bind_group_layouts: &[Some(&pass_layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("mvgrasp-render shadow pipeline"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: shader,
                entry_point: Some("vs_shadow"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: VERTEX_BYTES as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                })],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: SHADOW_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: wgpu::DepthBiasState {
                    constant: 2,
                    slope_scale: 2.0,
                    clamp: 0.0,
                },
            }),
            multisample: wgpu::MultisampleState::default(),
            fragment: None,
            multiview_mask: None,
            cache: None,
        });
        Self {
            pipeline,
            pass_layout,
            lookup_layout,
        }
    }
}

impl ShadowMaps {
    /// Maps of `side` pixels (1 for the headlight's placeholder, which is never sampled).
    pub(crate) fn new(device: &wgpu::Device, pipeline: &ShadowPipeline, side: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("mvgrasp-render shadow maps"),
            size: wgpu::Extent3d {
                width: side,
                height: side,
                depth_or_array_layers: MAX_LIGHTS as u32,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SHADOW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let layers = (0..MAX_LIGHTS as u32)
            .map(|layer| {
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("mvgrasp-render shadow map"),
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer,
                    array_layer_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let array = texture.create_view(&wgpu::TextureViewDescriptor {
            label: Some("mvgrasp-render shadow maps"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("mvgrasp-render shadow sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let buffer = |label, size| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let pass_uniforms = buffer(
            "mvgrasp-render shadow pass",
            PASS_STRIDE * MAX_LIGHTS as u64,
        );
        let lookup_uniforms = buffer("mvgrasp-render shadow lookup", LIGHTS_UNIFORM_BYTES);
        let pass_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mvgrasp-render shadow pass"),
            layout: &pipeline.pass_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &pass_uniforms,
                    offset: 0,
                    size: NonZeroU64::new(64),
                }),
            }],
        });
        let lookup_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("mvgrasp-render shadow lookup"),
            layout: &pipeline.lookup_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: lookup_uniforms.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&array),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&sampler),
                },
            ],
        });
        Self {
            layers,
            pass_uniforms,
            pass_group,
            lookup_uniforms,
            lookup_group,
        }
    }

    /// Writes the lights' matrices for a scene within `bounds` and encodes one depth pass per
    /// light of `lighting` (none for the headlight).
    pub(crate) fn encode(
        &self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        pipeline: &ShadowPipeline,
        scene: &Scene,
        lighting: &Lighting,
    ) {
        let Lighting::World { lights, .. } = lighting else {
            return;
        };
        let mut pass_bytes = vec![0u8; (PASS_STRIDE * MAX_LIGHTS as u64) as usize];
        let mut lookup_bytes = vec![0u8; LIGHTS_UNIFORM_BYTES as usize];
        for (i, light) in lights.iter().take(MAX_LIGHTS).enumerate() {
            let m = column_major(&light_clip_from_world(light.towards_world, &scene.bounds));
            for (k, x) in m.iter().enumerate() {
                let bytes = x.to_ne_bytes();
                let at = i * PASS_STRIDE as usize + 4 * k;
                pass_bytes[at..at + 4].copy_from_slice(&bytes);
                lookup_bytes[64 * i + 4 * k..64 * i + 4 * k + 4].copy_from_slice(&bytes);
            }
        }
        queue.write_buffer(&self.pass_uniforms, 0, &pass_bytes);
        queue.write_buffer(&self.lookup_uniforms, 0, &lookup_bytes);
        for (i, layer) in self.layers.iter().enumerate().take(lights.len()) {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("mvgrasp-render shadow map"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: layer,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&pipeline.pipeline);
            pass.set_bind_group(0, &self.pass_group, &[(i as u64 * PASS_STRIDE) as u32]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.draw(0..scene.vertex_count, 0..1);
        }
    }
}

/// The scene's bounding sphere, world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bounds {
    pub center: [f32; 3],
    pub radius: f32,
}

/// Row-major orthographic projection of the sphere `bounds` seen from far along `towards`
/// (towards the light): x, y in [-1, 1] across the sphere, z (depth) 0 to 1 through it.
pub(crate) fn light_clip_from_world(towards: [f32; 3], bounds: &Bounds) -> [[f32; 4]; 4] {
    let norm = |v: [f32; 3]| {
        let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        v.map(|x| x / l)
    };
    let cross = |a: [f32; 3], b: [f32; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f32; 3], b: [f32; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    // The light looks along `forward`, from beyond the sphere.
    let forward = norm(towards.map(|x| -x));
    let helper = if forward[2].abs() < 0.9 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let right = norm(cross(helper, forward));
    let up = cross(forward, right);
    let r = bounds.radius.max(1e-6);
    let c = bounds.center;
    // depth 0 at the sphere's near side (centre - r along forward), 1 at its far side.
    let near = dot(forward, c) - r;
    [
        [right[0] / r, right[1] / r, right[2] / r, -dot(right, c) / r],
        [up[0] / r, up[1] / r, up[2] / r, -dot(up, c) / r],
        [
            forward[0] / (2.0 * r),
            forward[1] / (2.0 * r),
            forward[2] / (2.0 * r),
            -near / (2.0 * r),
        ],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::transform_point;

    #[test]
    fn the_light_projection_spans_the_sphere_near_to_far() {
        let bounds = Bounds {
            center: [0.1, 0.2, 0.3],
            radius: 0.5,
        };
        let m = light_clip_from_world([0.0, 0.0, 1.0], &bounds);
        // Seen from above: the sphere's top is depth 0, its bottom 1, its centre the middle.
        let top = transform_point(&m, [0.1, 0.2, 0.8]);
        let bottom = transform_point(&m, [0.1, 0.2, -0.2]);
        let centre = transform_point(&m, [0.1, 0.2, 0.3]);
        assert!(
            (top[2]).abs() < 1e-6 && (bottom[2] - 1.0).abs() < 1e-6,
            "{top:?} {bottom:?}"
        );
        assert!(centre[0].abs() < 1e-6 && centre[1].abs() < 1e-6 && (centre[2] - 0.5).abs() < 1e-6);
        // The sphere's side lands on the edge of the map.
        let side = transform_point(&m, [0.6, 0.2, 0.3]);
        assert!((side[0].hypot(side[1]) - 1.0).abs() < 1e-5, "{side:?}");
        // A slanted light: the point nearer the light has the smaller depth.
        let m = light_clip_from_world([0.3, -0.2, 0.7], &bounds);
        let nearer = transform_point(&m, [0.13, 0.18, 0.37]);
        assert!(nearer[2] < 0.5);
    }
}
