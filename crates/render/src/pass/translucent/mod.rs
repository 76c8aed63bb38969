//! Translucent shadows (`translucent.wgsl`, Gosselin et al.): the translucent casters' summed
//! opacity seen from the key light, tested against the shadow map's depth.

use std::sync::Arc;

use super::resources::Resources;
use super::setup::Features;
use super::shadow::{self, SHADOW_MAP};
use super::{Context, Described, FrameEncoder, Pass, PassState, Shape, Upload};
use crate::gpu::{Gpu, MeshPipeline, OPACITY_FORMAT, colour_attachment, depth_state, extent};

/// The translucent casters' summed opacity, as the passes after this one read it.
pub(crate) const SHADOW_OPACITY: &str = "shadow opacity";

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

const VERTEX: wgpu::BufferUsages = wgpu::BufferUsages::VERTEX;

/// One translucent caster's positions, per-vertex opacity and indices.
struct CasterBuffers {
    positions: wgpu::Buffer,
    opacity: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// What the translucent pass draws with: its bind group and the casters.
struct Prepared {
    bind_group: wgpu::BindGroup,
    casters: Vec<CasterBuffers>,
}

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
            &["uniforms", SHADOW_MAP],
            &[SHADOW_OPACITY],
        )
    }

    fn allocate(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &mut Resources) {
        let side = shadow::setup(upload).map_size;
        let opacity = gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow opacity"),
            size: extent(side, side),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: OPACITY_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        resources.put(SHADOW_OPACITY, opacity);
    }

    /// The casters' buffers (those with a valid triangle list) and a bind group that samples
    /// neither the shadow map nor the opacity being written.
    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        let casters = shadow::setup(upload)
            .translucent
            .iter()
            .filter(|c| !c.indices.is_empty() && c.indices.iter().all(|&i| (i as usize) < c.positions.len()))
            .map(|c| CasterBuffers {
                positions: gpu.buffer("translucent positions", bytemuck::cast_slice(&c.positions), VERTEX),
                opacity: gpu.buffer(
                    "translucent opacity",
                    bytemuck::cast_slice(&vec![c.opacity; c.positions.len()]),
                    VERTEX,
                ),
                indices: gpu.buffer("translucent indices", bytemuck::cast_slice(&c.indices), wgpu::BufferUsages::INDEX),
                count: c.indices.len() as u32,
            })
            .collect();
        Some(Box::new(Prepared { bind_group: upload.bind_group(gpu, resources, None, None, None), casters }))
    }

    /// Translucent casters into the opacity channels: cleared to 0, added up where the opaque
    /// depth does not hide them.
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let prepared: &Prepared = frame.state();
        let resources = &frame.scene.resources;
        let depth = resources.texture_view(SHADOW_MAP);
        let view = resources.texture_view(SHADOW_OPACITY);
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
        pass.set_bind_group(0, &prepared.bind_group, &[]);
        for caster in &prepared.casters {
            pass.set_vertex_buffer(0, caster.positions.slice(..));
            pass.set_vertex_buffer(1, caster.opacity.slice(..));
            pass.set_index_buffer(caster.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..caster.count, 0, 0..1);
        }
    }
}
