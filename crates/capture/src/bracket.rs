//! Exposure brackets (issue 39): several photos of one light at different exposure times merged
//! into one linear reading per pixel, so a mold's highlights and its furrows' floors are both
//! measured (DiLiGenT itself was shot with several exposures per light).
//!
//! A bracket's reading `v_j` (linear, full scale 1) at exposure time `t_j` estimates the radiance
//! `v_j / t_j`. Under a sensor whose noise is mostly additive (read noise, quantisation: the
//! regime where furrows are lost), that estimate's variance is `sigma^2 / t_j^2`, so the
//! inverse-variance merge weighs each usable bracket by `t_j^2`:
//!
//! `E = sum_j t_j^2 (v_j / t_j) / sum_j t_j^2 = sum_j t_j v_j / sum_j t_j^2`
//!
//! over the brackets that are usable at that pixel:
//! - a reading at or above `saturation` is clipped and says nothing beyond "bright": weight 0;
//! - a reading under `floor` is in the noise: weight 0 while some bracket is above the floor (a
//!   longer exposure measures that pixel), else all unsaturated readings count (the pixel is dark
//!   in every bracket, and their merge is the least noisy estimate there is).
//!
//! The merged reading is expressed at the shortest exposure (`E * t_min`), so it is at most 1
//! wherever the shortest bracket was not clipped; a pixel saturated in every bracket becomes NaN,
//! which every solver leaves out as it leaves out a saturated reading. Colour photos are merged
//! per pixel with one set of weights (a pixel saturated in any channel counts as saturated).

use skinkit_maps::{Photo, Samples};

use crate::{Error, Result};

/// Readings under this fraction of full scale are taken as in the sensor's noise floor when a
/// session's rig brackets a light (see the module docs; [`merge`] takes it as a parameter, and a
/// capture session merges at this floor).
pub const FLOOR: f32 = 0.02;

/// Merges the brackets of one light: `photos[j]` taken with exposure time `times[j]` (any unit,
/// only ratios matter), readings at or above `saturation` of full scale clipped, under `floor`
/// in the noise (see the module docs). Returns linear f32 readings at the shortest exposure.
///
/// # Errors
/// [`Error::InvalidInput`] naming the light when there is no bracket, the counts differ, a time
/// is not positive and finite, or the photos differ in size or channels.
pub fn merge(photos: &[Photo], times: &[f32], saturation: f32, floor: f32, light: &str) -> Result<Photo> {
    check(photos, times, light)?;
    let first = &photos[0];
    let c = first.channels().count();
    let t_min = times.iter().copied().fold(f32::INFINITY, f32::min);
    let mut out = vec![0.0f32; first.pixel_count() * c];
    let mut weights = vec![0.0f32; photos.len()];
    for p in 0..first.pixel_count() {
        usable(photos, times, p, saturation, floor, &mut weights);
        // With w_j = t_j on the usable brackets: sum_j t_j v_j / sum_j t_j^2.
        let total: f32 = weights.iter().zip(times).map(|(w, t)| w * t).sum();
        for k in 0..c {
            let i = p * c + k;
            out[i] = if total > 0.0 {
                let sum: f32 = photos.iter().zip(&weights).map(|(ph, w)| w * ph.linear(i)).sum();
                t_min * sum / total
            } else {
                f32::NAN
            };
        }
    }
    Photo::new(first.width(), first.height(), first.channels(), Samples::F32(out)).map_err(Error::Maps)
}

/// Writes `t_j` into `weights[j]` for the brackets usable at pixel `p` (not clipped; above the
/// floor when any bracket is), 0 for the others.
fn usable(photos: &[Photo], times: &[f32], p: usize, saturation: f32, floor: f32, weights: &mut [f32]) {
    let c = photos[0].channels().count();
    let clipped = |ph: &Photo| (0..c).any(|k| ph.samples().get(p * c + k) >= saturation * ph.samples().full_scale());
    let level = |ph: &Photo| (0..c).map(|k| ph.linear(p * c + k)).fold(f32::NEG_INFINITY, f32::max);
    let above_floor = photos.iter().any(|ph| !clipped(ph) && level(ph) >= floor);
    for ((w, ph), &t) in weights.iter_mut().zip(photos).zip(times) {
        let keep = !clipped(ph) && (!above_floor || level(ph) >= floor);
        *w = if keep { t } else { 0.0 };
    }
}

/// Checks a light's exposure times: each finite and positive.
///
/// # Errors
/// The message names the time by its place (`exposure time 2 is 0 (must be positive)`).
pub fn check_times(times: &[f32]) -> std::result::Result<(), String> {
    match times.iter().enumerate().find(|(_, t)| !(t.is_finite() && **t > 0.0)) {
        Some((j, t)) => Err(format!("exposure time {} is {t} (must be positive)", j + 1)),
        None => Ok(()),
    }
}

fn check(photos: &[Photo], times: &[f32], light: &str) -> Result<()> {
    let bad = |why: String| Err(Error::InvalidInput(format!("{light}: {why}")));
    if photos.is_empty() || photos.len() != times.len() {
        return bad(format!("{} bracket photos for {} exposure times", photos.len(), times.len()));
    }
    if let Err(why) = check_times(times) {
        return bad(why);
    }
    let shape = |p: &Photo| (p.width(), p.height(), p.channels());
    if let Some((j, p)) = photos.iter().enumerate().find(|(_, p)| shape(p) != shape(&photos[0])) {
        let (w, h) = (p.width(), p.height());
        let (w0, h0) = (photos[0].width(), photos[0].height());
        return bad(format!(
            "bracket {} is {w}x{h} {:?} but bracket 1 is {w0}x{h0} {:?}",
            j + 1,
            p.channels(),
            photos[0].channels()
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use skinkit_maps::Channels;

    fn grey(values: &[u16]) -> Photo {
        Photo::new(values.len(), 1, Channels::Gray, Samples::U16(values.to_vec())).unwrap()
    }

    /// Against hand-worked sums: pixel 0 usable in all three brackets, pixel 1 clipped in the
    /// longest, pixel 2 under the floor in the shortest (a longer bracket measures it), pixel 3
    /// dark in all (all count), pixel 4 clipped in all (NaN).
    #[test]
    fn merge_weighs_by_exposure_and_drops_clipped_and_buried_readings() {
        let f = 65535.0f32;
        let v = |x: f32| (x * f).round() as u16;
        let short = grey(&[v(0.1), v(0.2), v(0.001), v(0.001), 65535]);
        let mid = grey(&[v(0.2), v(0.4), v(0.02), v(0.002), 65535]);
        let long = grey(&[v(0.4), 65535, v(0.04), v(0.003), 65535]);
        let times = [1.0, 2.0, 4.0];
        let merged = merge(&[short, mid, long], &times, 0.995, 0.01, "light 1").unwrap();
        let Samples::F32(out) = merged.samples() else { panic!("float") };
        let q = |x: f32| (x * f).round() / f;
        let want = [
            (1.0 * q(0.1) + 2.0 * q(0.2) + 4.0 * q(0.4)) / 21.0,
            (1.0 * q(0.2) + 2.0 * q(0.4)) / 5.0,
            (2.0 * q(0.02) + 4.0 * q(0.04)) / 20.0,
            (1.0 * q(0.001) + 2.0 * q(0.002) + 4.0 * q(0.003)) / 21.0,
        ];
        for (p, w) in want.iter().enumerate() {
            assert!((out[p] - w).abs() < 1e-6, "pixel {p}: {} vs {w}", out[p]);
        }
        assert!(out[4].is_nan());
    }

    #[test]
    fn bad_brackets_are_refused_naming_the_light() {
        let e = merge(&[grey(&[1])], &[1.0, 2.0], 0.995, 0.0, "light 3").unwrap_err().to_string();
        assert!(e.starts_with("light 3: 1 bracket photos for 2 exposure times"), "{e}");
        let e = merge(&[grey(&[1]), grey(&[1])], &[1.0, 0.0], 0.995, 0.0, "light 3").unwrap_err().to_string();
        assert!(e.contains("exposure time 2 is 0"), "{e}");
        let e = merge(&[grey(&[1]), grey(&[1, 2])], &[1.0, 2.0], 0.995, 0.0, "light 3").unwrap_err().to_string();
        assert!(e.contains("bracket 2 is 2x1"), "{e}");
    }
}
