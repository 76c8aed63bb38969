//! Ambient light on pre-integrated skin through order-2 spherical harmonics (bands l = 0, 1, 2,
//! nine coefficients): the environment's radiance is projected once ([`Sh9`]), and the skin's
//! falloff D(N.L, 1/r) (Penner and Borshukov 2011, equation 1.1) is reduced to one convolution
//! factor per band and channel ([`skin_zonal`]), as the blog post "Pre-integrated skin shading:
//! curve approximation" (seed `001`) and Ramamoorthi and Hanrahan's "An efficient representation
//! for irradiance environment maps" (2001) do for Lambert.
//!
//! Definitions:
//!
//! - Basis: the real SH in Cartesian form of the unit direction `(x, y, z)` of the world frame,
//!   indexed `l (l + 1) + m` ([`index`]): `Y00 = 0.282095`, `Y1-1 = 0.488603 y`,
//!   `Y10 = 0.488603 z`, `Y11 = 0.488603 x`, `Y2-2 = 1.092548 xy`, `Y2-1 = 1.092548 yz`,
//!   `Y20 = 0.315392 (3 z^2 - 1)`, `Y21 = 1.092548 xz`, `Y22 = 0.546274 (x^2 - y^2)`. Their
//!   polar axis is +z; nothing here depends on it, since every kernel is zonal about the normal
//!   (the renderer's world is y up, which only [`Sh9::project_latlong`] has to know).
//! - Convolution (Funk-Hecke): for a kernel `f(n . w)`, `int L(w) f(n . w) dw =
//!   sum_l A_l sum_m L_lm Y_lm(n)` with `A_l = 2 pi int_0^pi f(cos t) P_l(cos t) sin t dt
//!   = sqrt(4 pi / (2l + 1)) zh_l`, `zh_l = 2 pi int f Y_l0 sin t dt` the zonal harmonic
//!   coefficient. For the clamped cosine `A = (pi, 2 pi / 3, pi / 4)` ([`LAMBERT_ZONAL`]).
//! - Skin: `f = D(cos t, 1/r)` over the whole sphere, t in [0, pi]: the falloff is non-zero
//!   below the horizon (the blog's point about equation 19). [`skin_zonal`] projects
//!   [`super::fit::reference_direct`] by Gauss-Legendre quadrature in `cos t`.
//! - The blog's `zh0`, `zh1` ([`blog_zonal`]) are these `zh_l` themselves, not ratios to
//!   Lambert: at r = 16 mm they reach Lambert's `sqrt(pi) / 2 = 0.8862` and
//!   `sqrt(pi / 3) = 1.0233` (the blog stores them remapped from [0.75, 1.05] in an 8-bit
//!   texture). Of the signs lost in extraction, `1.0 - x` and `1 - rc^3` are certain; the ZH0
//!   coefficients are read as positive (`+0.061659 / (3.2 curva + 0.4)` makes red reach
//!   Lambert's 0.8862 at r = 16 mm; a minus would leave it at 0.852). The blog has no band 2:
//!   [`blog_zonal`] uses Lambert's `pi / 4` there. They follow the table of the paper's listing
//!   normalisation ([`super::profile::Normalisation::OneD`]) over the full ring: against its
//!   factors the blog is within 3.0%, 0.26%, 0.15% (A_0, red, green, blue) and 1.7%, 0.21%,
//!   0.13% (A_1) for 1/r in [0.0625, 0.5] (the half ring misses A_1 red at r = 2 mm by 17%).
//!   Against ours ([`skin_zonal`], the sphere falloff, which keeps `A_0` at Lambert's pi: a
//!   uniformly lit sphere stays uniform) it is off by up to 15%, 1.0%, 0.33% (A_0) and 2.0%,
//!   0.31%, 0.097% (A_1), worst at r = 2 mm, where the blog's red A_0 = 3.63 and A_1 = 1.57
//!   against our 3.14 and 1.60 (Lambert: 3.14, 2.09).

use glam::Vec3;

/// Samples of 1/r in the zonal table the renderer builds (linear interpolation between them is
/// within 0.11% of the exact factors; see [`ZonalTable`]).
pub(crate) const ZONAL_SAMPLES: usize = 33;

/// The WGSL snippet with `sh9_basis`, `sh9_convolve`, `sh9_convolve_rgb` and `blog_zonal`.
pub const SKIN_SH_WGSL: &str = include_str!("../../shaders/skin_sh.wgsl");

/// Number of coefficients of order-2 SH.
pub const SH9: usize = 9;

/// `1 / (2 sqrt(pi))`.
const C0: f32 = 0.282_094_8;
/// `sqrt(3 / (4 pi))`.
const C1: f32 = 0.488_602_5;
/// `sqrt(15 / (4 pi))`.
const C2: f32 = 1.092_548_4;
/// `sqrt(5 / (16 pi))`.
const C20: f32 = 0.315_391_57;
/// `sqrt(15 / (16 pi))`.
const C22: f32 = 0.546_274_2;

/// Lambert's convolution factors `A_l` for l = 0, 1, 2: `pi`, `2 pi / 3`, `pi / 4`.
pub const LAMBERT_ZONAL: [f32; 3] =
    [std::f32::consts::PI, 2.0 * std::f32::consts::PI / 3.0, std::f32::consts::FRAC_PI_4];

/// Cells in the cosine for [`skin_zonal`] ([`zonal_factors`]: two samples per cell).
pub const ZONAL_STEPS: usize = 100;

/// Errors of this module's constructors.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ShError {
    /// The environment's texel count does not match its size.
    #[error("environment map is {width}x{height} but has {texels} texels (expected {expected})")]
    TexelCount { width: usize, height: usize, texels: usize, expected: usize },
    /// An environment side is zero.
    #[error("environment map is {width}x{height}: both sides must be at least 1")]
    EmptyMap { width: usize, height: usize },
    /// A zonal table's range or size is unusable.
    #[error(
        "zonal table of {n} samples over 1/r in [{inv_r_min}, {inv_r_max}] mm^-1: need n >= 2 and finite 0 <= min < max"
    )]
    BadTable { n: usize, inv_r_min: f32, inv_r_max: f32 },
}

/// This module's result.
pub type Result<T, E = ShError> = std::result::Result<T, E>;

/// The index of `Y_lm` in a [`Sh9`]: `l (l + 1) + m`.
pub const fn index(l: usize, m: i32) -> usize {
    ((l * (l + 1)) as i32 + m) as usize
}

/// All nine basis functions at unit direction `d`, in [`index`] order.
pub fn basis(d: Vec3) -> [f32; SH9] {
    let (x, y, z) = (d.x, d.y, d.z);
    [C0, C1 * y, C1 * z, C1 * x, C2 * x * y, C2 * y * z, C20 * (3.0 * z * z - 1.0), C2 * x * z, C22 * (x * x - y * y)]
}

/// The real SH `Y_lm` at unit direction `d`; 0 outside l <= 2, |m| <= l.
pub fn y(l: usize, m: i32, d: Vec3) -> f32 {
    if l > 2 || m.unsigned_abs() as usize > l {
        return 0.0;
    }
    basis(d)[index(l, m)]
}

/// The band of each coefficient in [`index`] order.
const BAND: [usize; SH9] = [0, 1, 1, 1, 2, 2, 2, 2, 2];

/// RGB radiance as order-2 SH: `coeffs[index(l, m)] = [L_lm red, green, blue]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sh9 {
    /// Coefficients in [`index`] order.
    pub coeffs: [[f32; 3]; SH9],
}

/// The direction of the equirectangular texel centre at column `u`, row `v` of a
/// `width x height` map: row 0 is the +y pole (up), column 0 starts at +z and longitude runs
/// toward +x, `w = (sin t sin p, cos t, sin t cos p)`, t the angle from +y, p = 2 pi u.
pub fn latlong_direction(width: usize, height: usize, column: usize, row: usize) -> Vec3 {
    let theta = std::f64::consts::PI * (row as f64 + 0.5) / height as f64;
    let phi = 2.0 * std::f64::consts::PI * (column as f64 + 0.5) / width as f64;
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new((st * sp) as f32, ct as f32, (st * cp) as f32)
}

/// The solid angle of a texel of row `row`: the exact area of its latitude band over `width`.
fn latlong_solid_angle(width: usize, height: usize, row: usize) -> f64 {
    let dt = std::f64::consts::PI / height as f64;
    let (t0, t1) = (row as f64 * dt, (row as f64 + 1.0) * dt);
    2.0 * std::f64::consts::PI * (t0.cos() - t1.cos()) / width as f64
}

impl Sh9 {
    /// A constant radiance `rgb` in every direction: `L00 = sqrt(4 pi) rgb`, the rest 0.
    pub fn constant(rgb: [f32; 3]) -> Self {
        let mut sh = Self::default();
        sh.coeffs[0] = rgb.map(|c| c * (4.0 * std::f32::consts::PI).sqrt());
        sh
    }

    /// A sky-to-ground gradient: `sky` toward `up`, `ground` opposite, linear in `up . w` in
    /// between, `L(w) = (sky + ground) / 2 + (sky - ground) / 2 (up . w)`. Band-limited to
    /// l <= 1, so the nine coefficients are exact. `up` is normalised (zero counts as +y).
    pub fn gradient(sky: [f32; 3], ground: [f32; 3], up: Vec3) -> Self {
        let up = up.try_normalize().unwrap_or(Vec3::Y);
        let mut sh = Self::constant(std::array::from_fn(|c| 0.5 * (sky[c] + ground[c])));
        // int (up . w) Y_1m(w) dw = C1 4 pi / 3 up_j, j = y, z, x for m = -1, 0, 1.
        let k = C1 * 4.0 * std::f32::consts::PI / 3.0;
        for (i, axis) in [(1, up.y), (2, up.z), (3, up.x)] {
            sh.coeffs[i] = std::array::from_fn(|c| 0.5 * (sky[c] - ground[c]) * k * axis);
        }
        sh
    }

    /// Projects an equirectangular map (`width x height` linear RGB texels, row-major, row 0 at
    /// the top, directions as [`latlong_direction`]), each texel weighted by its exact solid
    /// angle (the integral of `sin t dt dp` over it).
    ///
    /// # Errors
    /// [`ShError::EmptyMap`] for a zero side, [`ShError::TexelCount`] when `texels` is not
    /// `width * height` long.
    pub fn project_latlong(width: usize, height: usize, texels: &[[f32; 3]]) -> Result<Self> {
        if width == 0 || height == 0 {
            return Err(ShError::EmptyMap { width, height });
        }
        if texels.len() != width * height {
            return Err(ShError::TexelCount { width, height, texels: texels.len(), expected: width * height });
        }
        let mut acc = [[0.0f64; 3]; SH9];
        for row in 0..height {
            let weight = latlong_solid_angle(width, height, row);
            for column in 0..width {
                let y = basis(latlong_direction(width, height, column, row));
                let texel = texels[row * width + column];
                for (i, yi) in y.iter().enumerate() {
                    for c in 0..3 {
                        acc[i][c] += weight * f64::from(*yi) * f64::from(texel[c]);
                    }
                }
            }
        }
        Ok(Self { coeffs: acc.map(|a| a.map(|v| v as f32)) })
    }

    /// The band-limited radiance in direction `d`: `sum L_lm Y_lm(d)`.
    pub fn eval(&self, d: Vec3) -> [f32; 3] {
        self.convolve(d, &[[1.0; 3]; 3])
    }

    /// `sum_l zonal[l][c] sum_m L_lm,c Y_lm(n)`: the radiance convolved with a kernel zonal
    /// about the unit normal `n`, given its factors `A_l` per channel (`zonal[l][channel]`).
    pub fn convolve(&self, n: Vec3, zonal: &[[f32; 3]; 3]) -> [f32; 3] {
        let y = basis(n);
        let mut out = [0.0f32; 3];
        for (i, coeff) in self.coeffs.iter().enumerate() {
            for c in 0..3 {
                out[c] += zonal[BAND[i]][c] * coeff[c] * y[i];
            }
        }
        out
    }

    /// [`Sh9::convolve`] with a normal per channel (`normals[channel]`), for renderers that
    /// blur the normal per channel; the WGSL twin is `sh9_convolve_rgb`.
    pub fn convolve_per_channel(&self, normals: [Vec3; 3], zonal: &[[f32; 3]; 3]) -> [f32; 3] {
        std::array::from_fn(|c| self.convolve(normals[c], zonal)[c])
    }

    /// Lambert irradiance at unit normal `n` (Ramamoorthi and Hanrahan): `A = pi, 2 pi/3, pi/4`.
    pub fn irradiance_lambert(&self, n: Vec3) -> [f32; 3] {
        self.convolve(n, &LAMBERT_ZONAL.map(|a| [a; 3]))
    }
}

/// `A_l = 2 pi int_-1^1 f(u) P_l(u) du` (`u = cos t`) for l = 0, 1, 2, by two-point
/// Gauss-Legendre on `cells` even cells of u (rounded up to even, so the terminator u = 0 of
/// flat skin is a cell boundary and the clamped cosine is integrated exactly), for a kernel `f`
/// of the cosine that returns one value per channel.
pub fn zonal_factors(f: impl Fn(f64) -> [f64; 3] + Sync, cells: usize) -> [[f64; 3]; 3] {
    use rayon::prelude::*;
    let cells = (cells.max(2) + 1) & !1;
    let h = 2.0 / cells as f64;
    let offset = 0.5 * h / 3f64.sqrt();
    let nodes: Vec<f64> =
        (0..cells).flat_map(|i| [-1.0 + (i as f64 + 0.5) * h - offset, -1.0 + (i as f64 + 0.5) * h + offset]).collect();
    let terms: Vec<[[f64; 3]; 3]> = nodes
        .into_par_iter()
        .map(|u| {
            let legendre = [1.0, u, 0.5 * (3.0 * u * u - 1.0)];
            let value = f(u);
            legendre.map(|p| value.map(|v| std::f64::consts::PI * v * p * h))
        })
        .collect();
    let mut out = [[0.0; 3]; 3];
    for term in terms {
        for l in 0..3 {
            for c in 0..3 {
                out[l][c] += term[l][c];
            }
        }
    }
    out
}

/// The skin's convolution factors `A_l(1/r)` per channel (`[l][channel]`) from the true falloff
/// ([`super::fit::reference_direct`]) over the whole sphere. `1/r` is in mm^-1; negative or NaN
/// counts as 0 (Lambert). Costs twice [`ZONAL_STEPS`] falloff evaluations: tabulate it
/// ([`ZonalTable`]).
pub fn skin_zonal(inv_r_mm: f32) -> [[f32; 3]; 3] {
    let inv_r = if inv_r_mm.is_nan() { 0.0 } else { f64::from(inv_r_mm).max(0.0) };
    let falloff = super::sphere::SphereFalloff::new(&super::profile::Profile::default(), inv_r);
    zonal_factors(|c| falloff.at(c), ZONAL_STEPS).map(|a| a.map(|v| v as f32))
}

/// Skin irradiance at unit normal `n` under `sh`: `sum_l A_l,c(1/r) sum_m L_lm,c Y_lm(n)`.
/// Computes [`skin_zonal`] each call; with many normals, use [`Sh9::convolve`] on a table's row.
pub fn skin_irradiance(sh: &Sh9, n: Vec3, inv_r_mm: f32) -> [f32; 3] {
    sh.convolve(n, &skin_zonal(inv_r_mm))
}

/// [`skin_zonal`] sampled at `n` values of 1/r, evenly from `inv_r_min` to `inv_r_max`
/// inclusive, for a GPU texture: width `n` (1/r along u, texel centres on the samples), 3 rows
/// (row l holds `A_l`), RGB ([`ZonalTable::texels`]). Linear interpolation between 9 samples
/// over [0, 1] mm^-1 is within 1.5% of [`skin_zonal`], between 33 within 0.11% (the error falls
/// as `1 / n^2`); each sample costs one [`skin_zonal`].
#[derive(Debug, Clone, PartialEq)]
pub struct ZonalTable {
    /// 1/r of the first sample, mm^-1.
    pub inv_r_min: f32,
    /// 1/r of the last sample, mm^-1.
    pub inv_r_max: f32,
    /// Number of samples.
    pub n: usize,
    /// `rows[i][l][channel]`: `A_l` at sample i.
    pub rows: Vec<[[f32; 3]; 3]>,
}

impl ZonalTable {
    /// Tabulates [`skin_zonal`].
    ///
    /// # Errors
    /// [`ShError::BadTable`] unless `n >= 2` and `0 <= inv_r_min < inv_r_max`, both finite.
    pub fn build(inv_r_min: f32, inv_r_max: f32, n: usize) -> Result<Self> {
        let ok = n >= 2 && inv_r_min.is_finite() && inv_r_max.is_finite() && 0.0 <= inv_r_min && inv_r_min < inv_r_max;
        if !ok {
            return Err(ShError::BadTable { n, inv_r_min, inv_r_max });
        }
        let rows = (0..n).map(|i| skin_zonal(Self::at(inv_r_min, inv_r_max, n, i))).collect();
        Ok(Self { inv_r_min, inv_r_max, n, rows })
    }

    /// 1/r of sample `i`.
    fn at(lo: f32, hi: f32, n: usize, i: usize) -> f32 {
        lo + (hi - lo) * i as f32 / (n - 1) as f32
    }

    /// 1/r of sample `i`, mm^-1.
    pub fn inv_r(&self, i: usize) -> f32 {
        Self::at(self.inv_r_min, self.inv_r_max, self.n, i)
    }

    /// The factors at `inv_r_mm`, linear between samples, clamped to the ends (NaN: the first).
    pub fn sample(&self, inv_r_mm: f32) -> [[f32; 3]; 3] {
        let x = (inv_r_mm - self.inv_r_min) / (self.inv_r_max - self.inv_r_min) * (self.n - 1) as f32;
        let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, (self.n - 1) as f32) };
        let i = (x.floor() as usize).min(self.n - 2);
        let t = x - i as f32;
        let (a, b) = (&self.rows[i], &self.rows[i + 1]);
        std::array::from_fn(|l| std::array::from_fn(|c| a[l][c] + (b[l][c] - a[l][c]) * t))
    }

    /// RGBA texels (alpha 1), `n` wide and 3 high, row l = band l, row 0 first.
    pub fn texels(&self) -> Vec<[f32; 4]> {
        (0..3).flat_map(|l| self.rows.iter().map(move |row| [row[l][0], row[l][1], row[l][2], 1.0])).collect()
    }
}

/// The blog's closed-form zonal coefficients `zh0`, `zh1` per channel at `1/r` in mm^-1
/// (clamped to [0.0625, 0.5] like its direct curve), minus signs restored.
pub(crate) fn blog_zh(inv_r_mm: f32) -> [[f32; 3]; 2] {
    let curvature = super::fit::blog_curvature(inv_r_mm);
    let curva = (1.0 / (curvature * (0.5 - 0.0625) + 0.0625) - 2.0) / (16.0 - 2.0);
    let one_minus = 1.0 - curva;
    [blog_zh0(curva), blog_zh1(curva, one_minus)]
}

/// The blog's `ZH0` block.
fn blog_zh0(curva: f32) -> [f32; 3] {
    let remap = [3.0f32, 2.7].map(|s| {
        let r = 1.0 - (curva * s).clamp(0.0, 1.0);
        let r = r * r;
        r * r
    });
    let multiplier = [1.0 / (curva * 3.2 + 0.4), remap[0], remap[1]];
    let (scale, base) = ([0.061659f32, 0.00991683, 0.003783], [0.868938f32, 0.885506, 0.885400]);
    std::array::from_fn(|c| multiplier[c] * scale[c] + base[c])
}

/// The blog's `ZH1` block (its literals verbatim, more digits than f32 holds).
#[allow(clippy::excessive_precision)]
fn blog_zh1(curva: f32, one_minus: f32) -> [f32; 3] {
    let rc = 1.0 - (curva * 2.7).clamp(0.0, 1.0);
    let (scale, base) = ([0.197573092f32, 0.0117447875, 0.0040980375], [0.7672169f32, 1.009236, 1.017741]);
    let upper = [1.018366f32, 1.022107, 1.022232];
    std::array::from_fn(|c| {
        let lower = scale[c] * (1.0 - rc * rc * rc) + base[c];
        upper[c] + (lower - upper[c]) * (one_minus * one_minus)
    })
}

/// The blog's zonal approximation as convolution factors `A_l` (`[l][channel]`):
/// `sqrt(4 pi) zh0`, `sqrt(4 pi / 3) zh1`, and Lambert's `pi / 4` for band 2.
pub fn blog_zonal(inv_r_mm: f32) -> [[f32; 3]; 3] {
    let [zh0, zh1] = blog_zh(inv_r_mm);
    let four_pi = 4.0 * std::f32::consts::PI;
    [zh0.map(|z| four_pi.sqrt() * z), zh1.map(|z| (four_pi / 3.0).sqrt() * z), [LAMBERT_ZONAL[2]; 3]]
}
