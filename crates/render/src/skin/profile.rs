//! The skin diffusion profile R(d) as d'Eon and Luebke's sum of six Gaussians (GPU Gems 3,
//! chapter 14), with the definitions that change every table built from it made explicit
//! (`docs/references.md`):
//!
//! - [`Normalisation::TwoD`]: each Gaussian is the radial 2-D density `exp(-d^2 / 2v) / (2 pi v)`,
//!   so the profile integrates to the channel's weight sum (1) over the plane (d'Eon's definition).
//! - [`Normalisation::OneD`]: the pre-integrated paper's listing, `exp(-d^2 / 2v') / sqrt(2 pi v')`
//!   with `v' = 1.414 v`.
//!
//! Weights are the GPU Gems 3 values; the second green weight is 0.336 (Table 1.1 of the
//! pre-integrated paper prints 0.366, a typo; its own listing says 0.336). Each channel sums to 1.
//!
//! [`ring_integral`] is equation 1.1 of the pre-integrated paper evaluated by brute-force
//! quadrature, and [`sphere_integral`] the same falloff over a sphere's surface instead of a ring:
//! the slow, exact definitions every LUT, fit and shader path is measured against ([`falloff`]
//! picks one by [`Domain`]).

/// Variances of the six Gaussians, in mm^2.
pub const VARIANCES_MM2: [f64; 6] = [0.0064, 0.0484, 0.187, 0.567, 1.99, 7.41];

/// Weights of the six Gaussians for red, green and blue (each column sums to 1).
pub const WEIGHTS: [[f64; 3]; 6] = [
    [0.233, 0.455, 0.649],
    [0.100, 0.336, 0.344],
    [0.118, 0.198, 0.0],
    [0.113, 0.007, 0.007],
    [0.358, 0.004, 0.0],
    [0.078, 0.0, 0.0],
];

/// The listing's variance scale for [`Normalisation::OneD`].
pub(crate) const ONE_D_VARIANCE_SCALE: f64 = 1.414;

/// How each Gaussian of the profile is normalised.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Normalisation {
    /// `1 / (2 pi v)`: the radial 2-D Gaussian (d'Eon and Luebke).
    #[default]
    #[serde(rename = "2d")]
    TwoD,
    /// `1 / sqrt(2 pi v')`, `v' = 1.414 v`: the pre-integrated paper's listing.
    #[serde(rename = "1d")]
    OneD,
}

impl Normalisation {
    /// The name written in files and reports: `2d` or `1d`.
    pub fn name(self) -> &'static str {
        match self {
            Self::TwoD => "2d",
            Self::OneD => "1d",
        }
    }
}

/// What the pre-integration of equation 1.1 runs over: a ring (over which angles), or a whole
/// sphere.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Domain {
    /// `[-pi, pi]`: the paper's equation, the whole ring (the SH projection's).
    Full,
    /// `[-pi/2, pi/2]`: the paper's listing.
    Half,
    /// The surface of a sphere of radius `r` ([`sphere_integral`]): the light leaving a point of
    /// a sphere lit from one side, the profile spread over the surface by chord distance. Unlike
    /// the ring, whose 1-D cut weights each 2-D Gaussian by `1 / sqrt(2 pi v)` instead of its
    /// share, this keeps the profile's own weights: the cap within chord `d` of a point has area
    /// `pi d^2` exactly, as the disc of radius `d` on the plane. The default: it is what the
    /// texture-space reference computes on a sphere.
    #[default]
    Sphere,
}

impl Domain {
    /// The name written in files and reports: `full`, `half` or `sphere`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::Half => "half",
            Self::Sphere => "sphere",
        }
    }

    /// Half the angular extent: pi or pi / 2 (pi for the sphere: its polar angle's range).
    pub fn half_extent(self) -> f64 {
        match self {
            Self::Full | Self::Sphere => std::f64::consts::PI,
            Self::Half => std::f64::consts::FRAC_PI_2,
        }
    }
}

/// The sum-of-Gaussians profile under one normalisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Profile {
    /// How each Gaussian is normalised.
    pub normalisation: Normalisation,
}

impl Profile {
    /// The profile with `normalisation`.
    pub fn new(normalisation: Normalisation) -> Self {
        Self { normalisation }
    }

    /// The variance of Gaussian `i` as this normalisation uses it, mm^2.
    pub fn variance(&self, i: usize) -> f64 {
        match self.normalisation {
            Normalisation::TwoD => VARIANCES_MM2[i],
            Normalisation::OneD => VARIANCES_MM2[i] * ONE_D_VARIANCE_SCALE,
        }
    }

    /// Gaussian `i` at distance `d_mm` (any sign; finite for any input, 0 for NaN or infinity).
    pub fn gaussian(&self, i: usize, d_mm: f64) -> f64 {
        let v = self.variance(i);
        let norm = match self.normalisation {
            Normalisation::TwoD => 1.0 / (2.0 * std::f64::consts::PI * v),
            Normalisation::OneD => 1.0 / (2.0 * std::f64::consts::PI * v).sqrt(),
        };
        let g = norm * (-(d_mm * d_mm) / (2.0 * v)).exp();
        if g.is_finite() { g } else { 0.0 }
    }

    /// R(d) per channel (red, green, blue) at distance `d_mm` from the point of entry.
    pub fn eval(&self, d_mm: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (i, weights) in WEIGHTS.iter().enumerate() {
            let g = self.gaussian(i, d_mm);
            for c in 0..3 {
                out[c] += weights[c] * g;
            }
        }
        out
    }

    /// The profile's 1-D marginal at `x_mm`: the light a straight edge of light lets across a
    /// line `x_mm` away (the 2-D profile integrated along the edge). For a sum of radial 2-D
    /// Gaussians this is the sum of 1-D Gaussians of the same variances and weights, whichever
    /// normalisation the radial profile uses; it integrates to 1 over the line.
    pub fn marginal(&self, x_mm: f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (i, weights) in WEIGHTS.iter().enumerate() {
            let v = VARIANCES_MM2[i];
            let g = (-(x_mm * x_mm) / (2.0 * v)).exp() / (2.0 * std::f64::consts::PI * v).sqrt();
            let g = if g.is_finite() { g } else { 0.0 };
            for c in 0..3 {
                out[c] += weights[c] * g;
            }
        }
        out
    }
}

/// Equation 1.1, by brute force: the light leaving a ring of radius `r = 1 / inv_r_mm` lit
/// from one direction at angle `theta = acos(n_dot_l)` from the normal, per channel,
///
/// `D = sum_x max(0, cos(theta + x)) R(2 r sin(|x| / 2)) / sum_x R(2 r sin(|x| / 2))`
///
/// over `steps` midpoint samples of `x` in the domain. The denominator uses the same `r` as the
/// numerator (the listing's normalisation; the extracted equation's `R(2 sin(x/2))` is an
/// extraction error), so flat skin (`inv_r_mm = 0`) gives exactly `max(0, n_dot_l)`.
/// `n_dot_l` is clamped to [-1, 1]; a negative or non-finite `inv_r_mm` counts as 0.
/// [`Domain::Sphere`] counts as the full ring here ([`falloff`] dispatches it to the sphere).
pub fn ring_integral(profile: &Profile, domain: Domain, n_dot_l: f64, inv_r_mm: f64, steps: usize) -> [f64; 3] {
    let n_dot_l = if n_dot_l.is_nan() { 0.0 } else { n_dot_l.clamp(-1.0, 1.0) };
    let inv_r = if inv_r_mm.is_finite() && inv_r_mm > 0.0 { inv_r_mm } else { 0.0 };
    if inv_r == 0.0 {
        return [n_dot_l.max(0.0); 3];
    }
    let theta = n_dot_l.acos();
    let r = 1.0 / inv_r;
    let half = domain.half_extent();
    let steps = steps.max(2);
    let dx = 2.0 * half / steps as f64;
    let (mut light, mut total) = ([0.0f64; 3], [0.0f64; 3]);
    for k in 0..steps {
        let x = -half + (k as f64 + 0.5) * dx;
        let weight = profile.eval(2.0 * r * (0.5 * x).sin());
        let cosine = (theta + x).cos().max(0.0);
        for c in 0..3 {
            light[c] += cosine * weight[c];
            total[c] += weight[c];
        }
    }
    std::array::from_fn(|c| if total[c] > 0.0 { light[c] / total[c] } else { n_dot_l.max(0.0) })
}

/// Equation 1.1 over `domain`, by brute force: [`sphere_integral`] for [`Domain::Sphere`], else
/// [`ring_integral`]; `steps` samples per angle.
pub fn falloff(profile: &Profile, domain: Domain, n_dot_l: f64, inv_r_mm: f64, steps: usize) -> [f64; 3] {
    match domain {
        Domain::Sphere => sphere_integral(profile, n_dot_l, inv_r_mm, steps),
        Domain::Full | Domain::Half => ring_integral(profile, domain, n_dot_l, inv_r_mm, steps),
    }
}

/// The pre-integrated falloff on a sphere, by brute force: the light leaving a point of a sphere
/// of radius `r = 1 / inv_r_mm` lit from one direction at `theta = acos(n_dot_l)` from its normal,
///
/// `D = int max(0, N(p) . L) R(|p - o|) dA / int R(|p - o|) dA`
///
/// over the sphere's surface, with `p` at polar angle `phi` from the shading point `o` and
/// azimuth `psi` (so `N(p) . L = cos(theta) cos(phi) + sin(theta) sin(phi) cos(psi)`, the chord
/// `|p - o| = 2 r sin(phi / 2)`, `dA = r^2 sin(phi) dphi dpsi`), by `steps` midpoint samples of
/// each angle. Same conventions as [`ring_integral`] for flat skin and odd inputs.
pub fn sphere_integral(profile: &Profile, n_dot_l: f64, inv_r_mm: f64, steps: usize) -> [f64; 3] {
    let n_dot_l = if n_dot_l.is_nan() { 0.0 } else { n_dot_l.clamp(-1.0, 1.0) };
    let inv_r = if inv_r_mm.is_finite() && inv_r_mm > 0.0 { inv_r_mm } else { 0.0 };
    if inv_r == 0.0 {
        return [n_dot_l.max(0.0); 3];
    }
    let (cos_t, sin_t) = (n_dot_l, (1.0 - n_dot_l * n_dot_l).max(0.0).sqrt());
    let r = 1.0 / inv_r;
    let steps = steps.max(2);
    let (d_phi, d_psi) = (std::f64::consts::PI / steps as f64, std::f64::consts::TAU / steps as f64);
    let (mut light, mut total) = ([0.0f64; 3], [0.0f64; 3]);
    for k in 0..steps {
        let phi = (k as f64 + 0.5) * d_phi;
        let weight = profile.eval(2.0 * r * (0.5 * phi).sin());
        let area = phi.sin();
        let lit: f64 = (0..steps)
            .map(|m| (cos_t * phi.cos() + sin_t * phi.sin() * ((m as f64 + 0.5) * d_psi).cos()).max(0.0))
            .sum::<f64>()
            / steps as f64;
        for c in 0..3 {
            light[c] += lit * area * weight[c];
            total[c] += area * weight[c];
        }
    }
    std::array::from_fn(|c| if total[c] > 0.0 { light[c] / total[c] } else { n_dot_l.max(0.0) })
}
/// The kernel is cut where the chord reaches this many standard deviations (`exp(-40.5)`).
pub(crate) const KERNEL_CUT_SIGMAS: f64 = 9.0;

/// The 4-point Gauss-Legendre nodes and weights of `[a, a + h]`.
pub(crate) fn gauss_legendre_nodes(a: f64, h: f64) -> impl Iterator<Item = (f64, f64)> {
    const NODES: [(f64, f64); 4] = [
        (-0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
        (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
        (0.861_136_311_594_052_6, 0.347_854_845_137_453_85),
    ];
    NODES.into_iter().map(move |(node, weight)| (a + 0.5 * h * (node + 1.0), weight * 0.5 * h))
}
