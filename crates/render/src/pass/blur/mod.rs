//! TSD's blur (`blur.wgsl`): a Poisson disc scaled per texel by the light map's kernel size and
//! per pass by its stage ([`crate::skin::tsd`]), between the light maps; the first pass also
//! dilates across UV seams.

use std::sync::Arc;

use super::light_map::UNWRITTEN_TEXEL;
use super::setup::{self, TsdSetup};
use super::{Context, Described, FrameEncoder, Pass, Shape};
use crate::gpu::{Gpu, colour_attachment};
use crate::skin::options::TsdKernel;
use crate::skin::tsd;

/// TSD blur pass `.0` (0-based) of the ping-pong pair.
struct TsdBlur(u32);

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
        let mut described = Described::new(what, &[tsd::LIGHT_MAP_NAMES[from]], &[tsd::LIGHT_MAP_NAMES[to]]);
        if self.0 > 0 && kernel == TsdKernel::Gaussians {
            described.reads.push(tsd::LIGHT_MAP_NAMES[1].into());
        }
        described
    }

    fn culled_with_tsd(&self) -> bool {
        true
    }

    /// TSD blur `i`: over the whole map, into the map its bind group was made for (the first
    /// also dilates into the texels the light map left unwritten).
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let tsd = frame.scene.tsd();
        let (group, to) = &tsd.blur_groups[self.0 as usize];
        let view = tsd.maps[*to].create_view(&Default::default());
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd blur"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL)))],
            depth_stencil_attachment: None,
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&gpu.pipeline("tsd blur".into(), pipeline));
        pass.set_bind_group(0, group, &[]);
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

impl Gpu {
    /// One bind group per blur pass and the map it writes: pass `i` reads the map of
    /// [`tsd::blur_maps`] (and light map B, which the Gaussians add back), the first with a
    /// nearest sampler (it dilates), the others bilinear.
    pub(crate) fn blur_groups(
        &self,
        setup: &TsdSetup,
        maps: &[wgpu::Texture],
        stretch: &wgpu::Texture,
    ) -> Vec<(wgpu::BindGroup, usize)> {
        let stretch = stretch.create_view(&Default::default());
        let sampler = |label, filter| {
            self.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: filter,
                min_filter: filter,
                ..Default::default()
            })
        };
        let nearest = sampler("tsd dilation sampler", wgpu::FilterMode::Nearest);
        let linear = sampler("tsd blur sampler", wgpu::FilterMode::Linear);
        let (a, b) = (setup.kernel_scale[0], setup.kernel_scale[1]);
        let rgb0 = |v: [f32; 3]| [v[0], v[1], v[2], 0.0];
        let radius_table = tsd::radius_table();
        tsd::stages(setup.kernel, setup.passes)
            .into_iter()
            .enumerate()
            .map(|(i, stage)| {
                let inv_size = [1.0 / setup.size as f32; 2];
                let raw = BlurUniforms {
                    inv_size,
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
                    radius_table,
                };
                let buffer = self.buffer("tsd blur uniforms", bytemuck::bytes_of(&raw), wgpu::BufferUsages::UNIFORM);
                let (from, to) = tsd::blur_maps(setup.kernel, i as u32);
                let view = maps[from].create_view(&Default::default());
                // Map B is the target of the first pass: that one binds its own source instead
                // (its weight is 0).
                let added = maps[if i == 0 || maps.len() < 3 { from } else { 1 }].create_view(&Default::default());
                let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("tsd blur bind group"),
                    layout: &layout(self),
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::Sampler(if i == 0 { &nearest } else { &linear }),
                        },
                        wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&added) },
                        wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&stretch) },
                    ],
                });
                (group, to)
            })
            .collect()
    }
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
