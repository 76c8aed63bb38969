//! Writing what the subcommands share: a grown map's height, and reports and pages. An error says
//! which output failed by its role (`cannot write the batch report`) and the library error under
//! it names the file, once. (A capture's folder is `skinkit_capture::outputs`.)

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
    .context("cannot write the height map")?;
    Ok(height.report)
}

/// `cannot write {role}`: the context of a failed write of the output `role` (`the batch
/// report`), over the library error that names the file.
fn cannot_write(role: &str) -> String {
    format!("cannot write {role}")
}

/// Writes a value as pretty JSON as `relative` of the folder set `set`; an error says `cannot
/// write {role}` and its cause the final path.
///
/// # Errors
/// When it cannot be written.
pub fn write_json_in<T: Serialize>(set: &OutputSet, relative: &str, role: &str, value: &T) -> Result<()> {
    set.write(relative, |p| documents::write_json(p, value)).with_context(|| cannot_write(role))
}

/// Adds the loose file `path` to `set` and writes a value there as pretty JSON; an error says
/// `cannot write {role}` and its cause the path.
///
/// # Errors
/// When it cannot be written.
pub fn write_json_file<T: Serialize>(set: &mut OutputSet, path: &Path, role: &str, value: &T) -> Result<()> {
    set.write_file(path, |p| documents::write_json(p, value)).with_context(|| cannot_write(role))
}

/// Writes text (a page, a table) as the output `role`, atomically.
///
/// # Errors
/// When it cannot be written.
pub fn write_text(path: &Path, role: &str, text: &str) -> Result<()> {
    documents::write_text(path, text).with_context(|| cannot_write(role))
}

/// Writes a value as pretty JSON as the output `role`, atomically.
///
/// # Errors
/// When it cannot be written.
pub fn write_json<T: Serialize>(path: &Path, role: &str, value: &T) -> Result<()> {
    documents::write_json(path, value).with_context(|| cannot_write(role))
}
