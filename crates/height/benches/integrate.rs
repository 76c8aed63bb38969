//! Integration speed per integrator and size (`cargo bench -p skinkit-height`); the comparison
//! with SciPy's DCT Poisson solve on the same problem is `scripts/bench-height-vs-scipy.sh`.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use skinkit_height::{HeightOptions, Integrator, Scale, integrate};
use skinkit_maps::{Grid, NormalMap, Vec3};

/// A smooth, non-trivial normal map of `side x side` (the speed does not depend on the content).
fn normals(side: usize) -> NormalMap {
    let f = |x: usize, y: usize| {
        let (u, v) = (x as f32 * 0.05, y as f32 * 0.03);
        Vec3::new(0.2 * u.sin(), 0.2 * v.cos(), 1.0).normalize()
    };
    NormalMap::from_grid(Grid::from_fn(side, side, f))
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("integrate");
    group.sample_size(10);
    for side in [1024usize, 2048] {
        let map = normals(side);
        group.throughput(Throughput::Elements((side * side) as u64));
        for integrator in [Integrator::Neumann, Integrator::Periodic] {
            let options =
                HeightOptions { integrator: Some(integrator), scale: Scale::Texels, ..HeightOptions::default() };
            group.bench_with_input(BenchmarkId::new(integrator.name(), side), &map, |b, m| {
                b.iter(|| integrate(m, &options).unwrap())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
