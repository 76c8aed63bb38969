//! The capture pipeline shared by `capture`, `batch` and `demo`: load and check every input first,
//! solve, detrend, and only then write the outputs (atomically), timing each stage.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use serde::Serialize;
use skinkit_capture::solve::{self, AlbedoMap, PhotoStack, Solution, SolveConfig};
use skinkit_capture::{Rig, detrend, near};
use skinkit_maps::io::{self, Limits};
use skinkit_maps::normal::AngularStats;
use skinkit_maps::{Grid, NormalEncoding, NormalMap, Photo, Transfer, Vec3};

/// The files of one capture session.
#[derive(Clone, Debug)]
pub struct Session {
    pub rig: PathBuf,
    /// Photos in rig order.
    pub photos: Vec<PathBuf>,
    pub mask: Option<PathBuf>,
    /// Ambient frame; overrides the rig's own.
    pub ambient: Option<PathBuf>,
    /// Ground-truth normal map to compare against (samples and tests).
    pub truth: Option<PathBuf>,
}

/// Everything that shapes a capture besides its files.
#[derive(Clone, Debug)]
pub struct CaptureOptions {
    pub solve: SolveConfig,
    /// Side of the detrend block in pixels; 0 turns detrending off.
    pub detrend_block: usize,
    pub transfer: Transfer,
    pub encoding: NormalEncoding,
    pub limits: Limits,
}

/// Seconds spent in each stage.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    pub decode: f64,
    pub solve: f64,
    pub detrend: f64,
    /// Report statistics (normal tilt, error against the truth).
    pub stats: f64,
    pub write: f64,
    /// Seconds per output file (they are written concurrently, so these overlap).
    pub write_files: std::collections::BTreeMap<String, f64>,
    pub total: f64,
}

/// What `report.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct CaptureReport {
    pub rig: String,
    pub photos: Vec<String>,
    pub width: usize,
    pub height: usize,
    pub light_count: usize,
    pub solver: String,
    pub condition_number: f64,
    pub noise_amplification: f64,
    pub detrend_block: usize,
    pub valid_pixels: usize,
    pub invalid_pixels: usize,
    /// Angle of the output normals from +Z, in degrees (how rough the captured surface is).
    pub tilt_degrees: AngularStats,
    /// Angular error against the ground truth, when one was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_vs_truth_degrees: Option<AngularStats>,
    pub warnings: Vec<String>,
    pub timings_s: Timings,
    /// Peak resident memory of the process so far, in MiB (Linux only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_mib: Option<f64>,
}

/// A finished capture in memory.
pub struct Captured {
    pub solution: Solution,
    pub report: CaptureReport,
}

/// Reads every input, checks they fit together, solves and detrends. Writes nothing.
///
/// `stage` is told the name of each stage as it starts.
///
/// # Errors
/// When a file is unreadable or inputs do not fit together; the message names the file.
pub fn capture(session: &Session, options: &CaptureOptions, stage: &(dyn Fn(&str) + Sync)) -> Result<Captured> {
    let start = Instant::now();
    let mut timings = Timings::default();
    let rig = Rig::load(&session.rig).with_context(|| format!("cannot use rig {}", session.rig.display()))?;
    let conditioning = rig.check().with_context(|| format!("rig {}", session.rig.display()))?;
    let mut warnings: Vec<String> = conditioning.warning().into_iter().collect();
    if session.photos.len() != rig.lights.len() {
        bail!(
            "rig {} has {} lights but {} photos were given",
            session.rig.display(),
            rig.lights.len(),
            session.photos.len()
        );
    }

    stage("decode");
    let t = Instant::now();
    let photos = read_photos(&session.photos, options)?;
    let ambient_path = session.ambient.clone().or_else(|| rig.ambient.clone());
    let ambient = ambient_path.as_deref().map(|p| read_photo(p, options)).transpose()?;
    let mask = session.mask.as_deref().map(|p| read_mask(p, &options.limits)).transpose()?;
    let truth = session
        .truth
        .as_deref()
        .map(|p| {
            io::read_normal_map(p, options.encoding, &options.limits)
                .with_context(|| format!("ground truth {}", p.display()))
        })
        .transpose()?;
    timings.decode = t.elapsed().as_secs_f64();

    let names: Vec<String> = session.photos.iter().map(|p| p.display().to_string()).collect();
    let mut stack = PhotoStack::new(photos, names.clone())?;
    if let (Some(ambient), Some(path)) = (ambient, &ambient_path) {
        stack = stack.with_ambient(ambient, &path.display().to_string())?;
    }
    if let Some(mask) = mask {
        stack = stack.with_mask(mask)?;
    }
    let (width, height) = (stack.width(), stack.height());

    stage("solve");
    let t = Instant::now();
    // A rig that knows where its lamps are and how large a pixel is gets per-pixel light
    // directions and falloff; otherwise the lights are taken as distant (the paper).
    let near_lights = near::applies(&rig);
    let mut solution = if near_lights {
        near::solve(&stack, &rig, &options.solve)?
    } else {
        solve::solve(&stack, &rig, &options.solve, &solve::no_progress)?
    };
    drop(stack);
    timings.solve = t.elapsed().as_secs_f64();

    stage("detrend");
    let t = Instant::now();
    detrend::detrend(&mut solution.normals, options.detrend_block);
    timings.detrend = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let tilt = tilt_stats(&solution.normals);
    let error_vs_truth =
        truth.map(|truth| compare_with_truth(&solution.normals, truth, options.detrend_block)).transpose()?;
    if solution.stats.invalid_count * 10 > width * height {
        warnings.push(format!(
            "{} of {} pixels ({:.1}%) could not be solved (shadowed, saturated or too few usable lights)",
            solution.stats.invalid_count,
            width * height,
            100.0 * solution.stats.invalid_count as f64 / (width * height) as f64
        ));
    }
    timings.stats = t.elapsed().as_secs_f64();
    timings.total = start.elapsed().as_secs_f64();
    let report = CaptureReport {
        rig: session.rig.display().to_string(),
        photos: names,
        width,
        height,
        light_count: rig.lights.len(),
        solver: format!("{:?}{}", options.solve.method, if near_lights { " (near lights)" } else { "" }).to_lowercase(),
        condition_number: conditioning.condition_number,
        noise_amplification: conditioning.noise_amplification,
        detrend_block: options.detrend_block,
        valid_pixels: width * height - solution.stats.invalid_count,
        invalid_pixels: solution.stats.invalid_count,
        tilt_degrees: tilt,
        error_vs_truth_degrees: error_vs_truth,
        warnings,
        timings_s: timings,
        peak_memory_mib: peak_memory_mib(),
    };
    Ok(Captured { solution, report })
}

/// Decodes the photos in parallel (two at a time per core is enough to hide IO).
fn read_photos(paths: &[PathBuf], options: &CaptureOptions) -> Result<Vec<Photo>> {
    paths.par_iter().map(|p| read_photo(p, options)).collect()
}

fn read_photo(path: &Path, options: &CaptureOptions) -> Result<Photo> {
    let photo =
        io::read_photo(path, &options.limits).with_context(|| format!("cannot read photo {}", path.display()))?;
    // The transfer applies to integer photos only: float photos are linear by definition.
    Ok(if photo.bit_depth() == 32 { photo } else { photo.with_transfer(options.transfer) })
}

/// A mask image: nonzero pixels are the object.
fn read_mask(path: &Path, limits: &Limits) -> Result<Grid<bool>> {
    let map = io::read_scalar_map(path, limits).with_context(|| format!("cannot read mask {}", path.display()))?;
    Ok(map.map(|&v| v > 0.0))
}

/// Angular error against a ground-truth map, detrended the same way as the capture so the two
/// describe the same (fine-scale) surface.
fn compare_with_truth(normals: &NormalMap, mut truth: NormalMap, block: usize) -> Result<AngularStats> {
    if truth.size() != normals.size() {
        bail!(
            "ground truth is {}x{} but the photos are {}x{}",
            truth.width(),
            truth.height(),
            normals.width(),
            normals.height()
        );
    }
    detrend::detrend(&mut truth, block);
    Ok(normals.angular_error(&truth, None)?)
}

/// Angles of the valid normals from +Z.
fn tilt_stats(normals: &NormalMap) -> AngularStats {
    AngularStats::from_par_iter(normals.as_slice().par_iter().filter(|n| **n != Vec3::ZERO).map(|&n| tilt_degrees(n)))
}

/// Angle of a unit vector from +Z in degrees (atan2 form: exact near zero, unlike acos).
fn tilt_degrees(n: Vec3) -> f32 {
    n.truncate().length().atan2(n.z).to_degrees()
}

/// An output file's name and the function that writes it to a path.
type WriteJob<'a> = (&'a str, Box<dyn Fn(&Path) -> skinkit_maps::Result<()> + Sync + 'a>);

/// Writes `normal.exr`, `normal.png`, `albedo.png`, `confidence.png` and `report.json` into `dir`
/// (created if needed), each atomically. Returns the time spent.
///
/// # Errors
/// When the folder cannot be created or a file cannot be written.
pub fn write_outputs(dir: &Path, captured: &mut Captured, options: &CaptureOptions) -> Result<()> {
    let t = Instant::now();
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let s = &captured.solution;
    let jobs: [WriteJob; 4] = [
        ("normal.exr", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 32))),
        ("normal.png", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 16))),
        ("albedo.png", Box::new(|p| write_albedo(p, &s.albedo))),
        ("confidence.png", Box::new(|p| io::write_scalar_png(p, &s.confidence, 8))),
    ];
    let seconds: Vec<(String, f64)> = jobs
        .par_iter()
        .map(|(name, job)| {
            let t = Instant::now();
            job(&dir.join(name)).with_context(|| format!("cannot write {}", dir.join(name).display()))?;
            Ok((name.to_string(), t.elapsed().as_secs_f64()))
        })
        .collect::<Result<_>>()?;
    let report = &mut captured.report;
    report.timings_s.write_files = seconds.into_iter().collect();
    report.timings_s.write = t.elapsed().as_secs_f64();
    report.timings_s.total += report.timings_s.write;
    report.peak_memory_mib = peak_memory_mib();
    write_json(&dir.join("report.json"), report)
}

/// Albedo as 16-bit linear PNG: grey for grey photos, RGB for colour ones.
fn write_albedo(path: &Path, albedo: &AlbedoMap) -> skinkit_maps::Result<()> {
    match albedo {
        AlbedoMap::Gray(map) => io::write_scalar_png(path, map, 16),
        AlbedoMap::Rgb(map) => io::write_color_map(path, map, 16),
    }
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|e| skinkit_maps::Error::Io { path: path.to_owned(), source: e })
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

/// The process's peak resident set (VmHWM) in MiB, where /proc exposes it.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
