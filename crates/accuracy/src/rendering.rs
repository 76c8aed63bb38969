//! Rendering: every skin diffuse method of [`skinkit_render::skin::compare`] and its quality
//! knobs (LUT size, the ring or sphere table, texture-space diffusion's passes, light-map size
//! and kernel, the reference at half size), each render's error against the exact texture-space
//! reference (FLIP mean of the tone-mapped images, relative RMSE of linear radiance) and its GPU
//! frame time over the base pass's (the same scene, Lambert, no shadows), as the renderer's
//! `skin_methods` benchmark measures them.
//!
//! Needs a GPU adapter (lavapipe will do); without one the stage is returned skipped, with the
//! reason. Quick mode: the 6 mm skin sphere at 128x128 against a 512-texel reference, a few
//! methods, one timed frame after a warm-up; full: the sphere and the sample head at their
//! scenes' sizes, every method of [`Method::table`] against the 2048-texel reference, the median
//! of 7 frames.

use std::path::Path;
use std::time::Instant;

use skinkit_render::gpu::{Gpu, OutputFormat, Rendered};
use skinkit_render::load::{self, Loaded};
use skinkit_render::passes::SkinSetup;
use skinkit_render::scene::Scene;
use skinkit_render::shading::{RenderInputs, ToneCurve};
use skinkit_render::skin::compare::{self, Method};
use skinkit_render::skin::options::TsdKernel;

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::{Config, Error, Result};

/// What a mode renders.
struct Plan {
    /// Scene file stems in `samples/scenes/`, with their short names.
    scenes: Vec<(&'static str, &'static str)>,
    /// Image size over the scene's own, when set.
    size: Option<(u32, u32)>,
    reference: u32,
    methods: Vec<Method>,
    frames: usize,
}

fn plan(config: &Config) -> Plan {
    if config.quick {
        let tsd = |kernel, passes| Method::Tsd { kernel, passes, size: 256 };
        let methods = vec![
            Method::Lambert,
            Method::Blog,
            Method::OwnFit,
            Method::Lut { size: 32 },
            Method::Lut { size: 256 },
            Method::RingLut { size: 256 },
            tsd(TsdKernel::Gaussians, 1),
            tsd(TsdKernel::Gaussians, 2),
            tsd(TsdKernel::Single, 1),
            Method::Reference { size: 256 },
        ];
        Plan { scenes: vec![("skin-sphere", "sphere")], size: Some((128, 128)), reference: 512, methods, frames: 1 }
    } else {
        let mut methods = Method::table(2048);
        methods.pop(); // the reference itself: error 0 by definition
        Plan {
            scenes: vec![("skin-sphere", "sphere"), ("skin-compare", "head")],
            size: None,
            reference: 2048,
            methods,
            frames: 7,
        }
    }
}

/// The method's family: one curve of the plot.
fn family(method: &Method) -> &'static str {
    match method {
        Method::Lambert => "lambert",
        Method::Blog | Method::OwnFit => "closed forms",
        Method::Lut { .. } => "pre-integrated LUT",
        Method::RingLut { .. } => "LUT, the paper's ring",
        Method::Tsd { kernel: TsdKernel::Gaussians, .. } => "TSD, Gaussians",
        Method::Tsd { kernel: TsdKernel::Single, .. } => "TSD, single kernel",
        Method::Reference { .. } => "reference",
    }
}

/// Measures every method on every scene of the mode, or returns the stage skipped without an
/// adapter.
///
/// # Errors
/// [`Error::Render`] when a scene cannot be loaded or drawn although an adapter was found.
pub fn measure(config: &Config, progress: &dyn Fn(usize, usize)) -> Result<StageReport> {
    let plan = plan(config);
    let sizes = plan.size.map_or("each scene's own size".to_owned(), |(w, h)| format!("{w}x{h}"));
    let setup = format!(
        "Skin diffuse methods on {} at {sizes}, against the exact texture-space reference at {r}x{r} \
         texels; FLIP mean of the tone-mapped sRGB images (the plotted error), RMSE of linear \
         radiance relative to the reference's mean; frame time: GPU timestamps summed over the \
         passes, {} frame(s) after a warm-up (median), over the base pass's",
        plan.scenes.iter().map(|(f, _)| format!("`samples/scenes/{f}.toml`")).collect::<Vec<_>>().join(" and "),
        plan.frames,
        r = plan.reference
    );
    let mut report = StageReport::new(Stage::Rendering, setup, "FLIP mean", "frame time / base pass");
    let gpu = match Gpu::new() {
        Ok(gpu) => gpu,
        Err(e) => {
            report.skipped = Some(format!("no GPU adapter: {e}"));
            return Ok(report);
        }
    };
    report.setup.push_str(&format!("; adapter {}", gpu.adapter_name()));
    let total = plan.scenes.len() * (plan.methods.len() + 1);
    progress(0, total);
    let mut done = 0;
    for (file, short) in &plan.scenes {
        let scene_path = config.samples.join(format!("scenes/{file}.toml"));
        let prefix = if plan.scenes.len() > 1 { format!("{short}: ") } else { String::new() };
        let step = || {
            done += 1;
            progress(done, total);
        };
        report.choices.extend(measure_scene(&gpu, &scene_path, &plan, &prefix, step)?);
    }
    Ok(report)
}

/// One scene: the reference, then every method's error and frame time.
fn measure_scene(gpu: &Gpu, path: &Path, plan: &Plan, prefix: &str, mut step: impl FnMut()) -> Result<Vec<Choice>> {
    let render_err = |e: &dyn std::fmt::Display| Error::Render(format!("{}: {e}", path.display()));
    let scene = Scene::load(path).map_err(|e| render_err(&e))?;
    let (w, h) = plan.size.unwrap_or((scene.output.size[0], scene.output.size[1]));
    let loaded = load::load(&scene, w, h, gpu.max_texture_side()).map_err(|e| render_err(&e))?;
    let base =
        frame_seconds(gpu, &loaded.inputs, &SkinSetup::default(), (w, h), plan.frames).map_err(|e| render_err(&e))?;
    let reference = Method::Reference { size: plan.reference };
    let (ref_ldr, ref_hdr) = draw_method(gpu, &scene, &loaded, &reference, (w, h)).map_err(|e| render_err(&e))?.0;
    step();
    let mut choices = Vec::new();
    for method in &plan.methods {
        let t = Instant::now();
        let ((ldr, hdr), setup) = draw_method(gpu, &scene, &loaded, method, (w, h)).map_err(|e| render_err(&e))?;
        let cpu = t.elapsed().as_secs_f64();
        let frame = frame_seconds(gpu, &loaded.inputs, &setup, (w, h), plan.frames).map_err(|e| render_err(&e))?;
        let flip = compare::flip_mean(&ref_ldr.srgb_bytes, &ldr.srgb_bytes, w, h) as f64;
        let rmse = compare::rmse(&ref_hdr.pixels, &hdr.pixels) as f64;
        let mut choice = Choice::timed(
            &format!("{prefix}{}", family(method)),
            &method.name(),
            knobs(&[("method", method.name()), ("image", format!("{w}x{h}"))]),
            metrics(&[("FLIP mean", flip), ("relative RMSE", rmse), ("CPU setup and draw (s)", cpu)]),
            frame,
            plan.frames,
        );
        choice.cost = crate::timing::positive(frame / base.max(1e-9));
        choices.push(choice);
        step();
    }
    Ok(choices)
}

type Draw = ((Rendered, Rendered), SkinSetup);

/// The method's setup and its LDR (Reinhard, sRGB) and HDR (linear) renders.
fn draw_method(
    gpu: &Gpu,
    scene: &Scene,
    loaded: &Loaded,
    method: &Method,
    (w, h): (u32, u32),
) -> std::result::Result<Draw, String> {
    let setup = method.setup(scene, loaded).map_err(|e| format!("{}: {e}", method.name()))?;
    let once = |format: OutputFormat, tone: ToneCurve| -> std::result::Result<Rendered, String> {
        let inputs = RenderInputs { tone, ..loaded.inputs.clone() };
        let target = gpu.create_target(w, h, format).map_err(|e| e.to_string())?;
        let prepared = gpu.prepare_with(&inputs, &setup).map_err(|e| e.to_string())?;
        gpu.draw(&prepared, &target).map_err(|e| e.to_string())?;
        gpu.read(&target).map_err(|e| e.to_string())
    };
    let images = (once(OutputFormat::Srgb8, ToneCurve::Reinhard)?, once(OutputFormat::Hdr32, ToneCurve::None)?);
    Ok((images, setup))
}

/// The median GPU frame time in seconds over `frames` frames after a warm-up (wall clock where the
/// adapter has no timestamps).
fn frame_seconds(
    gpu: &Gpu,
    inputs: &RenderInputs,
    setup: &SkinSetup,
    (w, h): (u32, u32),
    frames: usize,
) -> std::result::Result<f64, String> {
    let target = gpu.create_target(w, h, OutputFormat::Srgb8).map_err(|e| e.to_string())?;
    let scene = gpu.prepare_with(inputs, setup).map_err(|e| e.to_string())?;
    gpu.draw(&scene, &target).map_err(|e| e.to_string())?;
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let t = Instant::now();
        let passes = gpu.draw_timed_passes(&scene, &target).map_err(|e| e.to_string())?;
        times.push(match passes {
            Some(passes) => passes.iter().map(|(_, d)| d.as_secs_f64()).sum(),
            None => t.elapsed().as_secs_f64(),
        });
    }
    Ok(crate::timing::positive(crate::timing::median(times)))
}
