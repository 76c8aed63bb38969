//! What a solve is asked to do: [`Method`], [`SolveConfig`], and where progress goes.

use crate::readings::{SHADOW_ABS, SHADOW_REL, Shadows};
use crate::{Error, Result};

/// Which per-pixel solve to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// One least-squares solve over all lights (the paper).
    LeastSquares,
    /// Drops shadowed and saturated readings as [`Method::Threshold`] does and keeps least squares
    /// on the rest where it explains them (relative residual within 2 %, or within what the
    /// image's measured noise floor leaves: `plan/noise.rs`); elsewhere the
    /// rank-trimmed fit of [`crate::robust`] (the brightest 40 % and darkest 10 % of the lit
    /// readings left out of the start, every light that agrees refitted).
    #[default]
    Robust,
    /// The earlier robust solve: drop readings under the shadow thresholds (`shadow_abs`,
    /// `shadow_rel` of the pixel's 90th-percentile reading) or saturated, least squares on the
    /// rest, no fit. Less accurate than [`Method::Robust`] on every case measured; faster only
    /// where pixels need the fit (highlights, inter-reflections).
    Threshold,
}

impl Method {
    /// Whether the method drops shadowed and saturated readings (all but least squares).
    pub(crate) fn drops_readings(self) -> bool {
        self != Method::LeastSquares
    }
}

/// Parameters of [`solve`](super::solve()); see the module docs for how the thresholds are applied.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveConfig {
    pub method: Method,
    /// Absolute shadow floor, as a fraction of full scale after ambient subtraction and division
    /// by the light's intensity ([`Shadows::abs`]).
    pub shadow_abs: f32,
    /// Shadow threshold relative to the pixel's own 90th-percentile usable reading
    /// ([`Shadows::rel`]); the robust fit, the threshold solve and the near-light solve all use it.
    pub shadow_rel: f32,
    /// Fraction of full scale at or above which a raw reading is saturated.
    pub saturation: f32,
    /// Fewest usable lights for a valid pixel (at least 3).
    pub min_lights: usize,
    /// Largest condition number `sigma_max / sigma_min` of the used lights' direction matrix.
    pub max_condition: f64,
    /// Subset pseudo-inverses kept per worker for rigs of more than [`DENSE_MAX_LIGHTS`](super::DENSE_MAX_LIGHTS) lights.
    pub cache_capacity: usize,
}

impl Default for SolveConfig {
    fn default() -> Self {
        SolveConfig {
            method: Method::Robust,
            shadow_abs: SHADOW_ABS,
            shadow_rel: SHADOW_REL,
            saturation: 0.995,
            min_lights: 3,
            max_condition: 50.0,
            cache_capacity: 4096,
        }
    }
}

impl SolveConfig {
    /// The shadow rule of [`Self::shadow_abs`] and [`Self::shadow_rel`].
    pub fn shadows(&self) -> Shadows {
        Shadows { abs: self.shadow_abs, rel: self.shadow_rel }
    }

    /// Checks every field's range.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field and its value.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &str, value: String, want: &str| {
            Err(Error::InvalidInput(format!("solve config: {field} = {value} must be {want}")))
        };
        if !(0.0..1.0).contains(&self.shadow_abs) {
            return bad("shadow_abs", self.shadow_abs.to_string(), "in [0, 1)");
        }
        if !(0.0..1.0).contains(&self.shadow_rel) {
            return bad("shadow_rel", self.shadow_rel.to_string(), "in [0, 1)");
        }
        if !(self.saturation > 0.0 && self.saturation <= 1.0) {
            return bad("saturation", self.saturation.to_string(), "in (0, 1]");
        }
        if self.min_lights < 3 {
            return bad("min_lights", self.min_lights.to_string(), "at least 3");
        }
        if self.max_condition.is_nan() || self.max_condition < 1.0 {
            return bad("max_condition", self.max_condition.to_string(), "at least 1");
        }
        if self.cache_capacity == 0 {
            return bad("cache_capacity", "0".into(), "at least 1");
        }
        Ok(())
    }
}

/// A solve reports one stage, `solve`, counted in rows, from worker threads.
pub use skinkit_maps::progress::{NoProgress, Progress};
