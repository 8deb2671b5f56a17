//! The render pipelines (one drawing both sides of triangles, one front faces only): `shader.wgsl`, the vertex layout of `mesh.rs`, a per-view uniform
//! block bound with a dynamic offset, two colour targets (RGB + id, depth z) and a z-buffer.

use std::num::NonZeroU64;

use crate::look::LIGHTING_UNIFORM_BYTES;
use crate::mesh::VERTEX_BYTES;
use crate::shadow::ShadowPipeline;
use crate::targets::{COLOR_FORMAT, DEPTH_OUT_FORMAT, ZBUFFER_FORMAT};

/// Bytes of the per-view uniform block: two 4x4 f32 matrices, then the lighting.
pub(crate) const VIEW_UNIFORM_BYTES: u64 = 128 + LIGHTING_UNIFORM_BYTES;

/// The compiled pipelines and the layout of their per-view bind group.
pub(crate) struct Pipeline {
    /// Draws both sides of every triangle ([`crate::Sides::Both`]).
    pub two_sided: wgpu::RenderPipeline,
    /// Culls back faces, counter-clockwise in the image being the front ([`crate::Sides::Front`]).
    pub front_only: wgpu::RenderPipeline,
    pub view_layout: wgpu::BindGroupLayout,
    /// The shadow maps' pass, and the layout of the views' shadow bindings (group 1).
    pub shadow: ShadowPipeline,
}

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
    0 => Float32x3, // position, world
    1 => Float32x3, // face normal, world
    2 => Unorm8x4,  // colour, alpha unused
    3 => Uint32,    // instance id
    4 => Unorm8x4,  // material: pattern code / 255, specular, shininess, frequency (log2-coded)
    5 => Unorm8x4,  // material: second colour, contrast
];

impl Pipeline {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("mvgrasp-render shader"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let view_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("mvgrasp-render view uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: NonZeroU64::new(VIEW_UNIFORM_BYTES),
                },
                count: None,
            }],
        });
        let shadow = ShadowPipeline::new(device, &shader);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("mvgrasp-render layout"),
            bind_group_layouts: &[Some(&view_layout), Some(&shadow.lookup_layout)],
            immediate_size: 0,
        });
        let replace = |format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let make = |label, cull_mode| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: VERTEX_BYTES as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &VERTEX_ATTRIBUTES,
                    })],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    front_face: wgpu::FrontFace::Ccw,
                    cull_mode,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: ZBUFFER_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                // One sample: depth and mask must not blend across edges.
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some("fs_main"),
                    compilation_options: Default::default(),
                    targets: &[replace(COLOR_FORMAT), replace(DEPTH_OUT_FORMAT)],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        Self {
            two_sided: make("mvgrasp-render two-sided pipeline", None),
            front_only: make("mvgrasp-render front-only pipeline", Some(wgpu::Face::Back)),
            view_layout,
            shadow,
        }
    }
}
