//! The base pass (`base.wgsl`): texture-space per-pixel bump mapping and the Lafortune BRDF into
//! the target (Haro et al. 2001, section 5), with the skin effects it reads; and the uniform block
//! every mesh pass reads.

use crate::gpu::{Gpu, MESH_BUFFERS, MeshPipeline, OutputFormat, PipelineKey, PreparedScene, Target, depth_state};
use crate::gpu::tone_code;
use crate::passes::{self, Features, SkinSetup, Table};
use crate::shading::{GreenAxis, LightKind, MAX_LIGHTS, MAX_LOBES, RenderInputs, SpecularMode};

/// One light as the shader reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightRaw {
    pub(crate) vector: [f32; 4],
    pub(crate) radiance: [f32; 4],
}

/// One lobe as the shader reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LobeRaw {
    pub(crate) cx: [f32; 4],
    pub(crate) cy: [f32; 4],
    pub(crate) cz: [f32; 4],
    pub(crate) n: [f32; 4],
}

/// The `Globals` uniform of common.wgsl, read by every mesh pass (832 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Globals {
    pub(crate) view_proj: [[f32; 4]; 4],
    pub(crate) eye: [f32; 4],
    pub(crate) diffuse: [f32; 4],
    pub(crate) counts: [u32; 4],
    pub(crate) options: [u32; 4],
    pub(crate) lights: [LightRaw; MAX_LIGHTS],
    pub(crate) lobes: [LobeRaw; MAX_LOBES],
    pub(crate) skin: [f32; 4],
    pub(crate) blur: [f32; 4],
    pub(crate) shadow_view_proj: [[f32; 4]; 4],
    pub(crate) shadow: [f32; 4],
    pub(crate) shadow_lut: [f32; 4],
    pub(crate) sh: [[f32; 4]; 9],
    pub(crate) zonal: [f32; 4],
    pub(crate) tsd: [f32; 4],
    pub(crate) tsd_kernel: [f32; 4],
}

pub(crate) fn vec4(v: glam::Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// A light as the shader reads it.
pub(crate) fn light_raw(light: &crate::shading::Light) -> LightRaw {
    let vector = match light.kind {
        LightKind::Directional { toward } => vec4(toward, 0.0),
        LightKind::Point { position } => vec4(position, 1.0),
    };
    LightRaw { vector, radiance: vec4(light.color * light.intensity, 0.0) }
}

/// The uniform block for `inputs` with the skin settings of `skin`.
pub(crate) fn globals(inputs: &RenderInputs, skin: &SkinSetup) -> Globals {
    let mut lights = [LightRaw { vector: [0.0; 4], radiance: [0.0; 4] }; MAX_LIGHTS];
    for (raw, light) in lights.iter_mut().zip(&inputs.lights) {
        *raw = light_raw(light);
    }
    let mut lobes = [LobeRaw { cx: [0.0; 4], cy: [0.0; 4], cz: [0.0; 4], n: [0.0; 4] }; MAX_LOBES];
    for (raw, lobe) in lobes.iter_mut().zip(&inputs.brdf.lobes) {
        *raw = LobeRaw { cx: vec4(lobe.cx, 0.0), cy: vec4(lobe.cy, 0.0), cz: vec4(lobe.cz, 0.0), n: vec4(lobe.n, 0.0) };
    }
    let map = |t: &Option<Table>| t.as_ref().map_or((0.0, 0.5), |t| (t.scale, t.offset));
    let (lut_scale, lut_offset) = map(&skin.diffuse_lut);
    let (shadow_scale, shadow_offset) = map(&skin.shadow_lut);
    let (zonal_scale, zonal_offset) = map(&skin.zonal);
    let key = skin.shadow.as_ref().map_or(MAX_LIGHTS as f32, |s| s.light as f32);
    let (shadow_view_proj, shadow, new_penumbra) = match &skin.shadow {
        Some(s) => (s.view_proj, [1.0 / s.map_size.max(1) as f32, s.filter as f32, s.texel, s.bias], s.new_penumbra),
        None => (glam::Mat4::IDENTITY, [1.0, 1.0, 0.0, 0.0], 1.0),
    };
    let (tsd, tsd_kernel) = match &skin.tsd {
        Some(t) => {
            let from_map = t.kernel_map.is_some();
            let kernel = if from_map {
                [t.kernel_scale[0], t.kernel_scale[1], 1.0, passes::MAX_KERNEL_TEXELS]
            } else {
                [passes::MAX_KERNEL_TEXELS, 0.0, 0.0, passes::MAX_KERNEL_TEXELS]
            };
            ([t.backface_bias, t.size as f32, t.kernel_mm, t.curvature_gain], kernel)
        }
        None => ([0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
    };
    let mut sh = [[0.0f32; 4]; 9];
    for (raw, c) in sh.iter_mut().zip(&skin.sh) {
        *raw = [c[0], c[1], c[2], 0.0];
    }
    Globals {
        view_proj: inputs.camera.view_proj.to_cols_array_2d(),
        eye: vec4(inputs.camera.eye, inputs.exposure),
        diffuse: vec4(inputs.brdf.diffuse, 0.0),
        counts: [
            inputs.lights.len().min(MAX_LIGHTS) as u32,
            inputs.brdf.lobes.len().min(MAX_LOBES) as u32,
            (inputs.specular == SpecularMode::Vertex) as u32,
            (inputs.green == GreenAxis::Down) as u32,
        ],
        options: [tone_code(inputs.tone), 0, 0, 0],
        lights,
        lobes,
        skin: [skin.curvature_scale, skin.mm_per_unit, lut_scale, lut_offset],
        blur: vec4(skin.normal_blur, key),
        shadow_view_proj: shadow_view_proj.to_cols_array_2d(),
        shadow,
        shadow_lut: [shadow_scale, shadow_offset, new_penumbra, 0.0],
        sh,
        zonal: [zonal_scale, zonal_offset, 0.0, 0.0],
        tsd,
        tsd_kernel,
    }
}

/// The base pass's pipeline for a target of `format`.
pub(crate) fn pipeline(format: OutputFormat, features: Features) -> MeshPipeline<'static> {
    MeshPipeline {
        label: "base pass pipeline",
        vertex_entry: "vs_main",
        buffers: &MESH_BUFFERS,
        fragment_entry: Some("fs_main"),
        target: Some(format.texture_format()),
        depth: depth_state(true, wgpu::CompareFunction::Less),
        features,
    }
}

impl Gpu {
    /// The base pass into `target`.
    pub(crate) fn encode_base(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PreparedScene,
        target: &Target,
        writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let pipeline = self.pipeline(PipelineKey::Base(target.format, scene.features));
        let mut pass = begin_pass(encoder, &target.color, &target.depth, scene.background, writes);
        pass.set_pipeline(&pipeline);
        self.draw_mesh(&mut pass, scene, &scene.bind_group);
    }
}

fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::Texture,
    depth: &wgpu::Texture,
    background: [f32; 4],
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    let target_view = target.create_view(&Default::default());
    let depth_view = depth.create_view(&Default::default());
    let [r, g, b, a] = background.map(f64::from);
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("base pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &target_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}
