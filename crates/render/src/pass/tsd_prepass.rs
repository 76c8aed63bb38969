//! TSD's back-face pre-pass (`tsd_prepass.wgsl`): the texture-space depth that keeps the
//! light-map pass off texels facing away from the eye.

use crate::gpu::{Gpu, PipelineKey, PreparedScene, depth_attachment};
use crate::pass::tsd::TsdResources;

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
