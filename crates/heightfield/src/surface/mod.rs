//! [`Surface`]: the analytic skin height function `h(x, y)` (mm, y up, origin at the field's
//! centre) with its exact gradient, the sum of a tilt plane, a Gaussian bulge, fine noise, furrows
//! and pores. Every term is at least C1, so the normal `normalize(-dh/dx, -dh/dy, 1)` is exact.

mod furrows;
mod hash;
mod kernel;
mod pores;
mod waves;

use std::ops::{Add, AddAssign};

use glam::{DVec2, DVec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

pub use pores::Pore;

use crate::Result;
use crate::params::{Bulge, SkinParams};
use furrows::Furrows;
use pores::{PoreField, Rect};
use waves::Waves;

/// RNG streams of the seeded components, so adding one never shifts another's draws.
const STREAM_PORES: u64 = 1;
const STREAM_WAVES: u64 = 2;

/// Height (mm) and gradient `(dh/dx, dh/dy)` at a point, x right and y up.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeightSample {
    pub height: f64,
    pub gradient: DVec2,
}

impl HeightSample {
    /// The unit surface normal `normalize(-dh/dx, -dh/dy, 1)`.
    pub fn normal(&self) -> DVec3 {
        DVec3::new(-self.gradient.x, -self.gradient.y, 1.0).normalize()
    }

    pub(crate) fn scaled(self, factor: f64) -> Self {
        HeightSample { height: self.height * factor, gradient: self.gradient * factor }
    }
}

impl Add for HeightSample {
    type Output = HeightSample;
    fn add(self, o: HeightSample) -> HeightSample {
        HeightSample { height: self.height + o.height, gradient: self.gradient + o.gradient }
    }
}

impl AddAssign for HeightSample {
    fn add_assign(&mut self, o: HeightSample) {
        *self = *self + o;
    }
}

/// The seeded features of one [`SkinParams`], evaluable anywhere (also outside the field).
pub struct Surface {
    params: SkinParams,
    pores: PoreField,
    furrows: Vec<Furrows>,
    waves: Waves,
}

impl Surface {
    /// Draws every random feature of `params`.
    ///
    /// # Errors
    /// When `params` fails [`SkinParams::validate`].
    pub fn new(params: &SkinParams) -> Result<Self> {
        params.validate()?;
        let pores = PoreField::new(&params.pores, pore_rect(params), &mut stream(params.seed, STREAM_PORES));
        let waves = Waves::new(&params.noise, &mut stream(params.seed, STREAM_WAVES));
        let furrows = params.furrows.iter().enumerate().map(|(i, f)| Furrows::new(f, params.seed, i)).collect();
        Ok(Surface { params: params.clone(), pores, furrows, waves })
    }

    pub fn params(&self) -> &SkinParams {
        &self.params
    }

    /// Every pore, including those in the margin just outside the field.
    pub fn pores(&self) -> &[Pore] {
        self.pores.pores()
    }

    /// Height and exact gradient at `(x_mm, y_mm)` (origin at the field's centre, y up).
    pub fn height_and_gradient(&self, x_mm: f64, y_mm: f64) -> HeightSample {
        let p = DVec2::new(x_mm, y_mm);
        self.smooth_terms(p) + self.waves.eval(x_mm, y_mm) + self.detail_terms(p)
    }

    /// Tilt and bulge.
    #[inline]
    fn smooth_terms(&self, p: DVec2) -> HeightSample {
        let tilt = DVec2::from_array(self.params.tilt);
        let plane = HeightSample { height: tilt.dot(p), gradient: tilt };
        match &self.params.bulge {
            Some(b) => plane + bulge(b, p),
            None => plane,
        }
    }

    /// Furrows and pores.
    #[inline]
    fn detail_terms(&self, p: DVec2) -> HeightSample {
        let furrows = self.furrows.iter().fold(HeightSample::default(), |s, f| s + f.eval(p));
        furrows + self.pores.eval(p)
    }

    /// The same as [`Surface::height_and_gradient`] with the noise taken from tabulated parts.
    #[inline]
    pub(crate) fn eval_tabulated(&self, p: DVec2, column: &[f64], row: &[f64]) -> HeightSample {
        self.smooth_terms(p) + self.waves.eval_tables(column, row) + self.detail_terms(p)
    }

    pub(crate) fn waves(&self) -> &Waves {
        &self.waves
    }
}

/// `height * exp(-r^2 / (2 sigma^2))`.
fn bulge(b: &Bulge, p: DVec2) -> HeightSample {
    let inv_var = 1.0 / (b.radius_mm * b.radius_mm);
    let h = b.height_mm * (-0.5 * p.length_squared() * inv_var).exp();
    HeightSample { height: h, gradient: p * (-h * inv_var) }
}

/// The field plus a margin of the largest pore radius, so pores just outside still dent the border.
fn pore_rect(params: &SkinParams) -> Rect {
    let (w, h) = params.extent_mm();
    let half = DVec2::new(w, h) * 0.5 + params.pores.radius_mm * (1.0 + params.pores.variation);
    Rect { min: -half, max: half }
}

fn stream(seed: u64, stream: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    rng
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Central differences of the height function in f64, step 1e-5 mm (truncation ~1e-10 relative
    /// for features 0.05 mm wide, rounding ~1e-12).
    fn numeric_gradient(s: &Surface, x: f64, y: f64) -> DVec2 {
        let e = 1e-5;
        let h = |x, y| s.height_and_gradient(x, y).height;
        DVec2::new((h(x + e, y) - h(x - e, y)) / (2.0 * e), (h(x, y + e) - h(x, y - e)) / (2.0 * e))
    }

    #[test]
    fn analytic_gradient_matches_central_differences_for_every_preset() {
        for params in [
            SkinParams::forehead(200, 150, 4),
            SkinParams::forehead_edge(200, 150, 4),
            SkinParams::nose(200, 150, 4),
            SkinParams::cheek(200, 150, 4),
        ] {
            let params = SkinParams { tilt: [0.03, -0.02], ..params };
            let s = Surface::new(&params).unwrap();
            let mut worst: f64 = 0.0;
            for i in 0..400 {
                let x = ((i * 37) % 200) as f64 * 0.0197 - 2.0;
                let y = ((i * 53) % 150) as f64 * 0.0203 - 1.5;
                let g = s.height_and_gradient(x, y).gradient;
                worst = worst.max((g - numeric_gradient(&s, x, y)).length());
            }
            assert!(worst < 1e-6, "worst gradient error {worst}");
        }
    }

    #[test]
    fn bulge_is_centred_and_rotationally_symmetric() {
        let params =
            SkinParams { bulge: Some(Bulge { height_mm: 0.5, radius_mm: 2.0 }), ..SkinParams::flat(8, 8, 0.1, 0) };
        let s = Surface::new(&params).unwrap();
        assert_eq!(s.height_and_gradient(0.0, 0.0).height, 0.5);
        let a = s.height_and_gradient(1.0, 0.0);
        let b = s.height_and_gradient(0.0, -1.0);
        assert!((a.height - 0.5 * (-0.125f64).exp()).abs() < 1e-15);
        assert!((a.height - b.height).abs() < 1e-15);
        assert!(a.gradient.x < 0.0 && b.gradient.y > 0.0);
    }
}
