//! The pipeline cache: every pipeline is built once per key (pass, features, target format) and
//! kept for the life of the [`Gpu`], so a second render of a scene builds none.

use super::{DEPTH_FORMAT, Gpu, LIGHT_MAP_FORMAT, OutputFormat};
use crate::passes::Features;
use crate::shading::Vertex;

/// Which pipeline: the base pass for an output format and features, or one of the skin passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum PipelineKey {
    Base(OutputFormat, Features),
    Shadow,
    Translucent,
    TsdPrepass(Features),
    LightMap(Features),
    Blur,
}

impl Gpu {
    /// The pipeline for `key`, built once.
    pub(crate) fn pipeline(&self, key: PipelineKey) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = cache.iter().find(|(k, _)| *k == key) {
            return p.clone();
        }
        let pipeline = self.build_pipeline(key);
        cache.push((key, pipeline.clone()));
        pipeline
    }

    fn build_pipeline(&self, key: PipelineKey) -> wgpu::RenderPipeline {
        if key == PipelineKey::Blur {
            return self.build_blur_pipeline();
        }
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2
        ];
        let skin_attributes = wgpu::vertex_attr_array![4 => Float32x2];
        let position_only =
            [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }];
        let stride = std::mem::size_of::<Vertex>() as u64;
        let step_mode = wgpu::VertexStepMode::Vertex;
        let full_buffers = [
            Some(wgpu::VertexBufferLayout { array_stride: stride, step_mode, attributes: &attributes }),
            Some(wgpu::VertexBufferLayout { array_stride: 8, step_mode, attributes: &skin_attributes }),
        ];
        let shadow_buffers =
            [Some(wgpu::VertexBufferLayout { array_stride: stride, step_mode, attributes: &position_only })];
        let translucent_position = wgpu::vertex_attr_array![0 => Float32x3];
        let translucent_opacity = wgpu::vertex_attr_array![1 => Float32x3];
        let translucent_buffers = [
            Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode, attributes: &translucent_position }),
            Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode, attributes: &translucent_opacity }),
        ];
        let features = match key {
            PipelineKey::Base(_, f) | PipelineKey::TsdPrepass(f) | PipelineKey::LightMap(f) => f,
            PipelineKey::Shadow | PipelineKey::Translucent | PipelineKey::Blur => Features::default(),
        };
        let constants = features.constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
        let depth = |write: bool, compare| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            })
        };
        let (label, vertex_entry, buffers, fragment, target, depth_stencil): (_, _, &[_], _, _, _) = match key {
            PipelineKey::Base(format, _) => (
                "base pass pipeline",
                "vs_main",
                &full_buffers,
                Some("fs_main"),
                Some(format.texture_format()),
                depth(true, wgpu::CompareFunction::Less),
            ),
            PipelineKey::Shadow => (
                "shadow map pipeline",
                "vs_shadow",
                &shadow_buffers,
                None,
                None,
                depth(true, wgpu::CompareFunction::Less),
            ),
            PipelineKey::Translucent => (
                "translucent shadows pipeline",
                "vs_translucent",
                &translucent_buffers,
                Some("fs_translucent"),
                Some(LIGHT_MAP_FORMAT),
                depth(false, wgpu::CompareFunction::Less),
            ),
            PipelineKey::TsdPrepass(_) => (
                "tsd back-face pre-pass pipeline",
                "vs_texture_space",
                &full_buffers,
                Some("fs_tsd_prepass"),
                None,
                depth(true, wgpu::CompareFunction::Always),
            ),
            PipelineKey::LightMap(_) => (
                "tsd light map pipeline",
                "vs_texture_space",
                &full_buffers,
                Some("fs_light_map"),
                Some(LIGHT_MAP_FORMAT),
                depth(false, wgpu::CompareFunction::Equal),
            ),
            PipelineKey::Blur => unreachable!("built above"),
        };
        let targets =
            [target.map(|format| wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let targets: &[Option<wgpu::ColorTargetState>] = if target.is_some() { &targets } else { &[] };
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some(vertex_entry),
                compilation_options: options.clone(),
                buffers,
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil,
            multisample: Default::default(),
            fragment: fragment.map(|entry| wgpu::FragmentState {
                module: &self.shader,
                entry_point: Some(entry),
                compilation_options: options.clone(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}
