//! The pipeline cache: every pipeline is built once per key (pass, features, target format) and
//! kept for the life of the [`Gpu`], so a second render of a scene builds none. The passes say
//! what their pipelines are ([`MeshPipeline`]); this module builds them.

use super::{DEPTH_FORMAT, Gpu, OutputFormat};
use crate::passes::Features;
use crate::shading::Vertex;

/// Which pipeline: a pass, with the shader features and target format it is built for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PipelineKey {
    Base(OutputFormat, Features),
    Shadow,
    Translucent,
    TsdPrepass(Features),
    LightMap(Features),
    Blur,
}

/// A mesh pass's pipeline in the shared module ([`crate::pass::BASE_WGSL`]): its entry points,
/// vertex buffers, colour target and depth test, and the features its override constants take.
pub(crate) struct MeshPipeline<'a> {
    pub(crate) label: &'static str,
    pub(crate) vertex_entry: &'static str,
    pub(crate) buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub(crate) fragment_entry: Option<&'static str>,
    pub(crate) target: Option<wgpu::TextureFormat>,
    /// A second colour target (TSD's light map writes the stretch map beside it).
    pub(crate) second_target: Option<wgpu::TextureFormat>,
    pub(crate) depth: Option<wgpu::DepthStencilState>,
    pub(crate) features: Features,
}

const STRIDE: u64 = std::mem::size_of::<Vertex>() as u64;
const MESH_ATTRIBUTES: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
    0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2
];
const SKIN_ATTRIBUTES: [wgpu::VertexAttribute; 1] = wgpu::vertex_attr_array![4 => Float32x2];
const POSITION_ATTRIBUTE: [wgpu::VertexAttribute; 1] =
    [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }];

/// The mesh's two vertex buffers: [`Vertex`] and the per-vertex skin attributes (1/r, mm per UV).
pub(crate) const MESH_BUFFERS: [Option<wgpu::VertexBufferLayout<'static>>; 2] = [
    Some(wgpu::VertexBufferLayout {
        array_stride: STRIDE,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &MESH_ATTRIBUTES,
    }),
    Some(wgpu::VertexBufferLayout {
        array_stride: 8,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &SKIN_ATTRIBUTES,
    }),
];

/// Only the positions of the mesh's vertex buffer.
pub(crate) const POSITION_BUFFER: [Option<wgpu::VertexBufferLayout<'static>>; 1] = [Some(wgpu::VertexBufferLayout {
    array_stride: STRIDE,
    step_mode: wgpu::VertexStepMode::Vertex,
    attributes: &POSITION_ATTRIBUTE,
})];

/// A depth test against [`DEPTH_FORMAT`], writing the depth or not.
pub(crate) fn depth_state(write: bool, compare: wgpu::CompareFunction) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

impl Gpu {
    /// The pipeline for `key`, built once.
    pub(crate) fn pipeline(&self, key: PipelineKey) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = cache.iter().find(|(k, _)| *k == key) {
            return p.clone();
        }
        let pipeline = crate::pass::build_pipeline(self, key);
        cache.push((key, pipeline.clone()));
        pipeline
    }

    /// Builds a mesh pass's pipeline in the shared module, with the shared bind group layout.
    pub(crate) fn mesh_pipeline(&self, spec: &MeshPipeline) -> wgpu::RenderPipeline {
        let constants = spec.features.constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
        let targets: Vec<Option<wgpu::ColorTargetState>> = [spec.target, spec.second_target]
            .into_iter()
            .flatten()
            .map(|format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL }))
            .collect();
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(spec.label),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some(spec.vertex_entry),
                compilation_options: options.clone(),
                buffers: spec.buffers,
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: spec.depth.clone(),
            multisample: Default::default(),
            fragment: spec.fragment_entry.map(|entry| wgpu::FragmentState {
                module: &self.shader,
                entry_point: Some(entry),
                compilation_options: options.clone(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
