//! Writing a capture: the maps of a [`Captured`] session (`skinkit_capture::session`, which
//! reads, solves and measures) into a folder, each file atomically and all in parallel, timing
//! each file; shared by `capture`, `batch` and `demo`.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Serialize;
use skinkit_capture::session::{CaptureOptions, Captured};
use skinkit_capture::solve::AlbedoMap;
use skinkit_maps::io;

/// An output file's name and the function that writes it to a path.
type WriteJob<'a> = (&'a str, Box<dyn Fn(&Path) -> skinkit_maps::Result<()> + Sync + 'a>);

/// Writes `normal.exr`, `normal.png`, `albedo.png`, `confidence.png` and `report.json` into `dir`
/// (created if needed), each atomically, the four maps concurrently. Adds the write time and the
/// peak memory to the report.
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
        w.write_all(text.as_bytes()).map_err(|e| skinkit_maps::Error::Io { path: path.to_owned(), error: e })
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
