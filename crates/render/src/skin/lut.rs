//! The pre-integrated diffuse falloff `D(N.L, 1/r)` of Penner and Borshukov (2011), equation
//! 1.1, tabulated for a shader: skin of curvature `1/r` lit from one side, the clamped cosine
//! blurred by the skin diffusion profile ([`super::profile`]) over a sphere of radius `r` (the
//! default, [`super::sphere`]) or along a ring, as the paper does.
//!
//! # Definitions
//!
//! - Profile: d'Eon and Luebke's six Gaussians with the chosen [`Normalisation`] (2-D `1/(2 pi v)`
//!   by default; the listing's 1-D `1/sqrt(2 pi 1.414 v)` on request).
//! - The chosen [`Domain`]: the sphere's surface by default, or the paper's ring over `[-pi, pi]`
//!   (equation 1.1) or `[-pi/2, pi/2]` (its listing). The ring cuts the 2-D profile along a line,
//!   which weights each Gaussian by `1 / sqrt(2 pi v)` instead of its share: it puts too much of
//!   the light into the narrow Gaussians and too little past the terminator. Against the exact
//!   texture-space reference on a 6 mm sphere lit from the side (unshadowed) the ring table's
//!   relative RMSE is 0.063 and the sphere's 0.0051 (Lambert: 0.075); on the nose close-up 0.021
//!   and 0.015 (Lambert 0.022). The book's tables ("Skin scattering"), from the `skin_methods` benchmark.
//! - The ring's cosine is clamped at 0 (`max(0, cos(theta + x))`), and the denominator uses the same `r`
//!   as the numerator (the listing's summed weights), so flat skin (`1/r = 0`) gives exactly
//!   `max(0, N.L)`.
//! - Curvature is `1/r` in 1/mm. The default range `[0, 1]` covers radii down to 1 mm (ears,
//!   nostrils, eyelids); a whole head is about 0.01 1/mm, so most of a face lives in the first rows.
//!
//! # Layout (other engines read it)
//!
//! Texels are RGB, row-major, row 0 at the **top** of the image.
//!
//! - Column `i` holds `N.L = 2u - 1` at its centre `u = (i + 0.5) / width`, so a shader samples at
//!   `u = N.L * 0.5 + 0.5` (the listing's `NdotL * 0.5 + 0.5`).
//! - Row `j` holds `1/r = inv_r_min + j * (inv_r_max - inv_r_min) / (height - 1)` at its centre
//!   (`inv_r_min` when `height == 1`): the first and last rows are exactly the range ends. A shader
//!   therefore samples at `v = (j + 0.5) / height` with `j` the fractional row,
//!   [`DiffuseLutSpec::v_for`].
//!
//! [`DiffuseLut::sample`] reads the table exactly as a GPU's bilinear, clamp-to-edge sampler would
//! at `(N.L * 0.5 + 0.5, v_for(1/r))` (with exact blend weights; GPUs quantise them to about 8
//! bits, an error far below the table's own smoothness). Upload as `Rgba32Float` or `Rgba16Float`
//! (the values lie in `[0, 1]`); 32-bit float textures are not filterable everywhere.
//!
//! # How it is built
//!
//! The profile is a sum of Gaussians, so numerator and denominator of equation 1.1 are sums of one
//! ring integral per Gaussian. With `K_i(x) = G_i(2 r sin(|x| / 2))` even in `x`,
//! `cos(theta + x) = cos(theta) cos(x) - sin(theta) sin(x)` turns the numerator over each interval
//! where the cosine is positive into `cos(theta) [C_i] - sin(theta) [S_i]`, with
//! `C_i(t) = int_0^t cos(x) K_i(x) dx` and `S_i(t) = int_0^t sin(x) K_i(x) dx`. Per row, `C_i`
//! and `S_i` are tabulated once on a grid that spans only where `K_i` is not negligible (an
//! angular width of about `sqrt(v_i) / r`, tiny for nearly flat skin), by 4-point Gauss-Legendre
//! per cell, and read between nodes by cubic Hermite interpolation (their derivatives are known).
//! The clamp's kinks then cost nothing, and narrow kernels are resolved at any curvature.

use rayon::prelude::*;

use super::profile::{Domain, KERNEL_CUT_SIGMAS, Normalisation, Profile, VARIANCES_MM2, WEIGHTS, gauss_legendre_nodes};
use super::sphere::SphereFalloff;

/// Largest side a table may have (a GPU's 2-D texture limit is at least 8192; 4096 is far beyond
/// any use: the tables are smooth).
pub const MAX_SIDE: u32 = 4096;

/// Bumped whenever a change to the builders changes texel values, so caches keyed on
/// [`DiffuseLut::cache_key`] or [`super::shadow::ShadowLut::cache_key`] are invalidated.
pub(crate) const BUILDER_VERSION: u32 = 2;

/// A table specification a caller got wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SpecError {
    /// A zero or too large side.
    #[error("{table} table: size {width}x{height} is not allowed (each side must be 1..={max})")]
    Size { table: &'static str, width: u32, height: u32, max: u32 },
    /// A range end that is not finite or negative.
    #[error("{table} table: {name} = {value} must be finite and >= 0")]
    Bound { table: &'static str, name: &'static str, value: f32 },
    /// A range whose end is not above its start.
    #[error("{table} table: {max_name} ({max}) must be greater than {min_name} ({min})")]
    Inverted { table: &'static str, min_name: &'static str, min: f32, max_name: &'static str, max: f32 },
    /// Any other parameter out of its range.
    #[error("{table} table: {name} = {value} {reason}")]
    Parameter { table: &'static str, name: &'static str, value: f32, reason: &'static str },
}

/// What a diffuse table covers and how it is defined.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffuseLutSpec {
    /// Columns (the N.L axis).
    pub width: u32,
    /// Rows (the 1/r axis).
    pub height: u32,
    /// How each Gaussian of the profile is normalised.
    pub normalisation: Normalisation,
    /// Over which angles the ring integral runs.
    pub domain: Domain,
    /// Curvature of row 0 (top), 1/mm.
    pub inv_r_min: f32,
    /// Curvature of the last row (bottom), 1/mm.
    pub inv_r_max: f32,
}

impl Default for DiffuseLutSpec {
    /// 256x256, 2-D normalisation, the sphere, `1/r` from 0 (flat) to 1/mm (r = 1 mm: ears and
    /// nostrils; a head is about 0.01/mm).
    fn default() -> Self {
        Self {
            width: 256,
            height: 256,
            normalisation: Normalisation::TwoD,
            domain: Domain::Sphere,
            inv_r_min: 0.0,
            inv_r_max: 1.0,
        }
    }
}

impl DiffuseLutSpec {
    /// Checks the sizes and the curvature range.
    ///
    /// # Errors
    /// A zero side or one above [`MAX_SIDE`]; a negative or non-finite range end; `inv_r_max` not
    /// above `inv_r_min`.
    pub fn validate(&self) -> Result<(), SpecError> {
        validate_size("diffuse", self.width, self.height)?;
        validate_range("diffuse", ("inv_r_min", self.inv_r_min), ("inv_r_max", self.inv_r_max))
    }

    /// The curvature (1/mm) at the centre of row `j` (row 0 at the top).
    pub fn inv_r_at(&self, j: u32) -> f32 {
        row_value(self.inv_r_min, self.inv_r_max, self.height, j)
    }

    /// The N.L at the centre of column `i`: `2 (i + 0.5) / width - 1`.
    pub fn n_dot_l_at(&self, i: u32) -> f32 {
        column_coordinate(i, self.width) * 2.0 - 1.0
    }

    /// The texture u a shader samples for `n_dot_l`: `saturate(N.L * 0.5 + 0.5)` (NaN gives 0,
    /// as `saturate` does on GPUs).
    pub(crate) fn u_for(&self, n_dot_l: f32) -> f32 {
        saturate(n_dot_l * 0.5 + 0.5)
    }

    /// The texture v a shader samples for a curvature `inv_r` (1/mm): the fractional row
    /// `j = (inv_r - inv_r_min) / (inv_r_max - inv_r_min) * (height - 1)` at its centre,
    /// `v = (j + 0.5) / height`. `inv_r` is clamped to the range first (NaN counts as
    /// `inv_r_min`), so `v` lies in `[0.5 / height, 1 - 0.5 / height]`.
    pub fn v_for(&self, inv_r: f32) -> f32 {
        v_for_range(self.inv_r_min, self.inv_r_max, self.height, inv_r)
    }

    /// A string naming every parameter (floats by their bits) and the builder version: equal keys
    /// mean equal tables.
    pub fn cache_key(&self) -> String {
        format!(
            "skinkit-diffuse-lut/v{BUILDER_VERSION}/{}x{}/{}/{}/inv_r:{:08x}-{:08x}",
            self.width,
            self.height,
            self.normalisation.name(),
            self.domain.name(),
            self.inv_r_min.to_bits(),
            self.inv_r_max.to_bits()
        )
    }
}

/// A built diffuse table: `width * height` RGB texels, row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct DiffuseLut {
    /// What the table covers.
    pub spec: DiffuseLutSpec,
    /// `D` per channel, `texels[j * width + i]`.
    pub texels: Vec<[f32; 3]>,
}

impl DiffuseLut {
    /// Builds the table (rows in parallel; the result does not depend on the thread count).
    ///
    /// # Errors
    /// When `spec` does not [`validate`](DiffuseLutSpec::validate).
    pub fn build(spec: &DiffuseLutSpec) -> Result<Self, SpecError> {
        spec.validate()?;
        let profile = Profile::new(spec.normalisation);
        let rows: Vec<Vec<[f32; 3]>> =
            (0..spec.height).into_par_iter().map(|j| build_row(spec, &profile, f64::from(spec.inv_r_at(j)))).collect();
        Ok(Self { spec: *spec, texels: rows.concat() })
    }

    /// The texel at column `i`, row `j`.
    pub fn texel(&self, i: u32, j: u32) -> [f32; 3] {
        self.texels[(j * self.spec.width + i) as usize]
    }

    /// `D(N.L, 1/r)` read as a GPU's bilinear clamp-to-edge sampler would at
    /// `(N.L * 0.5 + 0.5, v_for(1/r))`. Finite for any input.
    pub fn sample(&self, n_dot_l: f32, inv_r: f32) -> [f32; 3] {
        let s = &self.spec;
        bilinear(&self.texels, s.width, s.height, s.u_for(n_dot_l), s.v_for(inv_r))
    }

    /// The key of [`DiffuseLutSpec::cache_key`].
    pub fn cache_key(&self) -> String {
        self.spec.cache_key()
    }
}

/// One row of the table at curvature `inv_r`.
fn build_row(spec: &DiffuseLutSpec, profile: &Profile, inv_r: f64) -> Vec<[f32; 3]> {
    let columns = 0..spec.width;
    if inv_r <= 0.0 {
        return columns.map(|i| [spec.n_dot_l_at(i).max(0.0); 3]).collect();
    }
    if spec.domain == Domain::Sphere {
        return sphere_row(spec, profile, inv_r);
    }
    let half = spec.domain.half_extent();
    let rings: Vec<RingTable> = (0..VARIANCES_MM2.len()).map(|g| RingTable::new(profile, g, inv_r, half)).collect();
    columns.map(|i| texel_value(&rings, f64::from(spec.n_dot_l_at(i)), half)).collect()
}

/// Equation 1.1 at one N.L from the per-Gaussian tables of a row.
fn texel_value(rings: &[RingTable], n_dot_l: f64, half: f64) -> [f32; 3] {
    let theta = n_dot_l.clamp(-1.0, 1.0).acos();
    let (light, total) = rings.iter().zip(WEIGHTS.iter()).fold(([0.0; 3], [0.0; 3]), |(mut l, mut t), (ring, w)| {
        let (lit, all) = (ring.lit(theta, half), ring.total());
        for c in 0..3 {
            l[c] += w[c] * lit;
            t[c] += w[c] * all;
        }
        (l, t)
    });
    std::array::from_fn(|c| {
        let d = if total[c] > 0.0 { light[c] / total[c] } else { n_dot_l.max(0.0) };
        d.clamp(0.0, 1.0) as f32
    })
}

/// One row of the sphere table ([`Domain::Sphere`], [`super::sphere`]).
fn sphere_row(spec: &DiffuseLutSpec, profile: &Profile, inv_r: f64) -> Vec<[f32; 3]> {
    let sphere = SphereFalloff::new(profile, inv_r);
    (0..spec.width).map(|i| sphere.at(f64::from(spec.n_dot_l_at(i))).map(|d| d.clamp(0.0, 1.0) as f32)).collect()
}

/// Cells of the per-row tabulation of `C_i`, `S_i` (module docs).
const RING_CELLS: usize = 256;

/// The cumulative integrals `C(t)`, `S(t)` and `Z(t) = int_0^t K` of one Gaussian's ring kernel on
/// `[0, t_max]`, where `t_max` is the angle beyond which the kernel is negligible (or the domain
/// ends).
struct RingTable {
    t_max: f64,
    step: f64,
    kernel: Vec<f64>,
    cos_part: Vec<f64>,
    sin_part: Vec<f64>,
    total_half: f64,
}

impl RingTable {
    fn new(profile: &Profile, gaussian: usize, inv_r: f64, half: f64) -> Self {
        let r = 1.0 / inv_r;
        let k = |x: f64| profile.gaussian(gaussian, 2.0 * r * (0.5 * x).sin());
        let half_chord = 0.5 * KERNEL_CUT_SIGMAS * profile.variance(gaussian).sqrt() * inv_r;
        let t_max = (2.0 * half_chord.min(1.0).asin()).min(half);
        let step = t_max / RING_CELLS as f64;
        let kernel: Vec<f64> = (0..=RING_CELLS).map(|n| k(n as f64 * step)).collect();
        let (mut cos_part, mut sin_part) = (vec![0.0; RING_CELLS + 1], vec![0.0; RING_CELLS + 1]);
        let mut total_half = 0.0;
        for n in 0..RING_CELLS {
            let [c, s, z] = gauss_legendre_cell(&k, n as f64 * step, step);
            cos_part[n + 1] = cos_part[n] + c;
            sin_part[n + 1] = sin_part[n] + s;
            total_half += z;
        }
        Self { t_max, step, kernel, cos_part, sin_part, total_half }
    }

    /// `int K` over the whole domain.
    fn total(&self) -> f64 {
        2.0 * self.total_half
    }

    /// `int max(0, cos(theta + x)) K(x) dx` over `[-half, half]`: the cosine is positive on
    /// `(-pi/2 - theta, pi/2 - theta)` and, for the full ring, `(3 pi/2 - theta, 5 pi/2 - theta)`.
    fn lit(&self, theta: f64, half: f64) -> f64 {
        use std::f64::consts::FRAC_PI_2;
        let pieces = [(-FRAC_PI_2 - theta, FRAC_PI_2 - theta), (3.0 * FRAC_PI_2 - theta, 5.0 * FRAC_PI_2 - theta)];
        let (cos_t, sin_t) = (theta.cos(), theta.sin());
        pieces
            .iter()
            .map(|&(a, b)| (a.max(-half), b.min(half)))
            .filter(|(a, b)| b > a)
            .map(|(a, b)| {
                let (ca, sa) = self.at(a);
                let (cb, sb) = self.at(b);
                cos_t * (cb - ca) - sin_t * (sb - sa)
            })
            .sum::<f64>()
            .max(0.0)
    }

    /// `(C(t), S(t))` for any `t` in the domain: `C` is odd and `S` even in `t` (the kernel is
    /// even), both constant beyond `t_max`.
    fn at(&self, t: f64) -> (f64, f64) {
        let (c, s) = self.at_positive(t.abs());
        (c.copysign(t), s)
    }

    fn at_positive(&self, t: f64) -> (f64, f64) {
        if self.step <= 0.0 || t >= self.t_max {
            return (self.cos_part[RING_CELLS], self.sin_part[RING_CELLS]);
        }
        let n = ((t / self.step) as usize).min(RING_CELLS - 1);
        let (t0, h) = (n as f64 * self.step, self.step);
        let f = (t - t0) / h;
        let (k0, k1) = (self.kernel[n], self.kernel[n + 1]);
        let t1 = t0 + h;
        let c = hermite(self.cos_part[n], self.cos_part[n + 1], t0.cos() * k0 * h, t1.cos() * k1 * h, f);
        let s = hermite(self.sin_part[n], self.sin_part[n + 1], t0.sin() * k0 * h, t1.sin() * k1 * h, f);
        (c, s)
    }
}

/// 4-point Gauss-Legendre integrals of `cos(x) k(x)`, `sin(x) k(x)` and `k(x)` over `[a, a + h]`.
fn gauss_legendre_cell(k: &impl Fn(f64) -> f64, a: f64, h: f64) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (x, weight) in gauss_legendre_nodes(a, h) {
        let kw = k(x) * weight;
        out[0] += x.cos() * kw;
        out[1] += x.sin() * kw;
        out[2] += kw;
    }
    out
}

/// The cubic Hermite interpolant on one cell at fraction `f`, from values and derivatives (the
/// derivatives already scaled by the cell width).
fn hermite(p0: f64, p1: f64, m0: f64, m1: f64, f: f64) -> f64 {
    let (f2, f3) = (f * f, f * f * f);
    (2.0 * f3 - 3.0 * f2 + 1.0) * p0 + (f3 - 2.0 * f2 + f) * m0 + (-2.0 * f3 + 3.0 * f2) * p1 + (f3 - f2) * m1
}

// ---- Shared by the diffuse and shadow tables: layout, sampling, validation. ----

/// `x` clamped to `[0, 1]`, NaN to 0 (a GPU's `saturate`).
pub(crate) fn saturate(x: f32) -> f32 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

/// The texture coordinate of the centre of texel `i` of `n`: `(i + 0.5) / n`.
pub(crate) fn column_coordinate(i: u32, n: u32) -> f32 {
    ((f64::from(i) + 0.5) / f64::from(n)) as f32
}

/// The value at the centre of row `j` of `height` rows spanning `[min, max]` end to end.
pub(crate) fn row_value(min: f32, max: f32, height: u32, j: u32) -> f32 {
    if height <= 1 {
        return min;
    }
    let t = f64::from(j) / f64::from(height - 1);
    (f64::from(min) + t * (f64::from(max) - f64::from(min))) as f32
}

/// The texture v of `value` on rows laid out by [`row_value`] (clamped to the range, NaN to `min`).
pub(crate) fn v_for_range(min: f32, max: f32, height: u32, value: f32) -> f32 {
    if height <= 1 || max <= min {
        return 0.5;
    }
    let value = if value.is_nan() { min } else { value.clamp(min, max) };
    let row = (f64::from(value) - f64::from(min)) / (f64::from(max) - f64::from(min)) * f64::from(height - 1);
    ((row + 0.5) / f64::from(height)) as f32
}

/// Bilinear filtering with clamp-to-edge addressing at `(u, v)`, texel centres at `(i + 0.5) / n`,
/// as GPU samplers do. Non-finite coordinates count as 0.
pub(crate) fn bilinear(texels: &[[f32; 3]], width: u32, height: u32, u: f32, v: f32) -> [f32; 3] {
    let (i0, i1, fx) = taps(u, width);
    let (j0, j1, fy) = taps(v, height);
    let at = |i: usize, j: usize| texels[j * width as usize + i];
    let (a, b, c, d) = (at(i0, j0), at(i1, j0), at(i0, j1), at(i1, j1));
    std::array::from_fn(|k| {
        let top = f64::from(a[k]) * (1.0 - fx) + f64::from(b[k]) * fx;
        let bottom = f64::from(c[k]) * (1.0 - fx) + f64::from(d[k]) * fx;
        (top * (1.0 - fy) + bottom * fy) as f32
    })
}

/// The two texels and the blend weight one axis of a bilinear sampler uses at coordinate `u`.
fn taps(u: f32, n: u32) -> (usize, usize, f64) {
    let u = if u.is_finite() { f64::from(u) } else { 0.0 };
    let x = (u * f64::from(n) - 0.5).clamp(-1.0, f64::from(n));
    let x0 = x.floor();
    let last = f64::from(n - 1);
    let (i0, i1) = (x0.clamp(0.0, last) as usize, (x0 + 1.0).clamp(0.0, last) as usize);
    (i0, i1, x - x0)
}

/// Both sides in `1..=MAX_SIDE`.
pub(crate) fn validate_size(table: &'static str, width: u32, height: u32) -> Result<(), SpecError> {
    let ok = |s: u32| (1..=MAX_SIDE).contains(&s);
    if ok(width) && ok(height) { Ok(()) } else { Err(SpecError::Size { table, width, height, max: MAX_SIDE }) }
}

/// Both ends finite and non-negative, the second above the first.
pub(crate) fn validate_range(
    table: &'static str,
    (min_name, min): (&'static str, f32),
    (max_name, max): (&'static str, f32),
) -> Result<(), SpecError> {
    for (name, value) in [(min_name, min), (max_name, max)] {
        if !value.is_finite() || value < 0.0 {
            return Err(SpecError::Bound { table, name, value });
        }
    }
    if max <= min {
        return Err(SpecError::Inverted { table, min_name, min, max_name, max });
    }
    Ok(())
}
