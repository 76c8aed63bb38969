//! Throughput of the per-pixel solves (pixels per second) on 16-bit grey photos, 8 lights: at
//! 2048x2048 (64 MiB of samples, 80 MiB of output: memory-bound) and at sizes whose samples and
//! output fit in the caches (256x256: 1 + 1.25 MiB; 512x512: 4 + 5 MiB), where the kernel's own
//! rate shows.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_capture::solve::{Method, PhotoStack, SolveConfig, no_progress, solve, solve_into};
use skinkit_capture::{Light, Rig};
use skinkit_maps::{Channels, Photo, Samples};

fn ring(k: usize, theta: f32) -> Rig {
    let t = theta.to_radians();
    let lights = (0..k)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / k as f32;
            Light {
                direction: Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()),
                intensity: Vec3::ONE,
                position: None,
            }
        })
        .collect();
    Rig { lights, ..Rig::default() }
}

/// A bumpy surface lit by `rig`; with `shadows`, about 6% of readings are zeroed in patches.
fn photos(size: usize, rig: &Rig, shadows: bool) -> PhotoStack {
    let normal = |x: usize, y: usize| {
        let (u, v) = (x as f32 * 0.05, y as f32 * 0.043);
        Vec3::new(0.3 * u.sin(), 0.25 * v.cos(), 1.0).normalize()
    };
    let normals: Vec<Vec3> = (0..size * size).map(|p| normal(p % size, p / size)).collect();
    let photos = rig
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let samples = (0..size * size)
                .map(|p| {
                    let (x, y) = (p % size, p / size);
                    let occluded = shadows && ((x / 16 + 3 * (y / 16) + 5 * i) % 16 == 0);
                    let v = if occluded { 0.0 } else { 0.7 * normals[p].dot(l.direction).max(0.0) };
                    (v * 65535.0) as u16
                })
                .collect();
            Photo::new(size, size, Channels::Gray, Samples::U16(samples)).unwrap()
        })
        .collect();
    PhotoStack::new(photos, (0..rig.lights.len()).map(|i| format!("{i}.png")).collect()).unwrap()
}

fn bench_solve(c: &mut Criterion) {
    let size = 2048;
    let rig = ring(8, 45.0);
    let mut group = c.benchmark_group("solve_8_lights_u16");
    group
        .sample_size(10)
        .measurement_time(std::time::Duration::from_secs(4))
        .warm_up_time(std::time::Duration::from_secs(1));
    group.throughput(Throughput::Elements((size * size) as u64));
    for (method, shadows) in [(Method::LeastSquares, false), (Method::Robust, false), (Method::Robust, true)] {
        let stack = photos(size, &rig, shadows);
        let config = SolveConfig { method, ..SolveConfig::default() };
        let name = format!("{method:?}{}", if shadows { "_shadows" } else { "" });
        // The kernel, writing into maps reused between iterations.
        let mut out = solve(&stack, &rig, &config, &no_progress).unwrap();
        group.bench_with_input(BenchmarkId::new(format!("{name}_into"), size), &stack, |b, stack| {
            b.iter(|| solve_into(stack, &rig, &config, &no_progress, &mut out).unwrap())
        });
        // With fresh output maps each time (page faults included).
        if method == Method::LeastSquares {
            group.bench_with_input(BenchmarkId::new(name, size), &stack, |b, stack| {
                b.iter(|| solve(stack, &rig, &config, &no_progress).unwrap())
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
            let mut out = solve(&stack, &rig, &config, &no_progress).unwrap();
            group.bench_with_input(BenchmarkId::new(format!("{method:?}_into"), size), &stack, |b, stack| {
                b.iter(|| solve_into(stack, &rig, &config, &no_progress, &mut out).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_solve, bench_solve_cached);
criterion_main!(benches);
