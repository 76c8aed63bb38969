//! TSD's light map (`light_map.wgsl`): every light's diffuse irradiance in texture space, the
//! blur's kernel size in alpha, and the stretch map (the kernel's widening along u and v).

use std::sync::Arc;

use super::resources::Resources;
use super::setup::{self, TsdSetup};
use super::shadow::SHADOW_MAP;
use super::tsd::{self, DEPTH, STRETCH};
use super::{Context, Described, FrameEncoder, Pass, PassState, PreparedScene, Shape, Upload};
use crate::gpu::{
    Gpu, MESH_BUFFERS, MeshPipeline, STRETCH_FORMAT, Target, colour_attachment, depth_attachment, depth_state,
};
use crate::skin::tsd::LIGHT_MAP_NAMES;

/// TSD's light-map pass, after the pre-pass.
struct TsdLightMap;

/// The light-map pass, when `shape` runs texture-space diffusion.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    match shape.tsd_blurs {
        Some(_) => vec![Arc::new(TsdLightMap)],
        None => Vec::new(),
    }
}

/// What the light maps hold where no texel was drawn (the first blur dilates into them).
pub(crate) const UNWRITTEN_TEXEL: wgpu::Color = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 };
/// The stretch map where no texel was drawn: the isotropic kernel.
const UNSTRETCHED: wgpu::Color = wgpu::Color { r: 1.0, g: 1.0, b: 0.0, a: 0.0 };

/// The light map's uniforms (`LightMapUniforms` in light_map.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightMapUniforms {
    pub(crate) size: f32,
    pub(crate) kernel_mm: f32,
    pub(crate) curvature_gain: f32,
    pub(crate) max_radius: f32,
    pub(crate) kernel_from_map: u32,
    pub(crate) pad0: u32,
    pub(crate) pad1: u32,
    pub(crate) pad2: u32,
}

/// The light map's uniforms (a unit-sized placeholder without texture-space diffusion).
pub(crate) fn uniforms(tsd: Option<&TsdSetup>) -> LightMapUniforms {
    let (size, kernel_mm, curvature_gain, max_radius, from_map) = match tsd {
        Some(t) => (t.size as f32, t.kernel_mm, t.curvature_gain, setup::MAX_KERNEL_TEXELS, t.kernel_map.is_some()),
        None => (1.0, 0.0, 0.0, 1.0, false),
    };
    LightMapUniforms {
        size,
        kernel_mm,
        curvature_gain,
        max_radius,
        kernel_from_map: from_map as u32,
        pad0: 0,
        pad1: 0,
        pad2: 0,
    }
}

/// The light map's pipeline: depth test "equal" against the pre-pass, so only kept texels shade.
fn pipeline<'a>(
    module: &'a wgpu::ShaderModule,
    constants: &'a [(&'static str, f64)],
    format: wgpu::TextureFormat,
) -> MeshPipeline<'a> {
    MeshPipeline {
        label: "tsd light map pipeline",
        module,
        vertex_entry: "vs_texture_space",
        buffers: &MESH_BUFFERS,
        fragment_entry: Some("fs_light_map"),
        target: Some(format),
        second_target: Some(STRETCH_FORMAT),
        depth: depth_state(false, wgpu::CompareFunction::Equal),
        constants,
    }
}

impl Pass for TsdLightMap {
    fn name(&self) -> String {
        "tsd light map".into()
    }

    fn explain(&self, context: &Context) -> Described {
        let what = "diffuse irradiance of every light into texture space (key light through the shadow map), kernel \
                    size in alpha";
        let mut described = Described::new(
            what,
            &["vertices", "indices", "uniforms", "normal map", "per-vertex curvature", DEPTH],
            &[LIGHT_MAP_NAMES[0], STRETCH],
        );
        if context.graph.shadow.is_some() {
            described.reads.push(SHADOW_MAP.into());
        }
        if context.scene.skin.tsd.kernel_map.is_some() {
            described.reads.push("kernel map".into());
        }
        described
    }

    fn runs(&self, scene: &PreparedScene, target: &Target) -> bool {
        tsd::runs(scene, target)
    }

    fn allocate(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &mut Resources) {
        tsd::allocate_maps(gpu, tsd::setup(upload), resources);
    }

    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        Some(Box::new(tsd::texture_space_group(gpu, upload, resources)))
    }

    /// TSD's light map (depth "equal": only texels the pre-pass kept).
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let bind_group: &wgpu::BindGroup = frame.state();
        let resources = &frame.scene.resources;
        let (depth_view, view, stretch) = (
            resources.texture_view(DEPTH),
            resources.texture_view(LIGHT_MAP_NAMES[0]),
            resources.texture_view(STRETCH),
        );
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd light map"),
            color_attachments: &[
                Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL))),
                Some(colour_attachment(&stretch, wgpu::LoadOp::Clear(UNSTRETCHED))),
            ],
            depth_stencil_attachment: Some(depth_attachment(&depth_view, wgpu::LoadOp::Load)),
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let features = frame.scene.features;
        let pipeline = gpu.pipeline(format!("tsd light map {features:?}"), |gpu| {
            let format = gpu.light_map_format();
            gpu.mesh_pipeline(&pipeline(&super::mesh_module(gpu), &features.constants(), format))
        });
        pass.set_pipeline(&pipeline);
        gpu.draw_mesh(&mut pass, frame.scene, bind_group);
    }
}
