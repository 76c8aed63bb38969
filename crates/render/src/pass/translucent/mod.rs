//! Translucent shadows (`translucent.wgsl`, Gosselin et al.): the translucent casters' summed
//! opacity seen from the key light, tested against the shadow map's depth.

use std::sync::Arc;

use super::setup::Features;
use super::{Context, Described, FrameEncoder, Pass, Shape};
use crate::gpu::{Gpu, MeshPipeline, OPACITY_FORMAT, colour_attachment, depth_state};

/// The translucent casters' pass, drawn after the shadow map when the scene has casters.
struct TranslucentShadows;

/// The translucent casters' pass, when `shape` draws them.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    match shape.shadow_map && shape.translucent {
        true => vec![Arc::new(TranslucentShadows)],
        false => Vec::new(),
    }
}

const POSITION: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![0 => Float32x3];
const OPACITY: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![1 => Float32x3];

/// A caster's two vertex buffers: positions and per-vertex RGB opacity.
const CASTER_BUFFERS: [Option<wgpu::VertexBufferLayout<'static>>; 2] = [
    Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode: wgpu::VertexStepMode::Vertex, attributes: &POSITION }),
    Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode: wgpu::VertexStepMode::Vertex, attributes: &OPACITY }),
];

/// The casters' pipeline: tested against the opaque depth, not writing it.
fn pipeline<'a>(module: &'a wgpu::ShaderModule, constants: &'a [(&'static str, f64)]) -> MeshPipeline<'a> {
    MeshPipeline {
        label: "translucent shadows pipeline",
        module,
        vertex_entry: "vs_translucent",
        buffers: &CASTER_BUFFERS,
        fragment_entry: Some("fs_translucent"),
        target: Some(OPACITY_FORMAT),
        second_target: None,
        depth: depth_state(false, wgpu::CompareFunction::Less),
        constants,
    }
}

impl Pass for TranslucentShadows {
    fn name(&self) -> String {
        "translucent shadows".into()
    }

    fn explain(&self, _: &Context) -> Described {
        Described::new(
            "translucent casters seen from the key light, their opacity added where no opaque surface is in front",
            &["uniforms", "shadow map"],
            &["shadow opacity"],
        )
    }

    /// Translucent casters into the opacity channels: cleared to 0, added up where the opaque
    /// depth does not hide them.
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let shadow = frame.scene.shadow();
        let opacity = shadow.opacity.as_ref().expect("translucent shadows are listed with their map");
        let depth = shadow.depth.create_view(&Default::default());
        let view = opacity.create_view(&Default::default());
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("translucent shadows pass"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)))],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let pipeline = gpu.pipeline("translucent shadows".into(), |gpu| {
            let constants = Features::default().constants();
            gpu.mesh_pipeline(&pipeline(&super::mesh_module(gpu), &constants))
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &shadow.bind_group, &[]);
        for caster in &shadow.casters {
            pass.set_vertex_buffer(0, caster.positions.slice(..));
            pass.set_vertex_buffer(1, caster.opacity.slice(..));
            pass.set_index_buffer(caster.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..caster.count, 0, 0..1);
        }
    }
}
