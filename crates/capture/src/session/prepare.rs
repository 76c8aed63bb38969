//! What capture does to the photos before solving (issue 39): the list of corrections for the
//! report and `rig check`, and the flat-field or vignetting division with its common rescale.

use rayon::prelude::*;
use skinkit_maps::Photo;
use skinkit_maps::raw::RawMode;

use super::{CaptureOptions, context, read_photo};
use crate::{Error, Result, Rig, bracket, flat, near, solve};

/// A session's photos, in rig order with each bracketed light's brackets consecutive, as one
/// reading per light: bracketed lights merged ([`bracket::merge`] at [`bracket::FLOOR`]), the others unchanged;
/// with the readings' names (a merged light's is its first bracket's, with the count).
///
/// # Errors
/// [`Error::InvalidInput`] when the rig brackets a light and the session has an ambient frame
/// (its exposure is not known), or as [`bracket::merge`] naming the light.
pub(super) fn merge_brackets(
    rig: &Rig,
    photos: Vec<Photo>,
    names: &[String],
    ambient: bool,
    saturation: f32,
) -> Result<(Vec<Photo>, Vec<String>)> {
    if rig.lights().iter().all(|l| l.exposures().is_empty()) {
        return Ok((photos, names.to_vec()));
    }
    if ambient {
        return Err(Error::InvalidInput(
            "exposure brackets with an ambient frame are not supported yet (the frame's exposure is unknown)".into(),
        ));
    }
    let mut photos = photos.into_iter();
    let (mut merged, mut readings) = (Vec::new(), Vec::new());
    let mut at = 0;
    for (i, light) in rig.lights().iter().enumerate() {
        let n = light.photo_count();
        let group: Vec<Photo> = photos.by_ref().take(n).collect();
        let name = &names[at];
        at += n;
        if light.exposures().is_empty() {
            merged.extend(group);
            readings.push(name.clone());
        } else {
            merged.push(bracket::merge(
                &group,
                light.exposures(),
                saturation,
                bracket::FLOOR,
                &format!("light {}", i + 1),
            )?);
            readings.push(format!("{name} (+{} brackets)", n - 1));
        }
    }
    Ok((merged, readings))
}

/// What capture's flat-field step will do to the photos, for the report and `rig check`.
pub fn corrections(rig: &Rig, ambient: bool) -> Vec<String> {
    let flats = rig.lights().iter().filter(|l| l.flat().is_some()).count();
    let bracketed = rig.lights().iter().filter(|l| !l.exposures().is_empty()).count();
    let mut out = Vec::new();
    if bracketed > 0 {
        out.push(format!("exposure brackets merged ({bracketed} of {} lights)", rig.light_count()));
    }
    if ambient {
        out.push("ambient subtraction".to_owned());
    }
    if flats > 0 {
        out.push(format!("flat fields ({flats} of {} lights)", rig.light_count()));
    }
    let beams = rig.lights().iter().filter(|l| l.beam().is_some()).count();
    if beams > 0 && near::applies(rig) {
        out.push(format!("LED beam falloff, cos^mu ({beams} of {} lights)", rig.light_count()));
    }
    if !rig.vignetting().is_empty() && flats < rig.light_count() {
        out.push(format!(
            "vignetting model ({} of {} lights, those without flats)",
            rig.light_count() - flats,
            rig.light_count()
        ));
    }
    out
}

/// How camera RAW photos were read, for the report.
pub(super) fn raw_reading(mode: RawMode) -> String {
    let size = match mode {
        RawMode::Half => "half size, 2x2 Bayer binning",
        RawMode::Full => "full size, bilinear demosaicing",
    };
    format!("camera raw ({size}; black level subtracted, white level normalised, no white balance)")
}

/// With flat frames or a vignetting model in the rig: every photo minus the ambient frame,
/// divided by its light's flat field ([`crate::flat`]) or else the rig's vignetting gain, as
/// linear f32 readings, and no ambient frame left to subtract.
/// Without: the photos and the ambient frame unchanged. Division by a gain under 1 can lift a
/// reading over the solver's saturation level, so when it does, every corrected photo is
/// divided by one common `scale` (returned; normals do not change, the albedo is multiplied back).
pub(super) fn flatten(
    rig: &Rig,
    photos: Vec<Photo>,
    ambient: Option<Photo>,
    names: &[String],
    options: &CaptureOptions,
) -> Result<(Vec<Photo>, Option<Photo>, f32)> {
    if rig.lights().iter().all(|l| l.flat().is_none()) && rig.vignetting().is_empty() {
        return Ok((photos, ambient, 1.0));
    }
    let vignetting = match (rig.vignetting(), photos.first()) {
        ([], _) | (_, None) => None,
        (k, Some(p)) => {
            Some(flat::FlatField::vignetting(p.width(), p.height(), k).map_err(|e| context("rig".into(), e))?)
        }
    };
    let saturation = options.solve.saturation;
    let corrected = photos
        .par_iter()
        .zip(rig.lights())
        .zip(names)
        .enumerate()
        .map(|(i, ((photo, light), name))| {
            let flat = light
                .flat()
                .map(|path| {
                    let role = format!("rig light {}: flat", i + 1);
                    let frame = read_photo(path, &role, options)?;
                    flat::FlatField::from_photo(&frame, ambient.as_ref(), &path.display().to_string())
                })
                .transpose()?;
            flat::correct(photo, ambient.as_ref(), flat.as_ref().or(vignetting.as_ref()), saturation, name)
        })
        .collect::<Result<Vec<_>>>()?;
    // The uncorrected photos go before the rescale makes its copy (the memory estimate's stage 3).
    drop(photos);
    let top = corrected.iter().flat_map(|p| samples_f32(p).iter().copied()).fold(0.0f32, f32::max);
    let scale = if top >= 0.9 * saturation { top / (0.9 * saturation) } else { 1.0 };
    if scale == 1.0 {
        return Ok((corrected, None, 1.0));
    }
    let rescaled = corrected
        .into_iter()
        .map(|p| {
            let v = samples_f32(&p).iter().map(|x| x / scale).collect();
            Photo::new(p.width(), p.height(), p.channels(), skinkit_maps::Samples::F32(v)).map_err(Error::Maps)
        })
        .collect::<Result<Vec<_>>>()?;
    Ok((rescaled, None, scale))
}

/// The f32 samples of a corrected photo.
fn samples_f32(photo: &Photo) -> &[f32] {
    match photo.samples() {
        skinkit_maps::Samples::F32(v) => v,
        _ => &[],
    }
}

/// Multiplies the albedo by the common scale `flatten` divided the photos by.
pub(super) fn unscale_albedo(albedo: &mut solve::AlbedoMap, scale: f32) {
    if scale == 1.0 {
        return;
    }
    match albedo {
        solve::AlbedoMap::Gray(m) => m.as_mut_slice().iter_mut().for_each(|a| *a *= scale),
        solve::AlbedoMap::Rgb(m) => m.as_mut_slice().iter_mut().for_each(|a| *a *= scale),
    }
}
