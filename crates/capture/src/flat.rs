//! Flat fields (issue 39): how unevenly each light lights the field of view, measured from a
//! photo of a white target under that light, and divided out of the light's photos.
//!
//! LEDs a few centimetres from a small mold do not light it as a point at infinity: the
//! irradiance falls off across the field (distance, the LED's own beam, vignetting of the lens).
//! Capture pipelines divide each light's photo by a flat frame of a white target under the same
//! light; RTI flat-field tools fit a low-order polynomial per LED. Here the flat's luminance
//! (minus the ambient frame's, when there is one) is smoothed by a least-squares fit of a
//! bivariate polynomial of total degree [`DEGREE`] to its logarithm, in image coordinates scaled
//! to [-1, 1] (a flat is smooth; the fit removes its noise and the target's texture and has no
//! border bias; in the logarithm, products of falloffs (distance, beam, vignetting) add, a
//! hotspot's `(1 + d^2/R^2)^-1.5` is far closer to a low-order polynomial than in the flat
//! itself, and the gain is positive everywhere), then normalised to mean 1, so the rig's intensity of the light stays its mean intensity.
//! [`correct`] then turns a light's photo into linear readings `(I - ambient) / gain` (f32, full
//! scale 1), after the ambient subtraction as the model needs; a saturated raw reading becomes
//! NaN, which every solver leaves out as it leaves out a saturated one.

use nalgebra::{DMatrix, DVector};
use skinkit_maps::{Channels, Photo, Samples};

use crate::{Error, Result};

/// Total degree of the smoothing polynomial (28 terms).
pub const DEGREE: usize = 6;
/// Samples the fit uses at most (a regular subgrid of the flat).
const FIT_SAMPLES: usize = 16384;
/// Smallest normalised gain: a flat darker than this somewhere does not light that part.
const MIN_GAIN: f32 = 0.02;

/// One light's smoothed, normalised flat field: a gain per pixel, mean 1.
#[derive(Clone, Debug, PartialEq)]
pub struct FlatField {
    width: usize,
    height: usize,
    gain: Vec<f32>,
}

/// The monomials `u^a v^b`, `a + b <= DEGREE`, at `(u, v)`.
fn monomials(u: f64, v: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity((DEGREE + 1) * (DEGREE + 2) / 2);
    for total in 0..=DEGREE {
        for b in 0..=total {
            out.push(u.powi((total - b) as i32) * v.powi(b as i32));
        }
    }
    out
}

/// Pixel `(x, y)` in coordinates scaled to [-1, 1].
fn scaled(x: usize, y: usize, width: usize, height: usize) -> (f64, f64) {
    let s = |i: usize, n: usize| if n > 1 { 2.0 * i as f64 / (n - 1) as f64 - 1.0 } else { 0.0 };
    (s(x, width), s(y, height))
}

impl FlatField {
    /// The flat field of the white-target photo `flat` (named `name` in messages), minus
    /// `ambient` when given.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the flat when its size differs from the ambient frame's,
    /// it has no finite positive reading, or its fit falls under 2 % of its mean somewhere (the
    /// light does not reach that part of the field).
    pub fn from_photo(flat: &Photo, ambient: Option<&Photo>, name: &str) -> Result<Self> {
        let (w, h) = (flat.width(), flat.height());
        let mut lum = flat.luminance();
        if let Some(a) = ambient {
            if (a.width(), a.height()) != (w, h) {
                return Err(Error::InvalidInput(format!(
                    "flat {name} is {w}x{h} but the ambient frame is {}x{}",
                    a.width(),
                    a.height()
                )));
            }
            lum.iter_mut().zip(a.luminance()).for_each(|(v, a)| *v -= a);
        }
        let coefficients = fit(&lum, w, h).ok_or_else(|| {
            Error::InvalidInput(format!("flat {name}: no finite positive readings to fit a flat field to"))
        })?;
        Self::evaluate(&coefficients, w, h, name)
    }

    /// The fitted polynomial at every pixel, normalised to mean 1.
    fn evaluate(coefficients: &DVector<f64>, w: usize, h: usize, name: &str) -> Result<Self> {
        let gain: Vec<f64> = (0..w * h)
            .map(|p| {
                let (u, v) = scaled(p % w, p / w, w, h);
                monomials(u, v).iter().zip(coefficients.iter()).map(|(m, c)| m * c).sum::<f64>().exp()
            })
            .collect();
        Self::normalised(gain, w, h, &format!("flat {name}"))
    }

    /// A radial vignetting model for lights without flat frames (issue 39): the gain
    /// `1 + k1 r^2 + k2 r^4 + ...` with `r` the distance from the image centre over the half
    /// diagonal (1 in the corners), normalised to mean 1 like a fitted flat.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when a coefficient is not finite or the gain falls under 2 % of its
    /// mean somewhere (or is not positive).
    pub fn vignetting(w: usize, h: usize, k: &[f32]) -> Result<Self> {
        if let Some(c) = k.iter().find(|c| !c.is_finite()) {
            return Err(Error::InvalidInput(format!("vignetting coefficient {c} is not finite")));
        }
        let (cx, cy) = ((w as f64 - 1.0) / 2.0, (h as f64 - 1.0) / 2.0);
        let half_diagonal_sq = (cx * cx + cy * cy).max(1e-12);
        let gain: Vec<f64> = (0..w * h)
            .map(|p| {
                let (dx, dy) = ((p % w) as f64 - cx, (p / w) as f64 - cy);
                let r2 = (dx * dx + dy * dy) / half_diagonal_sq;
                1.0 + k.iter().rev().fold(0.0, |acc, &c| (acc + c as f64) * r2)
            })
            .collect();
        Self::normalised(gain, w, h, "vignetting")
    }

    /// `gain` divided by its mean, refused (naming `what`) where it falls under [`MIN_GAIN`].
    fn normalised(mut gain: Vec<f64>, w: usize, h: usize, what: &str) -> Result<Self> {
        let mean = gain.iter().sum::<f64>() / gain.len().max(1) as f64;
        if !(mean > 0.0 && mean.is_finite()) {
            return Err(Error::InvalidInput(format!("{what}: the gain has mean {mean}")));
        }
        gain.iter_mut().for_each(|g| *g /= mean);
        if let Some(p) = gain.iter().position(|&g| !(g >= MIN_GAIN as f64)) {
            return Err(Error::InvalidInput(format!(
                "{what}: the gain is {:.3} of its mean at pixel ({}, {}), under {MIN_GAIN}: \
                 the light does not reach that part of the field",
                gain[p],
                p % w,
                p / w
            )));
        }
        Ok(FlatField { width: w, height: h, gain: gain.into_iter().map(|g| g as f32).collect() })
    }

    /// The gain per pixel, row-major, mean 1.
    pub fn gain(&self) -> &[f32] {
        &self.gain
    }

    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
}

/// Least-squares coefficients of the smoothing polynomial of `ln lum` over a regular subgrid of
/// the finite, positive values of `lum`; `None` when there are too few.
fn fit(lum: &[f32], w: usize, h: usize) -> Option<DVector<f64>> {
    let terms = (DEGREE + 1) * (DEGREE + 2) / 2;
    let stride = ((w * h) as f64 / FIT_SAMPLES as f64).sqrt().ceil().max(1.0) as usize;
    let mut normal = DMatrix::<f64>::zeros(terms, terms);
    let mut rhs = DVector::<f64>::zeros(terms);
    let mut count = 0;
    for y in (0..h).step_by(stride) {
        for x in (0..w).step_by(stride) {
            let v = (lum[y * w + x] as f64).ln();
            if !v.is_finite() {
                continue;
            }
            let (u, s) = scaled(x, y, w, h);
            let m = DVector::from_vec(monomials(u, s));
            normal += &m * m.transpose();
            rhs += &m * v;
            count += 1;
        }
    }
    if count < terms {
        return None;
    }
    normal.svd(true, true).solve(&rhs, 1e-12).ok()
}

/// The photo of a light as linear readings (f32, full scale 1) after ambient subtraction and
/// division by the light's flat field; raw samples at or above `saturation` of full scale (any
/// channel) become NaN.
///
/// # Errors
/// [`Error::InvalidInput`] naming the photo when its size differs from the flat's or the
/// ambient frame's, or its channels from the ambient frame's.
pub fn correct(
    photo: &Photo,
    ambient: Option<&Photo>,
    flat: Option<&FlatField>,
    saturation: f32,
    name: &str,
) -> Result<Photo> {
    let (w, h) = (photo.width(), photo.height());
    let c = photo.channels().count();
    if let Some(f) = flat.filter(|f| f.size() != (w, h)) {
        let (fw, fh) = f.size();
        return Err(Error::InvalidInput(format!("photo {name} is {w}x{h} but its flat field is {fw}x{fh}")));
    }
    if let Some(a) = ambient.filter(|a| (a.width(), a.height(), a.channels()) != (w, h, photo.channels())) {
        return Err(Error::InvalidInput(format!(
            "photo {name} is {w}x{h} {:?} but the ambient frame is {}x{} {:?}",
            photo.channels(),
            a.width(),
            a.height(),
            a.channels()
        )));
    }
    let clip = saturation * photo.samples().full_scale();
    let mut out = vec![0.0f32; w * h * c];
    for p in 0..w * h {
        let saturated = (0..c).any(|k| photo.samples().get(p * c + k) >= clip);
        let gain = flat.map_or(1.0, |f| f.gain[p]);
        for k in 0..c {
            let i = p * c + k;
            let v = photo.linear(i) - ambient.map_or(0.0, |a| a.linear(i));
            out[i] = if saturated { f32::NAN } else { v / gain };
        }
    }
    let channels = if c == 3 { Channels::Rgb } else { Channels::Gray };
    Photo::new(w, h, channels, Samples::F32(out)).map_err(|e| Error::InvalidInput(format!("photo {name}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gray(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Photo {
        let v = (0..w * h).map(|p| f(p % w, p / w)).collect();
        Photo::new(w, h, Channels::Gray, Samples::F32(v)).unwrap()
    }

    /// The exponential of a quadratic is inside the fitted space: the fit returns it exactly,
    /// divided by its mean (computed here independently, in f64).
    #[test]
    fn an_exponential_quadratic_flat_is_recovered_exactly() {
        let (w, h) = (40, 30);
        let f = |x: usize, y: usize| {
            let (u, v) = (x as f64 / 39.0, y as f64 / 29.0);
            (-0.1 - 0.9 * u * u + 0.4 * u * v - 0.7 * v).exp()
        };
        let mean = (0..w * h).map(|p| f(p % w, p / w)).sum::<f64>() / (w * h) as f64;
        let flat = FlatField::from_photo(&gray(w, h, |x, y| f(x, y) as f32), None, "flat.png").unwrap();
        for p in 0..w * h {
            let want = f(p % w, p / w) / mean;
            assert!((flat.gain()[p] as f64 - want).abs() < 1e-4, "pixel {p}: {} against {want}", flat.gain()[p]);
        }
    }

    #[test]
    fn correction_subtracts_ambient_divides_by_the_flat_and_drops_saturation() {
        let (w, h) = (8, 8);
        let flat = FlatField::from_photo(&gray(w, h, |x, _| 0.5 + 0.05 * x as f32), None, "f").unwrap();
        let photo = gray(w, h, |x, y| if (x, y) == (3, 3) { 1.0 } else { 0.6 });
        let ambient = gray(w, h, |_, _| 0.1);
        let out = correct(&photo, Some(&ambient), Some(&flat), 0.995, "p").unwrap();
        let Samples::F32(v) = out.samples() else { panic!("f32 readings") };
        assert!(v[3 * w + 3].is_nan());
        let p = 2 * w + 5;
        assert!((v[p] - 0.5 / flat.gain()[p]).abs() < 1e-6, "{}", v[p]);
    }

    #[test]
    fn a_dark_corner_is_refused_with_the_flat_named() {
        let e = FlatField::from_photo(&gray(20, 20, |x, _| (-0.5 * x as f32).exp()), None, "flat-03.png").unwrap_err();
        assert!(e.to_string().contains("flat-03.png") && e.to_string().contains("does not reach"), "{e}");
    }
}
