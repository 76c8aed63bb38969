//! The debug view of tangent frames and UV stretch (`effects = ["debug-frames"]`), read back
//! from the GPU: a mesh whose stretch is known by construction is coloured as the stretch says,
//! a triangle without UV area is magenta, and the view runs after the base pass. Needs an
//! adapter (lavapipe in CI); never skips.

use crate::common::plain_inputs;
use glam::{Vec3, Vec4};
use skinkit_render::brdf::Lafortune;
use skinkit_render::effect::Effect;
use skinkit_render::gpu::{Gpu, OutputFormat, Rendered};
use skinkit_render::pass::setup::SkinSetup;
use skinkit_render::shading::{Camera, Light, LightKind, Vertex};

const SIZE: u32 = 64;

/// A quad at z = 0 over [x0, x1] x [-1, 1], facing +z, with UVs over (u0, v0, u1, v1).
fn quad(x0: f32, x1: f32, uv: [f32; 4], base: u32) -> (Vec<Vertex>, Vec<u32>) {
    let [u0, v0, u1, v1] = uv;
    let vertex = |x: f32, y: f32, uv: [f32; 2]| Vertex {
        position: [x, y, 0.0],
        normal: Vec3::Z.into(),
        tangent: Vec4::new(1.0, 0.0, 0.0, 1.0).into(),
        uv,
    };
    let vertices = vec![
        vertex(x0, -1.0, [u0, v1]),
        vertex(x1, -1.0, [u1, v1]),
        vertex(x1, 1.0, [u1, v0]),
        vertex(x0, 1.0, [u0, v0]),
    ];
    (vertices, vec![base, base + 1, base + 2, base, base + 2, base + 3])
}

fn render(vertices: Vec<Vertex>, indices: Vec<u32>, mm_per_unit: f32) -> (Rendered, Vec<String>) {
    let inputs = plain_inputs(
        (vertices, indices),
        Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 60.0, 1.0),
        vec![Light { kind: LightKind::Directional { toward: Vec3::Z }, color: Vec3::ONE, intensity: 1.0 }],
        Lafortune { diffuse: Vec3::splat(0.5), lobes: Vec::new() },
    );
    let skin = SkinSetup { effects: vec![Effect::DebugFrames], mm_per_unit, ..SkinSetup::default() };
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let prepared = gpu.prepare_with(&inputs, &skin).unwrap();
    let target = gpu.create_target(SIZE, SIZE, OutputFormat::Hdr32).unwrap();
    gpu.draw(&prepared, &target).unwrap();
    (gpu.read(&target).unwrap(), prepared.pass_names())
}

/// The pixel at (x, y) in [-1, 1]^2 of the quads' plane (the camera sees [-1.73, 1.73]).
fn pixel(image: &Rendered, x: f32, y: f32) -> [f32; 4] {
    let half = 3.0 * (30f32).to_radians().tan();
    let column = ((x / half * 0.5 + 0.5) * SIZE as f32) as usize;
    let row = ((0.5 - y / half * 0.5) * SIZE as f32) as usize;
    image.pixels[row * SIZE as usize + column]
}

#[test]
fn a_quarter_of_the_median_stretch_is_blue_and_the_median_white() {
    // Each quad is 10 x 20 mm (10 mm a unit). The left one covers half the UV square, 20 mm a
    // UV unit; the right one a sixteenth of it (0.125 x 0.25), 80 mm a UV unit. The median over
    // the eight vertices is 80: the right quad is white, the left two stops below, full blue.
    let (mut vertices, mut indices) = quad(-1.0, 0.0, [0.0, 0.0, 0.5, 1.0], 0);
    let (v, i) = quad(0.0, 1.0, [0.5, 0.0, 0.625, 0.25], 4);
    vertices.extend(v);
    indices.extend(i);
    let (image, passes) = render(vertices, indices, 10.0);
    assert_eq!(passes, ["base", "debug frames"]);
    let [r, g, b, _] = pixel(&image, -0.45, 0.1);
    assert!(b > 0.2 && b > 3.0 * r && b > 2.0 * g, "left quad should be blue: {r} {g} {b}");
    let [r, g, b, _] = pixel(&image, 0.55, 0.1);
    assert!(r > 0.2 && (r - b).abs() < 0.02 * r && (r - g).abs() < 0.02 * r, "right quad should be grey: {r} {g} {b}");
    assert!(image.pixels.iter().flatten().all(|c| c.is_finite()));
}

#[test]
fn a_quad_without_uv_area_is_magenta_and_finite() {
    let (vertices, indices) = quad(-1.0, 1.0, [0.3, 0.3, 0.3, 0.3], 0);
    let (image, _) = render(vertices, indices, 1.0);
    let [r, g, b, _] = pixel(&image, 0.3, 0.3);
    assert!(r > 0.2 && (r - b).abs() < 0.02 * r && g < 0.01 * r, "no UV area should be magenta: {r} {g} {b}");
    assert!(image.pixels.iter().flatten().all(|c| c.is_finite()));
}
