//! [`Method::Robust`](crate::solve::Method::Robust) in the solve: which pixels least squares on their
//! lit readings explains, and the [`crate::robust`] fit of the others.
//!
//! A pixel is first solved like [`Method::Threshold`](crate::solve::Method::Threshold) (least squares
//! over all lights, or over its lit, unsaturated readings when some are dropped: the cached
//! subset pseudo-inverses, vectorised). That answer stands when its relative residual is within
//! [`robust::AGREEMENT`] (its residual factor at least [`Fit::gate`]): the lit readings agree with
//! one Lambertian normal, so there is nothing left to reject. Only the other pixels (highlights,
//! inter-reflections, shadows the threshold misses) pay for the per-pixel rank-trimmed fit.

use glam::Vec3;

use super::Plan;
use crate::Result;
use crate::robust::{self, Lights, RobustConfig};
use crate::solve::chunk::Scratch;
use crate::solve::subsets::Subsets;
use crate::solve::{CHUNK, MAX_LIGHTS, NoiseFloor, RESIDUAL_SCALE, SolveConfig};

/// The fit's residual scale is floored at this many noise sigmas, so that its inlier test
/// (`2 s`) keeps readings within 3 sigma of the fit (99.7 % of the noise-only ones).
const NOISE_SCALES: f32 = 1.5;

/// What the robust fit of a solve needs, built once.
pub(in crate::solve) struct Fit {
    lights: Lights,
    config: RobustConfig,
    /// Residual factor of the confidence (`1 / (1 + (rho / RESIDUAL_SCALE)^2)`) below which a
    /// pixel is fitted: `1 / (1 + (AGREEMENT / RESIDUAL_SCALE)^2)`.
    pub(in crate::solve) gate: f32,
}

impl Fit {
    /// The fit for `lights` under `config` (its shadow rule, light-count and conditioning
    /// limits; the rest are [`RobustConfig`]'s defaults).
    pub(in crate::solve) fn new(lights: &[Vec3], config: &SolveConfig) -> Result<Self> {
        let config = RobustConfig {
            shadows: config.shadows(),
            min_lights: config.min_lights,
            max_condition: config.max_condition,
            ..RobustConfig::default()
        };
        config.validate()?;
        let agreement = robust::AGREEMENT / RESIDUAL_SCALE;
        Ok(Fit { lights: Lights::new(lights)?, config, gate: 1.0 / (1.0 + agreement * agreement) })
    }

    /// Adapts the gate and the fit's residual scale to a measured noise floor.
    pub(in crate::solve) fn adapt(&mut self, floor: &NoiseFloor) {
        let agreement = floor.gate / RESIDUAL_SCALE;
        self.gate = 1.0 / (1.0 + agreement * agreement);
        self.config.noise_floor = NOISE_SCALES * floor.sigma;
    }

    /// Whether a least-squares answer with this residual factor (0 when it failed) stands.
    #[inline(always)]
    pub(in crate::solve) fn agrees(&self, factor: f32) -> bool {
        factor >= self.gate
    }
}

impl Plan<'_> {
    /// [`Method::Robust`](crate::solve::Method::Robust): measures the stack's noise floor and adapts the
    /// fit to it (`noise.rs`); returns what was measured.
    pub(in crate::solve) fn adapt_to_noise(&mut self, height: usize) -> Option<NoiseFloor> {
        self.fit.as_ref()?;
        let floor = self.noise_floor(height, robust::AGREEMENT)?;
        if let Some(fit) = self.fit.as_mut() {
            fit.adapt(&floor);
        }
        Some(floor)
    }

    /// Normal, albedo, confidence and lights used of pixel `j` of the chunk, by the robust fit of
    /// its loaded readings (condition numbers from the dense subset table when there is one).
    pub(in crate::solve) fn finish_fit(
        &self,
        fit: &Fit,
        j: usize,
        s: &Scratch,
        subsets: &Subsets,
    ) -> (Vec3, Vec3, f32, usize) {
        let mut r = [0.0f32; MAX_LIGHTS];
        let mut sat = [false; MAX_LIGHTS];
        for i in 0..self.k {
            r[i] = s.r[i * CHUNK + j];
            sat[i] = s.sat[i * CHUNK + j] != 0;
        }
        let condition = |bits| subsets.dense_condition(bits);
        let f = robust::fit_pixel_cached(&r[..self.k], &sat[..self.k], &fit.lights, &fit.config, &condition);
        if f.used() == 0 {
            return (Vec3::ZERO, Vec3::ZERO, 0.0, 0);
        }
        let albedo = if self.rgb { self.rgb_albedo(j, f.inliers, f.normal, s) } else { Vec3::splat(f.albedo) };
        (f.normal, albedo, f.confidence, f.used())
    }
}
