//! Rendering: every skin diffuse method of [`skinkit_render::compare`] and its quality
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

use skinkit_maps::error::one_line;
use skinkit_render::compare::{self, Method};
use skinkit_render::renderer::{Encoding, Frame, FrameOptions, Prepared, Renderer, Shading};
use skinkit_render::scene::Scene;
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
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let plan = plan(config);
    let sizes = plan.size.map_or("each scene's own size".to_owned(), |(w, h)| format!("{w}x{h}"));
    let setup = format!(
        "Skin diffuse methods on {} at {sizes}, against the exact texture-space reference at {r}x{r} \
         texels; FLIP mean of the tone-mapped sRGB images (the plotted error), RMSE of linear \
         radiance relative to the reference's mean; frame time: GPU timestamps summed over the \
         passes, {} frame(s) after a warm-up (median), over the base pass's; the reference's frame \
         adds its CPU bake, which it redoes whenever a light or the pose moves",
        plan.scenes.iter().map(|(f, _)| format!("`samples/scenes/{f}.toml`")).collect::<Vec<_>>().join(" and "),
        plan.frames,
        r = plan.reference
    );
    let mut report = StageReport::new(Stage::Rendering, setup, "FLIP mean", "frame time / base pass");
    let renderer = match Renderer::new() {
        Ok(renderer) => renderer,
        Err(e) => {
            report.skipped = Some(format!("no GPU adapter: {e}"));
            return Ok(report);
        }
    };
    report.setup.push_str(&format!("; adapter {}", renderer.adapter_name()));
    let total = plan.scenes.len() * (plan.methods.len() + 1);
    let tally = crate::Tally::start(progress, Stage::Rendering, total);
    let mut done = 0;
    for (file, short) in &plan.scenes {
        let scene_path = config.samples.join(format!("scenes/{file}.toml"));
        let prefix = if plan.scenes.len() > 1 { format!("{short}: ") } else { String::new() };
        let step = || {
            done += 1;
            tally.done(done);
        };
        report.choices.extend(measure_scene(&renderer, &scene_path, &plan, &prefix, step)?);
    }
    Ok(report)
}

/// One scene: the reference, then every method's error and frame time.
fn measure_scene(
    renderer: &Renderer,
    path: &Path,
    plan: &Plan,
    prefix: &str,
    mut step: impl FnMut(),
) -> Result<Vec<Choice>> {
    let render_err = |e: &dyn std::fmt::Display| Error::Render(format!("{}: {e}", path.display()));
    let scene = Scene::load(path).map_err(|e| render_err(&one_line(&e)))?;
    let size = plan.size.unwrap_or((scene.output.size[0], scene.output.size[1]));
    let plain = FrameOptions { shading: Shading::Plain, ..FrameOptions::new(size.0, size.1, Encoding::Display) };
    let mut base = renderer.prepare(&scene, &plain).map_err(|e| render_err(&one_line(&e)))?;
    let base = frame_seconds(renderer, &mut base, &scene, plan.frames).map_err(|e| render_err(&e))?;
    let reference = Method::Reference { size: plan.reference };
    let (mut prepared, ref_ldr) = prepare_and_draw(renderer, &scene, reference, size).map_err(|e| render_err(&e))?;
    let ref_hdr = draw_linear(renderer, &scene, &mut prepared, size).map_err(|e| render_err(&e))?;
    step();
    let mut choices = Vec::new();
    for method in &plan.methods {
        let t = Instant::now();
        let (mut prepared, ldr) = prepare_and_draw(renderer, &scene, *method, size).map_err(|e| render_err(&e))?;
        let hdr = draw_linear(renderer, &scene, &mut prepared, size).map_err(|e| render_err(&e))?;
        let cpu = t.elapsed().as_secs_f64();
        let (w, h) = size;
        let frame = frame_seconds(renderer, &mut prepared, &scene, plan.frames).map_err(|e| render_err(&e))?;
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
        // The reference bakes its light map on the CPU whenever a light or the pose moves, so
        // its frame is the bake and the draw; the draw alone reads a finished texture and was
        // charted as cheaper than Lambert.
        let per_frame = if matches!(method, Method::Reference { .. }) { cpu + frame } else { frame };
        choice.cost = crate::timing::positive(per_frame / base.max(1e-9));
        choices.push(choice);
        step();
    }
    Ok(choices)
}

/// The method's scene prepared once and its display-encoded (Reinhard, sRGB) frame from the
/// scene's first camera.
fn prepare_and_draw(
    renderer: &Renderer,
    scene: &Scene,
    method: Method,
    (w, h): (u32, u32),
) -> std::result::Result<(Prepared, Frame), String> {
    let options = FrameOptions { shading: Shading::Method(method), ..FrameOptions::new(w, h, Encoding::Display) };
    let mut prepared = renderer.prepare(scene, &options).map_err(|e| format!("{}: {}", method.name(), one_line(&e)))?;
    let frame = renderer.draw(&mut prepared, &scene.cameras[0]).map_err(|e| one_line(&e))?;
    Ok((prepared, frame))
}

/// The linear frame of `prepared`, which is left display-encoded again.
fn draw_linear(
    renderer: &Renderer,
    scene: &Scene,
    prepared: &mut Prepared,
    size: (u32, u32),
) -> std::result::Result<Frame, String> {
    renderer.retarget(scene, prepared, size, Encoding::Linear).map_err(|e| one_line(&e))?;
    let frame = renderer.draw(prepared, &scene.cameras[0]).map_err(|e| one_line(&e))?;
    renderer.retarget(scene, prepared, size, Encoding::Display).map_err(|e| one_line(&e))?;
    Ok(frame)
}

/// The median GPU frame time in seconds of `prepared` over `frames` frames after a warm-up
/// (wall clock where the adapter has no timestamps).
fn frame_seconds(
    renderer: &Renderer,
    prepared: &mut Prepared,
    scene: &Scene,
    frames: usize,
) -> std::result::Result<f64, String> {
    renderer.draw(prepared, &scene.cameras[0]).map_err(|e| one_line(&e))?;
    let mut times = Vec::new();
    for _ in 0..frames.max(1) {
        let t = Instant::now();
        let passes = renderer.draw_timed(prepared).map_err(|e| one_line(&e))?;
        times.push(match passes {
            Some(passes) => passes.iter().map(|(_, d)| d.as_secs_f64()).sum(),
            None => t.elapsed().as_secs_f64(),
        });
    }
    Ok(crate::timing::positive(crate::timing::median(times)))
}
