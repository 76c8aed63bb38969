//! The debug view of a mesh's texture-space frames and UV layout (`debug.wgsl`), for users
//! bringing their own heads: `effects = ["debug-frames"]` redraws the frame with the surface
//! coloured by its UV stretch (white at the mesh's median millimetres per UV unit, red where a
//! UV unit covers more skin, blue where less, a factor of 4 saturating; magenta where a triangle
//! has no UV area) over a checker of 16 cells per UV unit, mirrored UV islands hatched, and each
//! vertex's tangent (red), bitangent (green) and normal (blue) as short lines. It runs after the
//! base pass and replaces its colour; it is the book's worked example of adding an effect.

use std::sync::Arc;

use super::resources::Resources;
use super::{Context, Described, FrameEncoder, Pass, PassState, Shape, Upload, geometry};
use crate::effect::Effect;
use crate::gpu::{Gpu, OutputFormat, depth_state};
use crate::shading::Vertex;

/// The WGSL of the debug view, a module of its own.
pub const DEBUG_WGSL: &str = include_str!("debug.wgsl");

/// Checker cells per UV unit.
const CHECKER: f32 = 16.0;
/// The frame axes' length as a share of the mesh's bounding radius.
const AXIS_SHARE: f32 = 0.015;

/// The debug view's pass.
struct DebugFrames;

/// The debug view, when the scene lists `debug-frames`.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    match shape.effects.contains(&Effect::DebugFrames) {
        true => vec![Arc::new(DebugFrames)],
        false => Vec::new(),
    }
}

/// The debug view's uniforms (`DebugUniforms` in debug.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DebugUniforms {
    median_mm_per_uv: f32,
    axis_length: f32,
    checker: f32,
    pad0: f32,
}

/// What the debug view prepares for a scene: its bind group (the scene's uniform block and its
/// own) and the vertex count its axes are drawn for.
struct Prepared {
    bind_group: wgpu::BindGroup,
    vertex_count: u32,
}

impl Pass for DebugFrames {
    fn name(&self) -> String {
        "debug frames".into()
    }

    fn explain(&self, context: &Context) -> Described {
        let what = format!(
            "replaces the colour: UV stretch against the median mm per UV unit over a {CHECKER}-cell UV checker, \
             mirrored islands hatched, the tangent frames of {} vertices as lines",
            context.inputs.vertices.len()
        );
        Described::new(what, &["vertices", "indices", "uniforms"], &["colour target", "depth"])
    }

    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, _: &Resources) -> Option<PassState> {
        let inputs = upload.inputs;
        let raw = DebugUniforms {
            median_mm_per_uv: median_mm_per_uv(&inputs.vertices, &inputs.indices, upload.skin.mm_per_unit),
            axis_length: AXIS_SHARE * geometry::bounding_sphere(&inputs.vertices).1,
            checker: CHECKER,
            pad0: 0.0,
        };
        let buffer = gpu.buffer("debug frames uniforms", bytemuck::bytes_of(&raw), wgpu::BufferUsages::UNIFORM);
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("debug frames bind group"),
            layout: &layout(gpu),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: upload.uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: buffer.as_entire_binding() },
            ],
        });
        Some(Box::new(Prepared { bind_group, vertex_count: inputs.vertices.len() as u32 }))
    }

    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let prepared: &Prepared = frame.state();
        let (scene, target) = (frame.scene, frame.target);
        let format = target.format;
        let surface = gpu.pipeline(format!("debug frames surface {format:?}"), |gpu| pipeline(gpu, format, false));
        let axes = gpu.pipeline(format!("debug frames axes {format:?}"), |gpu| pipeline(gpu, format, true));
        let mut pass = super::target_pass(frame.encoder, "debug frames", target, scene.background, writes);
        pass.set_bind_group(0, &prepared.bind_group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_pipeline(&surface);
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..scene.index_count, 0, 0..1);
        // Six line-list vertices per mesh vertex, the mesh's vertex buffer stepped per instance.
        pass.set_pipeline(&axes);
        pass.draw(0..6, 0..prepared.vertex_count);
    }
}

/// The median over the vertices of their millimetres per UV unit ([`geometry::uv_stretch`]);
/// 0 for a mesh with none.
fn median_mm_per_uv(vertices: &[Vertex], indices: &[u32], mm_per_unit: f32) -> f32 {
    let mut stretch: Vec<f32> =
        geometry::uv_stretch(vertices, indices, mm_per_unit).into_iter().filter(|s| s.is_finite()).collect();
    if stretch.is_empty() {
        return 0.0;
    }
    let middle = stretch.len() / 2;
    *stretch.select_nth_unstable_by(middle, f32::total_cmp).1
}

/// The debug view's bindings (built once per device): the scene's uniform block, its own.
fn layout(gpu: &Gpu) -> wgpu::BindGroupLayout {
    let entry = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    gpu.shared("debug frames bind group layout", |gpu| {
        gpu.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("debug frames bind group layout"),
            entries: &[
                entry(0, wgpu::BufferBindingType::Storage { read_only: true }),
                entry(1, wgpu::BufferBindingType::Uniform),
            ],
        })
    })
}

const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2];

/// The surface's pipeline (triangles, depth written) or the axes' (lines over the mesh's
/// vertices per instance, depth tested against the surface's).
fn pipeline(gpu: &Gpu, format: OutputFormat, axes: bool) -> wgpu::RenderPipeline {
    let module = gpu.shader_module("debug.wgsl", DEBUG_WGSL);
    let layout = gpu.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("debug frames layout"),
        bind_group_layouts: &[Some(&layout(gpu))],
        immediate_size: 0,
    });
    let step_mode = if axes { wgpu::VertexStepMode::Instance } else { wgpu::VertexStepMode::Vertex };
    let buffers = [wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode,
        attributes: &VERTEX_ATTRIBUTES,
    }];
    let (vertex, fragment, topology) = match axes {
        true => ("vs_debug_axes", "fs_debug_axes", wgpu::PrimitiveTopology::LineList),
        false => ("vs_debug_surface", "fs_debug_surface", wgpu::PrimitiveTopology::TriangleList),
    };
    let targets = [Some(wgpu::ColorTargetState {
        format: format.texture_format(),
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })];
    gpu.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(if axes { "debug frames axes pipeline" } else { "debug frames surface pipeline" }),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: &[Some(buffers[0].clone())],
        },
        primitive: wgpu::PrimitiveState { topology, cull_mode: None, ..Default::default() },
        depth_stencil: depth_state(!axes, wgpu::CompareFunction::LessEqual),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(fragment),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vertex(position: [f32; 3], uv: [f32; 2]) -> Vertex {
        Vertex { position, normal: [0.0, 0.0, 1.0], tangent: [1.0, 0.0, 0.0, 1.0], uv }
    }

    #[test]
    fn the_median_stretch_is_the_square_root_of_area_over_uv_area() {
        // A 4 x 4 mm square mapped to half the UV square: 4 mm over 0.5 UV units = 8 mm a UV unit.
        let vertices = [
            vertex([0.0; 3], [0.0; 2]),
            vertex([4.0, 0.0, 0.0], [0.5, 0.0]),
            vertex([4.0, 4.0, 0.0], [0.5, 0.5]),
            vertex([0.0, 4.0, 0.0], [0.0, 0.5]),
        ];
        let median = median_mm_per_uv(&vertices, &[0, 1, 2, 0, 2, 3], 1.0);
        assert!((median - 8.0).abs() < 1e-5, "{median}");
        assert!((median_mm_per_uv(&vertices, &[0, 1, 2, 0, 2, 3], 10.0) - 80.0).abs() < 1e-3);
    }

    #[test]
    fn a_mesh_without_triangles_has_a_finite_median() {
        let median = median_mm_per_uv(&[vertex([0.0; 3], [0.0; 2])], &[], 1.0);
        assert!(median.is_finite());
        assert_eq!(median_mm_per_uv(&[], &[], 1.0), 0.0);
    }
}
