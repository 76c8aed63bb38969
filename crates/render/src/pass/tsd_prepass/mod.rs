//! TSD's back-face pre-pass (`tsd_prepass.wgsl`): the texture-space depth that keeps the
//! light-map pass off texels facing away from the eye.

use std::sync::Arc;

use super::resources::Resources;
use super::setup::TsdSetup;
use super::tsd::{self, DEPTH};
use super::{Context, Described, FrameEncoder, Pass, PassState, PreparedScene, Shape, Upload};
use crate::gpu::{Gpu, MESH_BUFFERS, MeshPipeline, Target, depth_attachment, depth_state};

/// TSD's back-face pre-pass, first of its passes.
struct TsdPrepass;

/// The pre-pass, when `shape` runs texture-space diffusion.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    match shape.tsd_blurs {
        Some(_) => vec![Arc::new(TsdPrepass)],
        None => Vec::new(),
    }
}

/// The pre-pass's uniforms (`PrepassUniforms` in tsd_prepass.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct PrepassUniforms {
    pub(crate) backface_bias: f32,
    pub(crate) pad0: f32,
    pub(crate) pad1: f32,
    pub(crate) pad2: f32,
}

/// The pre-pass's uniforms (zeros without texture-space diffusion).
pub(crate) fn uniforms(tsd: Option<&TsdSetup>) -> PrepassUniforms {
    let backface_bias = tsd.map_or(0.0, |t| t.backface_bias);
    PrepassUniforms { backface_bias, pad0: 0.0, pad1: 0.0, pad2: 0.0 }
}

/// The pre-pass's pipeline: the mesh at its UVs, depth only, every fragment kept but the culled.
fn pipeline<'a>(module: &'a wgpu::ShaderModule, constants: &'a [(&'static str, f64)]) -> MeshPipeline<'a> {
    MeshPipeline {
        label: "tsd back-face pre-pass pipeline",
        module,
        vertex_entry: "vs_texture_space",
        buffers: &MESH_BUFFERS,
        fragment_entry: Some("fs_tsd_prepass"),
        target: None,
        second_target: None,
        depth: depth_state(true, wgpu::CompareFunction::Always),
        constants,
    }
}

impl Pass for TsdPrepass {
    fn name(&self) -> String {
        "tsd back-face pre-pass".into()
    }

    fn explain(&self, context: &Context) -> Described {
        let what = format!(
            "mesh at its UVs; keeps texels with N.V > -{} (frustum culling skips every TSD pass when the head is off \
             screen)",
            context.scene.skin.tsd.backface_bias
        );
        Described::new(what, &["vertices", "indices", "uniforms"], &[DEPTH])
    }

    fn runs(&self, scene: &PreparedScene, target: &Target) -> bool {
        tsd::runs(scene, target)
    }

    fn allocate(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &mut Resources) {
        tsd::allocate_depth(gpu, tsd::setup(upload), resources);
    }

    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        Some(Box::new(tsd::texture_space_group(gpu, upload, resources)))
    }

    /// TSD's back-face pre-pass into the UV-space depth.
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let bind_group: &wgpu::BindGroup = frame.state();
        let depth_view = frame.scene.resources.texture_view(DEPTH);
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd back-face pre-pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&depth_view, wgpu::LoadOp::Clear(1.0))),
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let features = frame.scene.features;
        let pipeline = gpu.pipeline(format!("tsd back-face pre-pass {features:?}"), |gpu| {
            gpu.mesh_pipeline(&pipeline(&super::mesh_module(gpu), &features.constants()))
        });
        pass.set_pipeline(&pipeline);
        gpu.draw_mesh(&mut pass, frame.scene, bind_group);
        tsd::mark_drawn(frame.scene);
    }
}
