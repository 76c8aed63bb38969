//! The bytes a capture holds at its peak, worked out stage by stage from the inputs' headers
//! before any pixel is decoded (issue 15, D9; RAW, brackets and flat fields, issue 39).
//!
//! A capture holds, in order:
//! 1. **decode**: every photo as decoded, the ambient frame, the mask (1 byte a pixel) and the
//!    truth map (12), and, while camera RAW files decode (as many at once as rayon has
//!    threads), each one's file read twice (skinkit's copy and the decoder's) and its sensor's
//!    16-bit samples;
//! 2. **brackets**: each bracketed light's photos merged into one f32 reading per channel, its
//!    brackets dropped after the merge;
//! 3. **flat fields** (or the vignetting model): a corrected f32 copy of every photo made while
//!    the merged photos are held, and, per thread, a flat frame being decoded and fitted (its
//!    luminance 4, its fitted gain 8 then 4 bytes a pixel); then the corrected photos only;
//! 4. **solve**: the photos (corrected or not), the solution (normals 12, albedo 4 or 12,
//!    confidence 4 bytes a pixel), mask and truth;
//! 5. **detrend** and **height**: the photos dropped, the solution with a detrended copy of the
//!    normals (12), or the height with its slopes (3 grids of 4 bytes).
//!
//! The estimate is the largest stage.

use std::path::Path;

use skinkit_maps::limits::{self, ImageHeader};

use super::{CaptureOptions, Session, context};
use crate::{Error, Result, Rig};

/// Bytes a pixel of an f32 reading holds per channel.
const F32: u64 = 4;

/// What the estimate knows of one input image.
struct Input {
    header: ImageHeader,
    /// Bytes held only while it decodes (RAW files; 0 otherwise).
    transient: u64,
}

impl Input {
    fn decoded(&self) -> u64 {
        self.header.decoded_bytes()
    }

    /// Channels the solver reads (alpha dropped).
    fn channels(&self) -> u64 {
        u64::from(self.header.channels - u8::from(self.header.alpha)).max(1)
    }
}

/// Reads a header against the limits, checked against the first photo's size (`first`, its path
/// and size; `None` while reading that photo itself); `role` names the image in errors.
fn read(path: &Path, role: &str, options: &CaptureOptions, first: Option<(&Path, ImageHeader)>) -> Result<Input> {
    let raw = options.raw;
    let header = limits::image_header_as(path, options.limits.max_pixels, raw)
        .map_err(|e| context(role.to_owned(), e.into()))?;
    if let Some((first, h)) = first.filter(|(_, h)| (h.width, h.height) != (header.width, header.height)) {
        return Err(Error::InvalidInput(format!(
            "{role} ({}) is {}x{} but photo 1 ({}) is {}x{}",
            path.display(),
            header.width,
            header.height,
            first.display(),
            h.width,
            h.height
        )));
    }
    let transient =
        if skinkit_maps::raw::is_raw(path) { skinkit_maps::raw::decode_cost(path, &header, raw) } else { 0 };
    Ok(Input { header, transient })
}

/// Bytes a capture of `session` holds at its peak (the module's stages), from the images'
/// headers: no pixel is decoded; each header is checked against `options.limits`, and the mask,
/// the ambient frame and the truth map against the photos' size. The rig (for brackets and flat
/// fields) is read from `session.rig`; a rig that does not load is left for [`super::capture`]
/// to report, and the photos are then counted as if each light had one photo and no flat.
///
/// # Errors
/// When a header cannot be read, is over the pixel limit, or an image's size differs from the
/// first photo's.
pub fn memory_estimate(session: &Session, ambient: Option<&Path>, options: &CaptureOptions) -> Result<u64> {
    estimate(session, Rig::load(&session.rig).ok().as_ref(), ambient, options)
}

/// [`memory_estimate`] with the rig already loaded.
pub(super) fn estimate(
    session: &Session,
    rig: Option<&Rig>,
    ambient: Option<&Path>,
    options: &CaptureOptions,
) -> Result<u64> {
    let first = session
        .photos
        .first()
        .ok_or_else(|| Error::InvalidInput(format!("rig {}: no photos were given", session.rig.display())))?;
    let head = read(first, "photo 1", options, None)?.header;
    let read = |path: &Path, role: &str| read(path, role, options, Some((first, head)));
    let photos = (session.photos.iter().enumerate())
        .map(|(i, p)| read(p, &format!("photo {}", i + 1)))
        .collect::<Result<Vec<_>>>()?;
    let ambient = ambient.map(|p| read(p, "ambient frame")).transpose()?;
    let px = head.pixels();
    let mask = session.mask.as_deref().map(|p| read(p, "mask")).transpose()?.map_or(0, |_| px);
    let truth = session.truth.as_deref().map(|p| read(p, "ground truth")).transpose()?.map_or(0, |_| 12 * px);
    let flats = match rig {
        Some(rig) => (rig.lights().iter().enumerate())
            .filter_map(|(i, l)| l.flat().map(|p| read(p, &format!("rig light {}: flat", i + 1))))
            .collect::<Result<Vec<_>>>()?,
        None => Vec::new(),
    };
    let threads = rayon::current_num_threads();
    let ambient_bytes = ambient.as_ref().map_or(0, Input::decoded);
    let kept = mask + truth;

    let mut all: Vec<&Input> = photos.iter().chain(ambient.as_ref()).collect();
    let decoded: u64 = all.iter().map(|i| i.decoded()).sum();
    let decode = kept + decoded + largest_transients(&mut all, threads);
    let (bracket_peak, after_brackets, lights) = brackets(rig, &photos, px);
    let (flatten_peak, stack) = flatten(rig, &flats, after_brackets, lights, px, threads);
    let albedo = if photos[0].channels() >= 3 { 12 } else { 4 };
    let maps = px * (12 + albedo + 4);
    let solve = kept + maps + stack + if flatten_peak > 0 { 0 } else { ambient_bytes };
    let after = truth + maps + px * 12;
    let stages = [decode, kept + ambient_bytes + bracket_peak, kept + ambient_bytes + flatten_peak, solve, after];
    Ok(stages.into_iter().max().unwrap_or(0))
}

/// The sum of the `threads` largest decode transients (RAW files decoding at once).
fn largest_transients(inputs: &mut [&Input], threads: usize) -> u64 {
    inputs.sort_by_key(|i| std::cmp::Reverse(i.transient));
    inputs.iter().take(threads.max(1)).map(|i| i.transient).sum()
}

/// The merge of each bracketed light, lights in photo order: the peak bytes held, the photos'
/// bytes after it, and each light's channel count.
fn brackets(rig: Option<&Rig>, photos: &[Input], px: u64) -> (u64, u64, Vec<u64>) {
    let mut held: u64 = photos.iter().map(Input::decoded).sum();
    let mut peak = held;
    let Some(rig) = rig.filter(|r| r.lights().iter().map(crate::Light::photo_count).sum::<usize>() == photos.len())
    else {
        return (peak, held, photos.iter().map(Input::channels).collect());
    };
    let mut lights = Vec::new();
    let mut at = 0;
    for light in rig.lights() {
        let group = &photos[at..at + light.photo_count()];
        at += group.len();
        let channels = group[0].channels();
        lights.push(channels);
        if light.exposures().is_empty() {
            continue;
        }
        let merged = px * channels * F32;
        peak = peak.max(held + merged);
        held = held + merged - group.iter().map(Input::decoded).sum::<u64>();
    }
    (peak, held, lights)
}

/// The flat-field step: its peak bytes (0 when the rig corrects nothing) and the photos' bytes
/// after it (the merged photos' when it does not run).
fn flatten(rig: Option<&Rig>, flats: &[Input], photos: u64, lights: Vec<u64>, px: u64, threads: usize) -> (u64, u64) {
    let Some(rig) = rig.filter(|r| !flats.is_empty() || !r.vignetting().is_empty()) else {
        return (0, photos);
    };
    let corrected: u64 = lights.iter().map(|&c| px * c * F32).sum();
    let vignetting = if rig.vignetting().is_empty() { 0 } else { px * F32 };
    // Per flat being read: its decode (and RAW transient), luminance, the gain in f64 and f32.
    let mut per_flat: Vec<u64> = flats.iter().map(|f| f.decoded() + f.transient + px * (4 + 8 + 4)).collect();
    per_flat.sort_unstable_by(|a, b| b.cmp(a));
    let fitting: u64 = per_flat.iter().take(threads.max(1)).sum();
    // The common rescale makes a second copy one photo at a time, after the merged are dropped.
    let largest = lights.iter().map(|&c| px * c * F32).max().unwrap_or(0);
    let peak = (photos + corrected + vignetting + fitting).max(corrected + largest);
    (peak, corrected)
}
