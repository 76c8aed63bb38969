//! Writing a capture: the maps of a [`Captured`] session (`skinkit_capture::session`, which
//! reads, solves and measures) into a folder as one [`OutputSet`] (all files or none, the report
//! last), the maps in parallel, timing each file; shared by `capture`, `batch` and `demo`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Serialize;
use skinkit_capture::session::{CaptureOptions, Captured};
use skinkit_capture::solve::AlbedoMap;
use skinkit_maps::{OutputSet, io};

/// An output file's name and the function that writes it to a path.
type WriteJob<'a> = (&'a str, Box<dyn Fn(&Path) -> skinkit_maps::Result<()> + Sync + 'a>);

/// The files of a capture folder; the report is written last and marks a complete set.
pub const CAPTURE_FILES: [&str; 6] =
    ["normal.exr", "normal.png", "albedo.png", "confidence.png", "height.exr", CAPTURE_MARKER];
/// The file whose presence marks a complete capture folder.
pub const CAPTURE_MARKER: &str = "report.json";

/// The staged output set of a capture into `dir` (made before the capture, so an interrupt
/// during the solve removes its staging folder too).
///
/// # Errors
/// When `dir` is a file or its staging folder cannot be created.
pub fn capture_set(dir: &Path) -> Result<OutputSet> {
    OutputSet::folder(dir, CAPTURE_MARKER).with_context(|| format!("cannot write output folder {}", dir.display()))
}

/// Writes `normal.exr`, `normal.png`, `albedo.png`, `confidence.png`, `height.exr` (when a pixel
/// was solved) and `report.json` into the folder set `set` (from [`capture_set`]), the maps
/// concurrently, and commits it: the folder
/// gets the whole set or keeps what it had. Adds the write time and the peak memory to the report.
/// Returns what the commit cleaned up from killed runs.
///
/// # Errors
/// When a file cannot be written or the set cannot be moved into place; `dir` names the folder.
pub fn write_outputs(
    set: OutputSet,
    dir: &Path,
    captured: &mut Captured,
    options: &CaptureOptions,
) -> Result<Vec<PathBuf>> {
    let t = Instant::now();
    let s = &captured.solution;
    let mut jobs: Vec<WriteJob> = vec![
        ("normal.exr", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 32))),
        ("normal.png", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 16))),
        ("albedo.png", Box::new(|p| write_albedo(p, &s.albedo))),
        ("confidence.png", Box::new(|p| io::write_scalar_png(p, &s.confidence, 8))),
    ];
    if let Some(height) = &captured.height {
        jobs.push(("height.exr", Box::new(move |p| write_height(p, height))));
    }
    let seconds: Vec<(String, f64)> = jobs
        .par_iter()
        .map(|(name, job)| {
            let t = Instant::now();
            set.write(name, |p| job(p)).with_context(|| format!("cannot write {}", dir.join(name).display()))?;
            Ok((name.to_string(), t.elapsed().as_secs_f64()))
        })
        .collect::<Result<_>>()?;
    let report = &mut captured.report;
    report.timings_s.write_files = seconds.into_iter().collect();
    report.timings_s.write = t.elapsed().as_secs_f64();
    report.timings_s.total += report.timings_s.write;
    report.peak_memory_mib = peak_memory_mib();
    write_json_in(&set, CAPTURE_MARKER, &dir.join(CAPTURE_MARKER), report)?;
    set.commit().with_context(|| format!("cannot write output folder {}", dir.display()))
}

/// Albedo as 16-bit linear PNG: grey for grey photos, RGB for colour ones.
fn write_albedo(path: &Path, albedo: &AlbedoMap) -> skinkit_maps::Result<()> {
    match albedo {
        AlbedoMap::Gray(map) => io::write_scalar_png(path, map, 16),
        AlbedoMap::Rgb(map) => io::write_color_map(path, map, 16),
    }
}

/// A height map as a float EXR (its unit, scale and integrator in the header).
pub fn write_height(path: &Path, height: &skinkit_height::Height) -> skinkit_maps::Result<()> {
    skinkit_height::deliver::write_exr(path, height, Default::default()).map_err(height_error)
}

/// Integrates a grown (toroidal) normal map periodically, so its height tiles, and adds it to
/// `set` at `path` (`.exr` float or `.png` 16-bit at midlevel 0.5).
///
/// # Errors
/// When the map has no valid texel or the file cannot be written.
pub fn grown_height(
    set: &mut OutputSet,
    path: &Path,
    normals: &skinkit_maps::NormalMap,
    mm_per_texel: Option<f64>,
) -> Result<skinkit_height::HeightReport> {
    let options = skinkit_height::HeightOptions {
        wraps: true,
        scale: skinkit_height::Scale::from_mm(mm_per_texel)?,
        ..Default::default()
    };
    let height = skinkit_height::integrate(normals, &options).context("cannot integrate the grown map")?;
    let storage = skinkit_height::deliver::ExrStorage::default();
    set.write_file(path, |p| {
        skinkit_height::deliver::write_height(p, &height, storage).map(|_| ()).map_err(height_error)
    })
    .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(height.report)
}

/// The height crate's errors as the maps crate's, which output sets carry.
pub fn height_error(e: skinkit_height::Error) -> skinkit_maps::Error {
    match e {
        skinkit_height::Error::Maps(e) => e,
        other => skinkit_maps::Error::InvalidParameter(other.to_string()),
    }
}

/// Writes a value as pretty JSON as `relative` of the folder set `set`; `shown` names it in errors.
///
/// # Errors
/// When it cannot be written.
pub fn write_json_in<T: Serialize>(set: &OutputSet, relative: &str, shown: &Path, value: &T) -> Result<()> {
    set.write(relative, |p| json_atomic(p, value)).with_context(|| format!("cannot write {}", shown.display()))
}

/// Adds the loose file `path` to `set` and writes a value there as pretty JSON.
///
/// # Errors
/// When it cannot be written.
pub fn write_json_file<T: Serialize>(set: &mut OutputSet, path: &Path, value: &T) -> Result<()> {
    set.write_file(path, |p| json_atomic(p, value)).with_context(|| format!("cannot write {}", path.display()))
}

fn json_atomic<T: Serialize>(path: &Path, value: &T) -> skinkit_maps::Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| skinkit_maps::Error::InvalidParameter(e.to_string()))?;
    text_atomic(path, &text)
}

fn text_atomic(path: &Path, text: &str) -> skinkit_maps::Result<()> {
    io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|e| skinkit_maps::Error::Io { path: path.to_owned(), error: e })
    })
}

/// Writes text (a page, a table), atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    text_atomic(path, text).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    json_atomic(path, value).with_context(|| format!("cannot write {}", path.display()))
}

/// The process's peak resident set (VmHWM) in MiB, where /proc exposes it.
pub fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}
