//! A face's folder: normal.png (16-bit) and normal.exr (float); labels.png; the height files
//! (height.exr in mm, height.png at midlevel 0.5, cavity.png, bands.exr); `exemplars/<region>.png`.
//! On a mesh over several UDIM tiles each map is one file per tile, the tile's number before the
//! extension (`normal.1001.png`, `height.1002.exr`, `labels.1003.png`, ...): the face is grown,
//! integrated and split into bands as one atlas ([`crate::udim`]), then cut, so the tiles meet
//! without a step and every height tile has the same PNG scale. [`file_names`] lists what a
//! layout's folder holds. Written into an [`OutputSet`], so that the folder appears whole or not
//! at all (the caller adds its report and commits).

use skinkit_maps::format::ImageFormat;
use std::borrow::Cow;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use skinkit_maps::io::{self, PngColour, PngLayout};
use skinkit_maps::{Grid, NormalEncoding, NormalMap, OutputSet};

use super::Face;
use crate::compose::NO_REGION;
use crate::layout::Layout;
use crate::{Error, Result};

/// The height files of a face folder (on UDIM tiles, one of each per tile).
pub const HEIGHT_FILES: [&str; 4] = ["height.exr", "height.png", "cavity.png", "bands.exr"];

/// The maps of a face folder other than the height files (on UDIM tiles, one of each per tile).
pub const MAP_FILES: [&str; 3] = ["normal.png", "normal.exr", "labels.png"];

/// The UDIM atlas a layout's maps are cut into, unless it is the one tile 1001.
fn udim_atlas(layout: &Layout) -> Option<&crate::udim::Atlas> {
    layout.atlas.as_ref().filter(|a| !a.is_single_1001())
}

/// What the names of a layout's files carry before their extension: nothing, or each tile's
/// number (`.1001`, `.1002`, ...).
fn tile_suffixes(layout: &Layout) -> Vec<String> {
    udim_atlas(layout).map_or(vec![String::new()], |a| a.tiles.iter().map(|t| format!(".{t}")).collect())
}

/// `name` (`normal.png`) with `suffix` before its extension (`normal.1001.png`).
fn with_suffix(name: &str, suffix: &str) -> String {
    match name.split_once('.') {
        Some((stem, ext)) => format!("{stem}{suffix}.{ext}"),
        None => format!("{name}{suffix}"),
    }
}

/// Every file [`Face::write_folder`] writes for `layout`, relative to the folder (the report,
/// which the caller writes, aside): what an output check compares with the inputs.
pub fn file_names(layout: &Layout) -> Vec<String> {
    let suffixes = tile_suffixes(layout);
    let maps = MAP_FILES.iter().chain(&HEIGHT_FILES);
    let mut names: Vec<String> = maps.flat_map(|n| suffixes.iter().map(move |s| with_suffix(n, s))).collect();
    names.extend(layout.regions.iter().map(|r| format!("exemplars/{}.png", r.name)));
    names
}

/// `grid` as the pieces its files hold, each with its [`tile_suffixes`] suffix: the whole map, or
/// on UDIM tiles one piece per tile.
fn pieces<'a, T: Clone>(layout: &Layout, grid: &'a Grid<T>) -> Result<Vec<(String, Cow<'a, Grid<T>>)>> {
    match udim_atlas(layout) {
        None => Ok(vec![(String::new(), Cow::Borrowed(grid))]),
        Some(atlas) => Ok(atlas.split(grid)?.into_iter().map(|(t, g)| (format!(".{t}"), Cow::Owned(g))).collect()),
    }
}

/// The role of a piece in messages: `the normal map`, or `the normal map of tile 1001`.
fn piece_role(role: &str, suffix: &str) -> String {
    match suffix.strip_prefix('.') {
        Some(tile) => format!("{role} of tile {tile}"),
        None => role.to_owned(),
    }
}

/// What a face's height files hold: the integration's report and how to load height.png.
#[derive(Clone, Debug, Serialize)]
pub struct FaceHeight {
    #[serde(flatten)]
    pub height: skinkit_height::HeightReport,
    pub png: skinkit_height::deliver::PngScale,
    /// The height's own normals against the face's normal map (through the same central
    /// differences), overall and on the regions' seams against off them.
    pub round_trip: skinkit_height::round_trip::Agreement,
}

impl Face {
    /// Writes the face's maps into the folder set `set` (its errors name each file's role and
    /// final path): the normals and the height files at once (two threads), then the labels and
    /// the exemplars. Returns the height files' report and the seconds they took.
    pub fn write_folder(&self, set: &OutputSet) -> Result<(FaceHeight, f64)> {
        let map = &self.composed.normals;
        let (normals, height) = rayon::join(
            || write_normals(set, &self.layout, map),
            || write_height(set, &self.layout, map, &self.composed.labels),
        );
        normals?;
        let height = height?;
        for (suffix, labels) in pieces(&self.layout, &self.composed.labels)? {
            let role = piece_role("the label map", &suffix);
            write_in(set, &with_suffix("labels.png", &suffix), &role, |p| write_labels(p, &labels))?;
        }
        for (region, ex) in self.layout.regions.iter().zip(&self.exemplars) {
            let role = format!("the {} exemplar", region.name);
            write_in(set, &format!("exemplars/{}.png", region.name), &role, |p| write_normal_map(p, ex))?;
        }
        Ok(height)
    }
}

/// The face's normal map as normal.png and normal.exr, one pair per UDIM tile on a mesh over
/// several ([`pieces`]).
fn write_normals(set: &OutputSet, layout: &Layout, map: &NormalMap) -> Result<()> {
    for (suffix, grid) in pieces(layout, map.grid())? {
        let piece = match grid {
            Cow::Borrowed(_) => Cow::Borrowed(map),
            Cow::Owned(g) => Cow::Owned(NormalMap::from_unit_grid(g)?),
        };
        let role = piece_role("the normal map", &suffix);
        for format in [ImageFormat::Png, ImageFormat::Exr] {
            let name = format!("normal{suffix}.{}", format.extension());
            write_in(set, &name, &role, |p| write_normal_map(p, &piece))?;
        }
    }
    Ok(())
}

/// Integrates the face's normals (Neumann: a face map does not wrap) into millimetres and writes
/// its [`HEIGHT_FILES`] (the EXRs ZIP-compressed, since face maps are large), per UDIM tile on a
/// mesh over several: integrated, banded and its PNG scale chosen over the whole atlas, then cut.
fn write_height(set: &OutputSet, layout: &Layout, map: &NormalMap, labels: &Grid<u16>) -> Result<(FaceHeight, f64)> {
    use skinkit_height::deliver;
    let t = Instant::now();
    let scale = skinkit_height::Scale::from_mm(Some(layout.mm_per_texel)).map_err(Error::Height)?;
    let options = skinkit_height::HeightOptions { scale, ..Default::default() };
    let height = skinkit_height::integrate(map, &options).map_err(Error::Height)?;
    let bands = deliver::bands(&height);
    let cavity = deliver::cavity(&bands);
    let png = match udim_atlas(layout) {
        None => write_height_files(set, "", &height, &bands, &cavity)?,
        Some(atlas) => {
            let (w, h) = height.map.size();
            let valid = atlas.split(&Grid::from_vec(w, h, height.valid.clone())?)?;
            let (maps, cavities) = (atlas.split(&height.map)?, atlas.split(&cavity)?);
            let (fine, middle, coarse) =
                (atlas.split(&bands.fine)?, atlas.split(&bands.middle)?, atlas.split(&bands.coarse)?);
            let mut png = None;
            for (i, (tile, map)) in maps.into_iter().enumerate() {
                let report = height.report.clone();
                let tile_height = skinkit_height::Height { map, valid: valid[i].1.as_slice().to_vec(), report };
                let [f, m, c] = [&fine, &middle, &coarse].map(|b| b[i].1.clone());
                let tile_bands = deliver::Bands { fine: f, middle: m, coarse: c };
                png = Some(write_height_files(set, &format!(".{tile}"), &tile_height, &tile_bands, &cavities[i].1)?);
            }
            png.expect("an atlas has at least one tile")
        }
    };
    let round_trip = skinkit_height::round_trip::height_agreement(map, &height, false, Some(labels));
    Ok((FaceHeight { height: height.report, png, round_trip }, t.elapsed().as_secs_f64()))
}

/// Writes one piece's [`HEIGHT_FILES`], each name with `suffix` before its extension, and
/// returns the PNG's scale (the whole atlas's: every tile's report is the atlas's).
fn write_height_files(
    set: &OutputSet,
    suffix: &str,
    height: &skinkit_height::Height,
    bands: &skinkit_height::deliver::Bands,
    cavity: &skinkit_maps::ScalarMap,
) -> Result<skinkit_height::deliver::PngScale> {
    use skinkit_height::deliver::{self, ExrStorage};
    let storage = ExrStorage { zip: true, half: false };
    let e = skinkit_maps::Error::from;
    let (name, role) = (|n: &str| with_suffix(n, suffix), |r: &str| piece_role(r, suffix));
    write_in(set, &name("height.exr"), &role("the height map"), |p| deliver::write_exr(p, height, storage).map_err(e))?;
    let mut png = None;
    let png16 = |p: &Path| deliver::write_png16(p, height).map(|s| png = Some(s)).map_err(e);
    write_in(set, &name("height.png"), &role("the height map"), png16)?;
    write_in(set, &name("bands.exr"), &role("the height bands"), |p| {
        deliver::write_bands_exr(p, height, bands, storage).map_err(e)
    })?;
    write_in(set, &name("cavity.png"), &role("the cavity map"), |p| deliver::write_cavity_png(p, cavity).map_err(e))?;
    Ok(png.expect("write_png16 returned its scale"))
}

/// Writes `name` of the folder set `set`; an error says `cannot write {role}` over the set's,
/// which names the final path.
fn write_in(
    set: &OutputSet,
    name: &str,
    role: &str,
    write: impl FnOnce(&Path) -> skinkit_maps::Result<()>,
) -> Result<()> {
    set.write(name, write).map_err(|source| Error::Write { role: role.to_owned(), source })
}

/// A normal map as 16-bit PNG or, for `.exr`, float EXR.
pub fn write_normal_map(path: &Path, map: &NormalMap) -> skinkit_maps::Result<()> {
    let bits = if ImageFormat::of(path) == Some(ImageFormat::Exr) { 32 } else { 16 };
    io::write_normal_map(path, map, NormalEncoding::default(), bits)
}

/// A distinct, stable colour per region index (golden-angle hues); black for no region.
pub fn label_colour(label: u16) -> [u16; 3] {
    if label == NO_REGION {
        return [0, 0, 0];
    }
    let hue = (label as f32 * 0.618_034).fract() * 6.0;
    let f = |n: f32| {
        let k = (n + hue) % 6.0;
        let v = 1.0 - (k.min(4.0 - k).clamp(0.0, 1.0)) * 0.75;
        (v * 255.0).round() as u16
    };
    [f(5.0), f(3.0), f(1.0)]
}

/// The region labels as an 8-bit sRGB PNG, one [`label_colour`] per region.
pub fn write_labels(path: &Path, labels: &Grid<u16>) -> skinkit_maps::Result<()> {
    let (w, h) = labels.size();
    io::write_png_rows(path, w, h, PngLayout::Rgb8, PngColour::Srgb, |y, row| {
        for (px, &l) in row.chunks_exact_mut(3).zip(labels.row(y)) {
            px.copy_from_slice(&label_colour(l));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_colours_differ_for_the_first_regions() {
        let colours: Vec<[u16; 3]> = (0..12).map(label_colour).collect();
        for (i, a) in colours.iter().enumerate() {
            assert!(a.iter().all(|&c| c <= 255));
            for b in &colours[..i] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(label_colour(NO_REGION), [0, 0, 0]);
    }
}
