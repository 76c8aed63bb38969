//! Robust per-pixel photometric stereo: every light's reading is evidence, weighed by how well
//! it fits a Lambertian surface with attached shadows.
//!
//! A pixel's readings `r_i` (linear, ambient-subtracted, divided by the light's intensity) obey
//! `r_i = max(0, g . L_i) + e_i` with `g = albedo * n` (Haro et al. 2001, equation 1, with the
//! attached shadow made explicit) and `e_i` small noise except at a few lights: specular
//! highlights and inter-reflections add light, cast shadows take it away. Those outliers are sparse
//! (Wu et al. 2010; Ikehata et al. 2012), so the fit looks for the `g` that most readings agree
//! with, in three steps:
//!
//! 1. **Shadows and a rank-trimmed start.** Saturated and non-finite readings never count;
//!    readings under `max(abs, rel * q90)` (`q90` the pixel's 90th-percentile reading, above a
//!    few highlights: [`readings::Shadows`], the rule every solver shares) are shadowed and never
//!    count either. Of the lit ones,
//!    sorted, the darkest [`RobustConfig::trim_dark`] (10 %) and the brightest
//!    [`RobustConfig::trim_bright`] (40 %: highlights and inter-reflections only add light) are
//!    left out, and least squares on the rest gives the first `g`. The thresholds are ranks of
//!    the pixel's own readings, so they follow its albedo and its lights.
//! 2. **Iteratively reweighted least squares** (only [`Estimator::Cauchy`] and [`Estimator::L1`])
//!    over all lit readings. A light the current `g` faces away from (`g . L_i <= 0`) predicts an
//!    attached shadow and carries no linear evidence, so it is left out; every other reading gets
//!    the weight of its residual `e_i = r_i - g . L_i` against the robust scale
//!    `s = 1.4826 median |e|` (floored at [`RobustConfig::scale_floor`] `|g|` and at
//!    [`RobustConfig::noise_floor`], the image's noise when the solve measured it): Cauchy
//!    `1 / (1 + (e / 2.385 s)^2)` (95 % efficient on Gaussian noise) or the L1 weight
//!    `1 / max(|e|, s / 10)` (the sparse-error regression of Ikehata et al. 2012, convex form).
//! 3. **Inlier refit.** The lit lights with `g . L_i > 0` and `|e_i| <= 2 s` are solved once more
//!    by plain least squares, so every reading that agrees counts, and a Lambertian pixel with a
//!    few outliers is recovered exactly, not merely down-weighted.
//!
//! [`Estimator::Trimmed`] (the default) skips step 2: on DiLiGenT cat and the synthetic molds it
//! was the most accurate (the book, "Robust solvers"); the reweightings stay for comparison.
//!
//! The fit is a pure function of its inputs (fixed iteration cap, a convergence test on `g`), so
//! results do not depend on threads. Too few usable readings, an ill-conditioned set of inliers
//! or a black pixel give [`PixelFit::INVALID`], never NaN.

mod linalg;

use glam::Vec3;
use skinkit_maps::limits::MAX_LIGHTS;

use crate::readings::{self, Shadows};
use crate::{Error, Result};
use linalg::Normal3;

/// Relative residual `|r - L g| / |r|` of the all-lights least squares up to which the solve
/// ([`crate::solve::Method::Robust`]) keeps it: the readings agree with one Lambertian normal
/// to within 2 %, about twice what 1 % camera noise gives, so there is nothing to reject.
pub const AGREEMENT: f32 = 0.02;
/// Cauchy tuning constant (95 % efficiency at the Gaussian).
const CAUCHY_C: f32 = 2.385;
/// MAD to standard deviation at the Gaussian.
const MAD_TO_SIGMA: f32 = 1.4826;
/// Residuals beyond this many scales are outliers in the final refit.
const REJECT_SCALES: f32 = 2.0;
/// Smallest `|g|` that still defines a normal (as in the least-squares solve).
const MIN_ALBEDO: f32 = 1e-6;
/// Relative residual at which the residual factor of the confidence is 1/2 (as in the solve).
const RESIDUAL_SCALE: f32 = 0.1;
/// Relative change of `g` below which the reweighting has converged.
const CONVERGED: f32 = 1e-6;

/// How residuals are weighted in the reweighting step.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// The rank-trimmed least squares alone (no reweighting).
    Trimmed,
    /// Cauchy weights `1 / (1 + (e / c s)^2)`.
    Cauchy,
    /// L1 (sparse residual) weights `1 / max(|e|, s / 10)`.
    L1,
}

/// Parameters of [`fit_pixel`].
#[derive(Clone, Debug, PartialEq)]
pub struct RobustConfig {
    pub estimator: Estimator,
    /// Which readings are shadowed and never used: the rule every solver shares
    /// ([`readings::Shadows`]); the solve passes its own [`crate::solve::SolveConfig::shadows`].
    pub shadows: Shadows,
    /// Fraction of a pixel's usable readings, darkest first, left out of the starting fit.
    pub trim_dark: f32,
    /// Fraction of a pixel's usable readings, brightest first, left out of the starting fit.
    pub trim_bright: f32,
    /// Reweighting iterations at most.
    pub iterations: usize,
    /// Smallest residual scale, as a fraction of `|g|` (keeps noise-free pixels well posed).
    pub scale_floor: f32,
    /// Smallest residual scale in reading units (full scale 1, unit light): the image's own noise
    /// `sigma` (the solve measures it, `solve/plan/noise.rs`), so no reading is rejected for noise
    /// alone; 0 for none.
    pub noise_floor: f32,
    /// Fewest inliers for a valid pixel (at least 3).
    pub min_lights: usize,
    /// Largest condition number `sigma_max / sigma_min` of the inliers' direction matrix.
    pub max_condition: f64,
}

impl Default for RobustConfig {
    fn default() -> Self {
        RobustConfig {
            estimator: Estimator::Trimmed,
            shadows: Shadows::default(),
            trim_dark: 0.1,
            trim_bright: 0.4,
            iterations: 12,
            scale_floor: 1e-3,
            noise_floor: 0.0,
            min_lights: 3,
            max_condition: 50.0,
        }
    }
}

impl RobustConfig {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field and its value.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &str, value: String, want: &str| {
            Err(Error::InvalidInput(format!("robust config: {field} = {value} must be {want}")))
        };
        if !(0.0..1.0).contains(&self.shadows.abs) {
            return bad("shadows.abs", self.shadows.abs.to_string(), "in [0, 1)");
        }
        if !(0.0..1.0).contains(&self.shadows.rel) {
            return bad("shadows.rel", self.shadows.rel.to_string(), "in [0, 1)");
        }
        if !(0.0..0.5).contains(&self.trim_dark) {
            return bad("trim_dark", self.trim_dark.to_string(), "in [0, 0.5)");
        }
        if !(0.0..0.5).contains(&self.trim_bright) {
            return bad("trim_bright", self.trim_bright.to_string(), "in [0, 0.5)");
        }
        if !(self.scale_floor > 0.0 && self.scale_floor < 1.0) {
            return bad("scale_floor", self.scale_floor.to_string(), "in (0, 1)");
        }
        if !(self.noise_floor >= 0.0 && self.noise_floor < 1.0) {
            return bad("noise_floor", self.noise_floor.to_string(), "in [0, 1)");
        }
        if self.min_lights < 3 {
            return bad("min_lights", self.min_lights.to_string(), "at least 3");
        }
        if self.max_condition.is_nan() || self.max_condition < 1.0 {
            return bad("max_condition", self.max_condition.to_string(), "at least 1");
        }
        Ok(())
    }
}

/// The fit of one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFit {
    /// Unit normal, `(0, 0, 0)` when invalid.
    pub normal: Vec3,
    /// `|g|`, zero when invalid.
    pub albedo: f32,
    /// In [0, 1]: fraction of lights that are inliers times `min(1, cond_all / cond_inliers)`
    /// times the residual factor `1 / (1 + (rho / 0.1)^2)` over the inliers; 0 when invalid.
    pub confidence: f32,
    /// Bit `i` set when light `i` is an inlier of the final refit.
    pub inliers: u128,
}

impl PixelFit {
    /// The fit of a pixel with no normal.
    pub const INVALID: PixelFit = PixelFit { normal: Vec3::ZERO, albedo: 0.0, confidence: 0.0, inliers: 0 };

    /// Number of inlier lights.
    pub fn used(&self) -> usize {
        self.inliers.count_ones() as usize
    }
}

/// The lights of a rig as [`fit_pixel`] needs them: unit directions and the condition number of
/// all of them together.
#[derive(Clone, Debug)]
pub struct Lights {
    directions: Vec<Vec3>,
    condition: f64,
}

impl Lights {
    /// Normalises `directions`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are more than [`MAX_LIGHTS`] or fewer than 3, or a
    /// direction is zero or not finite.
    pub fn new(directions: &[Vec3]) -> Result<Self> {
        if !(3..=MAX_LIGHTS).contains(&directions.len()) {
            return Err(Error::InvalidInput(format!(
                "robust fit: {} lights, need 3 to {MAX_LIGHTS}",
                directions.len()
            )));
        }
        let mut gram = Normal3::default();
        let mut unit = Vec::with_capacity(directions.len());
        for (i, d) in directions.iter().enumerate() {
            let u = d.normalize_or_zero();
            if u == Vec3::ZERO || !u.is_finite() {
                return Err(Error::InvalidInput(format!("robust fit: light {}: direction {d} has no length", i + 1)));
            }
            gram.add(u, 1.0, 0.0);
            unit.push(u);
        }
        Ok(Lights { directions: unit, condition: gram.condition() })
    }

    pub fn len(&self) -> usize {
        self.directions.len()
    }
    pub fn is_empty(&self) -> bool {
        self.directions.is_empty()
    }
    pub fn directions(&self) -> &[Vec3] {
        &self.directions
    }
}

/// The readings of one pixel that may be used, and working space, on the stack.
struct Pixel<'a> {
    lights: &'a [Vec3],
    r: [f32; MAX_LIGHTS],
    /// Indices of the usable (finite, unsaturated) readings.
    usable: [u8; MAX_LIGHTS],
    count: usize,
}

/// Fits one pixel: `readings[i]` under light `i` (linear, ambient-subtracted, divided by the
/// light's intensity), `saturated[i]` when the raw reading clipped.
///
/// # Panics
/// When `readings` or `saturated` has a different length than `lights` (a caller's bug).
pub fn fit_pixel(readings: &[f32], saturated: &[bool], lights: &Lights, config: &RobustConfig) -> PixelFit {
    fit_directions(readings, saturated, &lights.directions, lights.condition, config)
}

/// [`fit_pixel`] taking the condition number of a set of lights (bit `i` for light `i`) from
/// `condition` when it knows it (the solve's cached subsets), instead of computing it (the
/// closed-form eigenvalues are a sixth of the fit's time at 8 lights).
pub(crate) fn fit_pixel_cached(
    readings: &[f32],
    saturated: &[bool],
    lights: &Lights,
    config: &RobustConfig,
    condition: &dyn Fn(u128) -> Option<f64>,
) -> PixelFit {
    let k = lights.len();
    let all = condition(if k == 128 { u128::MAX } else { (1u128 << k) - 1 }).unwrap_or(lights.condition);
    fit_with(readings, saturated, &lights.directions, all, config, condition)
}

/// [`fit_pixel`] with the pixel's own unit light `directions` (near lights turn across the
/// mold) and the condition number of all of them, which the confidence compares against.
///
/// # Panics
/// When the slices differ in length or hold more than [`MAX_LIGHTS`] lights (a caller's bug).
pub fn fit_directions(
    readings: &[f32],
    saturated: &[bool],
    directions: &[Vec3],
    condition_all: f64,
    config: &RobustConfig,
) -> PixelFit {
    fit_with(readings, saturated, directions, condition_all, config, &|_| None)
}

/// The fit of [`fit_directions`], with known condition numbers from `condition`.
fn fit_with(
    readings: &[f32],
    saturated: &[bool],
    directions: &[Vec3],
    condition_all: f64,
    config: &RobustConfig,
    condition: &dyn Fn(u128) -> Option<f64>,
) -> PixelFit {
    let k = directions.len();
    assert!(readings.len() == k && saturated.len() == k && k <= MAX_LIGHTS, "one reading per light");
    let mut px = Pixel::gather(readings, saturated, directions);
    if px.count < config.min_lights {
        return PixelFit::INVALID;
    }
    let Some(mut g) = px.trimmed_start(config) else {
        return PixelFit::INVALID;
    };
    if config.estimator != Estimator::Trimmed {
        g = px.reweight(g, config);
    }
    px.refit(g, condition_all, config, condition)
}

impl<'a> Pixel<'a> {
    fn gather(readings: &[f32], saturated: &[bool], lights: &'a [Vec3]) -> Self {
        let mut px = Pixel { lights, r: [0.0; MAX_LIGHTS], usable: [0; MAX_LIGHTS], count: 0 };
        for (i, (&v, &sat)) in readings.iter().zip(saturated).enumerate() {
            px.r[i] = v;
            if v.is_finite() && !sat {
                px.usable[px.count] = i as u8;
                px.count += 1;
            }
        }
        px
    }

    fn usable(&self) -> impl Iterator<Item = usize> + '_ {
        self.usable[..self.count].iter().map(|&i| i as usize)
    }

    /// Sorts the usable readings, drops those below the pixel's shadow threshold
    /// `max(abs, rel * q90)` (`q90` its 90th-percentile reading, above any few
    /// highlights) and solves least squares on the remaining ones ranked between the trimmed
    /// fractions. The usable set keeps only the lit readings, in ascending order.
    fn trimmed_start(&mut self, config: &RobustConfig) -> Option<Vec3> {
        let r = &self.r;
        let order = &mut self.usable[..self.count];
        order.sort_unstable_by(|&a, &b| r[a as usize].total_cmp(&r[b as usize]).then(a.cmp(&b)));
        let q90 = r[order[readings::reference_rank(self.count)] as usize];
        let threshold = readings::shadow_floor(config.shadows, q90 as f64) as f32;
        let dark = order.iter().take_while(|&&i| r[i as usize] < threshold).count();
        order.copy_within(dark.., 0);
        self.count -= dark;
        let n = self.count;
        if n < config.min_lights {
            return None;
        }
        let mut lo = (config.trim_dark * n as f32) as usize;
        let mut hi = n - (config.trim_bright * n as f32) as usize;
        // Keep at least the minimum: give back the brightest first, then the darkest.
        while hi - lo < config.min_lights {
            if hi < n { hi += 1 } else { lo -= 1 }
        }
        let mut eq = Normal3::default();
        for &i in &self.usable[lo..hi] {
            eq.add(self.lights[i as usize], 1.0, r[i as usize]);
        }
        eq.solve().or_else(|| self.least_squares(|_| true))
    }

    /// Least squares over the usable readings `keep` accepts.
    fn least_squares(&self, keep: impl Fn(usize) -> bool) -> Option<Vec3> {
        let mut eq = Normal3::default();
        for i in self.usable().filter(|&i| keep(i)) {
            eq.add(self.lights[i], 1.0, self.r[i]);
        }
        eq.solve()
    }

    /// The robust residual scale at `g` over the lights `g` faces: `1.4826 median |e|`, floored
    /// at `floor |g|` and at the noise floor `noise`.
    fn scale(&self, g: Vec3, floor: f32, noise: f32) -> f32 {
        let mut abs = [0.0f32; MAX_LIGHTS];
        let mut m = 0;
        for i in self.usable() {
            let p = g.dot(self.lights[i]);
            if p > 0.0 {
                abs[m] = (self.r[i] - p).abs();
                m += 1;
            }
        }
        let floor = (floor * g.length()).max(noise);
        if m == 0 {
            return floor;
        }
        let mid = m / 2;
        let (_, median, _) = abs[..m].select_nth_unstable_by(mid, f32::total_cmp);
        (MAD_TO_SIGMA * *median).max(floor)
    }

    /// Iteratively reweighted least squares from `g`; returns the last solvable `g`.
    fn reweight(&self, mut g: Vec3, config: &RobustConfig) -> Vec3 {
        for _ in 0..config.iterations {
            let s = self.scale(g, config.scale_floor, config.noise_floor);
            let mut eq = Normal3::default();
            for i in self.usable() {
                let l = self.lights[i];
                let p = g.dot(l);
                if p <= 0.0 {
                    continue;
                }
                let e = self.r[i] - p;
                let w = match config.estimator {
                    Estimator::Cauchy => 1.0 / (1.0 + (e / (CAUCHY_C * s)).powi(2)),
                    Estimator::L1 => 1.0 / e.abs().max(0.1 * s),
                    Estimator::Trimmed => 1.0,
                };
                eq.add(l, w, self.r[i]);
            }
            let Some(next) = eq.solve() else { break };
            let change = (next - g).length();
            g = next;
            if change <= CONVERGED * g.length() {
                break;
            }
        }
        g
    }

    /// The final least-squares refit on the inliers of `g`, with its confidence.
    fn refit(
        &self,
        g: Vec3,
        condition_all: f64,
        config: &RobustConfig,
        known: &dyn Fn(u128) -> Option<f64>,
    ) -> PixelFit {
        let s = self.scale(g, config.scale_floor, config.noise_floor);
        let mut eq = Normal3::default();
        let (mut inliers, mut rr) = (0u128, 0.0f32);
        for i in self.usable() {
            let l = self.lights[i];
            let p = g.dot(l);
            if p > 0.0 && (self.r[i] - p).abs() <= REJECT_SCALES * s {
                eq.add(l, 1.0, self.r[i]);
                inliers |= 1 << i;
                rr += self.r[i] * self.r[i];
            }
        }
        let used = inliers.count_ones() as usize;
        if used < config.min_lights {
            return PixelFit::INVALID;
        }
        let condition = known(inliers).unwrap_or_else(|| eq.condition());
        if used < config.min_lights || !(condition <= config.max_condition) {
            return PixelFit::INVALID;
        }
        let Some(g) = eq.solve() else { return PixelFit::INVALID };
        let len = g.length();
        if !(len > MIN_ALBEDO && len < f32::INFINITY) {
            return PixelFit::INVALID;
        }
        // |r|^2 - |L g|^2 is the squared residual of a least-squares fit; |L g|^2 = g . (L^T r).
        let fitted = g.dot(Vec3::from(eq.b));
        let residual =
            if rr > 0.0 { rr / (rr + (rr - fitted).max(0.0) / (RESIDUAL_SCALE * RESIDUAL_SCALE)) } else { 1.0 };
        let share = used as f32 / self.lights.len() as f32;
        let conditioning = (condition_all / condition).min(1.0) as f32;
        PixelFit { normal: g / len, albedo: len, confidence: share * conditioning * residual, inliers }
    }
}

#[cfg(test)]
mod tests;
