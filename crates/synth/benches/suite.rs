//! The synthesis suite: skinkit's default against the peer (the `texture-synthesis` crate, in the
//! same process) on a fixed set of exemplars, 3 seeds each, and the cost of growing large maps.
//!
//! Quality (256x256 from each 128x128 exemplar of [`exemplars::all`]), per exemplar the mean of
//! seeds 1-3:
//! * energy: [`window_energy`] (5x5 windows, every other output texel) over the exemplar's own
//!   [`self_energy`], so exemplars of any contrast compare; lower is better;
//! * copy: the largest block copied verbatim with one offset ([`metrics::copy_statistics`]) as a
//!   share of the exemplar's area (worst seed);
//! * distribution: slope histogram ([`metrics::slope_distance`]) for normals, channel histogram
//!   ([`metrics::channel_distance`]) for colour; spectrum: radial spectra;
//! * variation: the output's slope (or channel) deviation over the exemplar's, worst seed
//!   ([`metrics::slope_variation_ratio`], [`metrics::variation_ratio`]); under 0.5 is a collapse.
//!
//! Speed: 512x512 from the 128x128 heightfield forehead, both synthesisers, median of 3 runs; then
//! skinkit alone from 512^2 up to 4096x2048 (and 8192^2 with `SYNTH_SUITE_LARGE=1`), seconds per
//! megatexel and the process's peak resident memory after each size.
//!
//! Outputs: the markdown tables on stderr and in `target/synth-suite.md`. With `SYNTH_SUITE_DOCS=1`
//! the tables also replace the block between the suite markers in the book's chapter
//! `docs/book/src/synthesis.md`, and a contact sheet (exemplar | peer | skinkit per exemplar, seed
//! 1, normals shaded) goes to `docs/synth-contact-sheet.png` (the peer then runs again for seed 1, for its output).
//!
//! The three texture photos come from the folder `SYNTH_SUITE_TEXTURES` names (without it they
//! are skipped, and the report has 9 exemplars). Knobs for experiments: `SYNTH_SUITE_CONFIG` (keys as `k=2,j=1,...`, see [`parse_config`]),
//! `SYNTH_SUITE_ONLY` (a substring of exemplar names), `SYNTH_SUITE_SEEDS` (how many),
//! `SYNTH_SUITE_SPEED=0` (skip the speed part), `SYNTH_SUITE_WINDOWS=1` (where each output's
//! energy sits, see [`window_shares`]; the peer's only when it runs, not from the cache),
//! `SYNTH_SUITE_SPECTRA=1` (per-ring spectrum ratios of normal maps), `SYNTH_SUITE_USAGE=1`
//! (whether the sources copied carry the exemplar's fine detail, see [`detail_usage`]). Peer scores are cached in
//! `target/synth-suite-peer.tsv` (keyed by exemplar, seed and size; delete it to rerun the peer).
//! Run with `cargo bench -p skinkit-synth --bench suite` (a plain `main`, `harness = false`).

#[path = "suite/exemplars.rs"]
mod exemplars;
#[path = "suite/peer.rs"]
mod peer;
#[path = "suite/report.rs"]
mod report;

use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_synth::energy::{self_energy, window_energy};
use skinkit_synth::metrics::{self, DEFAULT_SPECTRUM_BINS as BINS};
use skinkit_synth::{Search, Start, SynthConfig, synthesize, synthesize_normals};

use exemplars::{Exemplar, Texels};

/// Output side of the quality part.
const OUT: usize = 256;
/// Energy window side and sampling stride.
const WINDOW: usize = 5;
const STRIDE: usize = 2;

fn env(key: &str) -> Option<String> {
    std::env::var(key).ok().filter(|v| !v.is_empty())
}

/// `target/` of the workspace (or `CARGO_TARGET_DIR`).
fn target_dir() -> PathBuf {
    env("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"))
}

/// The configuration under test: the defaults, changed by `key=value` pairs (k: k-coherence k;
/// n: neighbourhood side; m: coarser window side; c / cc: finest and coarser correction passes;
/// l / fl / cp: occurrence penalty, at the finest level, in the corrections; lp: layout penalty;
/// L: levels; up: upsampled start (1) or scanline (0); j: jitter; w: exemplar wrap; cap: copy cap,
/// share of the exemplar's area; fb / ffb: k-coherence tree fallback ratio, at the finest level,
/// 0 = none; rr: its rerank count; po: seam-polishing passes; kb / fkb: coherence bias, at the
/// finest level; dw: detail weight of normal maps, 0 = none; rs: robust scale).
fn parse_config(spec: &str, width: usize, height: usize, seed: u64) -> SynthConfig {
    let mut config = SynthConfig { seed, ..SynthConfig::new(width, height) };
    for kv in spec.split(',').filter(|s| !s.is_empty()) {
        let (k, v) = kv.split_once('=').expect("key=value");
        let f: f64 = v.parse().expect("number");
        match k {
            "k" => {
                if let Search::KCoherence { k, .. } = &mut config.search {
                    *k = f as usize;
                }
            }
            "n" => config.neighbourhood = f as usize,
            "c" => config.corrections = f as usize,
            "cc" => config.coarse_corrections = Some(f as usize),
            "l" => config.occurrence_penalty = f as f32,
            "fl" => config.finest_penalty = Some(f as f32),
            "cp" => config.correction_penalty = Some(f as f32),
            "L" => config.levels = f as usize,
            "up" => config.start = if f > 0.0 { Start::Upsampled } else { Start::Scanline },
            "j" => config.jitter = f as usize,
            "w" => config.exemplar_wrap = f > 0.0,
            "m" => config.parent = f as usize,
            "po" => config.polish = f as usize,
            "fb" => {
                if let Search::KCoherence { fallback, .. } = &mut config.search {
                    *fallback = (f > 0.0).then_some(f as f32);
                }
            }
            "rr" => {
                if let Search::KCoherence { rerank, .. } = &mut config.search {
                    *rerank = f as usize;
                }
            }
            "ffb" => config.finest_fallback = (f > 0.0).then_some(f as f32),
            "kb" => config.coherence_bias = f as f32,
            "fkb" => config.finest_coherence_bias = Some(f as f32),
            "dw" => config.detail_weight = f as f32,
            "rs" => config.robust_scale = f as f32,
            "lp" => config.layout_penalty = f as f32,
            "cap" => config.copy_cap = (f > 0.0).then_some(f as f32),
            other => panic!("unknown key {other}"),
        }
    }
    config
}

/// Scores of one output.
#[derive(Clone, Copy, Debug, Default)]
pub struct Scores {
    pub energy: f64,
    pub copy: f64,
    pub distribution: f64,
    pub spectrum: f64,
    pub variation: f64,
}

fn score(output: &Texels, coords: &Grid<[u32; 2]>, ex: &Exemplar, own: f64) -> Scores {
    let (ew, eh) = ex.texels.grid().size();
    let energy = window_energy(output.grid(), ex.texels.grid(), WINDOW, STRIDE) / own.max(1e-12);
    if env("SYNTH_SUITE_WINDOWS").is_some() {
        window_shares(output, ex, own);
    }
    if let (Some(_), Texels::Normal(o), Texels::Normal(e)) = (env("SYNTH_SUITE_SPECTRA"), output, &ex.texels) {
        let (so, se) = (metrics::normal_spectrum(o, BINS), metrics::normal_spectrum(e, BINS));
        let ratio: Vec<String> = so.iter().zip(&se).map(|(a, b)| format!("{:+.2}", (a / b).log10())).collect();
        eprintln!("    spectrum log10(out / exemplar) per ring: {}", ratio.join(" "));
    }
    if env("SYNTH_SUITE_USAGE").is_some() {
        detail_usage(output.grid(), coords, ex.texels.grid());
    }
    let copy = metrics::copy_statistics(coords, (ew, eh), false).largest_block as f64 / (ew * eh) as f64;
    let (distribution, spectrum, variation) = match (output, &ex.texels) {
        (Texels::Normal(o), Texels::Normal(e)) => (
            metrics::slope_distance(o, e),
            metrics::normal_spectrum_distance(o, e, BINS),
            metrics::slope_variation_ratio(o, e),
        ),
        (Texels::Color(o), Texels::Color(e)) => (
            metrics::channel_distance(o, e),
            metrics::color_spectrum_distance(o, e, BINS),
            metrics::variation_ratio(o, e),
        ),
        _ => unreachable!("outputs are of their exemplar's kind"),
    };
    Scores { energy, copy, distribution, spectrum, variation }
}

/// Squared difference of texel `(x, y)` from the mean of its 4 neighbours (a high-pass).
fn detail(g: &Grid<Vec3>, x: isize, y: isize, wrap: bool) -> f64 {
    let at = |x, y| if wrap { *g.get_wrapped(x, y) } else { *g.get_clamped(x, y) };
    let around = at(x - 1, y) + at(x + 1, y) + at(x, y - 1) + at(x, y + 1);
    (at(x, y) - 0.25 * around).length_squared() as f64
}

/// Whether the output draws on the exemplar's detailed texels in their share
/// (`SYNTH_SUITE_USAGE=1`): the mean [`detail`] of the exemplar (inside a 2-texel margin), of the
/// sources the output copies, and of the output itself. Nearest-neighbour search favours smooth
/// windows, so an output that loses fine detail shows it here first.
fn detail_usage(output: &Grid<Vec3>, coords: &Grid<[u32; 2]>, exemplar: &Grid<Vec3>) {
    let (ew, eh) = exemplar.size();
    let mean = |v: Vec<f64>| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let inner = (2..eh.saturating_sub(2)).flat_map(|y| (2..ew.saturating_sub(2)).map(move |x| (x, y)));
    let all = mean(inner.map(|(x, y)| detail(exemplar, x as isize, y as isize, false)).collect());
    let used = mean(coords.as_slice().iter().map(|&[x, y]| detail(exemplar, x as isize, y as isize, false)).collect());
    let (w, h) = output.size();
    let cells = (0..h).flat_map(|y| (0..w).map(move |x| (x, y)));
    let out = mean(cells.map(|(x, y)| detail(output, x as isize, y as isize, true)).collect());
    eprintln!(
        "    detail: exemplar {all:.3e}, at the sources used {used:.3e} ({:.2}), output {out:.3e} ({:.2})",
        used / all,
        out / all
    );
}

/// Where the energy sits (`SYNTH_SUITE_WINDOWS=1`): the share of output windows found verbatim in
/// the exemplar (under 1e-3 of its own figure: copy interiors; the peer's 8-bit output never
/// scores exactly 0), the mean of the others, and quantiles, all over the exemplar's own figure.
fn window_shares(output: &Texels, ex: &Exemplar, own: f64) {
    let mut m: Vec<f64> = skinkit_synth::energy::window_minima(output.grid(), ex.texels.grid(), WINDOW, STRIDE)
        .iter()
        .map(|&v| v as f64 / own.max(1e-12))
        .collect();
    m.sort_by(f64::total_cmp);
    let n = m.len().max(1) as f64;
    let inside = m.iter().filter(|&&v| v < 1e-3).count();
    let rest = &m[inside..];
    let rest_mean = rest.iter().sum::<f64>() / rest.len().max(1) as f64;
    let q = |f: f64| m.get(((n - 1.0) * f) as usize).copied().unwrap_or(0.0);
    eprintln!(
        "    windows: verbatim {:.3}, mean of the rest {rest_mean:.3}, quantiles 0.5 {:.3} 0.75 {:.3} 0.9 {:.3} 0.99 {:.3}",
        inside as f64 / n,
        q(0.5),
        q(0.75),
        q(0.9),
        q(0.99)
    );
}

/// One skinkit synthesis of `ex` under `config`.
fn run_skinkit(ex: &Exemplar, config: &SynthConfig) -> (Texels, Grid<[u32; 2]>) {
    match &ex.texels {
        Texels::Normal(n) => {
            let s = synthesize_normals(n, config, &skinkit_maps::progress::NoProgress).expect("valid configuration");
            (Texels::Normal(s.normals), s.coords)
        }
        Texels::Color(c) => {
            let s = synthesize(c, config, &skinkit_maps::progress::NoProgress).expect("valid configuration");
            (Texels::Color(s.texels), s.coords)
        }
    }
}

/// Quality of both synthesisers on one exemplar: per seed `(peer, skinkit)` scores, and the seed-1
/// outputs for the contact sheet.
fn quality(
    ex: &Exemplar,
    seeds: u64,
    spec: &str,
    cache: &mut report::PeerCache,
    sheet: bool,
) -> report::ExemplarResult {
    let own = self_energy(ex.texels.grid(), WINDOW, STRIDE);
    let mut result = report::ExemplarResult { name: ex.name.clone(), ..Default::default() };
    for seed in 1..=seeds {
        let key = format!("{}\t{seed}\t{OUT}", ex.name);
        // For the contact sheet, seed 1 runs the peer again (its output goes on the sheet).
        let peer_scores = match cache.get(&key).filter(|_| seed > 1 || !sheet) {
            Some(s) => s,
            None => {
                let p = peer::run(&ex.texels, OUT, OUT, seed);
                let s = score(&p.texels, &p.coords, ex, own);
                cache.put(&key, s);
                if seed == 1 {
                    result.peer_output = Some(p.texels);
                }
                s
            }
        };
        let config = parse_config(spec, OUT, OUT, seed);
        let start = Instant::now();
        let (texels, coords) = run_skinkit(ex, &config);
        let seconds = start.elapsed().as_secs_f64();
        let ours = score(&texels, &coords, ex, own);
        eprintln!(
            "  {} seed {seed}: peer {peer_scores:.3?}\n  {:>w$}  ours {ours:.3?} {seconds:.2} s",
            ex.name,
            "",
            w = ex.name.len() + 7
        );
        if seed == 1 {
            result.output = Some(texels);
        }
        result.peer.push(peer_scores);
        result.ours.push(ours);
    }
    result
}

fn main() {
    if std::env::args().any(|a| a == "--test" || a == "--list") {
        return; // `cargo test --benches` runs benches in test mode: nothing to check here.
    }
    let spec = env("SYNTH_SUITE_CONFIG").unwrap_or_default();
    let seeds: u64 = env("SYNTH_SUITE_SEEDS").map_or(3, |s| s.parse().expect("a seed count"));
    let only = env("SYNTH_SUITE_ONLY");
    let docs = env("SYNTH_SUITE_DOCS").is_some_and(|v| v == "1");
    let load_start = report::load_average();
    let mut cache = report::PeerCache::load(target_dir().join("synth-suite-peer.tsv"));
    let mut results = Vec::new();
    for ex in exemplars::all().iter().filter(|e| only.as_ref().is_none_or(|o| e.name.contains(o.as_str()))) {
        eprintln!("{}...", ex.name);
        let mut r = quality(ex, seeds, &spec, &mut cache, docs);
        r.exemplar = Some(ex.texels.clone());
        results.push(r);
    }
    cache.save();
    let speed = if env("SYNTH_SUITE_SPEED").is_some_and(|v| v == "0") { None } else { Some(report::speed(&spec)) };
    let load = format!("{load_start} / {}", report::load_average());
    let markdown = report::markdown(&results, speed.as_ref(), &spec, seeds, &load);
    eprintln!("\n{markdown}");
    let out = target_dir().join("synth-suite.md");
    std::fs::write(&out, &markdown).expect("writes the suite report");
    eprintln!("written to {}", out.display());
    if docs {
        report::splice_doc(&markdown);
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/synth-contact-sheet.png");
        report::contact_sheet(&results).save(&path).expect("writes the contact sheet");
        eprintln!("contact sheet: {}", path.display());
    }
}
