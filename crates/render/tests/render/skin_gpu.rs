//! GPU tests of the skin passes driven through `setup::SkinSetup` directly: the key light's
//! shadow map (occluded texels dark, its box filter a linear ramp), texture-space diffusion (a
//! constant light map survives the blur, a shadow edge is softened, UV borders are dilated),
//! the LUT path reading the table it is given, and every feature combination compiling.
//! Needs an adapter (lavapipe in CI); never skips.

use crate::common::plain_inputs;
use glam::{Vec3, Vec4};
use skinkit_render::brdf::Lafortune;
use skinkit_render::gpu::Table;
use skinkit_render::gpu::{Gpu, OutputFormat};
use skinkit_render::pass::geometry;
use skinkit_render::pass::setup::{self, DiffuseMode, Features, ShadowSetup, SkinSetup, TsdSetup};
use skinkit_render::shading::{Camera, Light, LightKind, RenderInputs, Vertex};
use skinkit_render::skin::options::TsdKernel;

const SIZE: u32 = 96;

fn gpu() -> Gpu {
    Gpu::new().unwrap_or_else(|e| panic!("{e}"))
}

fn vertex(p: Vec3, uv: [f32; 2]) -> Vertex {
    Vertex { position: p.into(), normal: Vec3::Z.into(), tangent: Vec4::new(1.0, 0.0, 0.0, 1.0).into(), uv }
}

/// A quad in z = `z` over [x0, x1] x [y0, y1], facing +z, with UVs covering `uv` (u0, v0, u1, v1).
fn quad(x0: f32, x1: f32, y0: f32, y1: f32, z: f32, uv: [f32; 4], base: u32) -> (Vec<Vertex>, Vec<u32>) {
    let [u0, v0, u1, v1] = uv;
    let vertices = vec![
        vertex(Vec3::new(x0, y0, z), [u0, v1]),
        vertex(Vec3::new(x1, y0, z), [u1, v1]),
        vertex(Vec3::new(x1, y1, z), [u1, v0]),
        vertex(Vec3::new(x0, y1, z), [u0, v0]),
    ];
    (vertices, vec![base, base + 1, base + 2, base, base + 2, base + 3])
}

/// The floor [-1, 1]^2 at z = 0 (UVs [0, 1]^2) and, optionally, a blocker over x < 0 at z = 0.5
/// (UVs squeezed into a corner strip nobody looks at).
fn floor_and_blocker(blocker: bool) -> (Vec<Vertex>, Vec<u32>) {
    let (mut v, mut i) = quad(-1.0, 1.0, -1.0, 1.0, 0.0, [0.0, 0.0, 1.0, 1.0], 0);
    if blocker {
        let (bv, bi) = quad(-3.0, 0.0, -3.0, 3.0, 0.5, [0.0, 0.0, 0.01, 0.01], 4);
        v.extend(bv);
        i.extend(bi);
    }
    (v, i)
}

fn inputs(mesh: (Vec<Vertex>, Vec<u32>)) -> RenderInputs {
    plain_inputs(
        mesh,
        // Looking down at the floor from below the blocker's height is impossible; look from
        // straight above through it would hide the floor, so the camera sits under z = 0.5.
        Camera::look_at(Vec3::new(0.0, 0.0, 0.45), Vec3::ZERO, Vec3::Y, 130.0, 1.0),
        vec![Light { kind: LightKind::Directional { toward: Vec3::Z }, color: Vec3::ONE, intensity: 2.0 }],
        Lafortune { diffuse: Vec3::splat(0.5), lobes: Vec::new() },
    )
}

fn shadow_setup(inputs: &RenderInputs, filter: u32) -> ShadowSetup {
    let (centre, radius) = geometry::bounding_sphere(&inputs.vertices);
    let map_size = 256;
    let (view_proj, texel) = geometry::light_view_proj(&inputs.lights[0], centre, radius, map_size);
    ShadowSetup {
        light: 0,
        map_size,
        filter,
        bias: 1.0,
        disc_radius: 0.0,
        view_proj,
        texel,
        new_penumbra: 0.25,
        translucent: Vec::new(),
    }
}

fn render(gpu: &Gpu, inputs: &RenderInputs, skin: &SkinSetup) -> Vec<[f32; 4]> {
    let target = gpu.create_target(SIZE, SIZE, OutputFormat::Hdr32).unwrap();
    let scene = gpu.prepare_with(inputs, skin).unwrap();
    gpu.draw(&scene, &target).unwrap();
    gpu.read(&target).unwrap().pixels
}

/// Red channel along the image's middle row.
fn middle_row(pixels: &[[f32; 4]]) -> Vec<f32> {
    let y = SIZE as usize / 2;
    (0..SIZE as usize).map(|x| pixels[y * SIZE as usize + x][0]).collect()
}

/// rho_d / pi * E for the floor lit head-on.
fn lit_value() -> f32 {
    0.5 / std::f32::consts::PI * 2.0
}

#[test]
fn shadow_map_darkens_what_the_blocker_hides_and_nothing_else() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(true));
    let lit = render(&gpu, &scene, &SkinSetup::default());
    let skin = SkinSetup {
        features: Features { shadows: true, ..Default::default() },
        shadow: Some(shadow_setup(&scene, 3)),
        ..Default::default()
    };
    let shadowed = render(&gpu, &scene, &skin);
    let (row_lit, row_shadowed) = (middle_row(&lit), middle_row(&shadowed));
    let expected = lit_value();
    // Without shadows the whole visible floor is lit.
    for (x, v) in row_lit.iter().enumerate().skip(8).take(80) {
        assert!((v - expected).abs() < 1e-3 * expected, "x {x}: unshadowed {v} vs {expected}");
    }
    // With them, left of the blocker's edge (x = 0 is the image centre) is dark, right is lit,
    // away from the edge's penumbra.
    let half = SIZE as usize / 2;
    for x in 8..half - 8 {
        assert!(row_shadowed[x] < 1e-4, "x {x} should be in shadow: {}", row_shadowed[x]);
    }
    for x in half + 8..SIZE as usize - 8 {
        assert!((row_shadowed[x] - expected).abs() < 1e-3 * expected, "x {x} should be lit: {}", row_shadowed[x]);
    }
}

#[test]
fn box_filtered_shadow_edge_is_a_monotone_ramp_as_wide_as_the_filter() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(true));
    let ramp = |filter: u32| {
        let skin = SkinSetup {
            features: Features { shadows: true, ..Default::default() },
            shadow: Some(shadow_setup(&scene, filter)),
            ..Default::default()
        };
        let row = middle_row(&render(&gpu, &scene, &skin));
        let expected = lit_value();
        let inside = row.iter().filter(|&&v| v > 0.02 * expected && v < 0.98 * expected).count();
        for w in row.windows(2).skip(4).take(SIZE as usize - 10) {
            assert!(w[1] >= w[0] - 1e-5, "the penumbra must rise monotonically toward the light: {row:?}");
        }
        inside
    };
    let (narrow, wide) = (ramp(1), ramp(9));
    assert!(wide > narrow + 2, "a 9-tap filter must widen the penumbra: {narrow} vs {wide} pixels");
}

fn tsd_setup(passes: u32) -> TsdSetup {
    TsdSetup {
        size: 128,
        kernel: TsdKernel::Single,
        passes,
        kernel_map: None,
        kernel_scale: [3.0, 2.0],
        kernel_mm: 0.05,
        curvature_gain: 0.0,
        backface_bias: 0.3,
        reuse_below_px: 0.0,
    }
}

fn tsd_skin(scene: &RenderInputs, passes: u32, shadows: bool) -> SkinSetup {
    let stretch = geometry::uv_stretch(&scene.vertices, &scene.indices, 1.0);
    SkinSetup {
        features: Features { diffuse: DiffuseMode::LightMap, shadows, ..Default::default() },
        vertex_skin: stretch.iter().map(|&s| [0.0, s]).collect(),
        shadow: shadows.then(|| shadow_setup(scene, 1)),
        tsd: Some(tsd_setup(passes)),
        ..Default::default()
    }
}

#[test]
fn texture_space_diffusion_keeps_uniform_light_and_softens_a_shadow_edge() {
    let gpu = gpu();
    // Uniform light: the blurred, dilated light map equals Lambert everywhere on the floor.
    let open = inputs(floor_and_blocker(false));
    let lambert = middle_row(&render(&gpu, &open, &SkinSetup::default()));
    let tsd = middle_row(&render(&gpu, &open, &tsd_skin(&open, 3, false)));
    for x in 4..SIZE as usize - 4 {
        // Rgba16Float light map: half-float rounding of the irradiance.
        assert!((tsd[x] - lambert[x]).abs() < 2e-3 * lambert[x], "x {x}: tsd {} vs lambert {}", tsd[x], lambert[x]);
    }
    // A hard shadow edge (1-tap filter) is spread over more pixels by the blur passes.
    let blocked = inputs(floor_and_blocker(true));
    let width = |row: &[f32]| {
        let e = lit_value();
        row.iter().filter(|&&v| v > 0.05 * e && v < 0.95 * e).count()
    };
    let hard = width(&middle_row(&render(&gpu, &blocked, &tsd_skin(&blocked, 0, true))));
    let soft = width(&middle_row(&render(&gpu, &blocked, &tsd_skin(&blocked, 4, true))));
    assert!(soft > hard, "four blur passes must widen the edge: {hard} vs {soft} pixels");
}

/// Surfaces whose UVs leave the light map's square (the sample head's eyes, at u + 1) are not
/// drawn into it: with texture-space diffusion they are shaded directly, Lambert and the key
/// light's shadow map, not from whatever the light map holds at its edge.
#[test]
fn tsd_shades_surfaces_outside_the_light_map_directly() {
    let gpu = gpu();
    let shifted = |blocker: bool| {
        let (mut v, i) = floor_and_blocker(blocker);
        for vertex in &mut v[..4] {
            vertex.uv[0] += 1.0;
        }
        inputs((v, i))
    };
    let open = shifted(false);
    let lambert = middle_row(&render(&gpu, &open, &SkinSetup::default()));
    let tsd = middle_row(&render(&gpu, &open, &tsd_skin(&open, 2, false)));
    for x in 8..SIZE as usize - 8 {
        assert!((tsd[x] - lambert[x]).abs() < 1e-3 * lambert[x], "x {x}: tsd {} vs lambert {}", tsd[x], lambert[x]);
    }
    let blocked = shifted(true);
    let direct = SkinSetup {
        features: Features { shadows: true, ..Default::default() },
        shadow: Some(shadow_setup(&blocked, 1)),
        ..Default::default()
    };
    let want = middle_row(&render(&gpu, &blocked, &direct));
    let got = middle_row(&render(&gpu, &blocked, &tsd_skin(&blocked, 2, true)));
    let half = SIZE as usize / 2;
    assert!(want[half - 8] < 1e-4 && want[half + 8] > 0.5 * lit_value(), "the blocker's shadow: {want:?}");
    for x in 8..SIZE as usize - 8 {
        assert!(
            (got[x] - want[x]).abs() <= 1e-3 * lit_value(),
            "x {x}: tsd {} vs shadowed lambert {}",
            got[x],
            want[x]
        );
    }
}

#[test]
fn tsd_gaussians_keep_uniform_light_and_scatter_red_farther_than_blue() {
    // The profile's Gaussians on a 20 mm floor (128 texels of 0.16 mm): the weights of each
    // channel sum to 1, so uniform light stays Lambert; at a shadow edge red's penumbra is wider
    // than blue's (red's widest Gaussian has sigma 2.7 mm, blue's 0.75 mm with weight 0.007).
    let gpu = gpu();
    let gaussians = |scene: &RenderInputs, shadows: bool| {
        let stretch = geometry::uv_stretch(&scene.vertices, &scene.indices, 10.0);
        let mut skin = tsd_skin(scene, 2, shadows);
        skin.vertex_skin = stretch.iter().map(|&s| [0.0, s]).collect();
        skin.mm_per_unit = 10.0;
        let tsd = skin.tsd.as_mut().unwrap();
        (tsd.kernel, tsd.kernel_mm) = (TsdKernel::Gaussians, skinkit_render::skin::tsd::GAUSSIANS_KERNEL_MM);
        tsd.kernel_scale = [setup::MAX_KERNEL_TEXELS, 0.0];
        skin
    };
    let row = |pixels: &[[f32; 4]], c: usize| -> Vec<f32> {
        let y = SIZE as usize / 2;
        (0..SIZE as usize).map(|x| pixels[y * SIZE as usize + x][c]).collect()
    };
    let open = inputs(floor_and_blocker(false));
    let lambert = render(&gpu, &open, &SkinSetup::default());
    let tsd = render(&gpu, &open, &gaussians(&open, false));
    for c in 0..3 {
        let (want, got) = (row(&lambert, c), row(&tsd, c));
        for x in 4..SIZE as usize - 4 {
            assert!((got[x] - want[x]).abs() < 3e-3 * want[x], "channel {c} x {x}: {} vs {}", got[x], want[x]);
        }
    }
    let blocked = inputs(floor_and_blocker(true));
    let edge = render(&gpu, &blocked, &gaussians(&blocked, true));
    let width = |c: usize| {
        let r = row(&edge, c);
        let lit = r.iter().cloned().fold(0.0f32, f32::max);
        r.iter().filter(|&&v| v > 0.05 * lit && v < 0.95 * lit).count()
    };
    // On a flat floor (UV stretch the same along u and v) more passes only make each
    // Gaussian's shape smoother: the edge keeps its place (the row's lit share) and its width.
    let edge_at = |passes: u32| {
        let mut skin = gaussians(&blocked, true);
        skin.tsd.as_mut().unwrap().passes = passes;
        let r = row(&render(&gpu, &blocked, &skin), 0);
        let lit = r.iter().cloned().fold(0.0f32, f32::max);
        let band = r.iter().filter(|&&v| v > 0.05 * lit && v < 0.95 * lit).count();
        (r.iter().map(|v| v / lit).sum::<f32>(), band)
    };
    let ((one, one_band), (eight, eight_band)) = (edge_at(1), edge_at(8));
    assert!((one - eight).abs() < 1.0, "the lit share of the row moved by {} pixels from 1 to 8 passes", one - eight);
    assert!(one_band.abs_diff(eight_band) <= 2, "the red penumbra: {one_band} pixels at 1 pass, {eight_band} at 8");
    let (red, blue) = (width(0), width(2));
    assert!(red > blue + 2, "red's penumbra must be wider than blue's: {red} vs {blue} pixels");
    // The same floor with its v range halved: a texel spans twice the mm along v as along u, and
    // the mean stretch sits between them. The stretch map widens the kernel along u (across this
    // edge) back to its size in mm, so the edge keeps its width; without it the edge would be
    // about 1.4x narrower.
    let (mut squashed, indices) = floor_and_blocker(true);
    for v in &mut squashed[..4] {
        v.uv[1] *= 0.5;
    }
    let squashed = inputs((squashed, indices));
    let r = row(&render(&gpu, &squashed, &gaussians(&squashed, true)), 0);
    let lit = r.iter().cloned().fold(0.0f32, f32::max);
    let squashed_red = r.iter().filter(|&&v| v > 0.05 * lit && v < 0.95 * lit).count();
    assert!(squashed_red.abs_diff(red) <= 2 + red / 10, "red's penumbra: {squashed_red} pixels squashed, {red} square");
}

#[test]
fn tsd_pass_list_follows_the_setup() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(true));
    let prepared = gpu.prepare_with(&scene, &tsd_skin(&scene, 2, true)).unwrap();
    assert_eq!(
        prepared.pass_names(),
        ["shadow map", "tsd back-face pre-pass", "tsd light map", "tsd blur 1", "tsd blur 2", "base"]
    );
    let plain = gpu.prepare(&scene).unwrap();
    assert_eq!(plain.pass_names(), ["base"]);
    if gpu.has_timestamps() {
        let target = gpu.create_target(SIZE, SIZE, OutputFormat::Hdr32).unwrap();
        let timed = gpu.draw_timed_passes(&prepared, &target).unwrap().unwrap();
        assert_eq!(timed.len(), 6);
        assert!(timed.iter().all(|(_, d)| *d > std::time::Duration::ZERO), "{timed:?}");
    }
}

#[test]
fn lut_path_reads_the_table_it_is_given() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(false));
    // A LUT that is 0.25 everywhere in red, 0.5 in green, 1 in blue: the floor's diffuse becomes
    // rho / pi * E * (0.25, 0.5, 1) whatever N.L and 1/r are.
    let table = Table { width: 8, height: 4, texels: vec![[0.25, 0.5, 1.0]; 32], scale: 1.0, offset: 0.0 };
    let skin = SkinSetup {
        features: Features { diffuse: DiffuseMode::Lut, ..Default::default() },
        diffuse_lut: Some(table),
        ..Default::default()
    };
    let pixels = render(&gpu, &scene, &skin);
    let centre = pixels[(SIZE / 2 * SIZE + SIZE / 2) as usize];
    let e = lit_value();
    for (c, k) in [0.25f32, 0.5, 1.0].iter().enumerate() {
        assert!((centre[c] - e * k).abs() < 1e-4, "channel {c}: {} vs {}", centre[c], e * k);
    }
}

#[test]
fn every_feature_combination_compiles_and_draws_finite_pixels() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(true));
    let table = || Some(Table { width: 4, height: 4, texels: vec![[0.5; 3]; 16], scale: 1.0, offset: 0.0 });
    let zonal = Some(Table { width: 4, height: 3, texels: vec![[1.0; 3]; 12], scale: 1.0, offset: 0.0 });
    let modes = [DiffuseMode::Lambert, DiffuseMode::Lut, DiffuseMode::Blog, DiffuseMode::OwnFit, DiffuseMode::LightMap];
    for diffuse in modes {
        for bits in 0..8u32 {
            let (shadows, sh_ambient, derivative_curvature) = (bits & 1 != 0, bits & 2 != 0, bits & 4 != 0);
            let features = Features {
                diffuse,
                derivative_curvature,
                sh_ambient,
                shadows,
                shadow_scattering: shadows && derivative_curvature,
                translucent_shadows: shadows && sh_ambient,
            };
            let mut skin = tsd_skin(&scene, 1, shadows);
            skin.features = features;
            if let Some(shadow) = skin.shadow.as_mut().filter(|_| features.translucent_shadows) {
                shadow.translucent = vec![lens()];
            }
            skin.tsd = (diffuse == DiffuseMode::LightMap).then(|| tsd_setup(1));
            skin.diffuse_lut = table();
            skin.shadow_lut = table();
            skin.zonal = zonal.clone();
            skin.sh[0] = [0.3, 0.3, 0.3];
            let pixels = render(&gpu, &scene, &skin);
            assert!(pixels.iter().flatten().all(|v| v.is_finite()), "{features:?}: non-finite pixels");
        }
    }
}

/// A translucent quad over x < 0 at z = 0.5 (where the opaque blocker sits in the other tests),
/// stopping 70% of red, nothing of green, 40% of blue.
fn lens() -> setup::TranslucentCaster {
    setup::TranslucentCaster {
        positions: vec![[-3.0, -3.0, 0.5], [0.0, -3.0, 0.5], [0.0, 3.0, 0.5], [-3.0, 3.0, 0.5]],
        indices: vec![0, 1, 2, 0, 2, 3],
        opacity: [0.7, 0.0, 0.4],
    }
}

#[test]
fn translucent_casters_tint_the_key_light_where_they_cover_it() {
    let gpu = gpu();
    // No opaque blocker: the floor alone, and the lens above its left half.
    let scene = inputs(floor_and_blocker(false));
    let mut shadow = shadow_setup(&scene, 1);
    shadow.translucent = vec![lens()];
    let skin = SkinSetup {
        features: Features { shadows: true, translucent_shadows: true, ..Default::default() },
        shadow: Some(shadow),
        ..Default::default()
    };
    let prepared = gpu.prepare_with(&scene, &skin).unwrap();
    assert_eq!(prepared.pass_names(), ["shadow map", "translucent shadows", "base"]);
    let pixels = render(&gpu, &scene, &skin);
    let y = SIZE as usize / 2;
    let at = |x: usize| pixels[y * SIZE as usize + x];
    let e = lit_value();
    let (left, right) = (at(16), at(SIZE as usize - 16));
    for (c, through) in [0.3f32, 1.0, 0.6].iter().enumerate() {
        assert!(
            (left[c] - e * through).abs() < 2e-3 * e,
            "under the lens, channel {c}: {} vs {}",
            left[c],
            e * through
        );
        assert!((right[c] - e).abs() < 1e-3 * e, "beside it, channel {c}: {} vs {e}", right[c]);
    }
    // Behind an opaque blocker the lens adds nothing (the blocker's own shadow is already black)
    // and without the feature the lens is ignored.
    let plain =
        render(&gpu, &scene, &SkinSetup { features: Features { shadows: true, ..Default::default() }, ..skin.clone() });
    let l = plain[y * SIZE as usize + 16];
    assert!((l[0] - e).abs() < 1e-3 * e, "without translucent shadows the lens is ignored: {}", l[0]);
}

#[test]
fn tsd_culling_skips_an_off_screen_head_and_reuses_a_distant_ones_light_map() {
    let gpu = gpu();
    let scene = inputs(floor_and_blocker(false));
    let target = gpu.create_target(SIZE, SIZE, OutputFormat::Hdr32).unwrap();
    // Frustum culling: looking away from the floor, no TSD pass runs (zero time) but the base does.
    let mut away = scene.clone();
    away.camera = Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, 10.0), Vec3::Y, 45.0, 1.0);
    let prepared = gpu.prepare_with(&away, &tsd_skin(&away, 2, false)).unwrap();
    if let Some(passes) = gpu.draw_timed_passes(&prepared, &target).unwrap() {
        for (name, d) in &passes {
            assert_eq!(name.starts_with("tsd"), d.is_zero(), "{name}: {d:?}");
        }
    }
    // Distance culling: with a threshold above the head's size the first frame fills the light
    // map and later frames keep it, so moving the light changes nothing; without it they follow.
    // From afar (the camera inside the head's bounding sphere never counts as distant).
    let mut scene = scene;
    scene.camera = Camera::look_at(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, Vec3::Y, 45.0, 1.0);
    let frame_after_moving_light = |reuse_below_px: f32| {
        let mut skin = tsd_skin(&scene, 1, false);
        skin.tsd.as_mut().unwrap().reuse_below_px = reuse_below_px;
        let mut prepared = gpu.prepare_with(&scene, &skin).unwrap();
        gpu.draw(&prepared, &target).unwrap();
        let dim = Light { kind: LightKind::Directional { toward: Vec3::Z }, color: Vec3::ONE, intensity: 1.0 };
        prepared.set_light(0, &dim);
        gpu.draw(&prepared, &target).unwrap();
        gpu.read(&target).unwrap().pixels[(SIZE / 2 * SIZE + SIZE / 2) as usize][0]
    };
    let e = lit_value();
    let reused = frame_after_moving_light(1e9);
    let updated = frame_after_moving_light(0.0);
    assert!((reused - e).abs() < 2e-3 * e, "the reused light map keeps the first frame's light: {reused} vs {e}");
    assert!((updated - e / 2.0).abs() < 2e-3 * e, "an updated light map follows the light: {updated} vs {}", e / 2.0);
}

#[test]
fn sh_ambient_matches_the_cpu_irradiance_of_the_environment() {
    use skinkit_render::skin::sh::Sh9;
    let gpu = gpu();
    let mut scene = inputs(floor_and_blocker(false));
    scene.lights[0].intensity = 0.0;
    // The floor faces +z; a gradient sky along +z gives it a closed-form irradiance.
    let sh = Sh9::gradient([0.6, 0.5, 0.4], [0.1, 0.05, 0.02], Vec3::Z);
    let skin = SkinSetup {
        features: Features { sh_ambient: true, ..Default::default() },
        sh: sh.coeffs,
        ..Default::default()
    };
    let pixels = render(&gpu, &scene, &skin);
    let centre = pixels[(SIZE / 2 * SIZE + SIZE / 2) as usize];
    let expected = sh.irradiance_lambert(Vec3::Z);
    for c in 0..3 {
        // rho_d / pi * E with rho_d = 0.5.
        let want = 0.5 / std::f32::consts::PI * expected[c];
        assert!((centre[c] - want).abs() < 1e-4 + 1e-4 * want, "channel {c}: {} vs {want}", centre[c]);
    }
}
