//! The accuracy-against-time table of issue 3 (for the book's "Growing a map" chapter): a 256x256
//! normal map grown from the 128x128 forehead heightfield's normals, for every search mode x causal
//! neighbourhood side N x pyramid levels, each cell giving seconds and neighbourhood-matching energy
//! (also relative to exact search with the same N and levels) and the slope-histogram distance.
//!
//! Modes: exact (exhaustive, the reference); PCA to D in {4, 8, 16, 32} dimensions + kd-tree,
//! re-ranking the best 8 in full space (with Ashikhmin coherence candidates, the config's default);
//! k-coherence k = 4 (the scanline start's search); and, to show what the correction pass adds,
//! k-coherence and PCA-8 with one correction pass; last, the default ([`SynthConfig::new`]:
//! coordinate upsampling, k = 2, three passes at the coarser levels and one at the finest, seam
//! polishing, copy cap, no occurrence penalty). The other rows take [`SynthConfig::scanline`]'s other options (3x3
//! parent window, the occurrence penalty, seed 1).
//!
//! * Energy: [`window_energy`] with 5x5 windows for every N (so cells compare), finest level, every
//!   other texel per axis; lower is better. Slope distance: [`metrics::slope_distance`] against the
//!   exemplar.
//! * Seconds: the median of 3 runs, or one run when it takes over [`SLOW_SECONDS`] (exact search:
//!   10-60 s a run, PCA-32 up to exact's time, since a kd-tree in 32 dimensions scans nearly all).
//! * A configuration that panics is reported as such in its cell, and the other cells still run.
//!
//! By default only N = 5 with 3 and 5 levels runs (a few minutes); `SYNTH_TABLE_FULL=1` runs N in
//! {3, 5, 7} x levels in {1, 2, 3}, plus N = 5 with 5 levels (20-30 minutes on 2 shared cores,
//! mostly exact and PCA-32). The
//! table goes to stderr and, as markdown, to `target/synth-table.md`. A report generator with a
//! plain `main` (`harness = false`): `cargo bench -p skinkit-synth --bench table`.

use std::any::Any;
use std::panic::AssertUnwindSafe;
use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use skinkit_heightfield::SkinParams;
use skinkit_maps::{Grid, NormalMap};
use skinkit_synth::energy::window_energy;
use skinkit_synth::metrics;
use skinkit_synth::{Search, SynthConfig, synthesize};

const SEED: u64 = 1;
const EXEMPLAR_SIDE: usize = 128;
const OUTPUT_SIDE: usize = 256;
const ENERGY_WINDOW: usize = 5;
const ENERGY_STRIDE: usize = 2;
/// Timed runs per cell (median)...
const RUNS: usize = 3;
/// ...unless a run takes longer than this many seconds.
const SLOW_SECONDS: f64 = 5.0;

/// One row of the table: a search mode and its correction passes.
#[derive(Clone, Copy)]
struct Mode {
    name: &'static str,
    /// The search (the default's own for the upsampled row).
    search: Search,
    corrections: usize,
    /// [`SynthConfig::new`] (the upsampled default, its search included) instead of
    /// [`SynthConfig::scanline`].
    upsampled: bool,
}

const fn mode(name: &'static str, search: Search, corrections: usize) -> Mode {
    Mode { name, search, corrections, upsampled: false }
}

const fn pca(dims: usize) -> Search {
    Search::Approximate { dims, rerank: 8 }
}

/// Every mode, exact first (the others' energies are divided by its energy).
const MODES: [Mode; 9] = [
    mode("exact", Search::Exact, 0),
    mode("PCA-4, rerank 8", pca(4), 0),
    mode("PCA-8, rerank 8", pca(8), 0),
    mode("PCA-16, rerank 8", pca(16), 0),
    mode("PCA-32, rerank 8", pca(32), 0),
    mode("k-coherence k=4", Search::K_COHERENCE, 0),
    mode("PCA-8, rerank 8", pca(8), 1),
    mode("k-coherence k=4", Search::K_COHERENCE, 1),
    Mode {
        name: "default (upsampled, k-coherence k=2, tree fallback)",
        search: Search::Exact, // replaced by the default's search
        corrections: skinkit_synth::config::DEFAULT_CORRECTIONS,
        upsampled: true,
    },
];

/// What one cell measured.
struct Scores {
    seconds: f64,
    energy: f64,
    slope: f64,
    warnings: Vec<String>,
}

/// One cell of the grid: its scores, or the message of the panic that stopped its synthesis (a
/// report generator should show a broken configuration rather than lose the other cells).
struct Cell {
    n: usize,
    levels: usize,
    mode: Mode,
    runs: usize,
    scores: Result<Scores, String>,
}

fn exemplar() -> Grid<Vec3> {
    let field = SkinParams::forehead(EXEMPLAR_SIDE, EXEMPLAR_SIDE, SEED).generate().expect("forehead preset generates");
    field.normals.grid().clone()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 { v[m] } else { 0.5 * (v[m - 1] + v[m]) }
}

/// Runs one cell: up to [`RUNS`] timed syntheses (all give the same bits: the synthesis is
/// deterministic), then the scores of the last output. A panic is caught and reported in the cell.
fn measure(ex: &Grid<Vec3>, ex_normals: &NormalMap, n: usize, levels: usize, mode: Mode) -> Cell {
    let base = if mode.upsampled {
        SynthConfig::new(OUTPUT_SIDE, OUTPUT_SIDE)
    } else {
        SynthConfig::scanline(OUTPUT_SIDE, OUTPUT_SIDE)
    };
    let config = SynthConfig {
        levels,
        search: if mode.upsampled { base.search } else { mode.search },
        neighbourhood: n,
        corrections: mode.corrections,
        seed: SEED,
        ..base
    };
    let run = || {
        let mut seconds = Vec::with_capacity(RUNS);
        let mut last = None;
        // One run is enough for the slow cells (exact search, PCA-32): they are not noise-bound.
        while seconds.len() < RUNS && seconds.iter().all(|&t| t < SLOW_SECONDS) {
            let start = Instant::now();
            last = Some(synthesize(ex, &config, &skinkit_maps::progress::NoProgress).expect("valid configuration"));
            seconds.push(start.elapsed().as_secs_f64());
        }
        (last.expect("at least one run"), seconds)
    };
    let result = std::panic::catch_unwind(AssertUnwindSafe(run)).map_err(panic_message);
    let runs = result.as_ref().map_or(1, |(_, seconds)| seconds.len());
    let scores = result.map(|(s, seconds)| {
        let energy = window_energy(&s.texels, ex, ENERGY_WINDOW, ENERGY_STRIDE);
        let out = NormalMap::from_unit_grid(s.texels).expect("outputs copy unit exemplar normals");
        let slope = metrics::slope_distance(&out, ex_normals);
        Scores { seconds: median(seconds), energy, slope, warnings: s.warnings }
    });
    Cell { n, levels, mode, runs, scores }
}

fn panic_message(payload: Box<dyn Any + Send>) -> String {
    let text =
        payload.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| payload.downcast_ref::<String>().cloned());
    format!("panicked: {}", text.unwrap_or_else(|| "(no message)".to_owned()))
}

/// The (N, levels) pairs to run.
fn grid() -> Vec<(usize, usize)> {
    if std::env::var("SYNTH_TABLE_FULL").is_ok_and(|v| v == "1") {
        let mut cells: Vec<_> = [3, 5, 7].into_iter().flat_map(|n| [1, 2, 3].map(|l| (n, l))).collect();
        cells.push((5, 5));
        cells
    } else {
        vec![(5, 3), (5, 5)]
    }
}

/// The 1-minute load average (`/proc/loadavg`), when the system has one: the machine is shared, so
/// the table says how busy it was.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "unknown".to_owned())
}

fn markdown(cells: &[Cell], load: &str) -> String {
    let mut s = String::from(
        "| N | levels | mode | corrections | seconds | runs | energy | energy / exact | slope distance |\n\
         | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
    );
    for c in cells {
        let exact = cells
            .iter()
            .find(|e| e.n == c.n && e.levels == c.levels && !e.mode.upsampled && e.mode.search == Search::Exact)
            .and_then(|e| e.scores.as_ref().ok());
        let head = format!("| {} | {} | {} | {} |", c.n, c.levels, c.mode.name, c.mode.corrections);
        s += &match &c.scores {
            Ok(q) => format!(
                "{head} {:.3} | {} | {:.5} | {} | {:.4} |\n",
                q.seconds,
                c.runs,
                q.energy,
                exact.map_or("-".to_owned(), |e| format!("{:.3}", q.energy / e.energy)),
                q.slope
            ),
            Err(message) => format!("{head} {message} | {} | - | - | - |\n", c.runs),
        };
    }
    let threads = rayon::current_num_threads();
    s += &format!(
        "\n{OUTPUT_SIDE}x{OUTPUT_SIDE} from the {EXEMPLAR_SIDE}x{EXEMPLAR_SIDE} forehead heightfield \
         normals, seed {SEED}, {threads} rayon threads. Energy: `window_energy`, \
         {ENERGY_WINDOW}x{ENERGY_WINDOW} windows for every N, every {ENERGY_STRIDE}nd texel per axis; \
         energy / exact: against exact search with the same N and levels (greedy exact search is not the \
         energy optimum, so other modes can score below 1). Seconds: median of `runs` runs (one when a run \
         took over {SLOW_SECONDS} s); 1-minute load average {load} (start / end; the machine is shared).\n"
    );
    s
}

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target"))
}

fn main() {
    // `cargo test --benches` runs bench targets without `--bench`: generate nothing then.
    if !std::env::args().any(|a| a == "--bench") {
        return;
    }
    let ex = exemplar();
    let ex_normals = NormalMap::from_unit_grid(ex.clone()).expect("heightfield normals are unit");
    let load_start = load_average();
    let mut cells = Vec::new();
    for (n, levels) in grid() {
        for mode in MODES {
            let cell = measure(&ex, &ex_normals, n, levels, mode);
            let what = format!("N={n} levels={levels} {:>16} corrections={}", mode.name, mode.corrections);
            match &cell.scores {
                Ok(q) => {
                    eprintln!("{what}: {:7.3} s, energy {:.5}, slope {:.4}", q.seconds, q.energy, q.slope);
                    for w in &q.warnings {
                        eprintln!("  warning: {w}");
                    }
                }
                Err(message) => eprintln!("{what}: {message}"),
            }
            cells.push(cell);
        }
        // Written after every (N, levels) group, so a long full run that is stopped keeps its rows.
        write_table(&markdown(&cells, &format!("{load_start} / {}", load_average())), false);
    }
    write_table(&markdown(&cells, &format!("{load_start} / {}", load_average())), true);
}

/// Writes `target/synth-table.md`; with `last`, also prints the table and where it went.
fn write_table(table: &str, last: bool) {
    let dir = target_dir();
    let path = dir.join("synth-table.md");
    let written = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&path, table));
    match written {
        Ok(()) if last => eprintln!("\n{table}\nwritten to {}", path.display()),
        Ok(()) => {}
        Err(e) => eprintln!("could not write {}: {e}", path.display()),
    }
}
