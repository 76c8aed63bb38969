//! One render job, what `skinkit render` and the demo's figures draw with: a scene file resolved
//! (its size and output path, with the command line's overrides), its images drawn through the
//! renderer's front door ([`Renderer`]) and staged in an output set, all or none, and its report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::Serialize;
use skinkit_maps::OutputSet;
use skinkit_maps::io::{self, PngLayout};
use skinkit_maps::limits;
use skinkit_render::compare::Method;
use skinkit_render::renderer::{Encoding, Frame, FrameOptions, Renderer, Shading};
use skinkit_render::renderer::{Plan, orbit};
use skinkit_render::scene::{self, Scene};

use crate::output::Output;
use skinkit_maps::progress::Progress;

/// One written image.
#[derive(Clone, Debug, Serialize)]
pub struct Image {
    pub path: String,
    pub camera: usize,
    pub frame: usize,
    /// Draw on the GPU and read back, seconds.
    pub render_seconds: f64,
    pub write_seconds: f64,
}

/// What `--json` and `--report` hold.
#[derive(Clone, Debug, Serialize)]
pub struct RenderReport {
    pub scene: String,
    pub adapter: String,
    pub width: u32,
    pub height: u32,
    pub vertices: usize,
    pub triangles: usize,
    pub plan: Plan,
    pub images: Vec<Image>,
    pub warnings: Vec<String>,
    /// Reading the mesh and maps and building frames.
    pub load_seconds: f64,
    /// Curvature, LUTs, SH and (with `--reference`) the reference light map, on the CPU.
    pub skin_seconds: f64,
    /// Uploading textures and buffers (mip chains included).
    pub upload_seconds: f64,
    pub total_seconds: f64,
}

/// Refuses, before any work, an image or report path that is a folder, one of the scene's
/// inputs or another output. Images are named as [`numbered`] names them.
pub fn check_outputs(job: &Job, scene: &Scene, path: &Path, report: Option<&Path>) -> Result<()> {
    let mut inputs = scene.input_files();
    // The scene file as the command line named it, too (the scene records it resolved).
    inputs.push(("the scene".to_owned(), job.scene.clone()));
    let cameras = scene.cameras.len();
    let frames = job.frames.unwrap_or(1);
    let images: Vec<PathBuf> = (0..cameras)
        .flat_map(|c| (0..frames).map(move |f| (c, f)))
        .map(|(c, f)| numbered(path, (cameras > 1).then_some(c), job.frames.map(|_| f)))
        .collect();
    let mut outputs: Vec<(&str, &Path)> = images.iter().map(|p| ("--out", p.as_path())).collect();
    outputs.extend(report.map(|p| ("--report", p)));
    Ok(skinkit_maps::gate::output_files(&outputs, &inputs)?)
}

/// Renders every image of a job on `renderer` and writes them, all or none (see [`render_into`]).
pub fn render(job: &Job, renderer: &Renderer, out: &Output) -> Result<RenderReport> {
    let resolved = resolve(job)?;
    check_outputs(job, &resolved.scene, &resolved.path, None)?;
    let mut set = OutputSet::files();
    let report = render_into(job, resolved, renderer, out, &mut set)?;
    set.commit().with_context(|| format!("cannot finish writing the images of {}", job.scene.display()))?;
    Ok(report)
}

/// One `skinkit render` invocation (also what `skinkit demo` renders its figures with).
pub struct Job {
    pub scene: PathBuf,
    /// Overrides the scene's `output.path`.
    pub out: Option<PathBuf>,
    /// Overrides the scene's `output.size`.
    pub size: Option<(usize, usize)>,
    /// Turntable frames per camera, if orbiting.
    pub frames: Option<usize>,
    /// Draw the exact texture-space reference with a light map this wide.
    pub reference: Option<u32>,
}

/// A job's scene, size and output path, checked.
pub struct Resolved {
    pub scene: Scene,
    pub width: u32,
    pub height: u32,
    pub path: PathBuf,
    pub format: scene::OutputFormat,
}

pub fn resolve(job: &Job) -> Result<Resolved> {
    resolve_for(job, false)
}

/// [`resolve`]; with `explain`, a scene without an output path explains as a PNG (nothing is
/// written).
pub fn resolve_for(job: &Job, explain: bool) -> Result<Resolved> {
    let scene = load_scene(&job.scene)?;
    let (width, height) = match job.size {
        Some((w, h)) => (side(w, "--size")?, side(h, "--size")?),
        None => (scene.output.size[0], scene.output.size[1]),
    };
    let path = match (&job.out, &scene.output.path) {
        (Some(p), _) | (None, Some(p)) => p.clone(),
        (None, None) if explain => PathBuf::from("explain.png"),
        (None, None) => bail!("{}: no output: give --out IMG or `output.path` in the scene", job.scene.display()),
    };
    let format = scene::OutputFormat::from_path(&path)
        .with_context(|| format!("{}: cannot write `{}`: use .png or .exr", job.scene.display(), path.display()))?;
    Ok(Resolved { scene, width, height, path, format })
}

/// The frames a job asks for: the size and encoding of its output, the scene's shading or with
/// `--reference` the exact light map, within `memory_limit`.
pub fn frame_options(r: &Resolved, job: &Job, memory_limit: u64) -> Result<FrameOptions> {
    let shading = match job.reference {
        None => Shading::Scene,
        Some(size) if (16..=8192).contains(&size) => Shading::Method(Method::Reference { size }),
        Some(size) => return Err(crate::output::usage(format!("--reference: {size} is outside 16..=8192 texels"))),
    };
    Ok(FrameOptions { shading, memory_limit, ..FrameOptions::new(r.width, r.height, Encoding::for_output(r.format)) })
}

/// Renders every image of a job, its scene already loaded and its outputs checked (`resolved`),
/// on `renderer` (a session: its shaders, pipelines and tables are reused by the next job) and
/// stages them in `set`.
pub fn render_into(
    job: &Job,
    resolved: Resolved,
    renderer: &Renderer,
    out: &Output,
    set: &mut OutputSet,
) -> Result<RenderReport> {
    let start = Instant::now();
    let frames = job.frames.unwrap_or(1);
    if !(1..=limits::MAX_FRAMES).contains(&frames) {
        return Err(crate::output::usage(format!(
            "--frames: {frames} is not a frame count from 1 to {}",
            limits::MAX_FRAMES
        )));
    }
    let options = frame_options(&resolved, job, out.memory_limit())?;
    let Resolved { scene, width, height, path, format } = resolved;
    if job.reference.is_some() {
        let size = job.reference.unwrap_or_default();
        out.note(format!("baking and scattering the {size}x{size} reference light map on the CPU"));
    }
    let mut prepared = renderer.prepare(&scene, &options)?;
    let explanation = prepared.explanation().clone();
    explanation.warnings.iter().for_each(|warning| out.warn(warning));
    // One (camera, frame) at a time: nothing is held per frame but its line in the report.
    let bar = out.progress((scene.cameras.len() * frames) as u64, "render");
    let mut images = Vec::new();
    for (c, f) in (0..scene.cameras.len()).flat_map(|c| (0..frames).map(move |f| (c, f))) {
        let camera = if job.frames.is_some() { orbit(&scene.cameras[c], f, frames) } else { scene.cameras[c] };
        let file = numbered(&path, (scene.cameras.len() > 1).then_some(c), job.frames.map(|_| f));
        let t = Instant::now();
        let frame = renderer.draw(&mut prepared, &camera)?;
        let render_seconds = t.elapsed().as_secs_f64();
        let write_seconds = stage(&frame, &file, format, set)?;
        images.push(Image { path: file.display().to_string(), camera: c, frame: f, render_seconds, write_seconds });
        bar.advance(1);
    }
    bar.clear();
    let times = prepared.times();
    Ok(RenderReport {
        scene: job.scene.display().to_string(),
        adapter: renderer.adapter_name(),
        width,
        height,
        vertices: prepared.vertex_count(),
        triangles: prepared.triangle_count(),
        plan: explanation.plan,
        images,
        warnings: explanation.warnings,
        load_seconds: times.load.as_secs_f64(),
        skin_seconds: times.skin.as_secs_f64(),
        upload_seconds: times.upload.as_secs_f64(),
        total_seconds: start.elapsed().as_secs_f64(),
    })
}

/// Stages `frame` in `set` as `file`: the seconds of the write.
fn stage(frame: &Frame, file: &Path, format: scene::OutputFormat, set: &mut OutputSet) -> Result<f64> {
    let t = Instant::now();
    set.write_file(file, |p| write_image(p, frame, format)).context("cannot write the rendered image")?;
    Ok(t.elapsed().as_secs_f64())
}

thread_local! {
    /// Scene files this thread has read (the test that `skinkit render` reads its scene once).
    pub static SCENE_LOADS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Reads a scene file: every scene of `render` is read here, and counted.
pub fn load_scene(path: &Path) -> Result<Scene> {
    SCENE_LOADS.with(|n| n.set(n.get() + 1));
    Ok(Scene::load(path)?)
}

pub fn side(v: usize, flag: &str) -> Result<u32> {
    u32::try_from(v)
        .ok()
        .filter(|&s| s <= scene::MAX_OUTPUT_SIDE)
        .with_context(|| format!("{flag}: {v} is above the largest output side, {}", scene::MAX_OUTPUT_SIDE))
}

/// `path` with `-camC` and `-FFFF` before the extension, for the parts given.
fn numbered(path: &Path, camera: Option<usize>, frame: Option<usize>) -> PathBuf {
    if camera.is_none() && frame.is_none() {
        return path.to_owned();
    }
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = path.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_default();
    let mut name = stem;
    if let Some(c) = camera {
        name.push_str(&format!("-cam{c}"));
    }
    if let Some(f) = frame {
        name.push_str(&format!("-{f:04}"));
    }
    path.with_file_name(format!("{name}.{ext}"))
}

/// Writes a rendered image atomically: PNG as 8-bit sRGB RGB, EXR as linear float RGB.
pub fn write_image(path: &Path, image: &Frame, format: scene::OutputFormat) -> skinkit_maps::Result<()> {
    let (w, h) = (image.width as usize, image.height as usize);
    match format {
        scene::OutputFormat::Png => {
            let samples: Vec<u16> =
                image.srgb_bytes.chunks_exact(4).flat_map(|px| [px[0], px[1], px[2]].map(u16::from)).collect();
            io::write_png(path, w, h, PngLayout::Rgb8, &samples)?;
        }
        scene::OutputFormat::Exr => {
            io::write_exr_rgb(path, w, h, |x, y| {
                let p = image.pixels[y * w + x];
                [p[0], p[1], p[2]]
            })?;
        }
    }
    Ok(())
}
