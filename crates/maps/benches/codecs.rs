//! Codec costs of a capture's inputs and outputs (issue 12): decoding a 16-bit grey photo, and
//! writing a float normal map as EXR under each compression, with the file size each gives
//! (printed once per compression, as a fraction of the uncompressed file).
//!
//! The normal map is what a capture writes: a rough surface's normals plus sensor-like noise in
//! every mantissa bit (a smooth synthetic map would flatter the compressors).
//!   cargo bench -p skinkit-maps --bench codecs

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::io::{self, ExrCompression, Limits, PngLayout};

const SIZE: usize = 1024;

/// A rough surface's unit normals with 0.3 % noise per component, row-major.
fn captured_like_normals(size: usize) -> Vec<[f32; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    (0..size * size)
        .map(|i| {
            let (x, y) = ((i % size) as f32, (i / size) as f32);
            let gx = 0.3 * (x * 0.05).sin() * (y * 0.031).cos() + rng.random_range(-0.003..0.003);
            let gy = 0.2 * (y * 0.07).sin() + rng.random_range(-0.003..0.003);
            let len = (gx * gx + gy * gy + 1.0).sqrt();
            [-gx / len, -gy / len, 1.0 / len]
        })
        .collect()
}

fn bench_exr_write(c: &mut Criterion) {
    let normals = captured_like_normals(SIZE);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("normal.exr");
    let pixel = |x: usize, y: usize| normals[y * SIZE + x];
    let mut group = c.benchmark_group(format!("exr_write_{SIZE}"));
    group.sample_size(10).measurement_time(std::time::Duration::from_secs(4));
    group.throughput(Throughput::Bytes((SIZE * SIZE * 12) as u64));
    let mut uncompressed = 0;
    for compression in [
        ExrCompression::Uncompressed,
        ExrCompression::RLE,
        ExrCompression::ZIP1,
        ExrCompression::ZIP16,
        ExrCompression::PIZ,
    ] {
        io::write_exr_rgb_compressed(&path, SIZE, SIZE, compression, pixel).unwrap();
        let bytes = std::fs::metadata(&path).unwrap().len();
        uncompressed = if compression == ExrCompression::Uncompressed { bytes } else { uncompressed };
        eprintln!("exr {compression:?}: {bytes} bytes, {:.3} of uncompressed", bytes as f64 / uncompressed as f64);
        group.bench_with_input(BenchmarkId::from_parameter(format!("{compression:?}")), &compression, |b, &c| {
            b.iter(|| io::write_exr_rgb_compressed(&path, SIZE, SIZE, c, pixel).unwrap())
        });
    }
    group.finish();
}

fn bench_png_decode(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let samples: Vec<u16> = (0..SIZE * SIZE)
        .map(|i| {
            let (x, y) = ((i % SIZE) as f32, (i / SIZE) as f32);
            (30000.0 + 12000.0 * (x * 0.02).sin() * (y * 0.013).cos() + rng.random_range(-300.0..300.0)) as u16
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("photo.png");
    io::write_png(&path, SIZE, SIZE, PngLayout::Gray16, &samples).unwrap();
    let mut group = c.benchmark_group(format!("png_decode_gray16_{SIZE}"));
    group.sample_size(10).measurement_time(std::time::Duration::from_secs(4));
    group.throughput(Throughput::Bytes((SIZE * SIZE * 2) as u64));
    group.bench_function("read_photo", |b| b.iter(|| io::read_photo(&path, &Limits::default()).unwrap()));
    group.finish();
}

criterion_group!(benches, bench_exr_write, bench_png_decode);
criterion_main!(benches);
