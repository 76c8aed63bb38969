//! The passes of a frame, one folder each with its WGSL beside it, each a `Pass`: what it is
//! called, what it explains of itself for `--explain`, and how it encodes itself. `PassList::of`
//! is the one list of them, in frame order: `shadow` (the key light's depth), `translucent` (the
//! translucent casters' opacity), `tsd_prepass`, `light_map` and `blur` (texture-space diffusion,
//! with what they share in `tsd`), then `base`. The graph ([`graph::PassGraph`]), the frame's
//! encoder (`frame`), its timestamps and `--explain` ([`explain::plan`]) all walk that list, and
//! no other type names the passes. What one pass writes and a later one reads (the shadow map,
//! TSD's light maps) is allocated by its writer into a registry by name (`resources`), so no
//! central type holds a pass's textures either. The book's "Adding an effect" walks through
//! adding one.
//!
//! Around the passes: what a scene's effects decide ([`graph`]), what they hand the GPU
//! ([`setup`], made by [`build`]), the geometry they need ([`geometry`]), the scene's textures and
//! the bind group they share (`textures`), the uniform block (`uniforms`: a part every pass reads,
//! then one struct per pass), and a scene's upload and the frame's encoder (`frame`).
//!
//! The mesh passes share one shader module, [`BASE_WGSL`], assembled here from `common.wgsl` and
//! each pass's file (one module compiled once per device, its pipelines differing by entry point
//! and override constants); the blur is a full-screen pass with its own module, [`BLUR_WGSL`].

pub(crate) mod base;
pub(crate) mod blur;
pub mod build;
mod debug;
pub mod explain;
mod frame;
pub mod geometry;
pub mod graph;
pub(crate) mod light_map;
mod resources;
pub mod setup;
pub(crate) mod shadow;
mod textures;
pub(crate) mod translucent;
pub(crate) mod tsd;
pub(crate) mod tsd_prepass;
pub(crate) mod uniforms;

use std::any::Any;
use std::sync::Arc;

pub use debug::DEBUG_WGSL;
pub use uniforms::{UNIFORM_BYTES, UniformLayout, uniform_layouts};

use crate::effect::Effect;
use crate::gpu::{Gpu, Target};
use crate::scene::Scene;
use crate::shading::RenderInputs;
use graph::PassGraph;
use resources::Resources;
use setup::{Features, SkinSetup};
use textures::SceneTextures;

/// The WGSL source of the mesh passes: the closed-form LUT fits, the shared part, then each
/// pass's file in frame order.
pub const BASE_WGSL: &str = concat!(
    include_str!("../../shaders/skin_fit.wgsl"),
    "\n",
    include_str!("common.wgsl"),
    "\n",
    include_str!("shadow/shadow.wgsl"),
    "\n",
    include_str!("translucent/translucent.wgsl"),
    "\n",
    include_str!("tsd/tsd.wgsl"),
    "\n",
    include_str!("tsd_prepass/tsd_prepass.wgsl"),
    "\n",
    include_str!("light_map/light_map.wgsl"),
    "\n",
    include_str!("base/base.wgsl"),
);

/// The WGSL source of texture-space diffusion's Poisson blur.
pub const BLUR_WGSL: &str = include_str!("blur/blur.wgsl");

/// The mesh passes' shader module ([`BASE_WGSL`]), compiled once per device.
pub(crate) fn mesh_module(gpu: &Gpu) -> wgpu::ShaderModule {
    gpu.shader_module("mesh passes (pass::BASE_WGSL)", BASE_WGSL)
}

/// One pass of a frame.
pub(crate) trait Pass: Send + Sync {
    /// Its name, as `--explain` and the GPU timings print it.
    fn name(&self) -> String;

    /// What it does, reads and writes, for `--explain`.
    fn explain(&self, context: &Context) -> Described;

    /// Whether it runs this frame (by default always; texture-space diffusion's passes skip
    /// together when the head is off screen or small enough to reuse an earlier light map).
    fn runs(&self, _scene: &PreparedScene, _target: &Target) -> bool {
        true
    }

    /// Creates what this pass writes that later passes read, once per scene, under the names
    /// `--explain` gives them ([`Resources`]; by default nothing). Every pass allocates before
    /// any prepares.
    fn allocate(&self, _gpu: &Gpu, _upload: &Upload<'_>, _resources: &mut Resources) {}

    /// Uploads what this pass alone draws with, once per scene, reading what earlier passes
    /// allocated from `resources` (by default nothing). The frame hands it back to
    /// [`Pass::encode`] ([`FrameEncoder::state`]).
    fn prepare(&self, _gpu: &Gpu, _upload: &Upload<'_>, _resources: &Resources) -> Option<PassState> {
        None
    }

    /// Records the pass into the frame's encoder.
    fn encode(&self, gpu: &Gpu, frame: &mut FrameEncoder<'_>, writes: Option<wgpu::RenderPassTimestampWrites<'_>>);
}

/// A render pass into the frame's target: its colour cleared to `background`, its depth cleared
/// and discarded at the end (the passes that draw the target, the base pass and the debug view).
pub(crate) fn target_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    label: &'static str,
    target: &Target,
    background: [f32; 4],
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    let target_view = target.color.create_view(&Default::default());
    let depth_view = target.depth.create_view(&Default::default());
    let [r, g, b, a] = background.map(f64::from);
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some(label),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &target_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

/// What a pass prepared for one scene ([`Pass::prepare`]), kept beside the scene.
pub(crate) type PassState = Box<dyn Any + Send + Sync>;

/// What a pass prepares itself from: the scene's inputs and setup, its uniform block, and the
/// textures and samplers every mesh pass binds.
pub(crate) struct Upload<'a> {
    pub(crate) inputs: &'a RenderInputs,
    pub(crate) skin: &'a SkinSetup,
    pub(crate) uniforms: &'a wgpu::Buffer,
    pub(crate) textures: &'a SceneTextures,
}

impl Upload<'_> {
    /// The mesh passes' bind group with the scene's textures and, of what earlier passes wrote,
    /// those named (`None`: a placeholder, as for a pass that writes that texture itself).
    pub(crate) fn bind_group(
        &self,
        gpu: &Gpu,
        resources: &Resources,
        shadow: Option<&str>,
        opacity: Option<&str>,
        light_map: Option<&str>,
    ) -> wgpu::BindGroup {
        let view = |name: Option<&str>| name.and_then(|n| resources.view(n));
        let (shadow, opacity, light_map) = (view(shadow), view(opacity), view(light_map));
        gpu.create_bind_group(self.textures, self.uniforms, shadow.as_ref(), opacity.as_ref(), light_map.as_ref())
    }
}

/// What a pass encodes into: the frame's command encoder, the scene it draws and its target,
/// and what the pass prepared for the scene.
pub(crate) struct FrameEncoder<'a> {
    pub(crate) encoder: &'a mut wgpu::CommandEncoder,
    pub(crate) scene: &'a PreparedScene,
    pub(crate) target: &'a Target,
    pub(crate) state: Option<&'a (dyn Any + Send + Sync)>,
}

impl<'a> FrameEncoder<'a> {
    /// What this pass prepared ([`Pass::prepare`]), as the type it prepared.
    pub(crate) fn state<T: 'static>(&self) -> &'a T {
        self.state.and_then(|s| s.downcast_ref::<T>()).expect("a pass reads the state it prepared")
    }
}

/// What a pass explains itself from.
pub(crate) struct Context<'a> {
    pub(crate) scene: &'a Scene,
    pub(crate) inputs: &'a RenderInputs,
    pub(crate) graph: &'a PassGraph,
}

/// What a pass does, reads and writes (resource names of [`explain::Plan::resources`]).
pub(crate) struct Described {
    pub(crate) what: String,
    pub(crate) reads: Vec<String>,
    pub(crate) writes: Vec<String>,
}

impl Described {
    /// A pass doing `what`, reading and writing the resources named.
    pub(crate) fn new(what: impl Into<String>, reads: &[&str], writes: &[&str]) -> Described {
        let names = |list: &[&str]| list.iter().map(|s| s.to_string()).collect();
        Described { what: what.into(), reads: names(reads), writes: names(writes) }
    }
}

/// What decides which passes a frame runs; a scene's graph and a setup give the same one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Shape {
    /// The key light's shadow map is drawn.
    pub(crate) shadow_map: bool,
    /// ... with translucent casters.
    pub(crate) translucent: bool,
    /// Texture-space diffusion runs, with this many blurs.
    pub(crate) tsd_blurs: Option<u32>,
    /// The scene's effects (for passes that only an effect adds, as the debug view).
    pub(crate) effects: Vec<Effect>,
}

/// What a pass module adds to a frame of a given shape (none, one, or several of its passes).
type PassesOf = fn(&Shape) -> Vec<Arc<dyn Pass>>;

/// The passes each pass module adds for a shape, in frame order: the one list of passes.
const PASSES: [PassesOf; 7] = [
    shadow::passes,
    translucent::passes,
    tsd_prepass::passes,
    light_map::passes,
    blur::passes,
    base::passes,
    debug::passes,
];

/// A frame's passes, in the order they run.
#[derive(Clone)]
pub struct PassList(pub(crate) Vec<Arc<dyn Pass>>);

impl PassList {
    /// The passes of `shape`, in frame order.
    pub(crate) fn of(shape: &Shape) -> PassList {
        PassList(PASSES.iter().flat_map(|passes| passes(shape)).collect())
    }

    /// Their names, in order.
    pub fn names(&self) -> Vec<String> {
        self.0.iter().map(|p| p.name()).collect()
    }

    /// How many passes run.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether there are none (never for a frame: the base pass always runs).
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl std::fmt::Debug for PassList {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_list().entries(self.names()).finish()
    }
}

impl PartialEq for PassList {
    fn eq(&self, other: &Self) -> bool {
        self.names() == other.names()
    }
}

impl serde::Serialize for PassList {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.names())
    }
}

/// A scene uploaded to the GPU by [`Gpu::prepare`], ready for [`Gpu::draw`].
pub struct PreparedScene {
    pub(crate) globals: uniforms::Globals,
    pub(crate) uniforms: wgpu::Buffer,
    pub(crate) vertices: wgpu::Buffer,
    pub(crate) vertex_skin: wgpu::Buffer,
    pub(crate) indices: wgpu::Buffer,
    pub(crate) index_count: u32,
    pub(crate) background: [f32; 4],
    pub(crate) features: Features,
    /// The passes [`Gpu::draw`] runs, in order ([`setup::SkinSetup::passes`]).
    pub(crate) passes: PassList,
    /// What each pass prepared, in the order of `passes`.
    pub(crate) states: Vec<Option<PassState>>,
    pub(crate) bounds: (glam::Vec3, f32),
    /// What the passes wrote for later passes to read, by name.
    pub(crate) resources: Resources,
}

impl PreparedScene {
    /// The shader features this scene's passes were compiled with.
    pub fn features(&self) -> Features {
        self.features
    }

    /// The passes [`Gpu::draw`] runs for this scene, in order.
    pub fn passes(&self) -> &PassList {
        &self.passes
    }

    /// Their names.
    pub fn pass_names(&self) -> Vec<String> {
        self.passes.names()
    }

    /// The names of the textures the passes allocated for later passes to read, in the order
    /// they did (the names `--explain` gives those resources).
    pub fn resource_names(&self) -> Vec<&'static str> {
        self.resources.texture_names()
    }

    /// Moves the camera: the next [`Gpu::draw`] uses `camera` (nothing is re-uploaded but the
    /// uniform block, which every draw writes anyway).
    pub(crate) fn set_camera(&mut self, camera: &crate::shading::Camera) {
        self.globals.scene.view_proj = camera.view_proj.to_cols_array_2d();
        self.globals.scene.eye = camera.eye.to_array();
    }

    /// Sets the tone curve of the next [`Gpu::draw`] (the target's format may still impose one).
    pub(crate) fn set_tone(&mut self, tone: crate::shading::ToneCurve) {
        self.globals.base.tone = base::tone_code(tone);
    }

    /// Replaces light `index` (below the scene's light count) for the next [`Gpu::draw`].
    pub fn set_light(&mut self, index: usize, light: &crate::shading::Light) {
        if index < self.globals.scene.light_count as usize {
            self.globals.scene.lights[index] = uniforms::light_raw(light);
        }
    }
}
