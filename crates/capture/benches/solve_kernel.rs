//! A fixed amount of solver work without criterion, for profiling and for CPU-time measurements
//! on a busy machine (user time of `N` iterations minus that of 0 iterations does not depend much
//! on other processes): `cargo bench -p skinkit-capture --bench solve_kernel -- [ls|robust|shadows]
//! [iterations] [size]`, e.g. with `RAYON_NUM_THREADS=1 /usr/bin/time -f %U`.

use skinkit_capture::solve::{Method, NoProgress, SolveConfig, solve, solve_into};

mod common;
use common::{photos, ring};

fn main() {
    let args: Vec<String> = std::env::args().filter(|a| !a.starts_with("--")).collect();
    let which = args.get(1).map_or("ls", |s| s.as_str());
    let iterations: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let size: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let rig = ring(8, 45.0);
    let stack = photos(size, &rig, which == "shadows");
    let method = if which == "ls" { Method::LeastSquares } else { Method::Robust };
    let config = SolveConfig { method, ..SolveConfig::default() };
    let mut out = solve(&stack, &rig, &config, &NoProgress).unwrap();
    let start = std::time::Instant::now();
    for _ in 0..iterations {
        solve_into(&stack, &rig, &config, &NoProgress, &mut out).unwrap();
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{which}: {:.1} Mpx/s wall ({iterations} x {size}x{size})",
        (iterations * size * size) as f64 / secs / 1e6
    );
}
