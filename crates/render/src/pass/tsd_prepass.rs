//! TSD's back-face pre-pass (`tsd_prepass.wgsl`): the texture-space depth that keeps the
//! light-map pass off texels facing away from the eye.

use crate::gpu::{Gpu, MESH_BUFFERS, MeshPipeline, PipelineKey, PreparedScene, depth_attachment, depth_state};
use crate::pass::tsd::TsdResources;
use crate::passes::{self, Features};

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
pub(crate) fn uniforms(tsd: Option<&passes::TsdSetup>) -> PrepassUniforms {
    let backface_bias = tsd.map_or(0.0, |t| t.backface_bias);
    PrepassUniforms { backface_bias, pad0: 0.0, pad1: 0.0, pad2: 0.0 }
}

/// The pre-pass's pipeline: the mesh at its UVs, depth only, every fragment kept but the culled.
pub(crate) fn pipeline(features: Features) -> MeshPipeline<'static> {
    MeshPipeline {
        label: "tsd back-face pre-pass pipeline",
        vertex_entry: "vs_texture_space",
        buffers: &MESH_BUFFERS,
        fragment_entry: Some("fs_tsd_prepass"),
        target: None,
        second_target: None,
        depth: depth_state(true, wgpu::CompareFunction::Always),
        features,
    }
}

impl Gpu {
    /// TSD's back-face pre-pass into the UV-space depth.
    pub(crate) fn encode_tsd_prepass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PreparedScene,
        tsd: &TsdResources,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let depth_view = tsd.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd back-face pre-pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&depth_view, wgpu::LoadOp::Clear(1.0))),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::TsdPrepass(scene.features)));
        self.draw_mesh(&mut pass, scene, &tsd.bind_group);
    }
}
