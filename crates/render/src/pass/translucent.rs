//! Translucent shadows (`translucent.wgsl`, Gosselin et al.): the translucent casters' summed
//! opacity seen from the key light, tested against the shadow map's depth.

use crate::gpu::{Gpu, MeshPipeline, OPACITY_FORMAT, PipelineKey, colour_attachment, depth_state};
use crate::pass::shadow::ShadowResources;
use crate::passes::Features;

/// One translucent caster's positions, per-vertex opacity and indices.
pub(crate) struct CasterBuffers {
    pub(crate) positions: wgpu::Buffer,
    pub(crate) opacity: wgpu::Buffer,
    pub(crate) indices: wgpu::Buffer,
    pub(crate) count: u32,
}

const POSITION: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const OPACITY: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Float32x3];

/// A caster's two vertex buffers: positions and per-vertex RGB opacity.
const CASTER_BUFFERS: [Option<wgpu::VertexBufferLayout<'static>>; 2] = [
    Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode: wgpu::VertexStepMode::Vertex, attributes: &POSITION }),
    Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode: wgpu::VertexStepMode::Vertex, attributes: &OPACITY }),
];

/// The casters' pipeline: tested against the opaque depth, not writing it.
pub(crate) fn pipeline() -> MeshPipeline<'static> {
    MeshPipeline {
        label: "translucent shadows pipeline",
        vertex_entry: "vs_translucent",
        buffers: &CASTER_BUFFERS,
        fragment_entry: Some("fs_translucent"),
        target: Some(OPACITY_FORMAT),
        second_target: None,
        depth: depth_state(false, wgpu::CompareFunction::Less),
        features: Features::default(),
    }
}

impl Gpu {
    /// Translucent casters into the opacity channels: cleared to 0, added up where the opaque
    /// depth does not hide them.
    pub(crate) fn encode_translucent(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shadow: &ShadowResources,
        opacity: &wgpu::Texture,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let depth = shadow.depth.create_view(&Default::default());
        let view = opacity.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("translucent shadows pass"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)))],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::Translucent));
        pass.set_bind_group(0, &shadow.bind_group, &[]);
        for caster in &shadow.casters {
            pass.set_vertex_buffer(0, caster.positions.slice(..));
            pass.set_vertex_buffer(1, caster.opacity.slice(..));
            pass.set_index_buffer(caster.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..caster.count, 0, 0..1);
        }
    }
}
