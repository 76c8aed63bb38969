//! The N-way multiresolution spline alone on a 4096x2048 map with 7 regions (the paper's face
//! map size and region count; the target is under 0.5 s on 2 cores).
//!
//! Labels come from the nearest of 7 fixed points; each region's piece is its bounding box grown by
//! the margin of the level count ([`piece_rect`]), filled with a cheap smooth normal map (a few
//! sinusoids per region). Before timing, one run per level count prints its seconds and the pieces'
//! total area, and the CPU seconds it used (the machine is shared: CPU time over the core count is
//! what the wall time would be alone); criterion then times 6 levels (margin 124 texels). Only `blend` is timed.

use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_stitch::spline::{Blend, Piece, SplineConfig, blend, piece_rect, region_bounds};

const WIDTH: usize = 4096;
const HEIGHT: usize = 2048;

/// Seven seed points in UV, roughly forehead, temples, nose, cheeks and chin.
const POINTS: [(f32, f32); 7] =
    [(0.5, 0.15), (0.2, 0.3), (0.8, 0.3), (0.5, 0.5), (0.25, 0.65), (0.75, 0.65), (0.5, 0.88)];

/// Region index of the nearest point per texel.
fn labels() -> Grid<u16> {
    Grid::from_fn(WIDTH, HEIGHT, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / WIDTH as f32, (y as f32 + 0.5) / HEIGHT as f32);
        let d = |&(pu, pv): &(f32, f32)| ((u - pu) * 2.0).powi(2) + (v - pv).powi(2);
        (0..POINTS.len()).min_by(|&a, &b| d(&POINTS[a]).total_cmp(&d(&POINTS[b]))).unwrap() as u16
    })
}

/// A smooth-ish unit normal map over `rect`-sized texels, different per region.
fn normals(width: usize, height: usize, x0: usize, y0: usize, region: usize) -> Grid<Vec3> {
    let f = 0.05 + 0.02 * region as f32;
    Grid::from_fn(width, height, |x, y| {
        let (gx, gy) = ((x + x0) as f32, (y + y0) as f32);
        let sx = 0.2 * (f * gx + region as f32).sin() + 0.1 * (0.31 * gx + 0.17 * gy).sin();
        let sy = 0.2 * (f * 1.3 * gy).cos() + 0.1 * (0.23 * gx - 0.29 * gy).cos();
        Vec3::new(sx, sy, 1.0).normalize()
    })
}

fn pieces(labels: &Grid<u16>, levels: usize) -> Vec<Piece> {
    region_bounds(labels, POINTS.len())
        .iter()
        .enumerate()
        .map(|(r, b)| {
            let rect = piece_rect(b.expect("every point owns texels"), levels, WIDTH, HEIGHT);
            Piece::new(rect.x0, rect.y0, normals(rect.width, rect.height, rect.x0, rect.y0, r))
        })
        .collect()
}

/// CPU seconds (user + system, all threads) this process has used, from `/proc/self/stat` (Linux;
/// 10 ms ticks): on a shared machine, CPU time / cores bounds what the wall time would be alone.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn bench_spline(c: &mut Criterion) {
    let labels = labels();
    for levels in [1, 4, 6, 8] {
        let pieces = pieces(&labels, levels);
        let area: usize = pieces.iter().map(|p| p.texels.len()).sum();
        let config = SplineConfig { levels, blend: Blend::NormalVectors };
        let (start, cpu) = (Instant::now(), cpu_seconds());
        blend(&labels, &pieces, &config).expect("valid pieces");
        let seconds = start.elapsed().as_secs_f64();
        let cpu = cpu_seconds().zip(cpu).map_or(f64::NAN, |(after, before)| after - before);
        let threads = rayon::current_num_threads();
        eprintln!(
            "{WIDTH}x{HEIGHT}, 7 regions, {levels} levels: {seconds:.3} s once on {threads} threads, \
             {cpu:.2} CPU s (pieces {:.2} x the map)",
            area as f64 / (WIDTH * HEIGHT) as f64
        );
    }
    let mut group = c.benchmark_group("spline_4096x2048_7_regions");
    group.sample_size(10).measurement_time(Duration::from_secs(6)).warm_up_time(Duration::from_secs(1));
    group.throughput(Throughput::Elements((WIDTH * HEIGHT) as u64));
    let levels = 6;
    let pieces = pieces(&labels, levels);
    let config = SplineConfig { levels, blend: Blend::NormalVectors };
    group.bench_with_input(BenchmarkId::new("normal_vectors", levels), &config, |b, config| {
        b.iter(|| blend(&labels, &pieces, config).expect("valid pieces"))
    });
    group.finish();
}

criterion_group!(benches, bench_spline);
criterion_main!(benches);
