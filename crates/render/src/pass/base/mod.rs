//! The base pass (`base.wgsl`): texture-space per-pixel bump mapping and the Lafortune BRDF into
//! the target (Haro et al. 2001, section 5), with the skin effects it reads.

use std::sync::Arc;

use super::graph::PassGraph;
use super::resources::Resources;
use super::setup::{DiffuseMode, Features, SkinSetup};
use super::shadow::SHADOW_MAP;
use super::translucent::SHADOW_OPACITY;
use super::{Context, Described, FrameEncoder, Pass, PassState, Shape, Upload};
use crate::gpu::{Gpu, MESH_BUFFERS, MeshPipeline, OutputFormat, Table, depth_state};
use crate::shading::{MAX_LOBES, RenderInputs, SpecularMode, ToneCurve};
use crate::skin::tsd;

/// The base pass, last of every frame.
struct Base;

/// The base pass: every frame draws it.
pub(crate) fn passes(_: &Shape) -> Vec<Arc<dyn Pass>> {
    vec![Arc::new(Base)]
}

impl Pass for Base {
    fn name(&self) -> String {
        "base".into()
    }

    fn explain(&self, context: &Context) -> Described {
        let mut described =
            Described::new(describe_base(context.inputs, context.graph), &[], &["colour target", "depth"]);
        described.reads = base_reads(context.graph);
        described
    }

    /// Its bind group: the shadow map, the casters' opacity and the light map (texture-space
    /// diffusion's last, or the caller's) as earlier passes wrote them, placeholders for those
    /// the scene has not.
    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        let light_map = upload.skin.tsd.as_ref().map(super::tsd::final_light_map);
        Some(Box::new(upload.bind_group(gpu, resources, Some(SHADOW_MAP), Some(SHADOW_OPACITY), light_map)))
    }

    /// The base pass into the frame's target.
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let (scene, target, bind_group) = (frame.scene, frame.target, frame.state::<wgpu::BindGroup>());
        let (format, features) = (target.format, scene.features);
        let pipeline = gpu.pipeline(format!("base {format:?} {features:?}"), |gpu| {
            gpu.mesh_pipeline(&pipeline(&super::mesh_module(gpu), &features.constants(), format))
        });
        let mut pass = super::target_pass(frame.encoder, "base pass", target, scene.background, writes);
        pass.set_pipeline(&pipeline);
        gpu.draw_mesh(&mut pass, scene, bind_group);
    }
}

/// The base pass's code of a tone curve (`tone` in `BaseUniforms`).
pub(crate) fn tone_code(curve: ToneCurve) -> u32 {
    match curve {
        ToneCurve::None => 0,
        ToneCurve::Clamp => 1,
        ToneCurve::Reinhard => 2,
    }
}

fn vec4(v: glam::Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// One Lafortune lobe as the shader reads it (`Lobe` in base.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LobeRaw {
    pub(crate) cx: [f32; 4],
    pub(crate) cy: [f32; 4],
    pub(crate) cz: [f32; 4],
    pub(crate) n: [f32; 4],
}

/// The base pass's uniforms (`BaseUniforms` in base.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct BaseUniforms {
    pub(crate) diffuse: [f32; 3],
    pub(crate) lobe_count: u32,
    pub(crate) normal_blur: [f32; 3],
    pub(crate) vertex_specular: u32,
    pub(crate) tone: u32,
    pub(crate) curvature_scale: f32,
    pub(crate) lut_scale: f32,
    pub(crate) lut_offset: f32,
    pub(crate) zonal_scale: f32,
    pub(crate) zonal_offset: f32,
    pub(crate) shadow_lut_scale: f32,
    pub(crate) shadow_lut_offset: f32,
    pub(crate) new_penumbra: f32,
    pub(crate) pad0: f32,
    pub(crate) pad1: f32,
    pub(crate) pad2: f32,
    pub(crate) lobes: [LobeRaw; MAX_LOBES],
    pub(crate) sh: [[f32; 4]; 9],
}

/// The base pass's uniforms for `inputs` with the skin settings of `skin`.
pub(crate) fn uniforms(inputs: &RenderInputs, skin: &SkinSetup) -> BaseUniforms {
    let mut lobes = [LobeRaw { cx: [0.0; 4], cy: [0.0; 4], cz: [0.0; 4], n: [0.0; 4] }; MAX_LOBES];
    for (raw, lobe) in lobes.iter_mut().zip(&inputs.brdf.lobes) {
        *raw = LobeRaw { cx: vec4(lobe.cx, 0.0), cy: vec4(lobe.cy, 0.0), cz: vec4(lobe.cz, 0.0), n: vec4(lobe.n, 0.0) };
    }
    let map = |t: &Option<Table>| t.as_ref().map_or((0.0, 0.5), |t| (t.scale, t.offset));
    let (lut_scale, lut_offset) = map(&skin.diffuse_lut);
    let (shadow_lut_scale, shadow_lut_offset) = map(&skin.shadow_lut);
    let (zonal_scale, zonal_offset) = map(&skin.zonal);
    let mut sh = [[0.0f32; 4]; 9];
    for (raw, c) in sh.iter_mut().zip(&skin.sh) {
        *raw = [c[0], c[1], c[2], 0.0];
    }
    BaseUniforms {
        diffuse: inputs.brdf.diffuse.to_array(),
        lobe_count: inputs.brdf.lobes.len().min(MAX_LOBES) as u32,
        normal_blur: skin.normal_blur.to_array(),
        vertex_specular: (inputs.specular == SpecularMode::Vertex) as u32,
        tone: tone_code(inputs.tone),
        curvature_scale: skin.curvature_scale,
        lut_scale,
        lut_offset,
        zonal_scale,
        zonal_offset,
        shadow_lut_scale,
        shadow_lut_offset,
        new_penumbra: skin.shadow.as_ref().map_or(1.0, |s| s.new_penumbra),
        pad0: 0.0,
        pad1: 0.0,
        pad2: 0.0,
        lobes,
        sh,
    }
}

/// The base pass's pipeline for a target of `format`.
fn pipeline<'a>(
    module: &'a wgpu::ShaderModule,
    constants: &'a [(&'static str, f64)],
    format: OutputFormat,
) -> MeshPipeline<'a> {
    MeshPipeline {
        label: "base pass pipeline",
        module,
        vertex_entry: "vs_main",
        buffers: &MESH_BUFFERS,
        fragment_entry: Some("fs_main"),
        target: Some(format.texture_format()),
        second_target: None,
        depth: depth_state(true, wgpu::CompareFunction::Less),
        constants,
    }
}

fn base_reads(graph: &PassGraph) -> Vec<String> {
    let mut reads: Vec<String> =
        ["vertices", "indices", "uniforms", "normal map", "albedo"].iter().map(|s| s.to_string()).collect();
    let optional = [
        (graph.vertex_curvature, "per-vertex curvature"),
        (graph.diffuse_lut, "diffuse LUT"),
        (graph.zonal_table, "zonal table"),
        (graph.shadow.is_some(), SHADOW_MAP),
        (graph.features.translucent_shadows, SHADOW_OPACITY),
        (graph.shadow_lut, "shadow LUT"),
    ];
    reads.extend(optional.into_iter().filter(|(on, _)| *on).map(|(_, name)| name.to_string()));
    if let Some(tsd) = graph.tsd {
        reads.push(tsd::LIGHT_MAP_NAMES[tsd::final_map(tsd.kernel, tsd.blurs)].into());
    }
    reads
}

fn describe_base(inputs: &RenderInputs, graph: &PassGraph) -> String {
    let specular = match inputs.specular {
        SpecularMode::Pixel => "per pixel",
        SpecularMode::Vertex => "per vertex (the paper's look)",
    };
    format!(
        "texture-space bump mapping and the Lafortune BRDF, lobes {specular}; diffuse: {}{}{}{}",
        describe_diffuse(&graph.features),
        if graph.features.shadows { "; key light shadowed" } else { "" },
        if graph.features.shadow_scattering { " with shadow scattering" } else { "" },
        if graph.features.sh_ambient { "; order-2 SH ambient" } else { "" },
    )
}

fn describe_diffuse(features: &Features) -> &'static str {
    match (features.diffuse, features.derivative_curvature) {
        (DiffuseMode::Lambert, _) => "Lambert",
        (DiffuseMode::Lut, false) => "pre-integrated LUT, per-vertex curvature, per-channel normals",
        (DiffuseMode::Lut, true) => "pre-integrated LUT, derivative curvature, per-channel normals",
        (DiffuseMode::Blog, _) => "the blog's closed-form pre-integrated curves",
        (DiffuseMode::OwnFit, _) => "our closed-form fit of the pre-integrated LUT",
        (DiffuseMode::LightMap, _) => "the blurred texture-space light map x albedo",
    }
}
