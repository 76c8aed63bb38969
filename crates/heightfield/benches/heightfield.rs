//! Throughput (texels per second) of generating a cheek field and of rendering it under an 8-light
//! ring with cast shadows, by field size.

use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_heightfield::render::{Quantise, RenderConfig, RenderLight, render};
use skinkit_heightfield::{SkinParams, generate};

fn bench_generate(c: &mut Criterion) {
    let mut group = c.benchmark_group("generate_cheek");
    group.sample_size(10).measurement_time(Duration::from_secs(4)).warm_up_time(Duration::from_secs(1));
    for size in [256, 1024] {
        let params = SkinParams::cheek(size, size, 1);
        group.throughput(Throughput::Elements((size * size) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(size), &params, |b, p| b.iter(|| generate(p).unwrap()));
    }
    group.finish();
}

fn bench_render(c: &mut Criterion) {
    let mut group = c.benchmark_group("render_8_lights_shadows_u16");
    group.sample_size(10).measurement_time(Duration::from_secs(4)).warm_up_time(Duration::from_secs(1));
    let lights = RenderLight::ring(8, 45.0, Vec3::ONE);
    let config = RenderConfig { shadows: true, noise_sigma: 0.002, format: Quantise::U16, ..RenderConfig::default() };
    for size in [256, 1024] {
        let field = generate(&SkinParams::nose(size, size, 1)).unwrap();
        group.throughput(Throughput::Elements((size * size * lights.len()) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(size), &field, |b, f| {
            b.iter(|| render(f, &lights, &config).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, bench_generate, bench_render);
criterion_main!(benches);
