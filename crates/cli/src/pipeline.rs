//! Writing what the subcommands share: a grown map's height, and reports and pages with the file
//! named in errors. (A capture's folder is `skinkit_capture::outputs`.)

use std::path::Path;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_maps::{OutputSet, documents};

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
        skinkit_height::deliver::write_height(p, &height, storage).map(|_| ()).map_err(skinkit_maps::Error::from)
    })
    .context("cannot write")?;
    Ok(height.report)
}

/// Writes a value as pretty JSON as `relative` of the folder set `set` (errors name its final path).
///
/// # Errors
/// When it cannot be written.
pub fn write_json_in<T: Serialize>(set: &OutputSet, relative: &str, value: &T) -> Result<()> {
    set.write(relative, |p| documents::write_json(p, value)).context("cannot write")
}

/// Adds the loose file `path` to `set` and writes a value there as pretty JSON.
///
/// # Errors
/// When it cannot be written.
pub fn write_json_file<T: Serialize>(set: &mut OutputSet, path: &Path, value: &T) -> Result<()> {
    set.write_file(path, |p| documents::write_json(p, value)).context("cannot write")
}

/// Writes text (a page, a table), atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    documents::write_text(path, text).context("cannot write")
}

/// Writes a value as pretty JSON, atomically.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    documents::write_json(path, value).context("cannot write")
}
