//! TSD's blur (`blur.wgsl`): a Poisson disc scaled per texel by the light map's kernel size and
//! per pass by its stage ([`crate::skin::tsd`]), between the light maps; the first pass also
//! dilates across UV seams.

use std::sync::Arc;

use super::light_map::UNWRITTEN_TEXEL;
use super::resources::Resources;
use super::setup::{self, TsdSetup};
use super::tsd::{self as shared, STRETCH};
use super::{Context, Described, FrameEncoder, Pass, PassState, PreparedScene, Shape, Upload};
use crate::gpu::{Gpu, Target, colour_attachment};
use crate::skin::options::TsdKernel;
use crate::skin::tsd::{self, LIGHT_MAP_NAMES};

/// TSD blur pass `.0` (0-based) of the ping-pong pair.
struct TsdBlur(u32);

/// What a blur pass draws with: its bind group and the light map it writes.
struct Prepared {
    bind_group: wgpu::BindGroup,
    to: &'static str,
}

/// The blur passes `shape` runs, in order.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    (0..shape.tsd_blurs.unwrap_or(0)).map(|i| Arc::new(TsdBlur(i)) as Arc<dyn Pass>).collect()
}

impl Pass for TsdBlur {
    fn name(&self) -> String {
        format!("tsd blur {}", self.0 + 1)
    }

    fn explain(&self, context: &Context) -> Described {
        let kernel = context.graph.tsd.map_or(TsdKernel::Single, |t| t.kernel);
        let (from, to) = tsd::blur_maps(kernel, self.0);
        let what = match (self.0, kernel) {
            (0, _) => "12-tap Poisson blur, dilating the UV borders",
            (_, TsdKernel::Single) => "12-tap Poisson blur",
            (_, TsdKernel::Gaussians) => {
                "12-tap Poisson blur by one Gaussian's increment, the weighted light map B added"
            }
        };
        let mut described = Described::new(what, &[LIGHT_MAP_NAMES[from], STRETCH], &[LIGHT_MAP_NAMES[to]]);
        if self.0 > 0 && kernel == TsdKernel::Gaussians {
            described.reads.push(LIGHT_MAP_NAMES[1].into());
        }
        described
    }

    fn runs(&self, scene: &PreparedScene, target: &Target) -> bool {
        shared::runs(scene, target)
    }

    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        let setup = shared::setup(upload);
        let (_, to) = tsd::blur_maps(setup.kernel, self.0);
        Some(Box::new(Prepared { bind_group: bind_group(gpu, setup, self.0, resources), to: LIGHT_MAP_NAMES[to] }))
    }

    /// TSD blur `i`: over the whole map, into the map its bind group was made for (the first
    /// also dilates into the texels the light map left unwritten).
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let prepared: &Prepared = frame.state();
        let view = frame.scene.resources.texture_view(prepared.to);
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd blur"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL)))],
            depth_stencil_attachment: None,
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&gpu.pipeline("tsd blur".into(), pipeline));
        pass.set_bind_group(0, &prepared.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// The blur's uniforms (`BlurUniforms` in blur.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct BlurUniforms {
    pub(crate) inv_size: [f32; 2],
    pub(crate) a: f32,
    pub(crate) b: f32,
    pub(crate) dilate: u32,
    /// The per-axis variance a unit radius stands for ([`setup::poisson_second_moment`] / 2).
    pub(crate) tap_variance: f32,
    /// [`setup::poisson_mean`].
    pub(crate) tap_mean: [f32; 2],
    /// Scales the blurred source per channel (w unused).
    pub(crate) source_scale: [f32; 4],
    /// Weight of light map B added after the blur per channel (w unused).
    pub(crate) irradiance_weight: [f32; 4],
    /// [`setup::poisson_axis_variance`].
    pub(crate) axis_variance: [f32; 2],
    pub(crate) pad0: f32,
    pub(crate) pad1: f32,
    /// [`tsd::radius_table`].
    pub(crate) radius_table: [[f32; 4]; tsd::RADIUS_TABLE_LEN / 2],
}

/// Blur `i`'s bind group: it reads the map of [`tsd::blur_maps`] (and light map B, which the
/// Gaussians add back), the first with a nearest sampler (it dilates), the others bilinear.
fn bind_group(gpu: &Gpu, setup: &TsdSetup, i: u32, resources: &Resources) -> wgpu::BindGroup {
    let view = |name: &str| resources.texture_view(name);
    let filter = if i == 0 { wgpu::FilterMode::Nearest } else { wgpu::FilterMode::Linear };
    let sampler = gpu.device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some(if i == 0 { "tsd dilation sampler" } else { "tsd blur sampler" }),
        address_mode_u: wgpu::AddressMode::ClampToEdge,
        address_mode_v: wgpu::AddressMode::ClampToEdge,
        mag_filter: filter,
        min_filter: filter,
        ..Default::default()
    });
    let stage = tsd::stages(setup.kernel, setup.passes)[i as usize];
    let (a, b) = (setup.kernel_scale[0], setup.kernel_scale[1]);
    let rgb0 = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
    let raw = BlurUniforms {
        inv_size: [1.0 / setup.size as f32; 2],
        a: a * stage.scale,
        b: b * stage.scale,
        dilate: stage.dilate as u32,
        tap_variance: setup::poisson_second_moment() / 2.0,
        tap_mean: setup::poisson_mean(),
        source_scale: rgb0(stage.source_scale),
        irradiance_weight: rgb0(stage.irradiance_weight),
        axis_variance: setup::poisson_axis_variance(),
        pad0: 0.0,
        pad1: 0.0,
        radius_table: tsd::radius_table(),
    };
    let buffer = gpu.buffer("tsd blur uniforms", bytemuck::bytes_of(&raw), wgpu::BufferUsages::UNIFORM);
    let (from, _) = tsd::blur_maps(setup.kernel, i);
    // Map B is the target of the first pass: that one binds its own source instead (its weight
    // is 0), as does the single kernel, which keeps no map B.
    let added = if i == 0 || tsd::map_count(setup.kernel) < 3 { from } else { 1 };
    let (source, added, stretch) = (view(LIGHT_MAP_NAMES[from]), view(LIGHT_MAP_NAMES[added]), view(STRETCH));
    let texture = |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
    gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("tsd blur bind group"),
        layout: &layout(gpu),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() },
            texture(1, &source),
            wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::Sampler(&sampler) },
            texture(3, &added),
            texture(4, &stretch),
        ],
    })
}

/// A filterable 2-D float texture read by the blur's fragment stage.
fn texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// The blur's bindings (built once per device): uniforms, the source map, its sampler, light map
/// B, the stretch map.
fn layout(gpu: &Gpu) -> wgpu::BindGroupLayout {
    gpu.shared("tsd blur bind group layout", |gpu| {
        gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tsd blur bind group layout"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture_entry(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
                texture_entry(3),
                texture_entry(4),
            ],
        })
    })
}

/// The blur's pipeline: a full-screen triangle in its own module ([`super::BLUR_WGSL`]).
fn pipeline(gpu: &Gpu) -> wgpu::RenderPipeline {
    let module = gpu.shader_module("blur.wgsl", super::BLUR_WGSL);
    let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("tsd blur layout"),
        bind_group_layouts: &[Some(&layout(gpu))],
        immediate_size: 0,
    });
    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("tsd blur pipeline"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_full_screen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_blur"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: gpu.light_map_format(),
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}
