//! [`Method::Robust`](super::Method::Robust) in the solve: which pixels the all-lights least
//! squares explains, and the [`crate::robust`] fit of the others.

use glam::Vec3;

use super::plan::{Plan, Scratch};
use super::{CHUNK, RESIDUAL_SCALE, SolveConfig};
use crate::Result;
use crate::robust::{self, Lights, RobustConfig};

/// What the robust fit of a solve needs, built once.
pub(super) struct Fit {
    lights: Lights,
    config: RobustConfig,
    /// All-lights confidence (its residual factor) below which a pixel is fitted:
    /// `1 / (1 + (AGREEMENT / RESIDUAL_SCALE)^2)`.
    gate: f32,
}

impl Fit {
    /// The fit for `lights` under `config` (its light-count and conditioning limits, its absolute
    /// shadow floor; the rest are [`RobustConfig`]'s defaults).
    pub(super) fn new(lights: &[Vec3], config: &SolveConfig) -> Result<Self> {
        let config = RobustConfig {
            shadow_abs: config.shadow_abs,
            min_lights: config.min_lights,
            max_condition: config.max_condition,
            ..RobustConfig::default()
        };
        config.validate()?;
        let agreement = robust::AGREEMENT / RESIDUAL_SCALE;
        Ok(Fit { lights: Lights::new(lights)?, config, gate: 1.0 / (1.0 + agreement * agreement) })
    }

    /// Whether a pixel with this all-lights confidence (0 when least squares failed) and this
    /// many dropped readings needs the fit.
    #[inline(always)]
    pub(super) fn needed(&self, confidence: f32, dropped: u32) -> bool {
        dropped > 0 || !(confidence >= self.gate)
    }
}

impl Plan<'_> {
    /// Normal, albedo, confidence and lights used of pixel `j` of the chunk, by the robust fit of
    /// its loaded readings.
    pub(super) fn finish_fit(&self, fit: &Fit, j: usize, s: &Scratch) -> (Vec3, Vec3, f32, usize) {
        let mut r = [0.0f32; super::MAX_LIGHTS];
        let mut sat = [false; super::MAX_LIGHTS];
        for i in 0..self.k {
            r[i] = s.r[i * CHUNK + j];
            sat[i] = s.sat[i * CHUNK + j] != 0;
        }
        let f = robust::fit_pixel(&r[..self.k], &sat[..self.k], &fit.lights, &fit.config);
        if f.used() == 0 {
            return (Vec3::ZERO, Vec3::ZERO, 0.0, 0);
        }
        let albedo = if self.rgb { self.rgb_albedo(j, f.inliers, f.normal, s) } else { Vec3::splat(f.albedo) };
        (f.normal, albedo, f.confidence, f.used())
    }
}
