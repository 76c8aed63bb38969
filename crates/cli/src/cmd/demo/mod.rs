//! `skinkit demo`: the pipeline that exists, run over the bundled samples. Today that is capture
//! of every sample mold with both solvers, each result's error against its ground truth, and what
//! the robust solver's accuracy costs in time; then each mold's robust normal map grown to
//! 1024x1024 by synthesis, its albedo replayed through the same coordinate map, with the quality
//! metrics of every growth; then the sample face (`samples/face/layout.toml`, seven regions)
//! stitched at 2048x1024 (`--full`: 4096x2048) from the molds just captured; the renders of the
//! face map (figures 7 and 8, the skin figure); the quick run of `skinkit accuracy` (what each
//! choice of every stage costs in time, into `accuracy/`); last the report page, `index.html`
//! ([`page`]), which shows each stage's accuracy plot beside its pictures.

mod figure7;
mod figures;
mod height;
mod page;
mod round_trip;

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_capture::solve::AlbedoMap;
use skinkit_maps::NormalEncoding;
use skinkit_maps::io;
use skinkit_synth::{Map, QualityReport, SynthConfig, coords};

use skinkit_capture::session::{self, CaptureOptions, Captured, Session};

use crate::face::{StitchOptions, face_to_dir};
use crate::machine::Machine;
use crate::output::Output;
use crate::pipeline;
use crate::solve_flags::{SolveArgs, SolverArg};
use figures::{FiguresReport, figures};
use skinkit_maps::progress::Progress;
use skinkit_stitch::FaceReport;
use skinkit_stitch::face::ExemplarCache;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output folder.
    #[arg(long, default_value = "demo-out", value_name = "DIR")]
    pub out: PathBuf,
    /// Folder of sample molds (default: the repository's samples/molds).
    #[arg(long, value_name = "DIR")]
    pub samples: Option<PathBuf>,
    /// Size each mold's captured map is grown to.
    #[arg(long, default_value = "1024x1024", value_parser = crate::flags::image_size, value_name = "WxH")]
    pub synth_size: (usize, usize),
    /// Seed of the syntheses.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Stitch the sample face map at 4096x2048 (default 2048x1024).
    #[arg(long)]
    pub full: bool,
    /// Skip the renders of the face map (figures 7 and 8).
    #[arg(long)]
    pub no_render: bool,
    /// Skip the quick accuracy run (`skinkit accuracy --quick`, about half a minute).
    #[arg(long)]
    pub no_accuracy: bool,
}

/// Wall-clock seconds of each stage.
#[derive(Serialize, Default)]
struct DemoSeconds {
    capture: f64,
    synthesis: f64,
    face: Option<f64>,
    renders: Option<f64>,
    accuracy: Option<f64>,
    page: f64,
    total: f64,
}

#[derive(Serialize)]
struct MoldResult {
    region: String,
    solver: String,
    mean_error_deg: f32,
    rms_error_deg: f32,
    p95_error_deg: f32,
    invalid_pixels: usize,
    solve_seconds: f64,
    output: String,
}

#[derive(Serialize)]
struct GrowthResult {
    region: String,
    width: usize,
    height: usize,
    seconds: f64,
    quality: QualityReport,
    output: String,
}

#[derive(Serialize)]
struct DemoReport {
    machine: Machine,
    seconds: DemoSeconds,
    /// The report page.
    page: Option<String>,
    molds: Vec<MoldResult>,
    growths: Vec<GrowthResult>,
    face: Option<FaceReport>,
    renders: Option<FiguresReport>,
    /// The quick accuracy run (`accuracy/accuracy.json`).
    accuracy: Option<skinkit_accuracy::Report>,
}

/// The repository's sample molds, found from the source tree this binary was built from, or in the
/// current folder.
fn default_samples() -> PathBuf {
    let here = PathBuf::from("samples/molds");
    if here.is_dir() { here } else { Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds") }
}

fn options(solver: SolverArg, out: &Output) -> Result<CaptureOptions> {
    SolveArgs::defaults(solver).options(out)
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let samples = args.samples.clone().unwrap_or_else(default_samples);
    let mut seconds = DemoSeconds::default();
    let (molds, growths, mut cache) = capture_and_grow(&args, &samples, out, &mut seconds)?;
    let t = Instant::now();
    let face = stitch_face(&args, &samples, &mut cache, out)?;
    seconds.face = face.as_ref().map(|_| t.elapsed().as_secs_f64());
    let t = Instant::now();
    let mm_per_texel = face.as_ref().map(|f| f.mm_per_texel);
    let renders = if face.is_some() && !args.no_render { render_figures(&args, mm_per_texel, out)? } else { None };
    seconds.renders = renders.as_ref().map(|_| t.elapsed().as_secs_f64());
    let t = Instant::now();
    let accuracy = if args.no_accuracy { None } else { Some(quick_accuracy(&args, &samples, out)?) };
    seconds.accuracy = accuracy.as_ref().map(|_| t.elapsed().as_secs_f64());
    let machine = Machine::this();
    let mut report = DemoReport { machine, seconds, page: None, molds, growths, face, renders, accuracy };
    let t = Instant::now();
    out.note("writing the report page");
    report.seconds.total = start.elapsed().as_secs_f64();
    let page = page::write(&args.out, &samples, &report)?;
    report.page = Some(page.display().to_string());
    report.seconds.page = t.elapsed().as_secs_f64();
    report.seconds.total = start.elapsed().as_secs_f64();
    pipeline::write_json(&args.out.join("demo-report.json"), "the demo report", &report)?;
    out.result(&report, || human(&report, &args.out));
    Ok(0)
}

/// The demo's report in words: the molds' accuracy, the growths, the face, the renders, the times.
fn human(report: &DemoReport, out_dir: &Path) -> String {
    let mut s = molds_and_growths(report);
    if let Some(f) = &report.face {
        s += &format!(
            "\nface {}x{}: {} regions, {} spline levels, seam gradient ratio {:.2}, mean jump {:.2} deg, {:.1} s\n",
            f.width,
            f.height,
            f.regions.len(),
            f.levels,
            f.seams.summary.mean_gradient_ratio.unwrap_or(f64::NAN),
            f.seams.summary.mean_jump_degrees,
            f.seconds.total
        );
    }
    if let Some(r) = &report.renders {
        s += &renders_text(r);
    }
    s += &format!("outputs and demo-report.json in {}\n", out_dir.display());
    s += &format!("report page: {}\n", report.page.as_deref().unwrap_or("-"));
    let t = &report.seconds;
    s + &format!(
        "total {:.1} s (capture {:.1}, synthesis {:.1}, face {:.1}, renders {:.1}, accuracy {:.1}, page {:.1}) on {}",
        t.total,
        t.capture,
        t.synthesis,
        t.face.unwrap_or(0.0),
        t.renders.unwrap_or(0.0),
        t.accuracy.unwrap_or(0.0),
        t.page,
        report.machine.summary()
    )
}

/// The molds' accuracy and the growths' quality, as two tables.
fn molds_and_growths(report: &DemoReport) -> String {
    let mut s = format!(
        "{:<14} {:<7} {:>10} {:>9} {:>9} {:>8} {:>9}\n",
        "mold", "solver", "mean deg", "rms deg", "p95 deg", "invalid", "solve ms"
    );
    for m in &report.molds {
        s += &format!(
            "{:<14} {:<7} {:>10.3} {:>9.3} {:>9.3} {:>8} {:>9.2}\n",
            m.region,
            m.solver,
            m.mean_error_deg,
            m.rms_error_deg,
            m.p95_error_deg,
            m.invalid_pixels,
            m.solve_seconds * 1e3
        );
    }
    s += &format!(
        "\n{:<14} {:>10} {:>8} {:>10} {:>10} {:>9}\n",
        "grown", "size", "seconds", "slope W1", "spectrum", "largest"
    );
    for g in &report.growths {
        s += &format!(
            "{:<14} {:>10} {:>8.2} {:>10.4} {:>10.3} {:>9}\n",
            g.region,
            format!("{}x{}", g.width, g.height),
            g.seconds,
            g.quality.slope_distance.unwrap_or(f64::NAN),
            g.quality.spectrum_distance,
            g.quality.largest_block
        );
    }
    s
}

/// The figures rendered, and what figure 7's highlights measure.
fn renders_text(r: &FiguresReport) -> String {
    let mut s = String::new();
    let draw: f64 = r.renders.iter().flat_map(|j| &j.images).map(|i| i.render_seconds).sum();
    s += &format!(
        "\nrenders on {}: {} (with and without fine-scale structure), {} (four light directions); {:.2} s drawing\n",
        r.renders.first().map_or("", |j| j.adapter.as_str()),
        r.figure7.image,
        r.figure8,
        draw
    );
    let (skin, smooth) = (&r.figure7.skin, &r.figure7.smooth);
    s += &format!(
        "figure 7 highlights (brightest {:.0} %): the specular lobes make {:.0} % of a pixel (median {:.0} %; smooth head {:.0} %), local contrast of the sheen {:.3} with the grown map, {:.3} without\n",
        skinkit_render::highlight::HIGHLIGHT_FRACTION * 100.0,
        skin.mean * 100.0,
        skin.median * 100.0,
        smooth.mean * 100.0,
        skin.local_contrast,
        smooth.local_contrast
    );
    if let Some(t) = &r.height_round_trip {
        s += &format!(
            "figure 7 lit from the face height's own normals: FLIP {:.3} against the normal map ({:.3} of it from the differencing, {:.3} against the differenced map)\n",
            t.flip_height_vs_map, t.flip_differenced_vs_map, t.flip_height_vs_differenced_map
        );
    }
    s
}

/// Molds, growths and the capture cache the face reuses.
type Captures = (Vec<MoldResult>, Vec<GrowthResult>, ExemplarCache);

/// Captures every sample mold with both solvers and grows each robust map, with a progress bar
/// per stage; adds each stage's time to `seconds`.
fn capture_and_grow(args: &Args, samples: &Path, out: &Output, seconds: &mut DemoSeconds) -> Result<Captures> {
    let mut regions: Vec<PathBuf> = std::fs::read_dir(samples)
        .with_context(|| {
            format!("cannot list sample molds in {} (run `skinkit samples` to make them)", samples.display())
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    regions.sort();
    // A demo of nothing is not a success (issue 42, D14): an empty report page would say it was.
    if regions.is_empty() {
        anyhow::bail!("{}: no sample molds in this folder (run `skinkit samples` to make them)", samples.display());
    }
    let (mut molds, mut captured_maps) = (Vec::new(), Vec::new());
    let t = Instant::now();
    let bar = out.progress(regions.len() as u64 * 2, "capture");
    for dir in &regions {
        let region = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let files = Session::from_dir(dir)?;
        for solver in [SolverArg::Robust, SolverArg::Ls] {
            let (mold, captured) = capture_mold(args, &region, &files, solver, out)?;
            molds.push(mold);
            if solver == SolverArg::Robust {
                captured_maps.push((dir, region.clone(), captured));
            }
            bar.advance(1);
        }
    }
    bar.clear();
    seconds.capture = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let bar = out.progress(captured_maps.len() as u64, "synthesis");
    let (mut growths, mut cache) = (Vec::new(), ExemplarCache::new());
    for (dir, region, captured) in captured_maps {
        let target = args.out.join("synth").join(&region);
        growths.push(grow(&region, &captured, args.synth_size, args.seed, &target)?);
        cache.insert(dir.canonicalize().unwrap_or_else(|_| dir.clone()), captured.solution.normals);
        bar.advance(1);
    }
    bar.clear();
    seconds.synthesis = t.elapsed().as_secs_f64();
    Ok((molds, growths, cache))
}

/// Captures one mold with `solver` into `capture/REGION/SOLVER` and measures it against its truth.
fn capture_mold(
    args: &Args,
    region: &str,
    files: &Session,
    solver: SolverArg,
    out: &Output,
) -> Result<(MoldResult, Captured)> {
    let options = options(solver, out)?;
    let mut captured = session::capture(files, &options, &skinkit_maps::progress::NoProgress)?;
    let target = args.out.join("capture").join(region).join(solver.name());
    skinkit_capture::outputs::write(skinkit_capture::outputs::output_set(&target)?, &mut captured, &options)?;
    let r = &captured.report;
    let e = r.error_vs_truth_degrees.context("sample mold without truth.png")?;
    let mold = MoldResult {
        region: region.to_owned(),
        solver: solver.name().into(),
        mean_error_deg: e.mean,
        rms_error_deg: e.rms,
        p95_error_deg: e.p95,
        invalid_pixels: r.invalid_pixels,
        solve_seconds: r.timings_s.solve,
        output: target.display().to_string(),
    };
    Ok((mold, captured))
}

/// The sample face (`samples/../face/layout.toml`) stitched from the captured molds, when the
/// layout exists.
fn stitch_face(args: &Args, samples: &Path, cache: &mut ExemplarCache, out: &Output) -> Result<Option<FaceReport>> {
    let layout = samples.join("../face/layout.toml");
    if !layout.is_file() {
        out.note(format!("no face layout at {}: the face map is skipped", layout.display()));
        return Ok(None);
    }
    let size = if args.full { (4096, 2048) } else { (2048, 1024) };
    out.note(format!("stitching the sample face at {}x{}", size.0, size.1));
    let options = StitchOptions { size: Some(size), seed: args.seed, ..StitchOptions::for_layout(layout) };
    Ok(Some(face_to_dir(&options, &args.out.join("face"), cache, out, Instant::now())?))
}

/// `skinkit accuracy --quick` on the samples the demo ran on, into `accuracy/`.
fn quick_accuracy(args: &Args, molds: &Path, out: &Output) -> Result<skinkit_accuracy::Report> {
    out.note("measuring what each choice of every stage costs (skinkit accuracy --quick)");
    let samples = molds.parent().map_or_else(|| PathBuf::from("samples"), Path::to_path_buf);
    let config = skinkit_accuracy::Config { quick: true, seed: args.seed, samples };
    super::accuracy::to_dir(&config, &skinkit_accuracy::Stage::ALL, &args.out.join("accuracy"), out)
}

/// Figures 7, 8 and the skin figure of the face map; `None` (with a warning saying why) on a
/// machine without a GPU adapter, since the maps are still worth having.
fn render_figures(args: &Args, mm_per_texel: Option<f64>, out: &Output) -> Result<Option<FiguresReport>> {
    out.note("rendering the sample head and a patch of the face map (figures 7 and 8)");
    match figures(&args.out.join("face").join("normal.png"), mm_per_texel, &args.out.join("render"), out) {
        Ok(r) => Ok(Some(r)),
        Err(e)
            if e.downcast_ref::<skinkit_render::renderer::GpuError>()
                .is_some_and(|g| matches!(g, skinkit_render::renderer::GpuError::NoAdapter { .. })) =>
        {
            out.warn(format!("figures skipped: {e}"));
            Ok(None)
        }
        Err(e) => Err(e),
    }
}

/// Grows a captured mold's normal map to `size` with the default synthesis options, replays its
/// albedo through the same coordinates, and writes normal.png (16-bit), albedo.png, coords.png
/// and height.exr.
fn grow(region: &str, captured: &Captured, size: (usize, usize), seed: u64, dir: &Path) -> Result<GrowthResult> {
    let start = Instant::now();
    let config = SynthConfig { seed, ..SynthConfig::new(size.0, size.1) };
    let exemplar = &captured.solution.normals;
    let grown = skinkit_synth::synthesize_normals(exemplar, &config, &skinkit_maps::progress::NoProgress)
        .with_context(|| format!("cannot grow the {region} mold's normal map"))?;
    let seconds = start.elapsed().as_secs_f64();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let normal = dir.join("normal.png");
    io::write_normal_map(&normal, &grown.normals, NormalEncoding::default(), 16)
        .context("cannot write the grown normal map")?;
    let albedo = dir.join("albedo.png");
    match &captured.solution.albedo {
        AlbedoMap::Gray(map) => io::write_scalar_png(&albedo, &skinkit_synth::replay(&grown.coords, map)?, 16),
        AlbedoMap::Rgb(map) => io::write_color_map(&albedo, &skinkit_synth::replay(&grown.coords, map)?, 16),
    }
    .context("cannot write the grown albedo map")?;
    let coords_path = dir.join("coords.png");
    coords::write(&coords_path, &grown.coords).context("cannot write the coordinate map")?;
    // The grown map's height, periodic so it tiles, in mm at the capture's pixel size.
    let mut set = skinkit_maps::OutputSet::files();
    crate::pipeline::grown_height(&mut set, &dir.join("height.exr"), &grown.normals, captured.report.mm_per_pixel)?;
    set.commit().context("cannot finish writing the grown height map")?;
    let quality = QualityReport::new(
        &Map::Normal(exemplar.clone()),
        &Map::Normal(grown.normals),
        &grown.coords,
        false,
        grown.guards,
    )
    .expect("both maps are normal maps");
    Ok(GrowthResult {
        region: region.to_owned(),
        width: size.0,
        height: size.1,
        seconds,
        quality,
        output: normal.display().to_string(),
    })
}
