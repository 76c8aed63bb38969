//! Throughput of the per-pixel solves (pixels per second) on 16-bit grey photos, 8 lights (with
//! about half the pixels dropping a shadowed reading, or with a highlight to reject): at
//! 2048x2048 (64 MiB of samples, 80 MiB of output: memory-bound) and at sizes whose samples and
//! output fit in the caches (256x256: 1 + 1.25 MiB; 512x512: 4 + 5 MiB), where the kernel's own
//! rate shows.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use skinkit_capture::solve::{Method, NoProgress, SolveConfig, solve, solve_into};

mod common;
use common::{photos, photos_with, ring};

fn bench_solve(c: &mut Criterion) {
    let size = 2048;
    let rig = ring(8, 45.0);
    let mut group = c.benchmark_group("solve_8_lights_u16");
    group
        .sample_size(10)
        .measurement_time(std::time::Duration::from_secs(4))
        .warm_up_time(std::time::Duration::from_secs(1));
    group.throughput(Throughput::Elements((size * size) as u64));
    let cases = [
        (Method::LeastSquares, false, false),
        (Method::Robust, false, false),
        (Method::Robust, true, false),
        (Method::Robust, false, true),
        (Method::Threshold, false, false),
        (Method::Threshold, true, false),
    ];
    for (method, shadows, highlights) in cases {
        let stack = photos_with(size, &rig, shadows, highlights);
        let config = SolveConfig { method, ..SolveConfig::default() };
        let name = format!(
            "{method:?}{}{}",
            if shadows { "_shadows" } else { "" },
            if highlights { "_highlights" } else { "" }
        );
        // The kernel, writing into maps reused between iterations.
        let mut out = solve(&stack, &rig, &config, &NoProgress).unwrap();
        group.bench_with_input(BenchmarkId::new(format!("{name}_into"), size), &stack, |b, stack| {
            b.iter(|| solve_into(stack, &rig, &config, &NoProgress, &mut out).unwrap())
        });
        // With fresh output maps each time (page faults included).
        if method == Method::LeastSquares {
            group.bench_with_input(BenchmarkId::new(name, size), &stack, |b, stack| {
                b.iter(|| solve(stack, &rig, &config, &NoProgress).unwrap())
            });
        }
    }
    group.finish();
}

fn bench_solve_cached(c: &mut Criterion) {
    let rig = ring(8, 45.0);
    let mut group = c.benchmark_group("solve_8_lights_u16_cache_resident");
    group
        .sample_size(20)
        .measurement_time(std::time::Duration::from_secs(3))
        .warm_up_time(std::time::Duration::from_secs(1));
    for size in [256, 512] {
        group.throughput(Throughput::Elements((size * size) as u64));
        for method in [Method::LeastSquares, Method::Robust] {
            let stack = photos(size, &rig, false);
            let config = SolveConfig { method, ..SolveConfig::default() };
            let mut out = solve(&stack, &rig, &config, &NoProgress).unwrap();
            group.bench_with_input(BenchmarkId::new(format!("{method:?}_into"), size), &stack, |b, stack| {
                b.iter(|| solve_into(stack, &rig, &config, &NoProgress, &mut out).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_solve, bench_solve_cached);
criterion_main!(benches);
