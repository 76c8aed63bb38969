//! Closed forms of the pre-integrated diffuse falloff D(N.L, 1/r) (Penner and Borshukov 2011,
//! equation 1.1), cheap enough to replace the lookup table in a shader.
//!
//! The truth is [`reference_direct`]: the falloff with the default definitions (2-D normalised sum
//! of Gaussians over a sphere's surface, [`super::sphere`], curvature `1/r` in 1/mm).
//!
//! Two closed forms are measured against it:
//!
//! - [`blog_direct`]: the hand-fitted curves of the blog post "Pre-integrated skin shading: curve
//!   approximation" (seed `001`), transcribed with the minus signs the text extraction lost
//!   restored (`1.0  x` is `1.0 - x`, `mad(NdotL, m, 0.99  m)` is `NdotL * m + (0.99 - m)`, the
//!   final blend weight `mad(c2, -1.0 * c2, 1.0)` is `1 - (1 - curva)^4`). The blog's
//!   `curvature` in [0, 1] stands for `r = 1 / (curvature (0.5 - 0.0625) + 0.0625)`, r from 16
//!   down to 2; we read r in millimetres, so `curvature = (1/r - 0.0625) / 0.4375`
//!   (`blog_curvature`). Outside `1/r` in [0.0625, 0.5] mm^-1 the blog's curve is clamped to
//!   its end curves: below 0.0625 it stays the r = 16 mm curve (not the clamped N.L of flat skin).
//!   The blog fitted its own table (whose definitions it does not state; see below), so its
//!   error here is the error against our table, not a measure of the blog's care.
//! - [`own_direct`]: our fit, per channel a mixture of two smoothed ramps times a gain,
//!
//!   `D = g(k) * (ramp(N.L, w1(k)) + (ramp(N.L, w2(k)) - ramp(N.L, w1(k))) * beta)`, with
//!   `k = clamp(1/r, 0, 1)`, `w_i(k) = a_i k / (1 + |b_i| k)`, `g(k) = 1 - c k^2 / (1 + |d| k^2)` and
//!   `ramp(x, w) = (clamp(x, -w, w) + w)^2 / (4 w) + max(x - w, 0)`,
//!
//!   the clamped ramp `max(x, 0)` convolved with a box of half-width `w` (so it is exactly 0 for
//!   `x < -w`, exactly `x` above `w`, C1 everywhere). Blurring the clamped cosine over the
//!   surface by a narrow kernel does this near the terminator, and dims it by a factor elsewhere (the
//!   gain); two widths stand for the profile's narrow and wide Gaussians. At `1/r = 0` both
//!   widths are `OWN_MIN_WIDTH`, which gives the clamped N.L to within that width. The seven
//!   coefficients per channel ([`OWN_FIT`]) are the least-squares fit ([`fit_own_direct`],
//!   Levenberg-Marquardt) on [`FitGrid::FIT`]; `1/r` above 1 mm^-1 is clamped to 1. On the GPU
//!   this is two clamps, two divides and about a dozen multiply-adds per pixel for all three
//!   channels (vectorised), no table and no transcendental.
//!
//! Measured by [`fit_report_on`], absolute error against [`reference_direct`] (red, green, blue):
//!
//! | grid | closed form | max | rms |
//! | --- | --- | --- | --- |
//! | [`FitGrid::BLOG_RANGE`] (201 N.L x 29 1/r in [0.0625, 0.5]) | blog | 0.20, 0.018, 0.0075 | 0.043, 0.0065, 0.0017 |
//! | | own | 0.0095, 0.00125, 0.00057 | 0.0035, 0.00032, 0.00013 |
//! | [`FitGrid::FULL`] (201 x 41 in [0, 1]) | blog (clamped) | 0.29, 0.051, 0.025 | 0.068, 0.011, 0.0039 |
//! | | own | 0.013, 0.0026, 0.0013 | 0.0036, 0.00070, 0.00032 |
//!
//! Red is the hard channel: its wide Gaussians reach across a small sphere, so its widths and
//! dimming saturate with curvature (hence the rational forms; widths linear in `k` and a
//! quadratic gain left red's rms error at 0.009 over the whole range).
//!
//! The blog's largest errors are in red near the terminator at r = 2 mm: its table scatters
//! far more light past N.L = 0 than ours, so it is brighter there by up to 0.20. Its table was
//! most likely built with the pre-integrated paper's listing normalisation
//! ([`super::profile::Normalisation::OneD`], full ring): against that table the blog's rms error
//! falls to 0.030, 0.0069, 0.0017 (max 0.19, 0.022, 0.0058), and its zonal factors agree with it
//! to 3% ([`super::sh`]). [`fit_own_direct`] takes any samples, so the same form can be refitted
//! to another definition's table.
//!
//! The WGSL twins are in `shaders/skin_fit.wgsl` ([`SKIN_FIT_WGSL`]).

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::profile::Profile;
use super::sphere::SphereFalloff;

/// The lower end of the blog's range of 1/r, mm^-1 (r = 16 mm).
pub const BLOG_INV_R_MIN: f32 = 0.0625;
/// The upper end of the blog's range of 1/r, mm^-1 (r = 2 mm).
pub const BLOG_INV_R_MAX: f32 = 0.5;

/// The WGSL snippet with `blog_direct` and `own_direct` (no bindings, no entry points).
pub const SKIN_FIT_WGSL: &str = include_str!("../../shaders/skin_fit.wgsl");

/// The true falloff D(N.L, 1/r) per channel, with the default definitions.
pub fn reference_direct(n_dot_l: f64, inv_r_mm: f64) -> [f64; 3] {
    SphereFalloff::new(&Profile::default(), inv_r_mm).at(n_dot_l)
}

/// `x` with NaN replaced by `fallback`.
fn or_if_nan(x: f32, fallback: f32) -> f32 {
    if x.is_nan() { fallback } else { x }
}

/// HLSL's `saturate`.
fn saturate(x: f32) -> f32 {
    x.clamp(0.0, 1.0)
}

/// HLSL's `lerp`, written as the WGSL twin writes it.
fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + (b - a) * t
}

/// The blog's `curvature` in [0, 1] for `1/r` in mm^-1: 0 at r = 16 mm, 1 at r = 2 mm, clamped
/// outside (NaN counts as flat skin, so 0).
pub(crate) fn blog_curvature(inv_r_mm: f32) -> f32 {
    let inv_r = or_if_nan(inv_r_mm, 0.0);
    saturate((inv_r - BLOG_INV_R_MIN) / (BLOG_INV_R_MAX - BLOG_INV_R_MIN))
}

/// The blog's per-channel constants for its curve at r = 2 mm (`curve0`) and r = 16 mm (`curve1`).
mod blog {
    pub(crate) const RANGE_MIN: [f32; 3] = [0.0, 0.3, 0.3];
    pub(crate) const RANGE_MAX: [f32; 3] = [1.0, 0.7, 0.7];
    pub(crate) const OFFSET: [f32; 3] = [0.0, 0.06, 0.06];
    pub(crate) const LOWER_SCALE: [f32; 3] = [0.65, 0.5, 0.9];
    pub(crate) const LOWER_ADD: [f32; 3] = [0.045, 0.0, 0.0];
    pub(crate) const SLOPE0: [f32; 3] = [1.75, 2.0, 1.97];
    pub(crate) const TOP0: [f32; 3] = [0.99, 0.99, 0.99];
    pub(crate) const LERP_MIN: [f32; 3] = [0.0, 0.35, 0.35];
    pub(crate) const LERP_MAX: [f32; 3] = [1.0, 0.7, 0.6];
    pub(crate) const SLOPE1: [f32; 3] = [1.95, 2.0, 2.0];
    pub(crate) const TOP1: [f32; 3] = [0.99, 0.99, 1.0];
}

/// The blog's `curve0` (r = 2 mm) for channel `c` at `ndl01 = N.L / 2 + 1 / 2`.
fn blog_curve0(ndl01: f32, c: usize) -> f32 {
    let (lo, hi) = (blog::RANGE_MIN[c], blog::RANGE_MAX[c]);
    let t = saturate(ndl01 * (1.0 / (hi - lo)) + (blog::OFFSET[c] + lo) / (lo - hi));
    let mut lower = t * t * blog::LOWER_SCALE[c] + blog::LOWER_ADD[c];
    if c == 2 {
        lower *= t;
    }
    let upper = saturate(ndl01 * blog::SLOPE0[c] + (blog::TOP0[c] - blog::SLOPE0[c]));
    let (lerp_lo, lerp_hi) = (blog::LERP_MIN[c], blog::LERP_MAX[c]);
    let lerp_t = saturate(ndl01 * (1.0 / (lerp_hi - lerp_lo)) + lerp_lo / (lerp_lo - lerp_hi));
    lerp(lower, upper, lerp_t * lerp_t)
}

/// The blog's `curve1` (r = 16 mm) for channel `c` at `ndl01 = N.L / 2 + 1 / 2`.
fn blog_curve1(ndl01: f32, c: usize) -> f32 {
    saturate(ndl01 * blog::SLOPE1[c] + (blog::TOP1[c] - blog::SLOPE1[c]))
}

/// The blog's closed-form falloff per channel (red, green, blue) at `n_dot_l` in [-1, 1] and
/// `1/r` in mm^-1 (clamped to [0.0625, 0.5]); NaN N.L counts as 0.
pub fn blog_direct(n_dot_l: f32, inv_r_mm: f32) -> [f32; 3] {
    let ndl01 = or_if_nan(n_dot_l, 0.0).clamp(-1.0, 1.0) * 0.5 + 0.5;
    let curvature = blog_curvature(inv_r_mm);
    let curva = (1.0 / (curvature * (0.5 - 0.0625) + 0.0625) - 2.0) / (16.0 - 2.0);
    let one_minus = 1.0 - curva;
    let one_minus2 = one_minus * one_minus;
    let blend = one_minus2 * -one_minus2 + 1.0;
    std::array::from_fn(|c| lerp(blog_curve0(ndl01, c), blog_curve1(ndl01, c), blend))
}

/// Number of coefficients per channel of [`own_direct`].
pub const OWN_FIT_PARAMS: usize = 7;

/// Smallest ramp width of [`own_direct`]: flat skin gives the clamped N.L to within this.
pub(crate) const OWN_MIN_WIDTH: f32 = 1e-6;

/// The fitted coefficients of [`own_direct`], `OWN_FIT[i][channel]`, i in order: `a1, b1`
/// (first width `a1 k / (1 + |b1| k)`), `a2, b2` (second width), `beta` (mix), `c, d` (gain
/// `1 - c k^2 / (1 + |d| k^2)`). Reproduced by [`fit_own_direct`] on [`FitGrid::FIT`] from
/// [`OWN_FIT_START`].
pub const OWN_FIT: [[f32; 3]; OWN_FIT_PARAMS] = [
    [1.119658, 0.19147016, 0.13902761],
    [3.4801114, 0.0030810947, -2.3454774e-8],
    [4.6450677, 0.85098916, 0.51528525],
    [0.48916852, 0.0025143863, 0.004884143],
    [0.27000952, 0.22228076, 0.20613755],
    [1.7764238, 0.06646401, 0.024659198],
    [3.7490337, 0.10559194, 0.048895348],
];

/// Where [`fit_own_direct`] starts to land on [`OWN_FIT`]: per channel, the widths, mix and gain
/// read off fits at single curvatures (red's widths and dimming saturate as the sphere shrinks
/// below the profile's reach; green's and blue's stay nearly linear).
pub const OWN_FIT_START: [[f64; 3]; OWN_FIT_PARAMS] = [
    [0.7, 0.19, 0.14],
    [1.8, 0.0, 0.0],
    [3.7, 0.85, 0.52],
    [0.1, 0.0, 0.0],
    [0.26, 0.22, 0.2],
    [1.5, 0.06, 0.02],
    [3.3, 0.0, 0.0],
];

/// The smoothed ramp of [`own_direct`]: `max(x, 0)` convolved with a box of half-width `w > 0`.
fn ramp(x: f32, w: f32) -> f32 {
    let t = x.clamp(-w, w) + w;
    t * t * (0.25 / w) + (x - w).max(0.0)
}

/// [`ramp`] in f64 for the fit.
fn ramp64(x: f64, w: f64) -> f64 {
    let t = x.clamp(-w, w) + w;
    t * t * (0.25 / w) + (x - w).max(0.0)
}

/// Our closed-form falloff per channel at `n_dot_l` (clamped to [-1, 1], NaN counts as 0) and
/// `1/r` in mm^-1 (clamped to [0, 1], NaN counts as 0).
pub fn own_direct(n_dot_l: f32, inv_r_mm: f32) -> [f32; 3] {
    let x = or_if_nan(n_dot_l, 0.0).clamp(-1.0, 1.0);
    let k = or_if_nan(inv_r_mm, 0.0).clamp(0.0, 1.0);
    let p = &OWN_FIT;
    std::array::from_fn(|c| {
        let w1 = (p[0][c] * k / (1.0 + p[1][c].abs() * k)).max(OWN_MIN_WIDTH);
        let w2 = (p[2][c] * k / (1.0 + p[3][c].abs() * k)).max(OWN_MIN_WIDTH);
        let gain = 1.0 - p[5][c] * k * k / (1.0 + p[6][c].abs() * k * k);
        let (r1, r2) = (ramp(x, w1), ramp(x, w2));
        gain * (r1 + (r2 - r1) * p[4][c])
    })
}

/// [`own_direct`]'s form for one channel with coefficients `p`, in f64, for the fit.
pub fn own_form(p: &[f64; OWN_FIT_PARAMS], n_dot_l: f64, inv_r_mm: f64) -> f64 {
    let (x, k) = (n_dot_l.clamp(-1.0, 1.0), inv_r_mm.clamp(0.0, 1.0));
    let min = f64::from(OWN_MIN_WIDTH);
    let w1 = (p[0] * k / (1.0 + p[1].abs() * k)).max(min);
    let w2 = (p[2] * k / (1.0 + p[3].abs() * k)).max(min);
    let gain = 1.0 - p[5] * k * k / (1.0 + p[6].abs() * k * k);
    let (r1, r2) = (ramp64(x, w1), ramp64(x, w2));
    gain * (r1 + (r2 - r1) * p[4])
}

/// A regular grid of (N.L, 1/r): `n_dot_l` points over [-1, 1] and `inv_r` points over
/// `[inv_r_min, inv_r_max]`, both ends included.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitGrid {
    /// Points along N.L (at least 2).
    pub n_dot_l: usize,
    /// Smallest 1/r, mm^-1.
    pub inv_r_min: f64,
    /// Largest 1/r, mm^-1.
    pub inv_r_max: f64,
    /// Points along 1/r (at least 2).
    pub inv_r: usize,
}

impl FitGrid {
    /// The grid [`OWN_FIT`] was fitted on: 101 N.L x 33 1/r over [0, 1].
    pub const FIT: Self = Self { n_dot_l: 101, inv_r_min: 0.0, inv_r_max: 1.0, inv_r: 33 };
    /// The blog's range, finer in N.L than the fit and offset from it: 201 x 29 over [0.0625, 0.5].
    pub const BLOG_RANGE: Self = Self { n_dot_l: 201, inv_r_min: 0.0625, inv_r_max: 0.5, inv_r: 29 };
    /// The whole fitted range at the report's resolution: 201 x 41 over [0, 1].
    pub const FULL: Self = Self { n_dot_l: 201, inv_r_min: 0.0, inv_r_max: 1.0, inv_r: 41 };

    /// Every (N.L, 1/r) of the grid, 1/r outermost.
    pub fn points(&self) -> Vec<(f64, f64)> {
        let along = |n: usize, lo: f64, hi: f64, i: usize| lo + (hi - lo) * i as f64 / (n.max(2) - 1) as f64;
        let mut out = Vec::with_capacity(self.n_dot_l * self.inv_r);
        for j in 0..self.inv_r.max(2) {
            let k = along(self.inv_r, self.inv_r_min, self.inv_r_max, j);
            for i in 0..self.n_dot_l.max(2) {
                out.push((along(self.n_dot_l, -1.0, 1.0, i), k));
            }
        }
        out
    }
}

/// One sample of the true falloff.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// N.L.
    pub n_dot_l: f64,
    /// 1/r, mm^-1.
    pub inv_r: f64,
    /// [`reference_direct`] there.
    pub d: [f64; 3],
}

/// [`reference_direct`] at every point of `grid`.
pub fn reference_samples(grid: &FitGrid) -> Vec<Sample> {
    let points = grid.points();
    let d: Vec<[f64; 3]> = points.par_iter().map(|&(x, k)| reference_direct(x, k)).collect();
    points.iter().zip(d).map(|(&(n_dot_l, inv_r), d)| Sample { n_dot_l, inv_r, d }).collect()
}

/// Levenberg-Marquardt iterations of [`fit_own_direct`] (it converges in far fewer).
const FIT_ITERATIONS: usize = 200;

/// The coefficients of [`own_direct`] fitted by least squares to `samples`, per channel,
/// starting from `start` (`start[i][channel]`, as [`OWN_FIT`]): Levenberg-Marquardt on the
/// absolute error with a forward-difference Jacobian.
pub fn fit_own_direct(samples: &[Sample], start: &[[f64; 3]; OWN_FIT_PARAMS]) -> [[f64; 3]; OWN_FIT_PARAMS] {
    let mut out = [[0.0; 3]; OWN_FIT_PARAMS];
    for c in 0..3 {
        let p = fit_channel(samples, c, std::array::from_fn(|i| start[i][c]));
        for i in 0..OWN_FIT_PARAMS {
            out[i][c] = p[i];
        }
    }
    out
}

/// The residuals `own_form - D` of channel `c` over `samples`.
fn residuals(samples: &[Sample], c: usize, p: &[f64; OWN_FIT_PARAMS]) -> DVector<f64> {
    DVector::from_iterator(samples.len(), samples.iter().map(|s| own_form(p, s.n_dot_l, s.inv_r) - s.d[c]))
}

/// The forward-difference Jacobian of [`residuals`] at `p`, whose residuals are `r`.
fn jacobian(samples: &[Sample], c: usize, p: &[f64; OWN_FIT_PARAMS], r: &DVector<f64>) -> DMatrix<f64> {
    let mut j = DMatrix::zeros(samples.len(), OWN_FIT_PARAMS);
    for q in 0..OWN_FIT_PARAMS {
        let mut moved = *p;
        let h = 1e-7 * (1.0 + p[q].abs());
        moved[q] += h;
        j.set_column(q, &((residuals(samples, c, &moved) - r) / h));
    }
    j
}

/// Levenberg-Marquardt for one channel.
fn fit_channel(samples: &[Sample], c: usize, mut p: [f64; OWN_FIT_PARAMS]) -> [f64; OWN_FIT_PARAMS] {
    let mut r = residuals(samples, c, &p);
    let mut lambda = 1e-3;
    for _ in 0..FIT_ITERATIONS {
        let j = jacobian(samples, c, &p, &r);
        let (jtj, jtr) = (j.transpose() * &j, j.transpose() * &r);
        match lm_step(samples, c, &p, &r, &jtj, &jtr, &mut lambda) {
            Some((next, next_r)) => (p, r) = (next, next_r),
            None => break,
        }
    }
    p
}

/// One damped step that lowers the sum of squares, raising the damping until one does; `None`
/// when none does (converged).
fn lm_step(
    samples: &[Sample],
    c: usize,
    p: &[f64; OWN_FIT_PARAMS],
    r: &DVector<f64>,
    jtj: &DMatrix<f64>,
    jtr: &DVector<f64>,
    lambda: &mut f64,
) -> Option<([f64; OWN_FIT_PARAMS], DVector<f64>)> {
    let before = r.norm_squared();
    while *lambda < 1e12 {
        let mut a = jtj.clone();
        for q in 0..OWN_FIT_PARAMS {
            a[(q, q)] = a[(q, q)] * (1.0 + *lambda) + 1e-15;
        }
        if let Some(delta) = a.cholesky().map(|ch| ch.solve(&(-jtr))) {
            let next: [f64; OWN_FIT_PARAMS] = std::array::from_fn(|q| p[q] + delta[q]);
            let next_r = residuals(samples, c, &next);
            if next_r.norm_squared() < before * (1.0 - 1e-12) {
                *lambda = (*lambda * 0.3).max(1e-12);
                return Some((next, next_r));
            }
        }
        *lambda *= 10.0;
    }
    None
}

/// Max and rms absolute error per channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Errors {
    /// Largest absolute error.
    pub max: [f64; 3],
    /// Root mean square error.
    pub rms: [f64; 3],
}

impl Errors {
    /// The errors of `approx` against `samples`.
    pub fn of(samples: &[Sample], approx: impl Fn(f32, f32) -> [f32; 3]) -> Self {
        let mut out = Self::default();
        for s in samples {
            let a = approx(s.n_dot_l as f32, s.inv_r as f32);
            for (c, (value, truth)) in a.iter().zip(s.d).enumerate() {
                let e = (f64::from(*value) - truth).abs();
                out.max[c] = out.max[c].max(e);
                out.rms[c] += e * e;
            }
        }
        let n = samples.len().max(1) as f64;
        out.rms = out.rms.map(|ss| (ss / n).sqrt());
        out
    }
}

/// Errors of [`blog_direct`] and [`own_direct`] against [`reference_direct`] on one grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitReport {
    /// Where the errors were measured.
    pub grid: FitGrid,
    /// Largest error of the blog's curve, per channel.
    pub blog_max: [f64; 3],
    /// Rms error of the blog's curve, per channel.
    pub blog_rms: [f64; 3],
    /// Largest error of our fit, per channel.
    pub own_max: [f64; 3],
    /// Rms error of our fit, per channel.
    pub own_rms: [f64; 3],
}

/// [`fit_report_on`] the blog's range, [`FitGrid::BLOG_RANGE`].
pub fn fit_report() -> FitReport {
    fit_report_on(&FitGrid::BLOG_RANGE)
}

/// The errors of both closed forms against the truth on `grid`.
pub fn fit_report_on(grid: &FitGrid) -> FitReport {
    let samples = reference_samples(grid);
    let (blog, own) = (Errors::of(&samples, blog_direct), Errors::of(&samples, own_direct));
    FitReport { grid: *grid, blog_max: blog.max, blog_rms: blog.rms, own_max: own.max, own_rms: own.rms }
}
