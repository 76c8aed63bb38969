//! The passes of a frame, one module each, in the order `crate::graph::ordered_passes` gives:
//! `shadow` (the key light's depth), `translucent` (the translucent casters' opacity),
//! `tsd_prepass`, `light_map` and `blur` (texture-space diffusion, with what they share in
//! `tsd`), then `base`. Each module owns its WGSL (beside it), the resources it allocates,
//! its pipeline and how it encodes itself; `Gpu::encode_pass` is the one place a
//! [`PassKind`] is dispatched to its pass.
//!
//! The mesh passes share one uniform block (`uniforms`): a part every pass reads, then one
//! named struct per pass, declared beside it.
//!
//! The mesh passes share one shader module, [`BASE_WGSL`], assembled here from `common.wgsl` and
//! each pass's file (one module compiled once per device, its pipelines differing by entry point
//! and override constants); the blur is a full-screen pass with its own module, [`BLUR_WGSL`].

pub(crate) mod base;
pub(crate) mod blur;
pub(crate) mod light_map;
pub(crate) mod shadow;
pub(crate) mod translucent;
pub(crate) mod tsd;
pub(crate) mod tsd_prepass;
pub(crate) mod uniforms;

pub use uniforms::{UNIFORM_BYTES, UniformLayout, uniform_layouts};

use crate::gpu::{Gpu, PipelineKey, PreparedScene, Target};
use crate::graph::PassKind;

/// The WGSL source of the mesh passes: the closed-form LUT fits, the shared part, then each
/// pass's file in graph order.
pub const BASE_WGSL: &str = concat!(
    include_str!("../../shaders/skin_fit.wgsl"),
    "\n",
    include_str!("common.wgsl"),
    "\n",
    include_str!("shadow.wgsl"),
    "\n",
    include_str!("translucent.wgsl"),
    "\n",
    include_str!("tsd.wgsl"),
    "\n",
    include_str!("tsd_prepass.wgsl"),
    "\n",
    include_str!("light_map.wgsl"),
    "\n",
    include_str!("base.wgsl"),
);

/// The WGSL source of texture-space diffusion's Poisson blur.
pub const BLUR_WGSL: &str = include_str!("blur.wgsl");

impl Gpu {
    /// Encodes one pass of the graph.
    pub(crate) fn encode_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kind: PassKind,
        scene: &PreparedScene,
        target: &Target,
        writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let shadow = || scene.shadow.as_ref().expect("a shadow pass is listed only with its shadow map");
        let tsd = || scene.tsd.as_ref().expect("a TSD pass is listed only with its light maps");
        match kind {
            PassKind::ShadowMap => self.encode_shadow(encoder, scene, shadow(), writes),
            PassKind::TranslucentShadows => {
                let opacity = shadow().opacity.as_ref().expect("translucent shadows are listed with their map");
                self.encode_translucent(encoder, shadow(), opacity, writes);
            }
            PassKind::TsdPrepass => self.encode_tsd_prepass(encoder, scene, tsd(), writes),
            PassKind::TsdLightMap => self.encode_light_map(encoder, scene, tsd(), writes),
            PassKind::TsdBlur(i) => self.encode_blur(encoder, tsd(), i as usize, writes),
            PassKind::Base => self.encode_base(encoder, scene, target, writes),
        }
    }
}

/// Builds the pipeline of `key`: the one place a pipeline key is dispatched to its pass.
pub(crate) fn build_pipeline(gpu: &Gpu, key: PipelineKey) -> wgpu::RenderPipeline {
    match key {
        PipelineKey::Base(format, features) => gpu.mesh_pipeline(&base::pipeline(format, features)),
        PipelineKey::Shadow => gpu.mesh_pipeline(&shadow::pipeline()),
        PipelineKey::Translucent => gpu.mesh_pipeline(&translucent::pipeline()),
        PipelineKey::TsdPrepass(features) => gpu.mesh_pipeline(&tsd_prepass::pipeline(features)),
        PipelineKey::LightMap(features) => gpu.mesh_pipeline(&light_map::pipeline(features, gpu.light_map_format())),
        PipelineKey::Blur => blur::pipeline(gpu),
    }
}
