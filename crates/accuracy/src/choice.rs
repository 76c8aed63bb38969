//! The one row type of every stage ([`Choice`]: what was chosen, what it scored, what it cost)
//! and the reports that gather them ([`StageReport`], [`Report`]), serialisable as
//! `accuracy.json`.

use serde::{Deserialize, Serialize};

/// A stage of the pipeline whose choices are measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stage {
    /// Photometric stereo: lights, noise and solver.
    Capture,
    /// Removal of a mold's low-frequency tilt: block size.
    Detrend,
    /// Normal integration to height: each integrator on maps that wrap, do not, or have holes.
    Height,
    /// Texture synthesis: the default and each knob.
    Synthesis,
    /// The face map's boundaries: spline levels, curves, blending.
    Stitching,
    /// Skin scattering methods and their quality knobs.
    Rendering,
}

impl Stage {
    /// Every stage, in pipeline order.
    pub const ALL: [Stage; 6] =
        [Stage::Capture, Stage::Detrend, Stage::Height, Stage::Synthesis, Stage::Stitching, Stage::Rendering];

    /// The stage's name in files and tables (`capture`, `detrend`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Stage::Capture => "capture",
            Stage::Detrend => "detrend",
            Stage::Height => "height",
            Stage::Synthesis => "synthesis",
            Stage::Stitching => "stitching",
            Stage::Rendering => "rendering",
        }
    }
}

impl Stage {
    /// Why the stage's default stays when a choice beside it scores a lower error, one line: the
    /// error measures less than the default is chosen for. `None` where no such line is written.
    pub fn why_default_kept(self) -> Option<&'static str> {
        match self {
            Stage::Synthesis => Some(
                "the energy counts 5x5 windows only: fewer levels lose the exemplar's larger features \
                 (lower variation, higher slope distance) and more candidates cost time, for a few per cent",
            ),
            Stage::Stitching => Some(
                "a random curve is longer than a straight cut and crosses more features, so its mean jump \
                 is higher, but a straight seam is a line the eye follows; fewer spline levels suit this \
                 quick run's 512x256 map, where the exemplars are 64 texels wide",
            ),
            _ => None,
        }
    }
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// One measured number of a choice (an error, a size, a ratio).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metric {
    /// Name with its unit, e.g. `mean angular error (deg)`.
    pub name: String,
    /// The value; always finite (measures give 0 rather than NaN on degenerate inputs).
    pub value: f64,
}

/// One choice of a stage and what it scored and cost.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Choice {
    /// The curve of the plot this choice belongs to (e.g. `robust, noise 0.01`).
    pub series: String,
    /// The point's label (e.g. `8 lights`).
    pub label: String,
    /// The knobs set, `name = value`, for the table.
    pub knobs: Vec<(String, String)>,
    /// What was measured, the stage's error metric first.
    pub metrics: Vec<Metric>,
    /// Wall-clock seconds (the median of `runs` runs); for rendering, the frame's GPU time.
    pub seconds: f64,
    /// The plotted cost: `seconds`, or for rendering the frame time over the base pass's.
    pub cost: f64,
    /// Timed runs behind `seconds`.
    pub runs: usize,
}

impl Choice {
    /// A choice whose plotted cost is its seconds.
    pub fn timed(
        series: &str,
        label: &str,
        knobs: Vec<(String, String)>,
        metrics: Vec<Metric>,
        seconds: f64,
        runs: usize,
    ) -> Self {
        let seconds = crate::timing::positive(seconds);
        Choice { series: series.into(), label: label.into(), knobs, metrics, seconds, cost: seconds, runs }
    }

    /// The value of the metric called `name`, if measured.
    pub fn metric(&self, name: &str) -> Option<f64> {
        self.metrics.iter().find(|m| m.name == name).map(|m| m.value)
    }

    /// True for a stage's default: its series or label says `default`.
    pub fn is_default(&self) -> bool {
        self.series.contains("default") || self.label.contains("default")
    }

    /// The stage's error metric: the first one.
    pub fn error(&self) -> f64 {
        self.metrics.first().map_or(0.0, |m| m.value)
    }
}

/// `name = value` knob pairs from string slices.
pub fn knobs(pairs: &[(&str, String)]) -> Vec<(String, String)> {
    pairs.iter().map(|(k, v)| ((*k).to_owned(), v.clone())).collect()
}

/// Metrics from `(name, value)` pairs; a non-finite value becomes 0 (a measure's degenerate case).
pub fn metrics(pairs: &[(&str, f64)]) -> Vec<Metric> {
    pairs.iter().map(|(n, v)| Metric { name: (*n).to_owned(), value: if v.is_finite() { *v } else { 0.0 } }).collect()
}

/// Every choice of one stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageReport {
    /// Which stage.
    pub stage: Stage,
    /// What was measured on what, one sentence (the markdown's caption).
    pub setup: String,
    /// The plotted error metric's name (the first metric of every choice).
    pub error_metric: String,
    /// The plotted cost's name, e.g. `seconds` or `frame time / base pass`.
    pub cost_axis: String,
    /// The measured choices.
    pub choices: Vec<Choice>,
    /// Why the stage was not measured, when it was not (no GPU adapter).
    pub skipped: Option<String>,
    /// Seconds the whole stage took, set by [`crate::measure`].
    pub wall_seconds: f64,
}

impl StageReport {
    /// An empty stage report, choices to be pushed.
    pub fn new(stage: Stage, setup: String, error_metric: &str, cost_axis: &str) -> Self {
        StageReport {
            stage,
            setup,
            error_metric: error_metric.into(),
            cost_axis: cost_axis.into(),
            choices: Vec::new(),
            skipped: None,
            wall_seconds: 0.0,
        }
    }
}

impl StageReport {
    /// Each default that another choice beats by more than 1 % of its error, with the best such
    /// choice: `(winner, default)`. A default in a series of its own (`default: ...`) is compared
    /// with every choice; one inside a series (`holes: masked-pcg (default)`) with that series.
    pub fn defaults_beaten(&self) -> Vec<(&Choice, &Choice)> {
        self.choices
            .iter()
            .filter(|d| d.is_default())
            .filter_map(|d| {
                let rivals = self.choices.iter().filter(|c| !c.is_default());
                let best = rivals
                    .filter(|c| d.series == "default" || c.series == d.series)
                    .min_by(|a, b| a.error().total_cmp(&b.error()))?;
                (best.error() < 0.99 * d.error()).then_some((best, d))
            })
            .collect()
    }
}

/// A whole run: what `accuracy.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Report {
    /// Quick mode (small sizes, one run per choice) or the full one.
    pub quick: bool,
    /// The run's seed.
    pub seed: u64,
    /// Worker threads the measurements ran on.
    pub threads: usize,
    /// Timed runs per choice (median).
    pub runs: usize,
    /// One report per stage, in pipeline order.
    pub stages: Vec<StageReport>,
    /// Seconds of the whole run.
    pub wall_seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn choice(series: &str, label: &str, error: f64) -> Choice {
        Choice::timed(series, label, Vec::new(), metrics(&[("err", error)]), 0.1, 1)
    }

    #[test]
    fn a_default_beaten_by_more_than_a_percent_is_named_with_its_winner() {
        let mut stage = StageReport::new(Stage::Synthesis, String::new(), "err", "seconds");
        stage.choices =
            vec![choice("default", "default", 1.0), choice("levels", "L=3", 0.995), choice("k", "k=4", 0.9)];
        let beaten = stage.defaults_beaten();
        assert_eq!(beaten.len(), 1);
        assert_eq!((beaten[0].0.label.as_str(), beaten[0].1.label.as_str()), ("k=4", "default"));
        stage.choices.pop();
        assert!(stage.defaults_beaten().is_empty(), "within 1 % is a tie");
        // A default within a series meets only its series.
        stage.choices = vec![
            choice("wraps", "fft (default)", 1.0),
            choice("wraps", "dct", 0.5),
            choice("holes", "pcg (default)", 2.0),
            choice("holes", "dct", 30.0),
        ];
        let beaten = stage.defaults_beaten();
        assert_eq!(beaten.len(), 1);
        assert_eq!(beaten[0].1.label, "fft (default)");
    }
}
