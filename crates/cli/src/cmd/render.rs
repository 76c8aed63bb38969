//! `skinkit render`: a scene (TOML) drawn by the bundled wgpu renderer into PNG (sRGB, tone
//! mapped) or EXR (linear HDR) images (Haro et al. 2001, section 5; issue 5).
//!
//! One image per camera; `--orbit --frames N` turns each camera about its target in N steps (a
//! turntable). Several images get numbered names beside `--out`: `face-cam1.png`,
//! `face-0003.png`, `face-cam1-0003.png`. `--explain` prints the passes and GPU resources the
//! scene needs and renders nothing.

use std::path::PathBuf;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_maps::OutputSet;
use skinkit_maps::limits;
use skinkit_render::renderer::Plan;
use skinkit_render::renderer::{self, Renderer};
#[cfg(feature = "viewer")]
use skinkit_render::renderer::{Encoding, FrameOptions};
use skinkit_render::scene;

use crate::output::Output;
use crate::render_job::{Job, RenderReport, check_outputs, frame_options, render_into, resolve, resolve_for};
#[cfg(feature = "viewer")]
use crate::render_job::{load_scene, side};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output image (.png: sRGB, tone mapped; .exr: linear HDR). Default: the scene's
    /// `output.path`.
    #[arg(long, value_name = "IMG")]
    pub out: Option<PathBuf>,
    /// Image size (default: the scene's `output.size`; at most 16384 per side).
    #[arg(long, value_parser = render_size, value_name = "WxH")]
    pub size: Option<(usize, usize)>,
    /// Print the passes and GPU resources the scene needs, render nothing.
    #[arg(long)]
    pub explain: bool,
    /// Turn each camera about its target (a turntable sequence of `--frames` images).
    #[arg(long)]
    pub orbit: bool,
    /// Images per camera with `--orbit` (1 to 3600), drawn and written one at a time.
    #[arg(long, default_value_t = 1, value_name = "N", requires = "orbit", value_parser = frame_count)]
    pub frames: usize,
    /// Also write the report (JSON).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Draw the diffuse light with the exact texture-space reference (CPU, slow) instead of the
    /// scene's effects, its light map N texels wide (16 to 8192).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(16..=8192))]
    pub reference: Option<u32>,
}

/// A `--frames` value: 1 to [`limits::MAX_FRAMES`].
fn frame_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if (1..=limits::MAX_FRAMES).contains(&n) => Ok(n),
        _ => Err(format!("`{text}` is not a frame count from 1 to {}", limits::MAX_FRAMES)),
    }
}

/// A `--size` value within the renderer's largest output side.
fn render_size(text: &str) -> Result<(usize, usize), String> {
    crate::flags::size_at_most(scene::MAX_OUTPUT_SIDE as usize)(text)
}

/// The explain-only result.
#[derive(Clone, Debug, Serialize)]
pub struct Explained {
    scene: String,
    adapter: Option<String>,
    width: u32,
    height: u32,
    plan: Plan,
    warnings: Vec<String>,
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let job = Job {
        scene: args.scene,
        out: args.out,
        size: args.size,
        frames: if args.orbit { Some(args.frames) } else { None },
        reference: args.reference,
    };
    if args.explain {
        let explained = explain(&job)?;
        out.result(&explained, || explain_text(&explained));
        return Ok(0);
    }
    // Checked before the adapter opens: a wrong `--out` is a usage error whatever the GPU.
    let resolved = resolve(&job)?;
    check_outputs(&job, &resolved.scene, &resolved.path, args.report.as_deref())?;
    // One set: every image and the report appear together or not at all.
    let mut set = OutputSet::files();
    let report = render_into(&job, resolved, &Renderer::new()?, out, &mut set)?;
    if let Some(path) = &args.report {
        crate::pipeline::write_json_file(&mut set, path, "the render report", &report)?;
    }
    out.swept(&set.commit().context("cannot finish writing the render outputs")?);
    out.result(&report, || human(&report));
    Ok(0)
}

fn explain(job: &Job) -> Result<Explained> {
    let r = resolve_for(job, true)?;
    let renderer = Renderer::new().ok();
    let options = frame_options(&r, job, u64::MAX)?;
    let explained = renderer::explain(&r.scene, &options, renderer.as_ref())?;
    Ok(Explained {
        scene: job.scene.display().to_string(),
        adapter: renderer.map(|r| r.adapter_name()),
        width: r.width,
        height: r.height,
        plan: explained.plan,
        warnings: explained.warnings,
    })
}

/// `skinkit view`.
#[cfg(feature = "viewer")]
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Window size (default: the scene's `output.size`, at most 1280x960).
    #[arg(long, value_parser = render_size, value_name = "WxH")]
    pub size: Option<(usize, usize)>,
}

#[cfg(feature = "viewer")]
pub fn view(args: ViewArgs, out: &Output) -> Result<i32> {
    let scene = load_scene(&args.scene)?;
    let (width, height) = match args.size {
        Some((w, h)) => (side(w, "--size")?, side(h, "--size")?),
        None => (scene.output.size[0].min(1280), scene.output.size[1].min(960)),
    };
    let renderer = Renderer::new()?;
    let options =
        FrameOptions { memory_limit: out.memory_limit(), ..FrameOptions::new(width, height, Encoding::Display) };
    let session = skinkit_render::view::ViewSession::new(&renderer, scene, options)?;
    for warning in session.warnings() {
        out.warn(warning);
    }
    out.note("left drag: orbit, wheel: zoom, right drag: move the light, N: normal map, S: specular, V: per-vertex specular, 1-6: the scene's effects, R: reset, Esc: quit");
    skinkit_render::viewer::run(renderer, session)?;
    Ok(0)
}

fn explain_text(e: &Explained) -> String {
    let mut s = format!(
        "{} at {}x{} on {}\n",
        e.scene,
        e.width,
        e.height,
        e.adapter.as_deref().unwrap_or("no adapter (sizes assume an 8192 texture limit)")
    );
    s.push_str("passes:\n");
    for (i, p) in e.plan.passes.iter().enumerate() {
        s.push_str(&format!(
            "  {}. {}: {}\n     reads {}; writes {}\n",
            i + 1,
            p.name,
            p.what,
            p.reads.join(", "),
            p.writes.join(", ")
        ));
    }
    s.push_str("resources:\n");
    for r in &e.plan.resources {
        s.push_str(&format!("  {:<14} {:>10.2} MiB  {}\n", r.name, r.bytes as f64 / (1 << 20) as f64, r.detail));
    }
    s.push_str(&format!("  total          {:>10.2} MiB", e.plan.bytes() as f64 / (1 << 20) as f64));
    for w in &e.warnings {
        s.push_str(&format!("\nwarning: {w}"));
    }
    s
}

fn human(r: &RenderReport) -> String {
    let mut s = format!(
        "rendered {} image(s) of {}x{} on {} ({} vertices, {} triangles): load {:.2} s, upload {:.2} s",
        r.images.len(),
        r.width,
        r.height,
        r.adapter,
        r.vertices,
        r.triangles,
        r.load_seconds,
        r.upload_seconds
    );
    for i in &r.images {
        s.push_str(&format!("\n  {}  render {:.3} s, write {:.3} s", i.path, i.render_seconds, i.write_seconds));
    }
    s
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::output::GlobalArgs;
    use crate::render_job::SCENE_LOADS;

    fn quiet() -> Output {
        Output::new(&GlobalArgs { quiet: true, json: false, threads: None, memory_limit: None })
    }

    fn args(scene: &Path, out: &Path, explain: bool) -> Args {
        Args {
            scene: scene.to_owned(),
            out: Some(out.to_owned()),
            size: Some((32, 24)),
            explain,
            orbit: false,
            frames: 1,
            report: None,
            reference: None,
        }
    }

    /// Issue 38: `skinkit render` read its scene file twice (once to check the outputs, once to
    /// render). Needs an adapter (lavapipe) for the render; `--explain` runs without one.
    #[test]
    fn render_reads_its_scene_once() {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/scenes/skin-sphere.toml");
        let dir = tempfile::tempdir().unwrap();
        let image = dir.path().join("sphere.png");
        let loads = || SCENE_LOADS.with(|n| n.get());
        let before = loads();
        run(args(&scene, &image, true), &quiet()).unwrap();
        assert_eq!(loads() - before, 1, "--explain reads the scene once");
        let before = loads();
        run(args(&scene, &image, false), &quiet()).unwrap();
        assert_eq!(loads() - before, 1, "a render reads the scene once");
        assert!(image.exists());
    }
}
