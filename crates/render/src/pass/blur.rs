//! TSD's blur (`blur.wgsl`): a Poisson disc scaled per texel by the light map's kernel size and
//! per pass by its stage ([`crate::skin::tsd`]), between the light maps; the first pass also
//! dilates across UV seams.

use crate::gpu::{Gpu, PipelineKey, colour_attachment};
use crate::pass::light_map::UNWRITTEN_TEXEL;
use crate::pass::tsd::TsdResources;
use crate::passes;
use crate::skin::tsd;

/// The blur's uniforms (`BlurUniforms` in blur.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct BlurUniforms {
    pub(crate) inv_size: [f32; 2],
    pub(crate) a: f32,
    pub(crate) b: f32,
    pub(crate) dilate: u32,
    /// The per-axis variance a unit radius stands for ([`passes::poisson_second_moment`] / 2).
    pub(crate) tap_variance: f32,
    /// [`passes::poisson_mean`].
    pub(crate) tap_mean: [f32; 2],
    /// Scales the blurred source per channel (w unused).
    pub(crate) source_scale: [f32; 4],
    /// Weight of light map B added after the blur per channel (w unused).
    pub(crate) irradiance_weight: [f32; 4],
    /// [`passes::poisson_axis_variance`].
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
        setup: &passes::TsdSetup,
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
                    tap_variance: passes::poisson_second_moment() / 2.0,
                    tap_mean: passes::poisson_mean(),
                    source_scale: rgb0(stage.source_scale),
                    irradiance_weight: rgb0(stage.irradiance_weight),
                    axis_variance: passes::poisson_axis_variance(),
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
                    layout: &self.blur_layout,
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

    /// TSD blur `i`: over the whole map, into the map its bind group was made for (the first
    /// also dilates into the texels the light map left unwritten).
    pub(crate) fn encode_blur(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        tsd: &TsdResources,
        i: usize,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let (group, to) = &tsd.blur_groups[i];
        let view = tsd.maps[*to].create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd blur"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL)))],
            depth_stencil_attachment: None,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::Blur));
        pass.set_bind_group(0, group, &[]);
        pass.draw(0..3, 0..1);
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

/// The blur's bindings: uniforms, the source map, its sampler, light map B, the stretch map.
pub(crate) fn blur_bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
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
}

/// The blur's pipeline: a full-screen triangle in its own module.
pub(crate) fn pipeline(gpu: &Gpu) -> wgpu::RenderPipeline {
    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("tsd blur pipeline"),
        layout: Some(&gpu.blur_pipeline_layout),
        vertex: wgpu::VertexState {
            module: &gpu.blur_shader,
            entry_point: Some("vs_full_screen"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: Default::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &gpu.blur_shader,
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
