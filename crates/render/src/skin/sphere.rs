//! The pre-integrated falloff over a sphere ([`super::profile::Domain::Sphere`]): the light
//! leaving a point of a sphere of radius `r` lit from one side, the diffusion profile spread over
//! the surface by chord distance, computed to about 1e-6 (the brute force is
//! [`super::profile::sphere_integral`]).
//!
//! With the chord `d = 2 r sin(phi / 2)` as the variable (`phi` the polar angle from the shading
//! point), the sphere's area element `r^2 sin(phi) dphi dpsi` is exactly `d dd dpsi`, the plane's
//! (Archimedes: the cap within chord `d` has area `pi d^2`). So per Gaussian `G`
//!
//! `D = int G(d) d A(phi(d)) dd / (2 pi int G(d) d dd)` over `d` in `[0, min(2 r, cut)]`,
//!
//! where the azimuth integral `A(phi) = int max(0, a + b cos(psi)) dpsi` is closed: with
//! `a = cos(theta) cos(phi)`, `b = sin(theta) sin(phi)` and `psi0 = acos(-a / b)`,
//! `A = 2 (a psi0 + b sin(psi0))` (`2 pi a` when `a >= b`, 0 when `a <= -b`). `A` is C1, so
//! 4-point Gauss-Legendre cells need no breakpoints at its kinks.

use super::profile::{KERNEL_CUT_SIGMAS, Profile, VARIANCES_MM2, WEIGHTS, gauss_legendre_nodes};

/// Gauss-Legendre cells per Gaussian over its reach in the chord.
const CELLS: usize = 96;

/// The chord quadrature of one sphere radius, reused for every N.L.
pub(crate) struct SphereFalloff {
    /// Per Gaussian: the nodes `(cos phi, sin phi, G(d) d dd)` and `2 pi int G(d) d dd`.
    gaussians: Vec<(Vec<[f64; 3]>, f64)>,
}

impl SphereFalloff {
    /// The quadrature for a sphere of curvature `inv_r_mm` (1/mm; 0, negative or not finite
    /// count as flat skin, where the falloff is the clamped N.L).
    pub fn new(profile: &Profile, inv_r_mm: f64) -> Self {
        let inv_r = if inv_r_mm.is_finite() && inv_r_mm > 0.0 { inv_r_mm } else { 0.0 };
        let gaussians = (0..VARIANCES_MM2.len())
            .map(|g| {
                let mut reach = KERNEL_CUT_SIGMAS * profile.variance(g).sqrt();
                if inv_r > 0.0 {
                    reach = reach.min(2.0 / inv_r);
                }
                let h = reach / CELLS as f64;
                let nodes: Vec<[f64; 3]> = (0..CELLS)
                    .flat_map(|n| gauss_legendre_nodes(n as f64 * h, h))
                    .map(|(d, w)| {
                        let phi = 2.0 * (0.5 * d * inv_r).min(1.0).asin();
                        [phi.cos(), phi.sin(), w * profile.gaussian(g, d) * d]
                    })
                    .collect();
                let total = std::f64::consts::TAU * nodes.iter().map(|n| n[2]).sum::<f64>();
                (nodes, total)
            })
            .collect();
        Self { gaussians }
    }

    /// `D(N.L)` per channel (N.L clamped to [-1, 1], NaN counts as 0).
    pub fn at(&self, n_dot_l: f64) -> [f64; 3] {
        let n_dot_l = if n_dot_l.is_nan() { 0.0 } else { n_dot_l.clamp(-1.0, 1.0) };
        let (cos_t, sin_t) = (n_dot_l, (1.0 - n_dot_l * n_dot_l).max(0.0).sqrt());
        let (mut light, mut total) = ([0.0; 3], [0.0; 3]);
        for ((nodes, all), w) in self.gaussians.iter().zip(WEIGHTS.iter()) {
            let lit: f64 = nodes.iter().map(|&[c, s, weight]| weight * azimuth_lit(cos_t * c, sin_t * s)).sum();
            for ch in 0..3 {
                light[ch] += w[ch] * lit;
                total[ch] += w[ch] * all;
            }
        }
        std::array::from_fn(|ch| if total[ch] > 0.0 { light[ch] / total[ch] } else { n_dot_l.max(0.0) })
    }
}

/// `int max(0, a + b cos(psi)) dpsi` over `[0, 2 pi)`, for `b >= 0`.
fn azimuth_lit(a: f64, b: f64) -> f64 {
    if a >= b {
        std::f64::consts::TAU * a
    } else if a <= -b {
        0.0
    } else {
        let c = -a / b;
        2.0 * (a * c.acos() + b * (1.0 - c * c).max(0.0).sqrt())
    }
}
