//! Detrend cost against block size: running sums make block 200 cost what block 50 costs.

use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_capture::detrend::detrend;
use skinkit_maps::{Grid, NormalMap};

fn bench_detrend(c: &mut Criterion) {
    let size = 2048;
    let map = NormalMap::from_grid(Grid::from_fn(size, size, |x, y| {
        let (u, v) = (x as f32 * 0.01, y as f32 * 0.02);
        if (x * 7 + y * 3) % 97 == 0 { Vec3::ZERO } else { Vec3::new(0.3 * u.sin() + 0.2, 0.2 * v.cos(), 1.0) }
    }));
    let mut group = c.benchmark_group("detrend_2048");
    group
        .sample_size(10)
        .measurement_time(std::time::Duration::from_secs(5))
        .warm_up_time(std::time::Duration::from_secs(1));
    group.throughput(Throughput::Elements((size * size) as u64));
    for block in [50, 200] {
        group.bench_with_input(BenchmarkId::from_parameter(block), &block, |b, &block| {
            b.iter_batched_ref(|| map.clone(), |m| detrend(m, block), BatchSize::LargeInput)
        });
    }
    group.finish();
}

criterion_group!(benches, bench_detrend);
criterion_main!(benches);
