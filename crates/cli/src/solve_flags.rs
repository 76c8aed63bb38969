//! The solver flags `capture`, `batch`, `face` and `demo` share ([`SolveArgs`]), and their
//! conversion into the capture library's options.

use anyhow::{Context, Result};
use skinkit_capture::session::CaptureOptions;
use skinkit_capture::solve::{Method, SolveConfig};
use skinkit_maps::Limits;

use crate::flags::{Green, RawArg, TransferArg};
use crate::output::Output;

/// Solver and output options shared by `capture`, `batch` and `demo`.
#[derive(clap::Args, Debug, Clone)]
pub struct SolveArgs {
    /// `ls`: the paper's least squares over all lights; `robust`: least squares where it
    /// explains every reading, elsewhere a fit that drops shadows, saturation, the brightest
    /// (specular) readings and every reading that disagrees; `threshold`: the earlier robust
    /// solve (drop readings under the shadow thresholds, solve from the rest; faster).
    #[arg(long, value_enum, default_value_t = SolverArg::Robust)]
    pub solver: SolverArg,
    /// Side of the low-frequency removal block in pixels (the paper's 50); 0 turns it off.
    #[arg(long, default_value_t = 50, value_name = "PIXELS", value_parser = crate::flags::usize_in(0, 16384))]
    pub detrend_block: usize,
    /// Robust and threshold solvers: readings below this fraction of full scale count as shadow.
    #[arg(long, value_name = "FRACTION", value_parser = shadow_fraction)]
    pub shadow_threshold: Option<f32>,
    /// Robust and threshold solvers: readings below this fraction of the pixel's 90th-percentile
    /// reading (its brightest with up to 9 lights) count as shadow [default: 0.1].
    #[arg(long, value_name = "FRACTION", value_parser = shadow_fraction)]
    pub shadow_relative: Option<f32>,
    /// Readings at or above this fraction of full scale count as saturated (above 0, at most 1).
    #[arg(long, value_name = "FRACTION", value_parser = saturation_fraction)]
    pub saturation: Option<f32>,
    /// Largest condition number of the rig's light directions a capture accepts (distant lights;
    /// `rig check` takes the same flag) [default: 50].
    #[arg(long, value_name = "C", value_parser = condition_limit)]
    pub max_condition: Option<f64>,
    /// How 8/16-bit photo values relate to light: `linear` (raw, machine-vision cameras) or `srgb`.
    #[arg(long, value_enum, default_value_t = TransferArg::Linear)]
    pub transfer: TransferArg,
    /// Green channel convention of the written normal.png / normal.exr.
    #[arg(long, value_enum, default_value_t = Green::Up)]
    pub green: Green,
    /// Camera RAW photos (DNG, CR2, NEF, ARW, ...): `half` bins each 2x2 Bayer cell into one
    /// pixel (no interpolation), `full` demosaics to the sensor's size. Either way the values are
    /// linear: black level subtracted, white level normalised, no white balance or tone curve.
    #[arg(long, value_enum, default_value_t = RawArg::Half)]
    pub raw: RawArg,
}

/// `--solver` values (the doc comment on `CaptureArgs::solver` says what each does).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SolverArg {
    Ls,
    Robust,
    Threshold,
}

impl SolverArg {
    /// The flag's value: `ls`, `robust` or `threshold`.
    pub fn name(self) -> &'static str {
        match self {
            SolverArg::Ls => "ls",
            SolverArg::Robust => "robust",
            SolverArg::Threshold => "threshold",
        }
    }
}

impl SolveArgs {
    /// The command's defaults with `solver` (what `demo` and `face` capture with).
    pub fn defaults(solver: SolverArg) -> Self {
        SolveArgs {
            solver,
            detrend_block: 50,
            shadow_threshold: None,
            shadow_relative: None,
            saturation: None,
            max_condition: None,
            transfer: TransferArg::Linear,
            green: Green::Up,
            raw: RawArg::Half,
        }
    }

    /// The validated library options, within the run's memory limit.
    pub fn options(&self, out: &Output) -> Result<CaptureOptions> {
        let defaults = SolveConfig::default();
        let solve = SolveConfig {
            method: match self.solver {
                SolverArg::Ls => Method::LeastSquares,
                SolverArg::Threshold => Method::Threshold,
                SolverArg::Robust => Method::Robust,
            },
            shadow_abs: self.shadow_threshold.unwrap_or(defaults.shadow_abs),
            shadow_rel: self.shadow_relative.unwrap_or(defaults.shadow_rel),
            saturation: self.saturation.unwrap_or(defaults.saturation),
            max_condition: self.max_condition.unwrap_or(defaults.max_condition),
            ..defaults
        };
        solve.validate().context("invalid solver option")?;
        Ok(CaptureOptions {
            solve,
            detrend_block: self.detrend_block,
            transfer: self.transfer.into(),
            encoding: self.green.encoding(),
            raw: self.raw.into(),
            limits: Limits::default(),
            memory_limit: out.memory_limit(),
        })
    }
}

/// The loosest condition limit a flag takes: beyond it a float32 photo's rounding alone (about
/// 1e-7) is amplified past the normals' own size, so no limit above it means anything.
pub const MAX_CONDITION_LIMIT: f64 = 1e7;

/// A `--max-condition` value: a finite number from 1 (a condition number's least) to
/// [`MAX_CONDITION_LIMIT`].
pub fn condition_limit(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && (1.0..=MAX_CONDITION_LIMIT).contains(&v) => Ok(v),
        _ => Err(format!("`{text}` is not a condition number limit: give a number from 1 to {MAX_CONDITION_LIMIT:e}")),
    }
}

/// A shadow threshold: a fraction in `[0, 1)` (as [`SolveConfig::validate`] requires), so a bad
/// value is a usage error (exit 2) rather than a failed run.
fn shadow_fraction(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if (0.0..1.0).contains(&v) => Ok(v),
        _ => Err(format!("`{text}` is not a fraction from 0 up to (not including) 1")),
    }
}

/// A saturation level: a fraction in `(0, 1]` (as [`SolveConfig::validate`] requires).
fn saturation_fraction(text: &str) -> Result<f32, String> {
    match text.parse::<f32>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!("`{text}` is not a fraction above 0 and at most 1")),
    }
}
