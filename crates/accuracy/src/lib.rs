//! What accuracy costs in time, stage by stage: every choice a user can make in capture, detrend,
//! synthesis, stitching and rendering, measured against an exact or ground-truth form on the
//! bundled samples (or synthetic heightfields with known normals), with its wall-clock time.
//!
//! * [`choice`]: the one row type ([`Choice`]) and the per-stage and whole-run reports.
//! * [`capture`], [`detrend`], [`height`], [`synthesis`], [`stitching`], [`rendering`]: one module per stage,
//!   each a `measure(&Config, progress)` that returns its [`StageReport`].
//! * [`markdown`] and [`plot`]: the report as `accuracy.md` and one error-against-time PNG per
//!   stage (plotters, the bitmap backend, text in the bundled font).
//!
//! Everything random takes the run's seed, so the same seed gives the same numbers (times apart).
//! Libraries never print: progress goes out through [`skinkit_maps::progress::Progress`], a stage
//! per measured stage counted in choices.

pub mod capture;
pub mod choice;
pub mod detrend;
pub mod error;
pub mod height;
pub mod markdown;
pub mod plot;
pub mod rendering;
pub mod stitching;
pub mod synthesis;
mod timing;

use std::path::PathBuf;
use std::time::Instant;

use skinkit_maps::progress::Progress;

pub use choice::{Choice, Metric, Report, Stage, StageReport};
pub use error::{Error, Result};

/// What a run measures and how thoroughly.
#[derive(Clone, Debug)]
pub struct Config {
    /// Small sizes, a couple of choices per knob, one timed run per choice.
    pub quick: bool,
    /// Seed of every random choice (heightfields, sensor noise, synthesis, curves).
    pub seed: u64,
    /// The repository's `samples/` folder (sample molds, face layout, scenes).
    pub samples: PathBuf,
}

impl Config {
    /// Timed runs per choice: one in quick mode, the median of three in the full mode.
    pub fn runs(&self) -> usize {
        if self.quick { 1 } else { 3 }
    }
}

/// A stage's progress told as the count of choices done so far: [`Progress`] is told the steps
/// each count adds.
pub(crate) struct Tally<'a> {
    progress: &'a dyn Progress,
    told: std::cell::Cell<usize>,
}

impl<'a> Tally<'a> {
    /// Starts `stage`'s progress over `total` choices.
    pub(crate) fn start(progress: &'a dyn Progress, stage: Stage, total: usize) -> Self {
        progress.start(stage.name(), total as u64);
        Tally { progress, told: std::cell::Cell::new(0) }
    }

    /// `done` choices of the stage are done.
    pub(crate) fn done(&self, done: usize) {
        self.progress.advance(done.saturating_sub(self.told.replace(done)) as u64);
    }
}

/// Measures one stage. A stage whose inputs are missing fails; a rendering stage without a GPU
/// adapter is returned as skipped, with the reason.
///
/// # Errors
/// When a stage's inputs cannot be read or a library refuses a configuration.
pub fn measure(stage: Stage, config: &Config, progress: &dyn Progress) -> Result<StageReport> {
    let start = Instant::now();
    let mut report = match stage {
        Stage::Capture => capture::measure(config, progress)?,
        Stage::Detrend => detrend::measure(config, progress)?,
        Stage::Height => height::measure(config, progress)?,
        Stage::Synthesis => synthesis::measure(config, progress)?,
        Stage::Stitching => stitching::measure(config, progress)?,
        Stage::Rendering => rendering::measure(config, progress)?,
    };
    progress.finish();
    report.wall_seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Same seed, same numbers (times apart); another seed, other numbers.
    #[test]
    fn a_stage_is_deterministic_under_its_seed() {
        let config = |seed| Config { quick: true, seed, samples: PathBuf::new() };
        let numbers = |seed| -> Vec<Vec<Metric>> {
            let report = measure(Stage::Capture, &config(seed), &skinkit_maps::progress::NoProgress).unwrap();
            report.choices.into_iter().map(|c| c.metrics).collect()
        };
        let first = numbers(5);
        assert_eq!(first, numbers(5));
        assert_ne!(first, numbers(6));
        assert!(first.iter().flatten().all(|m| m.value.is_finite()));
    }
}
