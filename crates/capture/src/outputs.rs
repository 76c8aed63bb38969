//! A capture's folder: the maps of a [`Captured`] session written as one [`OutputSet`] (all files
//! or none, the report last, the maps in parallel, each file timed), what `skinkit capture`,
//! `batch` and `demo` write.
//!
//! | file | holds |
//! | --- | --- |
//! | `normal.exr` | unit normals, float, in the session's normal encoding |
//! | `normal.png` | the same at 16 bits |
//! | `albedo.png` | albedo, 16-bit linear (grey for grey photos, RGB for colour ones) |
//! | `confidence.png` | the solve's confidence, 8-bit |
//! | `height.exr` | the integrated height in mm (when a pixel was solved), unit and scale in its header |
//! | `report.json` | the capture's report; its presence marks a complete folder |

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use skinkit_maps::{OutputSet, documents, io};

use crate::session::{CaptureOptions, Captured};
use crate::solve::AlbedoMap;
use crate::{Error, Result};

/// The files of a capture folder; the report is written last and marks a complete set.
pub const FILES: [&str; 6] = ["normal.exr", "normal.png", "albedo.png", "confidence.png", "height.exr", MARKER];
/// The file whose presence marks a complete capture folder.
pub const MARKER: &str = "report.json";

/// An output file's name, its role in errors (`the albedo map`) and the function that writes it
/// to a path.
type WriteJob<'a> = (&'a str, &'a str, Box<dyn Fn(&Path) -> skinkit_maps::Result<()> + Sync + 'a>);

/// The staged output set of a capture into `dir`, made before the capture so that an interrupt
/// during the solve removes its staging folder too.
pub fn output_set(dir: &Path) -> Result<OutputSet> {
    OutputSet::folder(dir, MARKER).map_err(|e| failed("cannot write the capture folder", e))
}

/// Writes the [`FILES`] into `set` (from [`output_set`]), the maps at once, adds the write times
/// and the peak memory to the report, writes it and commits: the folder gets the whole set or
/// keeps what it had. Returns what the commit cleaned up from killed runs. An error says which
/// file failed by its role (`cannot write the albedo map`); its cause names the path, once.
pub fn write(set: OutputSet, captured: &mut Captured, options: &CaptureOptions) -> Result<Vec<PathBuf>> {
    let t = Instant::now();
    let s = &captured.solution;
    let mut jobs: Vec<WriteJob> = vec![
        ("normal.exr", "the normal map", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 32))),
        ("normal.png", "the normal map", Box::new(|p| io::write_normal_map(p, &s.normals, options.encoding, 16))),
        ("albedo.png", "the albedo map", Box::new(|p| write_albedo(p, &s.albedo))),
        ("confidence.png", "the confidence map", Box::new(|p| io::write_scalar_png(p, &s.confidence, 8))),
    ];
    if let Some(height) = &captured.height {
        jobs.push(("height.exr", "the height map", Box::new(move |p| write_height(p, height))));
    }
    let seconds: Vec<(String, f64)> = jobs
        .par_iter()
        .map(|(name, role, job)| {
            let t = Instant::now();
            set.write(name, |p| job(p)).map_err(|e| failed(&format!("cannot write {role}"), e))?;
            Ok((name.to_string(), t.elapsed().as_secs_f64()))
        })
        .collect::<Result<_>>()?;
    let report = &mut captured.report;
    report.timings_s.write_files = seconds.into_iter().collect();
    report.timings_s.write = t.elapsed().as_secs_f64();
    report.timings_s.total += report.timings_s.write;
    report.peak_memory_mib = skinkit_maps::limits::peak_resident_mib();
    set.write(MARKER, |p| documents::write_json(p, &*report))
        .map_err(|e| failed("cannot write the capture report", e))?;
    set.commit().map_err(|e| failed("cannot finish writing the capture outputs", e))
}

/// `context` (what failed, in the user's words: `cannot write the albedo map`) over the maps
/// crate's error, which names the file: the path is said once, by the cause.
fn failed(context: &str, cause: skinkit_maps::Error) -> Error {
    Error::Context { context: context.to_owned(), cause: Box::new(Error::Maps(cause)) }
}

/// Albedo as 16-bit linear PNG: grey for grey photos, RGB for colour ones.
fn write_albedo(path: &Path, albedo: &AlbedoMap) -> skinkit_maps::Result<()> {
    match albedo {
        AlbedoMap::Gray(map) => io::write_scalar_png(path, map, 16),
        AlbedoMap::Rgb(map) => io::write_color_map(path, map, 16),
    }
}

/// A height map as a float EXR (its unit, scale and integrator in the header).
fn write_height(path: &Path, height: &skinkit_height::Height) -> skinkit_maps::Result<()> {
    Ok(skinkit_height::deliver::write_exr(path, height, Default::default())?)
}
