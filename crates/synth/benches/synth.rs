//! Synthesis time by search mode: 256x256 and 512x512 normal maps grown from a 128x128 forehead
//! heightfield's normals (3 levels, 5x5 causal + 3x3 coarser neighbourhoods).
//!
//! Modes: exact, PCA-8 rerank-8 with coherence, and k-coherence (k = 4 or 8, with and without
//! the kd-tree fallback, 5x5 or 7x7 causal window).
//!
//! Before timing, every mode runs once and its neighbourhood-matching energy
//! ([`skinkit_synth::energy::window_energy`], 5x5 windows, finest level, every other texel) is
//! printed next to exact search's at 256x256. Exact search is timed only with
//! `SYNTH_BENCH_EXACT=1` (about 20 s a run); it always runs once for the reference energy.
//! `SYNTH_BENCH_LARGE=1` also times one 4096x2048 run with [`Search::K_COHERENCE`].

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_heightfield::SkinParams;
use skinkit_maps::Grid;
use skinkit_synth::energy::window_energy;
use skinkit_synth::{Search, SynthConfig, synthesize};

/// Name, search mode and current-level neighbourhood side of each benched configuration.
const MODES: [(&str, Search, usize); 6] = [
    ("exact", Search::Exact, 5),
    ("pca8_rerank8", Search::Approximate { dims: 8, rerank: 8 }, 5),
    ("kcoherence4", Search::KCoherence { k: 4, fallback: None, dims: 8, rerank: 8 }, 5),
    ("kcoherence4_fallback2", Search::KCoherence { k: 4, fallback: Some(2.0), dims: 8, rerank: 8 }, 5),
    ("kcoherence8", Search::KCoherence { k: 8, fallback: None, dims: 8, rerank: 8 }, 5),
    ("kcoherence4_7x7", Search::KCoherence { k: 4, fallback: None, dims: 8, rerank: 8 }, 7),
];

fn config(side: usize, search: Search, neighbourhood: usize) -> SynthConfig {
    SynthConfig { levels: 3, search, neighbourhood, seed: 1, ..SynthConfig::new(side, side) }
}

fn exemplar() -> Grid<Vec3> {
    let field = SkinParams::forehead(128, 128, 1).generate().expect("forehead preset generates");
    field.normals.grid().clone()
}

/// Runs every mode once per size and prints seconds and energy (relative to exact at 256).
fn report_energies(ex: &Grid<Vec3>) {
    let mut reference = None;
    for side in [256, 512] {
        for (name, search, n) in MODES {
            if side > 256 && search == Search::Exact {
                continue;
            }
            let start = Instant::now();
            let s = synthesize(ex, &config(side, search, n), &skinkit_maps::progress::NoProgress)
                .expect("valid configuration");
            let seconds = start.elapsed().as_secs_f64();
            let e = window_energy(&s.texels, ex, 5, 2);
            let exact = *reference.get_or_insert(e);
            eprintln!("{side}x{side} {name:>22}: {seconds:6.2} s once, energy {e:.5} ({:.3} x exact@256)", e / exact);
        }
    }
    if std::env::var("SYNTH_BENCH_LARGE").is_ok_and(|v| v == "1") {
        let search = Search::K_COHERENCE;
        let c = SynthConfig { width: 4096, height: 2048, ..config(256, search, 5) };
        let start = Instant::now();
        let s = synthesize(ex, &c, &skinkit_maps::progress::NoProgress).expect("valid configuration");
        let seconds = start.elapsed().as_secs_f64();
        let e = window_energy(&s.texels, ex, 5, 16);
        eprintln!("4096x2048 {search:?}: {seconds:.2} s once, energy {e:.5} (every 16th texel)");
    }
}

fn bench_synthesis(c: &mut Criterion) {
    let ex = exemplar();
    report_energies(&ex);
    let with_exact = std::env::var("SYNTH_BENCH_EXACT").is_ok_and(|v| v == "1");
    let mut group = c.benchmark_group("synthesize_from_128");
    group.sample_size(10).measurement_time(Duration::from_secs(5)).warm_up_time(Duration::from_secs(1));
    for side in [256, 512] {
        group.throughput(Throughput::Elements((side * side) as u64));
        for (name, search, n) in MODES {
            if search == Search::Exact && (side > 256 || !with_exact) {
                continue;
            }
            let cfg = config(side, search, n);
            group.bench_with_input(BenchmarkId::new(name, side), &cfg, |b, cfg| {
                b.iter(|| synthesize(&ex, cfg, &skinkit_maps::progress::NoProgress).expect("valid configuration"))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_synthesis);
criterion_main!(benches);
