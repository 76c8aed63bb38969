//! Rendered photos against hand-computed shading: Lambert on flat fields, near-light falloff, the
//! orientation of a bump, cast shadows behind a ridge, saturation, noise statistics and
//! determinism.

use glam::{DVec2, Vec3};
use skinkit_heightfield::render::{Albedo, Quantise, RenderConfig, RenderLight, Specular, render, render_ambient};
use skinkit_heightfield::{HeightSample, Heightfield, SkinParams, generate};
use skinkit_maps::{Channels, ColorMap, Photo, Samples};

fn flat(w: usize, h: usize) -> Heightfield {
    generate(&SkinParams::flat(w, h, 0.05, 0)).unwrap()
}

fn rgb_float() -> RenderConfig {
    RenderConfig { channels: Channels::Rgb, ..RenderConfig::default() }
}

fn f32s(photo: &Photo) -> &[f32] {
    match photo.samples() {
        Samples::F32(v) => v,
        other => panic!("expected float samples, got {}-bit", other.bit_depth()),
    }
}

#[test]
fn flat_field_gives_albedo_times_irradiance_times_cosine() {
    let field = flat(12, 9);
    let albedo = Vec3::new(0.6, 0.5, 0.3);
    let config = RenderConfig { albedo: Albedo::Constant(albedo), ..rgb_float() };
    let dir = Vec3::new(0.3, -0.5, 0.8);
    let e = Vec3::new(0.9, 1.0, 1.1);
    let photos = render(&field, &[RenderLight::directional(dir, e)], &config).unwrap();
    let cos = 0.8 / (0.09f64 + 0.25 + 0.64).sqrt();
    for (i, v) in f32s(&photos[0]).iter().enumerate() {
        let expect = albedo[i % 3] as f64 * e[i % 3] as f64 * cos;
        assert!((*v as f64 - expect).abs() < 1e-6, "sample {i}: {v} vs {expect}");
    }
    // Grey photos carry the Rec. 709 luminance of the same values.
    let grey =
        render(&field, &[RenderLight::directional(dir, e)], &RenderConfig { channels: Channels::Gray, ..config })
            .unwrap();
    let lum = (0.2126 * 0.54 + 0.7152 * 0.5 + 0.0722 * 0.33) * cos;
    assert!(f32s(&grey[0]).iter().all(|v| (*v as f64 - lum).abs() < 1e-6));
}

#[test]
fn near_light_falls_off_with_distance_and_is_exact_at_the_centre() {
    let field = flat(21, 15);
    let p = glam::DVec3::new(3.0, -2.0, 10.0);
    let light = RenderLight::point(p.as_vec3(), Vec3::ONE);
    let config = RenderConfig { albedo: Albedo::Constant(Vec3::ONE), ..RenderConfig::default() };
    let photo = &render(&field, &[light], &config).unwrap()[0];
    for row in 0..15 {
        for col in 0..21 {
            let (x, y) = field.texel_to_mm(col, row);
            let d = p - glam::DVec3::new(x, y, 0.0);
            // Irradiance |P|^2 / |P - X|^2 times the cosine d.z / |d| (flat normal +z).
            let expect = p.length_squared() / d.length_squared() * d.z / d.length();
            let v = f32s(photo)[row * 21 + col] as f64;
            assert!((v - expect).abs() < 1e-6, "({col}, {row}): {v} vs {expect}");
        }
    }
    // The centre texel sits at the origin: exactly E * cos of the direction to the light.
    assert!((f32s(photo)[7 * 21 + 10] as f64 - 10.0 / p.length()).abs() < 1e-6);
}

#[test]
fn a_bump_lit_from_the_top_of_the_image_is_brighter_on_top() {
    // A smooth bump at the centre (y up); light from +y, i.e. toward image row 0.
    let bump = |x: f64, y: f64| {
        let h = 0.2 * (-(x * x + y * y) / 0.5).exp();
        HeightSample { height: h, gradient: DVec2::new(x, y) * (-2.0 * h / 0.5) }
    };
    let field = Heightfield::from_fn(41, 41, 0.05, bump).unwrap();
    let light = RenderLight::directional(Vec3::new(0.0, 0.7, 0.7), Vec3::ONE);
    let photo = &render(&field, &[light], &RenderConfig::default()).unwrap()[0];
    let at = |col: usize, row: usize| f32s(photo)[row * 41 + col];
    assert!(at(20, 12) > 1.2 * at(20, 28), "upper flank {} lower flank {}", at(20, 12), at(20, 28));
    assert!((at(12, 20) - at(28, 20)).abs() < 1e-6, "left and right flanks differ");
}

/// A ridge along y at x = 0, 0.5 mm tall: light from +x at 30 deg elevation throws its shadow
/// toward -x, reaching about 0.5 / tan 30 = 0.87 mm from the crest on flat ground.
fn ridge() -> Heightfield {
    let f = |x: f64, _y: f64| {
        let h = 0.5 * (-x * x / (2.0 * 0.1 * 0.1)).exp();
        HeightSample { height: h, gradient: DVec2::new(-x / 0.01 * h, 0.0) }
    };
    Heightfield::from_fn(100, 10, 0.05, f).unwrap()
}

#[test]
fn a_ridge_casts_a_shadow_away_from_the_light() {
    let field = ridge();
    let (elevation, e) = (30f32.to_radians(), 1.0);
    let light = RenderLight::directional(Vec3::new(elevation.cos(), 0.0, elevation.sin()), Vec3::splat(e));
    let config = RenderConfig { shadows: true, albedo: Albedo::Constant(Vec3::ONE), ..RenderConfig::default() };
    let photo = &render(&field, &[light], &config).unwrap()[0];
    let lit = elevation.sin();
    for row in 0..10 {
        for col in 0..100 {
            let x = field.texel_to_mm(col, row).0;
            let v = f32s(photo)[row * 100 + col];
            if (-0.75..-0.35).contains(&x) {
                assert_eq!(v, 0.0, "x = {x} should be in the cast shadow");
            } else if !(-1.0..=0.6).contains(&x) {
                assert!((v - lit).abs() < 1e-5, "x = {x} should be lit: {v}");
            }
        }
    }
    // Without shadows the same ground is lit.
    let unshadowed = &render(&field, &[light], &RenderConfig { shadows: false, ..config }).unwrap()[0];
    let x_col = 40; // x = -0.475 mm, where the ridge's tail tilts the normal by about 3e-4
    assert!((f32s(unshadowed)[x_col] - lit).abs() < 1e-3 && f32s(photo)[x_col] == 0.0);
}

#[test]
fn near_light_shadows_stop_at_the_light() {
    // A near light 0.6 mm beside the crest and 0.1 mm up, far below its top: the ground beyond the
    // ridge is shadowed, the ground on the light's side is lit even though the line from it through
    // the light, continued, would hit the ridge.
    let field = ridge();
    let light = RenderLight::point(Vec3::new(0.6, 0.0, 0.1), Vec3::ONE);
    let config = RenderConfig { shadows: true, ..RenderConfig::default() };
    let photo = &render(&field, &[light], &config).unwrap()[0];
    let value_at = |x_mm: f64| f32s(photo)[5 * 100 + ((x_mm / 0.05) + 49.5).round() as usize];
    assert_eq!(value_at(-1.0), 0.0);
    assert!(value_at(2.4) > 0.0 && value_at(0.3) > 0.0);
}

#[test]
fn saturation_clips_to_full_scale() {
    let field = flat(4, 4);
    let light = [RenderLight::directional(Vec3::Z, Vec3::ONE)];
    let base = RenderConfig { albedo: Albedo::Constant(Vec3::splat(0.5)), ..RenderConfig::default() };
    let cases = [
        (Quantise::U16, 1.0, 32768.0),
        (Quantise::U16, 3.0, 65535.0),
        (Quantise::U8, 1.0, 128.0),
        (Quantise::U8, 3.0, 255.0),
        (Quantise::Float, 3.0, 1.0),
        (Quantise::U16, -1.0, 0.0),
    ];
    for (format, exposure, expect) in cases {
        let photo = &render(&field, &light, &RenderConfig { format, exposure, ..base.clone() }).unwrap()[0];
        let s = photo.samples();
        assert!((0..s.len()).all(|i| s.get(i) == expect), "{format:?} x{exposure}: {} vs {expect}", s.get(0));
    }
}

#[test]
fn noise_has_the_requested_standard_deviation() {
    let field = flat(128, 128);
    let config =
        RenderConfig { albedo: Albedo::Constant(Vec3::splat(0.5)), noise_sigma: 0.01, seed: 17, ..rgb_float() };
    let photos = render(&field, &[RenderLight::directional(Vec3::Z, Vec3::ONE); 2], &config).unwrap();
    let v = f32s(&photos[0]);
    let n = v.len() as f64;
    let mean = v.iter().map(|&x| x as f64).sum::<f64>() / n;
    let sd = (v.iter().map(|&x| (x as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    // 49152 samples: the standard error of the estimate is 0.3 %.
    assert!((sd / 0.01 - 1.0).abs() < 0.03, "sd {sd}");
    assert!((mean - 0.5).abs() < 3e-4, "mean {mean}");
    assert_ne!(photos[0], photos[1], "two lights share a noise stream");
}

#[test]
fn photos_are_identical_whatever_the_thread_count() {
    let field = generate(&SkinParams::nose(80, 64, 3)).unwrap();
    let lights = RenderLight::ring(3, 60.0, Vec3::new(1.0, 0.9, 0.8));
    let config = RenderConfig {
        shadows: true,
        specular: Some(Specular { strength: 0.2, shininess: 20.0 }),
        ambient: Vec3::splat(0.01),
        noise_sigma: 0.02,
        channels: Channels::Rgb,
        format: Quantise::U16,
        seed: 5,
        ..RenderConfig::default()
    };
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap();
    let one = pool(1).install(|| render(&field, &lights, &config).unwrap());
    let two = pool(2).install(|| render(&field, &lights, &config).unwrap());
    assert_eq!(one, two);
    let reseeded = render(&field, &lights, &RenderConfig { seed: 6, ..config }).unwrap();
    assert_ne!(one, reseeded);
}

#[test]
fn specular_ambient_and_albedo_maps_add_up() {
    let field = flat(6, 4);
    let light = [RenderLight::directional(Vec3::new(0.6, 0.0, 0.8), Vec3::ONE)];
    let map = ColorMap::from_fn(6, 4, |x, _| Vec3::splat(0.1 * x as f32));
    let config = RenderConfig {
        albedo: Albedo::Map(map),
        specular: Some(Specular { strength: 0.5, shininess: 8.0 }),
        ambient: Vec3::splat(0.05),
        exposure: 0.5,
        ..RenderConfig::default()
    };
    let photo = &render(&field, &light, &config).unwrap()[0];
    // Half vector of L = (0.6, 0, 0.8) and V = (0, 0, 1): n.H = 1.8 / |(0.6, 0, 1.8)|.
    let n_dot_h = 1.8 / (0.36f64 + 3.24).sqrt();
    for col in 0..6 {
        let expect = 0.5 * (0.1 * col as f64 * 0.8 + 0.5 * n_dot_h.powi(8) + 0.05);
        assert!((f32s(photo)[col] as f64 - expect).abs() < 1e-6, "col {col}");
    }
    let dark = render_ambient(&field, &config).unwrap();
    assert!(f32s(&dark).iter().all(|v| (v - 0.025).abs() < 1e-7));
}

#[test]
fn bad_inputs_are_refused_with_names() {
    let field = flat(4, 4);
    let config = RenderConfig::default();
    let err = render(
        &field,
        &[
            RenderLight::directional(Vec3::Z, Vec3::ONE),
            RenderLight { direction: Vec3::ZERO, ..RenderLight::directional(Vec3::Z, Vec3::ONE) },
        ],
        &config,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("render light 1") && err.contains("direction"), "{err}");
    let wrong = RenderConfig { albedo: Albedo::Map(ColorMap::filled(3, 4, Vec3::ONE)), ..config.clone() };
    assert!(render(&field, &[], &wrong).unwrap_err().to_string().contains("3x4"));
    let noisy = RenderConfig { noise_sigma: -1.0, ..config };
    assert!(render_ambient(&field, &noisy).is_err());
}

#[test]
fn no_shadow_acne_under_a_high_light() {
    // Cheek slopes stay under 60 deg (53 at this seed), so no ray rising at 60 deg above the mean
    // plane (a light 30 deg off the camera axis) can meet the surface: shadowed and unshadowed
    // photos must agree, except where the bilinear height grid misleads the march (allowed: 0.1 %
    // of texels; none at this seed).
    let field = generate(&SkinParams::cheek(256, 256, 21)).unwrap();
    let max_tilt = field.normals.as_slice().iter().map(|n| n.z.acos().to_degrees()).fold(0.0, f32::max);
    assert!(max_tilt < 58.0, "field too steep for this test: {max_tilt}");
    let lights = RenderLight::ring(4, 30.0, Vec3::ONE);
    let with = render(&field, &lights, &RenderConfig { shadows: true, ..RenderConfig::default() }).unwrap();
    let without = render(&field, &lights, &RenderConfig::default()).unwrap();
    for (a, b) in with.iter().zip(&without) {
        let differ = f32s(a).iter().zip(f32s(b)).filter(|(x, y)| x != y).count();
        assert!(differ * 1000 <= a.pixel_count(), "{differ} texels shadowed");
    }
    // A grazing light (10 deg above the plane) does find real cast shadows behind pore rims.
    let low = render(
        &field,
        &RenderLight::ring(1, 80.0, Vec3::ONE),
        &RenderConfig { shadows: true, ..RenderConfig::default() },
    )
    .unwrap();
    let dark = f32s(&low[0]).iter().filter(|v| **v == 0.0).count();
    assert!(dark > 100, "only {dark} dark texels under a grazing light");
}
