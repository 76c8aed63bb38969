//! A fixed amount of solver work without criterion, for profiling and for CPU-time measurements
//! on a busy machine (user time of `N` iterations minus that of 0 iterations does not depend much
//! on other processes): `cargo bench -p skinkit-capture --bench solve_kernel -- [ls|robust|shadows]
//! [iterations] [size]`, e.g. with `RAYON_NUM_THREADS=1 /usr/bin/time -f %U`.

use glam::Vec3;
use skinkit_capture::solve::{Method, PhotoStack, SolveConfig, no_progress, solve, solve_into};
use skinkit_capture::{Light, Rig};
use skinkit_maps::{Channels, Photo, Samples};

fn main() {
    let args: Vec<String> = std::env::args().filter(|a| !a.starts_with("--")).collect();
    let which = args.get(1).map_or("ls", |s| s.as_str());
    let iterations: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(10);
    let size: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2048);
    let lights: Vec<Light> = (0..8)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / 8.0;
            let t = 45f32.to_radians();
            Light {
                direction: Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()),
                intensity: Vec3::ONE,
                position: None,
            }
        })
        .collect();
    let rig = Rig { lights, ..Rig::default() };
    let shadows = which == "shadows";
    let photos: Vec<Photo> = rig
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let samples = (0..size * size)
                .map(|p| {
                    let (x, y) = (p % size, p / size);
                    let n = Vec3::new(0.3 * (x as f32 * 0.05).sin(), 0.25 * (y as f32 * 0.043).cos(), 1.0).normalize();
                    let occluded = shadows && ((x / 16 + 3 * (y / 16) + 5 * i) % 16 == 0);
                    (if occluded { 0.0 } else { 0.7 * n.dot(l.direction).max(0.0) } * 65535.0) as u16
                })
                .collect();
            Photo::new(size, size, Channels::Gray, Samples::U16(samples)).unwrap()
        })
        .collect();
    let stack = PhotoStack::new(photos, (0..8).map(|i| format!("{i}.png")).collect()).unwrap();
    let method = if which == "ls" { Method::LeastSquares } else { Method::Robust };
    let config = SolveConfig { method, ..SolveConfig::default() };
    let mut out = solve(&stack, &rig, &config, &no_progress).unwrap();
    let start = std::time::Instant::now();
    for _ in 0..iterations {
        solve_into(&stack, &rig, &config, &no_progress, &mut out).unwrap();
    }
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{which}: {:.1} Mpx/s wall ({iterations} x {size}x{size})",
        (iterations * size * size) as f64 / secs / 1e6
    );
}
