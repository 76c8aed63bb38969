//! The height files artists load, each saying in its header what it holds:
//!
//! * `height.exr`: one float channel `Y`, heights in the report's unit (mm when the scale is
//!   known), mean zero; a header attribute `skinkit` of `key=value` pairs (`content`, `unit`,
//!   `integrator`, `residual_rms`, `mm_per_texel`) and OpenEXR's `wrapmodes` for a map that tiles.
//! * a 16-bit PNG at midlevel 0.5: `value = 0.5 + h / scale`, so Blender's Displacement node
//!   (Midlevel 0.5, Scale = `scale`), ZBrush, Mari and Unreal get the height back as
//!   `(value - 0.5) * scale`; the scale is written in `tEXt` entries and returned for the report.
//! * a cavity map: the height's finest band (wavelengths under [`BAND_TEXELS`]`[0]` texels)
//!   normalised so that +-3 of its RMS span `[0, 1]`, 0.5 at the local surface, pores dark.
//! * bands: the height split by wavelength into three float channels R (fine), G (middle) and
//!   B (coarse) that sum to the height, the limits in the header.

use serde::Serialize;
use skinkit_maps::format::ImageFormat;
use skinkit_maps::io::{self, ExrChannel, ExrCompression, ExrOptions, PngColour, PngInfo, PngLayout};
use skinkit_maps::pyramid::{self, Border};
use skinkit_maps::{Grid, ScalarMap};
use std::path::Path;

use crate::{Height, Result};

/// Wavelengths (in texels) that split the bands: a Gaussian pyramid level `k` keeps wavelengths
/// over `2^(k+1)` texels, so levels 2 and 4 split at 8 and 32 texels.
pub const BAND_TEXELS: [f64; 2] = [8.0, 32.0];
/// Pyramid levels whose lowpasses split the bands ([`BAND_TEXELS`]).
const BAND_LEVELS: [usize; 2] = [2, 4];

/// How the height EXR is stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExrStorage {
    /// ZIP compression (lossless; worth it on the large, smooth face maps).
    pub zip: bool,
    /// Half floats (about 3 significant digits: plenty for display, not for re-integration).
    pub half: bool,
}

/// The header attributes every height file carries.
fn attributes(height: &Height) -> Vec<(String, String)> {
    let r = &height.report;
    let mut a = vec![
        ("skinkit.content".to_string(), "height".to_string()),
        ("skinkit.unit".to_string(), r.unit.to_string()),
        ("skinkit.integrator".to_string(), r.integrator.name().to_string()),
        ("skinkit.residual_rms".to_string(), format!("{:.6}", r.residual_rms)),
    ];
    if let Some(mm) = r.mm_per_texel {
        a.push(("skinkit.mm_per_texel".to_string(), format!("{mm}")));
    }
    a
}

/// The attributes as the one `skinkit` header attribute of an EXR, `key=value` pairs joined by
/// `"; "` (the `exr` crate keeps extra attributes in a hash map and writes them in a different
/// order in every process, so one attribute is what keeps the file's bytes reproducible).
fn exr_attribute(pairs: &[(String, String)]) -> (String, String) {
    let text: Vec<String> = pairs.iter().map(|(k, v)| format!("{}={v}", k.trim_start_matches("skinkit."))).collect();
    ("skinkit".to_string(), text.join("; "))
}

fn exr_options(height: &Height, storage: ExrStorage, extra: &[(String, String)]) -> ExrOptions {
    let mut pairs = attributes(height);
    pairs.extend_from_slice(extra);
    ExrOptions {
        compression: if storage.zip { ExrCompression::ZIP16 } else { ExrCompression::Uncompressed },
        half: storage.half,
        attributes: vec![exr_attribute(&pairs)],
        wrap_modes: (height.report.integrator == crate::Integrator::Periodic).then(|| "periodic,periodic".to_string()),
    }
}

/// Writes the height as a one-channel float EXR.
///
/// # Errors
/// When writing fails.
pub fn write_exr(path: &Path, height: &Height, storage: ExrStorage) -> Result<()> {
    let (w, h) = height.map.size();
    let channel = ExrChannel { name: "Y", samples: height.map.as_slice() };
    io::write_exr_channels(path, w, h, &[channel], &exr_options(height, storage, &[]))?;
    Ok(())
}

/// The full range of a 16-bit height PNG: twice the largest excursion from zero, rounded up to
/// two significant digits so that the number a user types into Blender is short.
pub fn png_scale(height: &Height) -> f64 {
    let r = &height.report;
    let reach = 2.0 * f64::from(r.min.abs().max(r.max.abs()));
    if !(reach > 0.0) {
        return 1.0;
    }
    let step = 10f64.powf(reach.log10().floor() - 1.0);
    (reach / step).ceil() * step
}

/// What a user needs to load a height PNG.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct PngScale {
    /// The value of zero height.
    pub midlevel: f64,
    /// Height (in `unit`s) between value 0 and value 1.
    pub scale: f64,
    pub unit: &'static str,
}

/// Writes the height as a 16-bit grey PNG at midlevel 0.5 and returns its scale.
///
/// # Errors
/// When writing fails.
pub fn write_png16(path: &Path, height: &Height) -> Result<PngScale> {
    let scale = png_scale(height);
    let unit = height.report.unit;
    let mut text = attributes(height);
    text.push(("skinkit.midlevel".to_string(), "0.5".to_string()));
    text.push(("skinkit.scale".to_string(), format!("{scale}")));
    text.push(("Description".to_string(), format!("height = (value - 0.5) * {scale} {unit}; linear, not a colour")));
    let (w, h) = height.map.size();
    let map = &height.map;
    let info = PngInfo { colour: PngColour::Linear, text: &text };
    io::write_png_rows_info(path, w, h, PngLayout::Gray16, &info, |y, row| {
        for (out, &v) in row.iter_mut().zip(map.row(y)) {
            *out = ((0.5 + f64::from(v) / scale).clamp(0.0, 1.0) * 65535.0).round() as u16;
        }
    })?;
    Ok(PngScale { midlevel: 0.5, scale, unit })
}

/// The height's three wavelength bands (fine, middle, coarse; they sum to the height).
pub struct Bands {
    pub fine: ScalarMap,
    pub middle: ScalarMap,
    pub coarse: ScalarMap,
}

/// Splits `height` at [`BAND_TEXELS`] with Gaussian pyramid lowpasses (wrapping for a map that
/// tiles).
pub fn bands(height: &Height) -> Bands {
    let border = border(height);
    let low = BAND_LEVELS.map(|levels| lowpass(&height.map, levels, border));
    let minus = |a: &ScalarMap, b: &ScalarMap| Grid::from_fn(a.width(), a.height(), |x, y| a.get(x, y) - b.get(x, y));
    Bands { fine: minus(&height.map, &low[0]), middle: minus(&low[0], &low[1]), coarse: low[1].clone() }
}

fn border(height: &Height) -> Border {
    if height.report.integrator == crate::Integrator::Periodic { Border::Wrap } else { Border::Clamp }
}

/// `g` reduced `levels` times and expanded back to its size.
fn lowpass(g: &ScalarMap, levels: usize, border: Border) -> ScalarMap {
    let mut stack = vec![g.clone()];
    for _ in 0..levels {
        let next = pyramid::reduce(stack.last().expect("one level at least"), border);
        stack.push(next);
    }
    let mut low = stack.pop().expect("one level at least");
    while let Some(finer) = stack.pop() {
        low = pyramid::expand(&low, finer.width(), finer.height(), border);
    }
    low
}

/// Writes the bands as R (fine), G (middle), B (coarse) float channels, with their wavelength
/// limits (`skinkit.band_limits`, in the height's unit) in the header.
///
/// # Errors
/// When writing fails.
pub fn write_bands_exr(path: &Path, height: &Height, bands: &Bands, storage: ExrStorage) -> Result<()> {
    let texel = height.report.mm_per_texel.unwrap_or(1.0);
    let [a, b] = BAND_TEXELS.map(|t| t * texel);
    let unit = height.report.unit;
    let limits = format!("R under {a} {unit}, G {a} to {b} {unit}, B over {b} {unit}, R + G + B = height");
    let options = exr_options(height, storage, &[("skinkit.band_limits".to_string(), limits)]);
    let (w, h) = height.map.size();
    let channels = [
        ExrChannel { name: "R", samples: bands.fine.as_slice() },
        ExrChannel { name: "G", samples: bands.middle.as_slice() },
        ExrChannel { name: "B", samples: bands.coarse.as_slice() },
    ];
    io::write_exr_channels(path, w, h, &channels, &options)?;
    Ok(())
}

/// The cavity map: the fine band over +-3 of its RMS mapped to `[0, 1]`, 0.5 at the local surface.
pub fn cavity(bands: &Bands) -> ScalarMap {
    let fine = bands.fine.as_slice();
    let rms = (fine.iter().map(|&v| f64::from(v) * f64::from(v)).sum::<f64>() / fine.len().max(1) as f64).sqrt();
    let span = if rms > 0.0 { 6.0 * rms } else { 1.0 } as f32;
    bands.fine.map(|&v| (0.5 + v / span).clamp(0.0, 1.0))
}

/// Writes the cavity map as a 16-bit linear grey PNG.
///
/// # Errors
/// When writing fails.
pub fn write_cavity_png(path: &Path, cavity: &ScalarMap) -> Result<()> {
    let text = [(
        "Description".to_string(),
        "cavity: 0.5 at the local surface, darker below it (pores, furrows); linear".to_string(),
    )];
    let info = PngInfo { colour: PngColour::Linear, text: &text };
    let (w, h) = cavity.size();
    io::write_png_rows_info(path, w, h, PngLayout::Gray16, &info, |y, row| {
        for (out, &v) in row.iter_mut().zip(cavity.row(y)) {
            *out = (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
        }
    })?;
    Ok(())
}

/// Writes the height by the extension of `path`: `.exr` as float ([`write_exr`]), `.png` as
/// 16-bit at midlevel 0.5 ([`write_png16`], whose scale is returned).
///
/// # Errors
/// When the extension is neither, or writing fails.
pub fn write_height(path: &Path, height: &Height, storage: ExrStorage) -> Result<Option<PngScale>> {
    match ImageFormat::of(path) {
        Some(ImageFormat::Exr) => write_exr(path, height, storage).map(|_| None),
        Some(ImageFormat::Png) => write_png16(path, height).map(Some),
        _ => Err(crate::Error::Parameter(format!(
            "{}: a height map is written as .exr (float) or .png (16-bit, midlevel 0.5)",
            path.display()
        ))),
    }
}
