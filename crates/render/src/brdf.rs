//! The Lafortune BRDF (Lafortune et al. 1997), the skin reflectance model of Haro et al. 2001,
//! section 5.2: a diffuse term plus a sum of generalised cosine lobes,
//!
//! `f(l, v) = rho_d / pi + sum_i max(0, Cx lx vx + Cy ly vy + Cz lz vz)^n_i`,
//!
//! evaluated per RGB channel in the local frame (x tangent, y bitangent, z normal), with both
//! directions pointing away from the surface. The model is not energy normalised.
//!
//! Numerical safety: a negative lobe base gives exactly 0 (the power of a negative number would
//! be NaN), and a lobe value is capped at [`LOBE_CEILING`] so that a base slightly above 1 raised
//! to a huge exponent (n = 10000) stays finite. The same rules are in `src/pass/base/base.wgsl`.

use glam::Vec3;

/// Largest value one lobe may contribute (per steradian). A lobe whose base exceeds 1 (possible
/// when |C| > 1, as in the skin set's grazing lobe) would overflow to infinity with a large
/// exponent; a BRDF value of 1e6 is already a near-delta highlight, so the cap only changes
/// results that would otherwise not be finite or would saturate any display.
pub const LOBE_CEILING: f32 = 1.0e6;

/// One generalised cosine lobe, each coefficient per RGB channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lobe {
    /// Coefficient on `lx vx` (tangent direction).
    pub cx: Vec3,
    /// Coefficient on `ly vy` (bitangent direction).
    pub cy: Vec3,
    /// Coefficient on `lz vz` (normal direction).
    pub cz: Vec3,
    /// Exponent.
    pub n: Vec3,
}

/// A Lafortune BRDF: diffuse albedo plus lobes.
#[derive(Debug, Clone, PartialEq)]
pub struct Lafortune {
    /// Diffuse albedo `rho_d` per RGB channel (the BRDF's diffuse term is `rho_d / pi`).
    pub diffuse: Vec3,
    /// The specular lobes.
    pub lobes: Vec<Lobe>,
}

impl Lobe {
    /// A lobe with `Cx = Cy = cxy` (isotropic), as in the skin set.
    pub fn isotropic(cxy: Vec3, cz: Vec3, n: Vec3) -> Self {
        Self { cx: cxy, cy: cxy, cz, n }
    }

    /// The lobe's value for `l` and `v` in the local frame, per channel.
    pub fn eval(&self, l: Vec3, v: Vec3) -> Vec3 {
        let base = self.cx * (l.x * v.x) + self.cy * (l.y * v.y) + self.cz * (l.z * v.z);
        Vec3::new(lobe_power(base.x, self.n.x), lobe_power(base.y, self.n.y), lobe_power(base.z, self.n.z))
    }
}

/// `max(0, base)^n`, capped at [`LOBE_CEILING`], never NaN (a NaN base gives 0).
pub fn lobe_power(base: f32, n: f32) -> f32 {
    // `!(base > 0)` also catches NaN.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(base > 0.0) {
        return 0.0;
    }
    let value = base.powf(n.max(0.0));
    if value.is_nan() { 0.0 } else { value.min(LOBE_CEILING) }
}

impl Lafortune {
    /// The 3-lobe skin set (pbrt-v1's skin material, from the Cornell skin measurements), as
    /// tabulated in docs/references.md, "Rendering". Lobe 0 has negative Cz: a grazing lobe that relies
    /// on the clamp of negative bases.
    #[allow(clippy::excessive_precision)] // The table's digits, verbatim (f32 rounds them).
    pub fn skin() -> Self {
        Self {
            diffuse: Vec3::new(0.428425, 0.301341, 0.331054),
            lobes: vec![
                Lobe::isotropic(
                    Vec3::new(-1.131747, -1.016939, -0.966018),
                    Vec3::new(-1.209182, -1.462488, -1.222419),
                    Vec3::new(6.421658, 3.699932, 3.524889),
                ),
                Lobe::isotropic(
                    Vec3::new(-0.546570, -0.643533, -0.638934),
                    Vec3::new(0.380123, 0.410559, 0.437367),
                    Vec3::new(3.685044, 4.266495, 4.539742),
                ),
                Lobe::isotropic(
                    Vec3::new(-0.998888, -1.020153, -1.027479),
                    Vec3::new(0.857998, 0.703913, 0.573625),
                    Vec3::new(64.208486, 63.919687, 43.809866),
                ),
            ],
        }
    }

    /// A purely diffuse BRDF.
    pub fn lambert(diffuse: Vec3) -> Self {
        Self { diffuse, lobes: Vec::new() }
    }

    /// The diffuse term `rho_d / pi`.
    pub(crate) fn diffuse_term(&self) -> Vec3 {
        self.diffuse / std::f32::consts::PI
    }

    /// The sum of the lobes only (no diffuse term).
    pub fn eval_specular(&self, l: Vec3, v: Vec3) -> Vec3 {
        self.lobes.iter().map(|lobe| lobe.eval(l, v)).sum()
    }

    /// The full BRDF value for `l` and `v` in the local frame (x tangent, y bitangent, z normal;
    /// both pointing away from the surface). Directions need not be in the upper hemisphere:
    /// the caller multiplies by the clamped cosine.
    pub fn eval(&self, l: Vec3, v: Vec3) -> Vec3 {
        self.diffuse_term() + self.eval_specular(l, v)
    }

    /// Directional-hemispherical reflectance for the incident direction `l` (local frame, unit):
    /// `integral over the upper hemisphere of f(l, v) cos(theta_v) dv`, by midpoint quadrature
    /// with `steps` intervals in theta and `2 * steps` in phi (in f64).
    pub fn albedo(&self, l: Vec3, steps: usize) -> Vec3 {
        let steps = steps.max(1);
        let d_theta = std::f64::consts::FRAC_PI_2 / steps as f64;
        let d_phi = std::f64::consts::PI / steps as f64;
        let mut sum = [0.0f64; 3];
        for i in 0..steps {
            let theta = (i as f64 + 0.5) * d_theta;
            let weight = theta.cos() * theta.sin() * d_theta * d_phi;
            for j in 0..2 * steps {
                let phi = (j as f64 + 0.5) * d_phi;
                let v =
                    Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, theta.cos() as f32);
                let f = self.eval(l, v);
                sum[0] += f.x as f64 * weight;
                sum[1] += f.y as f64 * weight;
                sum[2] += f.z as f64 * weight;
            }
        }
        Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
    }
}
