//! Synthesis: the default ([`SynthConfig::new`]) and each knob moved on its own (pyramid levels,
//! neighbourhood side, k-coherence candidates, correction passes, jitter), growing a map from a
//! square crop of the sample forehead mold's true normals (`samples/molds/forehead/truth.png`).
//!
//! Error: the neighbourhood-matching energy of the output ([`window_energy`], 5x5 windows, every
//! other texel per axis; as the book's synthesis table), beside the largest verbatim copy as a
//! share of the exemplar, the slope-histogram distance and the kept variation. Cost: the growth's
//! wall-clock time (the measures are not timed).

use glam::Vec3;
use skinkit_maps::io::{Limits, read_normal_map};
use skinkit_maps::{Grid, NormalEncoding, NormalMap};
use skinkit_synth::energy::window_energy;
use skinkit_synth::{Search, SynthConfig, metrics, synthesize};

use crate::choice::{Choice, Stage, StageReport, knobs, metrics as metric_list};
use crate::timing::median_of;
use crate::{Config, Result};

/// Window side and sampling stride of the energy.
const ENERGY_WINDOW: usize = 5;
const ENERGY_STRIDE: usize = 2;

/// One knob's name and the configurations it is tried at.
type Knob = (&'static str, Vec<(String, SynthConfig)>);

/// Exemplar side, output side and the knobs of a mode.
fn plan(config: &Config) -> (usize, usize, Vec<Knob>) {
    let (ex, side) = if config.quick { (64, 128) } else { (128, 256) };
    let base = SynthConfig { seed: config.seed, ..SynthConfig::new(side, side) };
    let pick = |quick: &[usize], full: &[usize]| if config.quick { quick.to_vec() } else { full.to_vec() };
    let with = |values: Vec<usize>, name: &str, f: &dyn Fn(usize) -> SynthConfig| {
        values.into_iter().map(|v| (format!("{name}={v}"), f(v))).collect::<Vec<_>>()
    };
    let k_search = |k: usize| match base.search {
        Search::KCoherence { fallback, dims, rerank, .. } => Search::KCoherence { k, fallback, dims, rerank },
        other => other,
    };
    let knobs: Vec<Knob> = vec![
        ("default", vec![("default".into(), base.clone())]),
        ("levels", with(pick(&[3], &[2, 3, 4]), "L", &|v| SynthConfig { levels: v, ..base.clone() })),
        ("neighbourhood", with(pick(&[3], &[3, 7]), "N", &|v| SynthConfig { neighbourhood: v, ..base.clone() })),
        ("candidates", with(pick(&[4], &[1, 4, 8]), "k", &|v| SynthConfig { search: k_search(v), ..base.clone() })),
        ("correction passes", with(pick(&[1], &[1, 3]), "passes", &|v| SynthConfig { corrections: v, ..base.clone() })),
        ("jitter", with(pick(&[1], &[1, 2, 4]), "jitter", &|v| SynthConfig { jitter: v, ..base.clone() })),
    ];
    (ex, side, knobs)
}

/// The top-left `side x side` crop of the forehead mold's true normals.
fn exemplar(config: &Config, side: usize) -> Result<Grid<Vec3>> {
    let path = config.samples.join("molds/forehead/truth.png");
    let map = read_normal_map(&path, NormalEncoding::default(), &Limits::default())?;
    let side = side.min(map.width()).min(map.height());
    Ok(Grid::from_fn(side, side, |x, y| map.get(x, y)))
}

/// Measures the default and every knob.
///
/// # Errors
/// When the sample mold cannot be read or a configuration is refused.
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let (ex_side, side, knobs_tried) = plan(config);
    let ex = exemplar(config, ex_side)?;
    let ex_normals = NormalMap::from_grid(ex.clone());
    let setup = format!(
        "{side}x{side} grown from the {0}x{0} top-left crop of `samples/molds/forehead/truth.png`, seed {1}; \
         energy: mean squared distance of every other texel's {ENERGY_WINDOW}x{ENERGY_WINDOW} window to \
         the nearest exemplar window; largest copy: the biggest verbatim block, % of the exemplar; \
         the default is 5 levels, N = 5, k = 2, 1 + 2 correction passes, no jitter",
        ex.width(),
        config.seed
    );
    let mut report = StageReport::new(Stage::Synthesis, setup, "energy", "seconds");
    let total: usize = knobs_tried.iter().map(|(_, v)| v.len()).sum();
    let tally = crate::Tally::start(progress, Stage::Synthesis, total);
    for (knob, tries) in &knobs_tried {
        for (label, synth) in tries {
            report.choices.push(grow(&ex, &ex_normals, knob, label, synth, config.runs())?);
            tally.done(report.choices.len());
        }
    }
    Ok(report)
}

/// One growth and its scores.
fn grow(
    ex: &Grid<Vec3>,
    ex_normals: &NormalMap,
    knob: &str,
    label: &str,
    synth: &SynthConfig,
    runs: usize,
) -> Result<Choice> {
    let (grown, seconds) = median_of(runs, || synthesize(ex, synth, &skinkit_maps::progress::NoProgress));
    let grown = grown?;
    let energy = window_energy(&grown.texels, ex, ENERGY_WINDOW, ENERGY_STRIDE);
    let copies = metrics::copy_statistics(&grown.coords, ex.size(), synth.exemplar_wrap);
    let copy_share = 100.0 * copies.largest_block as f64 / ex.len().max(1) as f64;
    let out = NormalMap::from_grid(grown.texels);
    let k = match synth.search {
        Search::KCoherence { k, .. } => k.to_string(),
        _ => "-".into(),
    };
    Ok(Choice::timed(
        knob,
        label,
        knobs(&[
            ("levels", synth.levels.to_string()),
            ("N", synth.neighbourhood.to_string()),
            ("k", k),
            ("passes", synth.corrections.to_string()),
            ("jitter", synth.jitter.to_string()),
        ]),
        metric_list(&[
            ("energy", energy),
            ("largest copy (% of exemplar)", copy_share),
            ("slope distance", metrics::slope_distance(&out, ex_normals)),
            ("variation", grown.guards.variation),
        ]),
        seconds,
        runs,
    ))
}
