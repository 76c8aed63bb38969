//! A face's folder: normal.png (16-bit) and normal.exr (float), or one pair per UDIM tile;
//! labels.png; the height files (height.exr in mm, height.png at midlevel 0.5, cavity.png,
//! bands.exr); `exemplars/<region>.png`. Written into an [`OutputSet`], so that the folder appears
//! whole or not at all (the caller adds its report and commits).

use skinkit_maps::format::ImageFormat;
use std::path::Path;
use std::time::Instant;

use serde::Serialize;
use skinkit_maps::io::{self, PngColour, PngLayout};
use skinkit_maps::{Grid, NormalEncoding, NormalMap, OutputSet};

use super::Face;
use crate::compose::NO_REGION;
use crate::layout::Layout;
use crate::{Error, Result};

/// The height files of a face folder.
pub const HEIGHT_FILES: [&str; 4] = ["height.exr", "height.png", "cavity.png", "bands.exr"];

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
            || write_height(set, map, self.layout.mm_per_texel, &self.composed.labels),
        );
        normals?;
        let height = height?;
        write_in(set, "labels.png", "the label map", |p| write_labels(p, &self.composed.labels))?;
        for (region, ex) in self.layout.regions.iter().zip(&self.exemplars) {
            let role = format!("the {} exemplar", region.name);
            write_in(set, &format!("exemplars/{}.png", region.name), &role, |p| write_normal_map(p, ex))?;
        }
        Ok(height)
    }
}

/// The face's normal map as normal.png and normal.exr, or on a mesh over several UDIM tiles one
/// pair per tile, `normal.<tile>.png` and `.exr` ([`crate::udim`]).
fn write_normals(set: &OutputSet, layout: &Layout, map: &NormalMap) -> Result<()> {
    let Some(atlas) = layout.atlas.as_ref().filter(|a| !a.is_single_1001()) else {
        write_in(set, "normal.png", "the normal map", |p| write_normal_map(p, map))?;
        return write_in(set, "normal.exr", "the normal map", |p| write_normal_map(p, map));
    };
    for (tile, grid) in atlas.split(map.grid())? {
        let tile_map = NormalMap::from_unit_grid(grid)?;
        let role = format!("the normal map of tile {tile}");
        for format in [ImageFormat::Png, ImageFormat::Exr] {
            let name = format!("normal.{tile}.{}", format.extension());
            write_in(set, &name, &role, |p| write_normal_map(p, &tile_map))?;
        }
    }
    Ok(())
}

/// Integrates the face's normals (Neumann: a face map does not wrap) into millimetres and writes
/// its [`HEIGHT_FILES`] (the EXRs ZIP-compressed, since face maps are large).
fn write_height(set: &OutputSet, map: &NormalMap, mm_per_texel: f64, labels: &Grid<u16>) -> Result<(FaceHeight, f64)> {
    use skinkit_height::deliver::{self, ExrStorage};
    let t = Instant::now();
    let scale = skinkit_height::Scale::from_mm(Some(mm_per_texel)).map_err(Error::Height)?;
    let options = skinkit_height::HeightOptions { scale, ..Default::default() };
    let height = skinkit_height::integrate(map, &options).map_err(Error::Height)?;
    let storage = ExrStorage { zip: true, half: false };
    let h = skinkit_maps::Error::from;
    write_in(set, "height.exr", "the height map", |p| deliver::write_exr(p, &height, storage).map_err(h))?;
    let mut png = None;
    let png16 = |p: &Path| deliver::write_png16(p, &height).map(|s| png = Some(s)).map_err(h);
    write_in(set, "height.png", "the height map", png16)?;
    let bands = deliver::bands(&height);
    write_in(set, "bands.exr", "the height bands", |p| {
        deliver::write_bands_exr(p, &height, &bands, storage).map_err(h)
    })?;
    let cavity = deliver::cavity(&bands);
    write_in(set, "cavity.png", "the cavity map", |p| deliver::write_cavity_png(p, &cavity).map_err(h))?;
    let png = png.expect("write_png16 returned its scale");
    let round_trip = skinkit_height::round_trip::height_agreement(map, &height, false, Some(labels));
    Ok((FaceHeight { height: height.report, png, round_trip }, t.elapsed().as_secs_f64()))
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
