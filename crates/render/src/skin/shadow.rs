//! The pre-integrated shadow scattering `P_S(s, w)` of Penner and Borshukov (2011), section 1.6:
//! a shadow value `s`, the lit share of a filter's footprint, is mapped back to its place in the penumbra, and
//! replaced by a narrower penumbra blurred by the skin diffusion profile,
//!
//! `P_S(s, w) = int P'(P^-1(s) w / 2 + x) R1(x) dx / int R1(x) dx`, `x` in mm.
//!
//! # Definitions
//!
//! - The shadow filter is shadow scattering's disc of taps: the lit share `s` of a disc of
//!   diameter `w` (mm) on the receiver's tangent plane, each tap compared at full shadow-map
//!   resolution. A straight edge at signed distance `t w / 2` from the disc's centre (lit side
//!   `t > 0`) leaves `P(t) = 1 - (acos t - t sqrt(1 - t^2)) / pi` of it lit; `P^-1` is found by
//!   bisection. A disc on the skin rather than a box of shadow-map texels makes `w` the same in
//!   every direction and on every slope to the light, so the table needs no per-pixel stretch, and
//!   the casters' silhouettes keep the map's resolution. (The paper filters the shadow map itself;
//!   with the map coarsened until its box spans the profile, the nose's shadow on the sample head
//!   shrank by millimetres and the table's error was 3.4x Lambert's sharp shadow.)
//! - The new penumbra `P'` is a linear ramp `new_penumbra * w` wide (what a box filter that wide
//!   would give), centred on the same edge: `P'(y) = clamp(0.5 + y / (new_penumbra * w), 0, 1)`.
//!   A directional light's true penumbra is a step; the default `new_penumbra = 0.05` keeps a
//!   quarter-millimetre ramp at the default 5 mm disc. A ramp has a closed form and is exact at
//!   `w -> 0` (a step).
//! - Beyond the disc (`s = 0` or `1`) the edge's distance is unknown. The integral there is the
//!   light a nearby edge would scatter; the table is stretched per channel so that those ends are
//!   exactly 0 and 1, so skin far from any shadow keeps its colour and the shading is continuous
//!   where the disc leaves the edge.
//! - `R1` is the profile's 1-D marginal ([`super::profile::Profile::marginal`]), not its radial
//!   slice: light crossing a straight edge is the 2-D profile integrated along the edge, a 1-D
//!   convolution with the marginal. The paper's listing weights by the radial slice `R(|x|)`
//!   (`Scatter(abs(a))`). In its 1-D normalisation that slice is itself a sum of 1-D Gaussians with
//!   the same weights but variances `1.414 v`, i.e. the marginal of a wider profile; a 2-D
//!   normalised slice would over-weight the narrow Gaussians (peaks scale as `1/v`, not
//!   `1/sqrt(v)`). The marginal of a sum of radial Gaussians is the sum of 1-D Gaussians with the
//!   same variances and weights whichever normalisation the radial profile uses, so this table
//!   does not depend on [`super::profile::Normalisation`]. It integrates to 1 per channel.
//! - The paper's `R(x / w)` form (the profile in penumbra units) and the listing's
//!   `newPenumbra(location + a / width)` are this integral with `x` in mm.
//!
//! # Layout
//!
//! RGB texels, row-major, row 0 at the top. Column `i` holds `s = (i + 0.5) / width` at its centre
//! (a shader samples at `u = s`). Row `j` holds the penumbra width
//! `w = w_min + j * (w_max - w_min) / (height - 1)` mm at its centre (as the diffuse table's
//! rows, [`ShadowLutSpec::v_for`]).
//!
//! # How it is built
//!
//! In closed form: a ramp of width `a` is a box-filtered step, so against a Gaussian of standard
//! deviation `sigma` it gives `(sigma / a) [Psi((y + a/2) / sigma) - Psi((y - a/2) / sigma)]` with
//! `Psi(t) = t Phi(t) + phi(t)` the integral of the normal CDF `Phi`; `Phi(y / sigma)` when
//! `a -> 0`. `Phi` comes from an `erf` series and an `erfc` continued fraction (about 1e-14).

use rayon::prelude::*;

/// Side of the shadow-scattering LUT the renderer builds.
pub(crate) const SHADOW_LUT_SIDE: u32 = 64;

use super::lut::{SpecError, bilinear, column_coordinate, row_value, saturate, v_for_range, validate_size};
use super::profile::{VARIANCES_MM2, WEIGHTS};

/// Widest penumbra a shadow table may cover, in mm (a metre, the range of every millimetre flag):
/// far wider than any skin's, and small enough that the convolution's quadrature still resolves
/// the profile (at `1e30` the fully lit column of the lower rows read 0, issue 42, D14).
pub const MAX_PENUMBRA_MM: f32 = 1000.0;

/// What a shadow table covers and how it is defined.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ShadowLutSpec {
    /// Columns (the shadow value axis).
    pub width: u32,
    /// Rows (the penumbra width axis).
    pub height: u32,
    /// Penumbra width of row 0 (top), mm.
    pub w_min_mm: f32,
    /// Penumbra width of the last row, mm.
    pub w_max_mm: f32,
    /// Width of the new penumbra `P'` as a fraction of the filtered one, in `(0, 1]`.
    pub new_penumbra: f32,
}

impl Default for ShadowLutSpec {
    /// 256x256, discs from 0.5 mm to 32 mm across (the profile's widest Gaussian has sigma
    /// 2.7 mm), new penumbra a twentieth of the disc.
    fn default() -> Self {
        Self { width: 256, height: 256, w_min_mm: 0.5, w_max_mm: 32.0, new_penumbra: 0.05 }
    }
}

impl ShadowLutSpec {
    /// Checks the sizes, the width range and the new penumbra.
    ///
    /// # Errors
    /// A zero side or one above [`super::lut::MAX_SIDE`]; a negative or non-finite width; `w_max`
    /// not above `w_min` or above [`MAX_PENUMBRA_MM`]; `new_penumbra` outside `(0, 1]`.
    pub fn validate(&self) -> Result<(), SpecError> {
        validate_size("shadow", self.width, self.height)?;
        super::lut::validate_range("shadow", ("w_min_mm", self.w_min_mm), ("w_max_mm", self.w_max_mm))?;
        if self.w_max_mm > MAX_PENUMBRA_MM {
            let reason = "must be at most 1000 mm (skinkit_render::skin::shadow::MAX_PENUMBRA_MM)";
            return Err(SpecError::Parameter { table: "shadow", name: "w_max_mm", value: self.w_max_mm, reason });
        }
        let p = self.new_penumbra;
        if !(p > 0.0 && p <= 1.0) {
            let reason = "must be in (0, 1] (a fraction of the filtered penumbra)";
            return Err(SpecError::Parameter { table: "shadow", name: "new_penumbra", value: p, reason });
        }
        Ok(())
    }

    /// The penumbra width (mm) at the centre of row `j`.
    pub fn w_at(&self, j: u32) -> f32 {
        row_value(self.w_min_mm, self.w_max_mm, self.height, j)
    }

    /// The shadow value at the centre of column `i`: `(i + 0.5) / width`.
    pub fn s_at(&self, i: u32) -> f32 {
        column_coordinate(i, self.width)
    }

    /// The texture v a shader samples for a penumbra width `w_mm`: the fractional row at its
    /// centre, `v = (j + 0.5) / height`, `w_mm` clamped to the range first (NaN counts as `w_min`).
    pub fn v_for(&self, w_mm: f32) -> f32 {
        v_for_range(self.w_min_mm, self.w_max_mm, self.height, w_mm)
    }

    /// A string naming every parameter (floats by their bits) and the builder version.
    pub fn cache_key(&self) -> String {
        format!(
            "skinkit-shadow-lut/v{}/{}x{}/disc/marginal/w:{:08x}-{:08x}/new:{:08x}",
            super::lut::BUILDER_VERSION,
            self.width,
            self.height,
            self.w_min_mm.to_bits(),
            self.w_max_mm.to_bits(),
            self.new_penumbra.to_bits()
        )
    }
}

/// A built shadow table: `width * height` RGB texels, row-major, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowLut {
    /// What the table covers.
    pub spec: ShadowLutSpec,
    /// `P_S` per channel, `texels[j * width + i]`.
    pub texels: Vec<[f32; 3]>,
}

impl ShadowLut {
    /// Builds the table (rows in parallel).
    ///
    /// # Errors
    /// When `spec` does not [`validate`](ShadowLutSpec::validate).
    pub fn build(spec: &ShadowLutSpec) -> Result<Self, SpecError> {
        spec.validate()?;
        let rows: Vec<Vec<[f32; 3]>> = (0..spec.height)
            .into_par_iter()
            .map(|j| {
                let w = f64::from(spec.w_at(j));
                (0..spec.width).map(|i| scattered(f64::from(spec.s_at(i)), w, f64::from(spec.new_penumbra))).collect()
            })
            .collect();
        Ok(Self { spec: *spec, texels: rows.concat() })
    }

    /// The texel at column `i`, row `j`.
    pub fn texel(&self, i: u32, j: u32) -> [f32; 3] {
        self.texels[(j * self.spec.width + i) as usize]
    }

    /// `P_S(s, w)` read as a GPU's bilinear clamp-to-edge sampler would at `(s, v_for(w))`
    /// (`s` saturated first, NaN to 0). Finite for any input.
    pub fn sample(&self, s: f32, w_mm: f32) -> [f32; 3] {
        let spec = &self.spec;
        bilinear(&self.texels, spec.width, spec.height, saturate(s), spec.v_for(w_mm))
    }

    /// The key of [`ShadowLutSpec::cache_key`].
    pub fn cache_key(&self) -> String {
        self.spec.cache_key()
    }
}

/// `P_S(s, w)` per channel in closed form (module docs), stretched so that a fully lit disc
/// (`s = 1`) gives 1 and a fully shadowed one 0: beyond the disc the edge's distance is unknown
/// and the far field must not change colour.
fn scattered(s: f64, w_mm: f64, new_penumbra: f64) -> [f32; 3] {
    let lo = scattered_at(0.0, w_mm, new_penumbra);
    let hi = scattered_at(1.0, w_mm, new_penumbra);
    let p = scattered_at(s, w_mm, new_penumbra);
    std::array::from_fn(|c| {
        let span = hi[c] - lo[c];
        let v = if span > 1e-9 { (p[c] - lo[c]) / span } else { p[c] };
        v.clamp(0.0, 1.0) as f32
    })
}

fn scattered_at(s: f64, w_mm: f64, new_penumbra: f64) -> [f64; 3] {
    let y = disc_offset(s.clamp(0.0, 1.0)) * 0.5 * w_mm;
    let a = new_penumbra * w_mm;
    let mut out = [0.0f64; 3];
    for (v, weights) in VARIANCES_MM2.iter().zip(WEIGHTS.iter()) {
        let e = ramp_against_gaussian(y, a, v.sqrt());
        for c in 0..3 {
            out[c] += weights[c] * e;
        }
    }
    out
}

/// The lit share of a unit disc whose centre is `t` from a straight shadow edge (lit side `t > 0`).
fn disc_coverage(t: f64) -> f64 {
    let t = t.clamp(-1.0, 1.0);
    1.0 - (t.acos() - t * (1.0 - t * t).sqrt()) / std::f64::consts::PI
}

/// The inverse of [`disc_coverage`] by bisection: the centre's signed distance, in radii.
fn disc_offset(s: f64) -> f64 {
    let (mut lo, mut hi) = (-1.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if disc_coverage(mid) < s { lo = mid } else { hi = mid }
    }
    0.5 * (lo + hi)
}

/// `E[clamp(0.5 + (y + X) / a, 0, 1)]` for `X ~ N(0, sigma^2)`.
fn ramp_against_gaussian(y: f64, a: f64, sigma: f64) -> f64 {
    if a <= 1e-9 * sigma {
        return normal_cdf(y / sigma);
    }
    let psi = |t: f64| t * normal_cdf(t) + normal_pdf(t);
    sigma / a * (psi((y + 0.5 * a) / sigma) - psi((y - 0.5 * a) / sigma))
}

fn normal_pdf(t: f64) -> f64 {
    (-0.5 * t * t).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// The standard normal CDF, accurate to about 1e-14 absolute (and relative in the lower tail).
pub(crate) fn normal_cdf(t: f64) -> f64 {
    let z = t / std::f64::consts::SQRT_2;
    if z >= 0.0 { 1.0 - 0.5 * erfc(z) } else { 0.5 * erfc(-z) }
}

/// `erfc(z)` for `z >= 0`: Taylor series of `erf` below 2.5, continued fraction above.
fn erfc(z: f64) -> f64 {
    if z < 2.5 { 1.0 - erf_series(z) } else { erfc_continued_fraction(z) }
}

fn erf_series(z: f64) -> f64 {
    // erf(z) = 2/sqrt(pi) sum_n (-1)^n z^(2n+1) / (n! (2n+1))
    let (mut term, mut sum) = (z, z);
    for n in 1..200 {
        term *= -z * z / n as f64;
        let add = term / (2 * n + 1) as f64;
        sum += add;
        if add.abs() < 1e-17 * sum.abs() {
            break;
        }
    }
    sum * 2.0 / std::f64::consts::PI.sqrt()
}

fn erfc_continued_fraction(z: f64) -> f64 {
    // erfc(z) = exp(-z^2) / sqrt(pi) / (z + (1/2) / (z + 1 / (z + (3/2) / (z + ...)))).
    let mut f = z;
    for n in (1..=80).rev() {
        f = z + 0.5 * n as f64 / f;
    }
    (-z * z).exp() / (std::f64::consts::PI.sqrt() * f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_matches_known_values() {
        // Reference values of Phi (to 15 digits).
        for (t, phi) in [
            (0.0, 0.5),
            (1.0, 0.841_344_746_068_542_9),
            (-2.0, 0.022_750_131_948_179_2),
            (3.5, 0.999_767_370_920_964),
            (-6.0, 9.865_876_450_377_012e-10),
        ] {
            let got = normal_cdf(t);
            assert!((got - phi).abs() <= 1e-13 + 1e-10 * phi, "Phi({t}) = {got}, expected {phi}");
        }
    }

    #[test]
    fn series_and_continued_fraction_agree_where_they_meet() {
        let (a, b) = (1.0 - erf_series(2.5), erfc_continued_fraction(2.5));
        assert!((a - b).abs() < 1e-13, "{a} vs {b}");
    }
}
