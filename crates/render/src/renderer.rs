//! The renderer's front door (issue 38): the one place that wires load, pass graph, skin set-up,
//! upload, draw and read back.
//!
//! A [`Renderer`] owns the device (shader modules, the pipeline cache, the tables cached by their
//! parameters); [`Renderer::prepare`] loads a [`Scene`] once into a [`Prepared`] value, checked
//! against a memory limit before anything is allocated, which can explain itself
//! ([`Prepared::explanation`], what `skinkit render --explain` prints) and draws frames returned in
//! memory ([`Renderer::draw`]), linear or display-encoded ([`Encoding`]: the tone curve is decided
//! here and nowhere else). The CLI, the viewer, the demo's figures, the accuracy run and the
//! benchmarks all go through it.
//!
//! ```no_run
//! use skinkit_render::renderer::{Encoding, FrameOptions, Renderer};
//! use skinkit_render::scene::Scene;
//!
//! let scene = Scene::load("samples/scenes/head.toml".as_ref())?;
//! let renderer = Renderer::new()?;
//! let options = FrameOptions::new(640, 480, Encoding::Display);
//! let mut prepared = renderer.prepare(&scene, &options)?;
//! let frame = renderer.draw(&mut prepared, &scene.cameras[0])?;
//! assert_eq!(frame.srgb_bytes.len(), 4 * 640 * 480);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::time::{Duration, Instant};

use crate::compare::Method;
use crate::gpu::{Gpu, OutputFormat, Target};
use crate::load::{self, LoadError, Loaded};
use crate::pass::explain;
use crate::pass::graph::PassGraph;
use crate::pass::setup::SkinSetup;
use crate::pass::{self, PreparedScene};
use crate::scene::{self, Scene};
use crate::shading::{Light, RenderInputs, ToneCurve};

pub use crate::gpu::Rendered as Frame;
/// What the front door's callers need of the layers behind it: the device's errors, the
/// headless loader's quieting, a plan as `--explain` prints it, a turntable's cameras.
pub use crate::gpu::{GpuError, quiet_vulkan_loader};
pub use crate::load::orbit;
pub use crate::pass::explain::Plan;

/// Largest texture side assumed by [`explain`] when no device is given (WebGPU's default).
pub const OFFLINE_TEXTURE_SIDE: u32 = 8192;

/// What can go wrong preparing or drawing a scene.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// The scene's mesh or maps could not be loaded, or a table could not be built.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// The device refused or failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The frame would take more memory than the limit allows.
    #[error(transparent)]
    Memory(#[from] skinkit_maps::Error),
}

/// Result alias for this module.
pub type Result<T, E = RenderError> = std::result::Result<T, E>;

/// How a frame's pixels come back: the one place that decides the tone curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Linear radiance, f32 RGBA, no tone curve (for EXR and measurements).
    Linear,
    /// Tone mapped (Reinhard, so highlights roll off instead of clipping) and sRGB encoded in
    /// 8 bits (for PNG and the screen).
    Display,
}

impl Encoding {
    /// The encoding of an output file format: PNG is for display, EXR stays linear.
    pub fn for_output(format: scene::OutputFormat) -> Encoding {
        match format {
            scene::OutputFormat::Png => Encoding::Display,
            scene::OutputFormat::Exr => Encoding::Linear,
        }
    }

    /// The target format and tone curve of this encoding.
    fn target(self) -> (OutputFormat, ToneCurve) {
        match self {
            Encoding::Display => (OutputFormat::Srgb8, ToneCurve::Reinhard),
            Encoding::Linear => (OutputFormat::Hdr32, ToneCurve::None),
        }
    }
}

/// How the diffuse light and the scene's effects are drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Shading {
    /// The scene's own effects, through its pass graph.
    #[default]
    Scene,
    /// One of the skin methods compared in [`crate::compare`] (its effects replace the
    /// scene's; [`Method::Reference`] bakes the exact light map on the CPU).
    Method(Method),
    /// The base pass alone: Lambert diffuse, no shadows, no tables (the cost baseline).
    Plain,
}

/// The size, encoding, shading and memory limit of a scene's frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameOptions {
    /// Frame width, pixels.
    pub width: u32,
    /// Frame height, pixels.
    pub height: u32,
    /// Linear or display-encoded pixels.
    pub encoding: Encoding,
    /// What draws the diffuse light.
    pub shading: Shading,
    /// Bytes a frame may take on the device and the host (`OutputFormat::frame_bytes`).
    pub memory_limit: u64,
}

impl FrameOptions {
    /// `width x height` frames of the scene's own shading, within the memory budget every stage
    /// defaults to ([`skinkit_maps::limits::default_memory_limit`]).
    pub fn new(width: u32, height: u32, encoding: Encoding) -> FrameOptions {
        let memory_limit = skinkit_maps::limits::default_memory_limit();
        FrameOptions { width, height, encoding, shading: Shading::Scene, memory_limit }
    }
}

/// What a scene needs and what was not built: the passes and resources of its graph, and the
/// notes for the user (computed normals, downscaled maps, effects left out).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Explanation {
    /// The passes in order and every GPU resource with its bytes.
    pub plan: Plan,
    /// Notes for the user.
    pub warnings: Vec<String>,
}

/// Seconds spent preparing a scene, by step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PrepareTimes {
    /// Reading the mesh and maps, building frames and the plan.
    pub load: Duration,
    /// Curvature, tables, SH and (for the reference) the CPU light map.
    pub skin: Duration,
    /// Uploading buffers and textures (mip chains included).
    pub upload: Duration,
}

/// A scene loaded, planned, set up and uploaded once, with its target: ready to draw frames.
pub struct Prepared {
    options: FrameOptions,
    loaded: Loaded,
    explanation: Explanation,
    times: PrepareTimes,
    scene: PreparedScene,
    target: Target,
}

impl Prepared {
    /// The options it was prepared with.
    pub fn options(&self) -> &FrameOptions {
        &self.options
    }

    /// Its passes, resources and notes.
    pub fn explanation(&self) -> &Explanation {
        &self.explanation
    }

    /// Vertices of the mesh as loaded (before frames).
    pub fn vertex_count(&self) -> usize {
        self.loaded.vertex_count
    }

    /// Triangles of the mesh.
    pub fn triangle_count(&self) -> usize {
        self.loaded.triangle_count
    }

    /// The scene's lights as loaded.
    pub fn lights(&self) -> &[Light] {
        &self.loaded.inputs.lights
    }

    /// What preparing cost.
    pub fn times(&self) -> PrepareTimes {
        self.times
    }

    /// Replaces light `index` (below the scene's light count) for the next frames.
    pub fn set_light(&mut self, index: usize, light: &Light) {
        self.scene.set_light(index, light);
    }
}

/// The device and everything cached on it across scenes.
pub struct Renderer {
    gpu: Gpu,
}

impl Renderer {
    /// Opens the first adapter on the backends named by `WGPU_BACKEND` (or the native ones).
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when no adapter exists, [`GpuError::Device`] when it refuses.
    pub fn new() -> Result<Renderer, GpuError> {
        Ok(Renderer { gpu: Gpu::new()? })
    }

    /// The adapter's name and backend.
    pub fn adapter_name(&self) -> String {
        self.gpu.adapter_name()
    }

    /// The device's largest texture side.
    pub fn max_texture_side(&self) -> u32 {
        self.gpu.max_texture_side()
    }

    /// Loads `scene` once and prepares it for `options`: memory checked first, then the mesh and
    /// maps, the pass graph and its plan, the skin set-up, the upload and the target.
    ///
    /// # Errors
    /// A frame over the memory limit, an unreadable mesh or map, a refused table, or a device
    /// error (sizes, limits, validation).
    pub fn prepare(&self, scene: &Scene, options: &FrameOptions) -> Result<Prepared> {
        let start = Instant::now();
        let (loaded, explanation) = self.load(scene, options)?;
        let load = start.elapsed();
        let mut prepared = self.prepare_loaded(scene, loaded, options, explanation)?;
        prepared.times.load = load;
        Ok(prepared)
    }

    /// The memory check, then the mesh and maps of `scene` and its explanation (the viewer keeps
    /// them to prepare its toggles from).
    pub(crate) fn load(&self, scene: &Scene, options: &FrameOptions) -> Result<(Loaded, Explanation)> {
        check_memory(scene, options)?;
        load_and_explain(scene, options, self.max_texture_side())
    }

    /// [`Renderer::prepare`] from loaded inputs: the skin set-up, the upload and the target.
    pub(crate) fn prepare_loaded(
        &self,
        scene: &Scene,
        loaded: Loaded,
        options: &FrameOptions,
        explanation: Explanation,
    ) -> Result<Prepared> {
        let start = Instant::now();
        let setup = skin_setup(scene, &loaded, options.shading)?;
        let skin = start.elapsed();
        let mut prepared = self.upload(loaded, &setup, options, explanation)?;
        prepared.times.skin = skin;
        Ok(prepared)
    }

    /// Prepares inputs that did not come from a scene file (benchmarks, the viewer's toggles):
    /// as [`Renderer::prepare`] from the upload on, with an empty explanation.
    ///
    /// # Errors
    /// As [`Renderer::prepare`].
    pub fn prepare_inputs(&self, inputs: RenderInputs, setup: &SkinSetup, options: &FrameOptions) -> Result<Prepared> {
        let loaded = Loaded { inputs, vertex_count: 0, triangle_count: 0, warnings: Vec::new() };
        self.upload(loaded, setup, options, Explanation::default())
    }

    /// Uploads `loaded` with `setup` (the tone curve of the options' encoding) and makes the target.
    fn upload(
        &self,
        mut loaded: Loaded,
        setup: &SkinSetup,
        options: &FrameOptions,
        explanation: Explanation,
    ) -> Result<Prepared> {
        let (format, tone) = options.encoding.target();
        loaded.inputs.tone = tone;
        let start = Instant::now();
        let scene = self.gpu.prepare_with(&loaded.inputs, setup)?;
        let times = PrepareTimes { upload: start.elapsed(), ..PrepareTimes::default() };
        let target = self.gpu.create_target(options.width, options.height, format)?;
        Ok(Prepared { options: *options, loaded, explanation, times, scene, target })
    }

    /// Gives `prepared` a `width x height` target of `encoding` for its next frames (a resized
    /// window; the linear twin of a display frame), memory-checked like [`Renderer::prepare`];
    /// nothing else is loaded, set up or uploaded again.
    ///
    /// # Errors
    /// A frame over the memory limit or a size the device refuses.
    pub fn retarget(
        &self,
        scene: &Scene,
        prepared: &mut Prepared,
        (width, height): (u32, u32),
        encoding: Encoding,
    ) -> Result<()> {
        let options = FrameOptions { width, height, encoding, ..prepared.options };
        check_memory(scene, &options)?;
        let (format, tone) = encoding.target();
        prepared.target = self.gpu.create_target(width, height, format)?;
        prepared.scene.set_tone(tone);
        prepared.loaded.inputs.tone = tone;
        prepared.options = options;
        Ok(())
    }

    /// Draws one frame of `prepared` seen from `camera` and reads it back.
    ///
    /// # Errors
    /// A device error (validation, a failed wait or map).
    pub fn draw(&self, prepared: &mut Prepared, camera: &scene::Camera) -> Result<Frame> {
        let (width, height) = (prepared.options.width, prepared.options.height);
        prepared.scene.set_camera(&load::gpu_camera(camera, width, height));
        self.gpu.draw(&prepared.scene, &prepared.target)?;
        Ok(self.gpu.read(&prepared.target)?)
    }

    /// Draws one frame from the camera `prepared` was loaded with, without reading it back, with
    /// each pass's GPU time (`None` where the adapter has no timestamps).
    ///
    /// # Errors
    /// A device error.
    pub fn draw_timed(&self, prepared: &Prepared) -> Result<Option<Vec<(String, Duration)>>> {
        Ok(self.gpu.draw_timed_passes(&prepared.scene, &prepared.target)?)
    }

    /// Draws one frame without reading it back (what a benchmark of the draw times).
    ///
    /// # Errors
    /// A device error.
    pub fn draw_only(&self, prepared: &Prepared) -> Result<()> {
        Ok(self.gpu.draw(&prepared.scene, &prepared.target)?)
    }
}

/// The passes and resources `scene` needs at `options`, without drawing: on `renderer`'s device,
/// or, with none, assuming an [`OFFLINE_TEXTURE_SIDE`] texture limit.
///
/// # Errors
/// An unreadable mesh or map.
pub fn explain(scene: &Scene, options: &FrameOptions, renderer: Option<&Renderer>) -> Result<Explanation> {
    let side = renderer.map_or(OFFLINE_TEXTURE_SIDE, Renderer::max_texture_side);
    Ok(load_and_explain(scene, options, side)?.1)
}

/// Refuses a frame over the memory limit, before anything is loaded or allocated.
fn check_memory(scene: &Scene, options: &FrameOptions) -> Result<()> {
    let (format, _) = options.encoding.target();
    let what = format!("rendering {}x{}", options.width, options.height);
    let bytes = format.frame_bytes(options.width, options.height);
    Ok(skinkit_maps::limits::check_memory(&scene.name(), &what, bytes, options.memory_limit)?)
}

/// The scene's mesh and maps, and the plan of its graph with the notes of both.
fn load_and_explain(scene: &Scene, options: &FrameOptions, max_texture_side: u32) -> Result<(Loaded, Explanation)> {
    let (width, height) = (options.width, options.height);
    let loaded = load::load(scene, width, height, max_texture_side)?;
    let graph = PassGraph::build(scene);
    let plan = explain::plan(scene, &loaded, &graph, width, height, options.encoding.target().0);
    let mut warnings = loaded.warnings.clone();
    warnings.extend(plan.notes.iter().cloned());
    Ok((loaded, Explanation { plan, warnings }))
}

/// The skin set-up `shading` asks for.
fn skin_setup(scene: &Scene, loaded: &Loaded, shading: Shading) -> Result<SkinSetup> {
    Ok(match shading {
        Shading::Scene => pass::build::setup(scene, loaded, &PassGraph::build(scene))?,
        Shading::Method(method) => method.setup(scene, loaded)?,
        Shading::Plain => SkinSetup::default(),
    })
}
