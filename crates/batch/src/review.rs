//! What a person looks at first after a batch: per session, the numbers that flag a bad capture
//! ([`Signs`]) and four small previews (the normals' relief under a raking light, the albedo,
//! the confidence, the integrated height in false colour), written to `OUT/batch-review/SESSION/` for the review page ([`page`](crate::page)).
//!
//! The numbers come from the capture in memory. A session skipped as up to date keeps the ones
//! its earlier run wrote (`signs.json` beside the previews); when those are gone, the previews
//! are drawn again from the session's own files and only the report's numbers are given.

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use skinkit_capture::session::Captured;
use skinkit_capture::solve::AlbedoMap;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::preview::{self, Picture};
use skinkit_maps::{Grid, NormalEncoding, NormalMap, OutputSet, ScalarMap};

use crate::resume::Done;

/// The folder of the previews in the output folder: `batch-review/SESSION/`.
pub const FOLDER: &str = "batch-review";
/// Longest side of a preview, pixels: small enough for 500 rows of three on one page.
pub const PREVIEW_SIDE: usize = 96;
/// The previews of a session, in the order the page shows them.
pub const PREVIEWS: [&str; 4] = ["relief.png", "albedo.png", "confidence.png", "height.png"];
/// The numbers of a session, beside its previews.
const SIGNS: &str = "signs.json";

/// The scale of the residual factor of the confidence, `1 / (1 + (rho / RESIDUAL_SCALE)^2)`
/// (`skinkit_capture::solve`'s module docs).
const RESIDUAL_SCALE: f64 = 0.1;

/// The numbers that flag a bad capture.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Signs {
    /// Share of the map's pixels with no normal (shadowed, saturated, masked out, black).
    pub invalid_share: f64,
    /// Share of the solved pixels that left out at least one of the rig's lights (a reading
    /// saturated or too dark): a saturated lamp or a mold in its own shadow raises it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dropped_share: Option<f64>,
    /// Median relative residual `|r - L g| / |r|` of the fit over the solved pixels, worked back
    /// from their confidence: exact for least squares, an upper bound for the robust solvers
    /// (whose confidence also counts the lights left out). A wrong rig raises it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residual: Option<f64>,
    /// Condition number of the rig's light directions.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub condition_number: Option<f64>,
    /// Lowest to highest integrated height over the solved pixels (`height.exr`): a mold's relief
    /// is tens of micrometres; millimetres mean a bowl the detrend left or a wrong scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_range: Option<HeightRange>,
}

/// The span of a session's height map and its unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HeightRange {
    /// Highest minus lowest height, in `unit`.
    pub span: f64,
    /// `"mm"` (the rig gave `mm_per_pixel`) or `"texel"`.
    pub unit: String,
}

impl HeightRange {
    /// The span of `report`'s height.
    pub fn of(report: &skinkit_height::HeightReport) -> Self {
        HeightRange { span: f64::from(report.max - report.min), unit: report.unit.to_owned() }
    }

    /// The span as the page shows it: micrometres for a height in millimetres.
    pub fn text(&self) -> String {
        if self.unit == "mm" { format!("{:.1} µm", 1000.0 * self.span) } else { format!("{:.2} texels", self.span) }
    }
}

/// The signs of a capture in memory.
pub fn signs(captured: &Captured) -> Signs {
    let (report, solution) = (&captured.report, &captured.solution);
    let pixels = (report.width * report.height).max(1);
    let used = &solution.stats.lights_used;
    let solved: usize = used.iter().sum();
    let partial: usize = used.iter().take(used.len().saturating_sub(1)).sum();
    Signs {
        invalid_share: report.invalid_pixels as f64 / pixels as f64,
        dropped_share: (solved > 0).then(|| partial as f64 / solved as f64),
        residual: median_residual(&solution.confidence),
        condition_number: Some(report.condition_number).filter(|c| c.is_finite()),
        height_range: report.height_map.as_ref().map(HeightRange::of),
    }
}

/// The residual `rho` of a confidence `c` whose other factors are 1: `c = 1 / (1 + (rho / s)^2)`.
pub fn residual_of(confidence: f64) -> f64 {
    RESIDUAL_SCALE * (1.0 / confidence - 1.0).max(0.0).sqrt()
}

/// The residual of the median confidence of the solved (positive) pixels; none when none is.
/// The residual falls as the confidence rises, so this is the median residual.
fn median_residual(confidence: &ScalarMap) -> Option<f64> {
    let mut solved: Vec<f32> = confidence.as_slice().iter().copied().filter(|c| *c > 0.0).collect();
    if solved.is_empty() {
        return None;
    }
    let mid = solved.len() / 2;
    let c = *solved.select_nth_unstable_by(mid, f32::total_cmp).1;
    Some(residual_of(f64::from(c)))
}

/// The maps a session's previews are drawn from.
struct Maps<'a> {
    normals: &'a NormalMap,
    albedo: &'a ScalarMap,
    confidence: &'a ScalarMap,
    /// The integrated height, non-finite where no pixel was solved; none when none was.
    height: Option<&'a ScalarMap>,
}

/// Writes the previews of `captured` and its `signs` into `dir`, as one output set (all or
/// nothing, `signs.json` last; an interrupt leaves no half folder).
///
/// # Errors
/// When the folder or a file cannot be written.
pub fn write_previews(dir: &Path, captured: &Captured, signs: &Signs) -> Result<()> {
    let solution = &captured.solution;
    let albedo = match &solution.albedo {
        AlbedoMap::Gray(map) => map.clone(),
        AlbedoMap::Rgb(map) => map.map(|c| 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z),
    };
    let height = captured.height.as_ref().map(|h| {
        let mut map = h.map.clone();
        map.as_mut_slice().iter_mut().zip(&h.valid).filter(|(_, ok)| !**ok).for_each(|(v, _)| *v = f32::NAN);
        map
    });
    let maps =
        Maps { normals: &solution.normals, albedo: &albedo, confidence: &solution.confidence, height: height.as_ref() };
    write_set(dir, &maps, signs)
}

/// Writes the previews of `maps` and `signs` as the review folder `dir`, all or none; an error
/// names the file's role, its cause the path.
fn write_set(dir: &Path, maps: &Maps, signs: &Signs) -> Result<()> {
    if let Some(parent) = dir.parent() {
        std::fs::create_dir_all(parent).with_context(|| format!("cannot create {}", parent.display()))?;
    }
    let set = OutputSet::folder(dir, SIGNS).context("cannot write the review folder")?;
    let pictures = [
        preview::shade_normals(maps.normals, preview::raking_light()),
        preview::gray(maps.albedo),
        confidence_picture(maps.confidence),
        height_picture(maps.height, maps.normals.size()),
    ];
    for (name, picture) in PREVIEWS.iter().zip(&pictures) {
        set.write(name, |p| preview::write_png(p, &preview::shrink(picture, PREVIEW_SIDE)))
            .with_context(|| format!("cannot write the {} preview", name.trim_end_matches(".png")))?;
    }
    set.write(SIGNS, |p| skinkit_maps::documents::write_json(p, signs)).context("cannot write the review signs")?;
    set.commit().context("cannot finish writing the review previews")?;
    Ok(())
}

/// The height in false colour over its robust range (unsolved pixels in the invalid colour); a
/// session with no height is all invalid.
fn height_picture(height: Option<&ScalarMap>, (width, rows): (usize, usize)) -> Picture {
    match height {
        Some(map) => {
            let (lo, hi) = preview::value_range(map.as_slice());
            preview::false_colour(map, lo, hi)
        }
        None => Grid::filled(width, rows, preview::INVALID),
    }
}

/// Confidence drawn as it is, 0 black and 1 white (a stretch would hide a low confidence).
fn confidence_picture(confidence: &ScalarMap) -> Picture {
    confidence.map(|c| {
        let g = (c.clamp(0.0, 1.0) * 255.0).round() as u8;
        [g, g, g]
    })
}

/// The signs of a session skipped as up to date: its earlier run's (`dir/signs.json`, with its
/// previews), else the report's share of invalid pixels and condition number, with the previews
/// drawn again from the session's files in `out_dir`.
///
/// # Errors
/// When the previews cannot be drawn from the session's files.
pub fn signs_of_skipped(out_dir: &Path, dir: &Path, done: &Done) -> Result<Signs> {
    let earlier: Option<Signs> =
        skinkit_maps::input::read_to_string(&dir.join(SIGNS), skinkit_maps::input::Kind::Report)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok());
    if let Some(signs) = earlier.filter(|_| PREVIEWS.iter().all(|p| dir.join(p).is_file())) {
        return Ok(signs);
    }
    let signs = Signs {
        invalid_share: done.invalid_pixels as f64 / done.pixels.max(1) as f64,
        dropped_share: None,
        residual: None,
        condition_number: done.condition_number,
        height_range: None,
    };
    redraw(out_dir, dir, &signs)?;
    Ok(signs)
}

/// The previews drawn from a capture folder's `normal.exr`, `albedo.png`, `confidence.png` and
/// `height.exr` (when it has one: a capture with no solved pixel writes none).
fn redraw(out_dir: &Path, dir: &Path, signs: &Signs) -> Result<()> {
    let limits = Limits::default();
    let normal = out_dir.join("normal.exr");
    let normals = io::read_normal_map(&normal, NormalEncoding::default(), &limits)
        .context("cannot read the session's normal map")?;
    let gray = |name: &str| -> Result<ScalarMap> {
        let path = out_dir.join(name);
        let photo = io::read_photo(&path, &limits).with_context(|| format!("cannot read the session's {name}"))?;
        Ok(Grid::from_vec(photo.width(), photo.height(), photo.luminance())?)
    };
    let height_path = out_dir.join("height.exr");
    let height = match height_path.is_file() {
        true => Some(io::read_exr_channel(&height_path, "Y", &limits).context("cannot read the session's height map")?),
        false => None,
    };
    let (albedo, confidence) = (gray("albedo.png")?, gray("confidence.png")?);
    let maps = Maps { normals: &normals, albedo: &albedo, confidence: &confidence, height: height.as_ref() };
    write_set(dir, &maps, signs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_residual_inverts_the_confidence_factor() {
        // The solver's factor, computed forward: 1 / (1 + (rho / 0.1)^2).
        for rho in [0.0, 0.01, 0.05, 0.1, 0.3, 2.0] {
            let c = 1.0 / (1.0 + (rho / 0.1f64).powi(2));
            assert!((residual_of(c) - rho).abs() < 1e-12, "{rho}");
        }
        assert_eq!(residual_of(1.0), 0.0);
    }

    #[test]
    fn the_median_residual_is_that_of_the_solved_pixels_median_confidence() {
        // Confidences of rho = 0.0, 0.1, 0.2 (1, 0.5, 0.2) and two unsolved pixels.
        let map = Grid::from_vec(5, 1, vec![0.0, 1.0, 0.5, 0.2, 0.0]).unwrap();
        assert!((median_residual(&map).unwrap() - 0.1).abs() < 1e-7);
        assert_eq!(median_residual(&Grid::filled(3, 3, 0.0)), None);
    }
}
