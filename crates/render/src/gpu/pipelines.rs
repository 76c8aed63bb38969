//! The caches: every pipeline is built once per key (its pass says what the key holds: the pass,
//! its shader features, its target format) and kept for the life of the [`Gpu`], so a second
//! render of a scene builds none; shader modules and layouts likewise, by name. The passes say
//! what their pipelines are ([`MeshPipeline`]); this module builds and keeps them.

use super::{DEPTH_FORMAT, Gpu};
use crate::shading::Vertex;
use std::sync::Arc;

/// A mesh pass's pipeline in the mesh passes' shared module: its entry points, vertex buffers,
/// colour target and depth test, and the values of the module's override constants.
pub(crate) struct MeshPipeline<'a> {
    pub(crate) label: &'static str,
    /// The shader module the entry points are in.
    pub(crate) module: &'a wgpu::ShaderModule,
    pub(crate) vertex_entry: &'static str,
    pub(crate) buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub(crate) fragment_entry: Option<&'static str>,
    pub(crate) target: Option<wgpu::TextureFormat>,
    /// A second colour target (TSD's light map writes the stretch map beside it).
    pub(crate) second_target: Option<wgpu::TextureFormat>,
    pub(crate) depth: Option<wgpu::DepthStencilState>,
    /// The pipeline-overridable constants (the shader features).
    pub(crate) constants: &'a [(&'static str, f64)],
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
    /// The pipeline of `key`, built by `build` the first time it is asked for. The key names
    /// the pass and everything its pipeline depends on (features, target format).
    pub(crate) fn pipeline(
        &self,
        key: String,
        build: impl FnOnce(&Gpu) -> wgpu::RenderPipeline,
    ) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = cache.iter().find(|(k, _)| *k == key) {
            return p.clone();
        }
        let pipeline = build(self);
        cache.push((key, pipeline.clone()));
        pipeline
    }

    /// The value named `name` (a shader module, a layout), built by `build` the first time.
    pub(crate) fn shared<T: Clone + Send + Sync + 'static>(
        &self,
        name: &'static str,
        build: impl FnOnce(&Gpu) -> T,
    ) -> T {
        let mut cache = self.shared.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(value) = cache.iter().find(|(k, _)| *k == name).and_then(|(_, v)| v.downcast_ref::<T>()) {
            return value.clone();
        }
        let value = build(self);
        cache.push((name, Arc::new(value.clone())));
        value
    }

    /// The WGSL module `source`, compiled once under `name`.
    pub(crate) fn shader_module(&self, name: &'static str, source: &'static str) -> wgpu::ShaderModule {
        self.shared(name, |gpu| {
            gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(name),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            })
        })
    }

    /// Builds a mesh pass's pipeline, with the shared bind group layout.
    pub(crate) fn mesh_pipeline(&self, spec: &MeshPipeline) -> wgpu::RenderPipeline {
        let options = wgpu::PipelineCompilationOptions { constants: spec.constants, ..Default::default() };
        let targets: Vec<Option<wgpu::ColorTargetState>> = [spec.target, spec.second_target]
            .into_iter()
            .flatten()
            .map(|format| Some(wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL }))
            .collect();
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(spec.label),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: spec.module,
                entry_point: Some(spec.vertex_entry),
                compilation_options: options.clone(),
                buffers: spec.buffers,
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: spec.depth.clone(),
            multisample: Default::default(),
            fragment: spec.fragment_entry.map(|entry| wgpu::FragmentState {
                module: spec.module,
                entry_point: Some(entry),
                compilation_options: options.clone(),
                targets: &targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
