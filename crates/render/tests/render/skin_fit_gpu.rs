//! The WGSL twins of `skin::fit` and `skin::sh` run on the GPU against their Rust originals.
//!
//! Needs an adapter: in CI that is lavapipe (`WGPU_BACKEND=vulkan`). It never passes by
//! skipping: with no adapter it fails with the fix.

use glam::Vec3;
use skinkit_render::skin::fit::{SKIN_FIT_WGSL, blog_direct, own_direct};
use skinkit_render::skin::sh::{SKIN_SH_WGSL, Sh9, blog_zonal};
use wgpu::util::DeviceExt;

const KERNEL: &str = "
@group(0) @binding(0) var<storage, read> cases: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> ambient: array<vec4<f32>, 9>;
@group(0) @binding(2) var<storage, read_write> results: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if (i >= arrayLength(&cases) / 2u) {
        return;
    }
    let a = cases[2u * i];
    let n = cases[2u * i + 1u].xyz;
    let coeffs = ambient;
    results[3u * i] = vec4<f32>(blog_direct(a.xyz, a.w), 0.0);
    results[3u * i + 1u] = vec4<f32>(own_direct(a.xyz, a.w), 0.0);
    results[3u * i + 2u] = vec4<f32>(sh9_convolve(coeffs, blog_zonal(a.w), n), 0.0);
}
";

fn device() -> (wgpu::Device, wgpu::Queue) {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .unwrap_or_else(|e| panic!("no GPU adapter ({e}): install mesa-vulkan-drivers and set WGPU_BACKEND=vulkan"));
    let desc = wgpu::DeviceDescriptor { label: Some("skin twins device"), ..Default::default() };
    pollster::block_on(adapter.request_device(&desc)).unwrap_or_else(|e| panic!("{e}"))
}

fn run(cases: &[[f32; 4]], ambient: &[[f32; 4]; 9]) -> Vec<[f32; 4]> {
    let (device, queue) = device();
    let source = format!("{SKIN_FIT_WGSL}\n{SKIN_SH_WGSL}\n{KERNEL}");
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("skin twins"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("skin twins"),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let storage = |label, contents: &[u8]| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage: wgpu::BufferUsages::STORAGE,
        })
    };
    let cases_buf = storage("cases", bytemuck::cast_slice(cases));
    let ambient_buf = storage("ambient", bytemuck::cast_slice(ambient));
    let size = (cases.len() / 2 * 3 * 16) as u64;
    let results = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("skin twins"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: cases_buf.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: ambient_buf.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: results.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("skin twins") });
    {
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("skin twins"), timestamp_writes: None });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((cases.len() as u32 / 2).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&results, 0, &readback, 0, size);
    queue.submit([encoder.finish()]);
    let (sender, receiver) = std::sync::mpsc::channel();
    readback.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = sender.send(r);
    });
    device.poll(wgpu::PollType::wait_indefinitely()).unwrap();
    receiver.recv().unwrap().unwrap();
    let bytes = readback.get_mapped_range(..).unwrap().to_vec();
    bytemuck::cast_slice(&bytes).to_vec()
}

#[test]
fn wgsl_twins_match_rust() {
    let sh = Sh9::gradient([0.8, 0.6, 0.5], [0.1, 0.08, 0.05], Vec3::new(0.2, 1.0, 0.1));
    let ambient: [[f32; 4]; 9] = std::array::from_fn(|i| [sh.coeffs[i][0], sh.coeffs[i][1], sh.coeffs[i][2], 0.0]);
    let mut cases = Vec::new();
    let mut expected = Vec::new();
    for j in 0..=24 {
        let inv_r = 1.1 * j as f32 / 24.0;
        for i in 0..=64 {
            let x = -1.0 + i as f32 / 32.0;
            let ndl = [x, (x + 0.013).min(1.0), (x - 0.021).max(-1.0)];
            let n = Vec3::new(x, 0.5, 0.3).normalize();
            cases.push([ndl[0], ndl[1], ndl[2], inv_r]);
            cases.push([n.x, n.y, n.z, 0.0]);
            let per = |f: fn(f32, f32) -> [f32; 3]| -> [f32; 3] { std::array::from_fn(|c| f(ndl[c], inv_r)[c]) };
            expected.push(per(blog_direct));
            expected.push(per(own_direct));
            expected.push(sh.convolve(n, &blog_zonal(inv_r)));
        }
    }
    let got = run(&cases, &ambient);
    let (mut worst, mut exact) = ([0.0f32; 3], [0usize; 3]);
    for (k, (g, e)) in got.iter().zip(&expected).enumerate() {
        for c in 0..3 {
            let d = (g[c] - e[c]).abs();
            worst[k % 3] = worst[k % 3].max(d / (1.0 + e[c].abs()));
            exact[k % 3] += usize::from(g[c] == e[c]);
        }
    }
    let total = expected.len() / 3 * 3;
    println!("worst relative difference (blog, own, sh) {worst:?}; exactly equal {exact:?} of {total}");
    // WGSL allows 2.5 ulp divisions and fused multiply-adds, so equality is not guaranteed;
    // a few ulp of the values (<= ~5) is what the same formula in another order would give.
    assert!(worst.iter().all(|w| *w < 1e-6), "{worst:?}");
}
