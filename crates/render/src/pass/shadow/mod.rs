//! The key light's shadow map (`shadow.wgsl`): the mesh's depth seen from the light, and the
//! filtered lookup the base and light-map passes read it with.

use std::sync::Arc;

use super::resources::Resources;
use super::setup::{Features, ShadowSetup};
use super::{Context, Described, FrameEncoder, Pass, PassState, Shape, Upload};
use crate::gpu::{Gpu, MeshPipeline, POSITION_BUFFER, depth_state};

/// The key light's depth, as the passes after this one read it.
pub(crate) const SHADOW_MAP: &str = "shadow map";

/// The shadow map pass, drawn when the key light casts shadows.
struct ShadowMap;

/// The shadow map's pass, when `shape` draws one.
pub(crate) fn passes(shape: &Shape) -> Vec<Arc<dyn Pass>> {
    match shape.shadow_map {
        true => vec![Arc::new(ShadowMap)],
        false => Vec::new(),
    }
}

impl Pass for ShadowMap {
    fn name(&self) -> String {
        "shadow map".into()
    }

    fn explain(&self, context: &Context) -> Described {
        let key = context.graph.shadow.map_or(0, |s| s.light);
        Described::new(
            format!("depth of the mesh seen from light[{key}], bounding its sphere tightly"),
            &["vertices", "indices", "uniforms"],
            &[SHADOW_MAP],
        )
    }

    fn allocate(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &mut Resources) {
        let side = setup(upload).map_size;
        resources.put(SHADOW_MAP, gpu.depth_texture("shadow map", side, side, true));
    }

    /// Its bind group: one that does not sample the map it writes.
    fn prepare(&self, gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> Option<PassState> {
        Some(Box::new(upload.bind_group(gpu, resources, None, None, None)))
    }

    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>) {
        let bind_group: &wgpu::BindGroup = frame.state();
        let view = frame.scene.resources.texture_view(SHADOW_MAP);
        let mut pass = frame.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        let pipeline = gpu.pipeline("shadow map".into(), |gpu| {
            let constants = Features::default().constants();
            gpu.mesh_pipeline(&pipeline(&super::mesh_module(gpu), &constants))
        });
        pass.set_pipeline(&pipeline);
        gpu.draw_mesh(&mut pass, frame.scene, bind_group);
    }
}

/// The scene's shadow-map settings (a shadow pass is listed only with them).
pub(crate) fn setup<'a>(upload: &Upload<'a>) -> &'a ShadowSetup {
    upload.skin.shadow.as_ref().expect("a shadow pass is listed only with its settings")
}

/// The shadow map's uniforms (`ShadowUniforms` in shadow.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct ShadowUniforms {
    pub(crate) view_proj: [[f32; 4]; 4],
    pub(crate) inv_size: f32,
    pub(crate) taps: f32,
    pub(crate) texel: f32,
    pub(crate) normal_offset: f32,
    pub(crate) disc_radius: f32,
    pub(crate) pad0: f32,
    pub(crate) pad1: f32,
    pub(crate) pad2: f32,
}

/// The shadow map's uniforms; an identity placeholder without one (never read: the shadow
/// branches are compiled out).
pub(crate) fn uniforms(shadow: Option<&ShadowSetup>) -> ShadowUniforms {
    match shadow {
        Some(s) => ShadowUniforms {
            view_proj: s.view_proj.to_cols_array_2d(),
            inv_size: 1.0 / s.map_size.max(1) as f32,
            taps: s.filter as f32,
            texel: s.texel,
            normal_offset: s.bias,
            disc_radius: s.disc_radius,
            pad0: 0.0,
            pad1: 0.0,
            pad2: 0.0,
        },
        None => ShadowUniforms {
            view_proj: glam::Mat4::IDENTITY.to_cols_array_2d(),
            inv_size: 1.0,
            taps: 1.0,
            texel: 0.0,
            normal_offset: 0.0,
            disc_radius: 0.0,
            pad0: 0.0,
            pad1: 0.0,
            pad2: 0.0,
        },
    }
}

/// The shadow map's pipeline: positions only, depth only.
fn pipeline<'a>(module: &'a wgpu::ShaderModule, constants: &'a [(&'static str, f64)]) -> MeshPipeline<'a> {
    MeshPipeline {
        label: "shadow map pipeline",
        module,
        vertex_entry: "vs_shadow",
        buffers: &POSITION_BUFFER,
        fragment_entry: None,
        target: None,
        second_target: None,
        depth: depth_state(true, wgpu::CompareFunction::Less),
        constants,
    }
}
