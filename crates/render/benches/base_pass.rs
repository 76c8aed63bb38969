//! Frame time of the base pass (issue 5): 1920x1080, a 4096x2048 normal map (the paper's size),
//! a 128x64-segment sphere (8385 vertices, under the paper's 15k), the 3-lobe skin BRDF per
//! pixel and two lights, into the linear encoding's Rgba32Float target (it was Rgba16Float before
//! the renderer's front door, issue 38, which offers linear and display encodings only).
//!
//! Only [`Renderer::draw_only`] is timed (encode, submit, wait for the GPU): the scene is uploaded
//! once (`upload` times that separately: CPU mip chain, f16 conversion, copy and the target). On the machines that
//! build skinkit this is a lavapipe figure (software Vulkan on the CPU), not a GPU one: it says
//! how long CI and a GPU-less user wait per frame, nothing about real-time rates on hardware.
//! Needs an adapter (`WGPU_BACKEND=vulkan` with Mesa's lavapipe). The GPU time of one pass from
//! timestamp queries (where the adapter has them) is printed before the criterion runs.
//!
//! Measured (llvmpipe, LLVM 15, 2 cores shared with other builds): draw about 150 ms per frame
//! (GPU timestamps agree), upload about 0.4 s. A plain full-screen pass sampling the same map
//! costs 25-29 ms here: the rest is the per-pixel Lafortune work (3 lobes x 2 lights of vector
//! `pow`, frames built per pixel) running on the CPU.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use skinkit_render::brdf::Lafortune;
use skinkit_render::pass::setup::SkinSetup;
use skinkit_render::renderer::{Encoding, FrameOptions, Renderer};
use skinkit_render::shading::{
    Camera, GreenAxis, Light, LightKind, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex,
};

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;

fn sphere(segments: u32, rings: u32) -> (Vec<Vertex>, Vec<u32>) {
    skinkit_render::shading::uv_sphere(segments, rings)
}

/// A 4096x2048 field of small bumps (not skin, but the same texture traffic).
fn bump_map() -> Texture {
    Texture::from_fn(4096, 2048, |x, y| {
        let (u, v) = (x as f32 * 0.37, y as f32 * 0.29);
        let n = Vec3::new(0.3 * u.sin() * v.cos(), 0.3 * u.cos() * v.sin(), 1.0).normalize();
        [n.x, n.y, n.z, 0.0]
    })
}

fn scene() -> RenderInputs {
    let (vertices, indices) = sphere(128, 64);
    let sun =
        |toward: Vec3, intensity: f32| Light { kind: LightKind::Directional { toward }, color: Vec3::ONE, intensity };
    RenderInputs {
        vertices,
        indices,
        camera: Camera::look_at(Vec3::new(0.0, 0.0, 2.6), Vec3::ZERO, Vec3::Y, 45.0, WIDTH as f32 / HEIGHT as f32),
        lights: vec![sun(Vec3::new(0.5, 0.4, 0.8), 3.0), sun(Vec3::new(-0.7, 0.1, 0.3), 1.0)],
        brdf: Lafortune::skin(),
        normal_map: bump_map(),
        green: GreenAxis::Up,
        albedo: Texture::solid([0.9, 0.8, 0.75, 1.0]),
        specular: SpecularMode::Pixel,
        exposure: 1.0,
        tone: ToneCurve::None,
        background: [0.0; 4],
    }
}

fn base_pass(c: &mut Criterion) {
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("{e}"));
    eprintln!("adapter: {}", renderer.adapter_name());
    let inputs = scene();
    let options = FrameOptions::new(WIDTH, HEIGHT, Encoding::Linear);
    let prepare = || renderer.prepare_inputs(inputs.clone(), &SkinSetup::default(), &options).unwrap();
    let prepared = prepare();
    if let Some(passes) = renderer.draw_timed(&prepared).unwrap() {
        let t: std::time::Duration = passes.iter().map(|(_, d)| *d).sum();
        eprintln!("base pass GPU time (timestamp queries): {t:?}");
    }
    let mut group = c.benchmark_group("base_pass");
    group.sample_size(10);
    group.throughput(Throughput::Elements(WIDTH as u64 * HEIGHT as u64));
    group.bench_function("draw_1920x1080_map_4096x2048", |b| b.iter(|| renderer.draw_only(&prepared).unwrap()));
    group.throughput(Throughput::Elements(4096 * 2048));
    group.bench_function("upload_map_4096x2048", |b| b.iter(prepare));
    group.finish();
}

criterion_group!(benches, base_pass);
criterion_main!(benches);
