//! Flat fields (issue 39): a mold lit with a strong non-uniform falloff per light (each LED's
//! hotspot toward its own side of the field, an eighth of the hotspot's irradiance at the far
//! corner) is solved with and without its flats, against the same mold under uniform lights.

use glam::Vec3;
use skinkit_capture::flat::{FlatField, correct};
use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_capture::solve::{self, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Heightfield, Quantise, RenderConfig, RenderLight, SkinParams};
use skinkit_maps::io::{self, PngLayout};
use skinkit_maps::{Channels, NormalEncoding, Photo, Samples};

const SIDE: usize = 128;
const K: usize = 8;
/// Light intensity: keeps the brightest falloff-lit reading under full scale.
const INTENSITY: f32 = 0.3;

/// The falloff of light `i` at pixel `p`: an LED's hotspot at 0.8 of the way to the field's
/// edge toward the light, `(1 + d^2 / 1.5)^-1.5`, normalised to mean 1 over the field.
fn falloffs() -> Vec<Vec<f64>> {
    (0..K)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / K as f64;
            let (cx, cy) = (0.8 * a.cos(), -0.8 * a.sin());
            let raw: Vec<f64> = (0..SIDE * SIDE)
                .map(|p| {
                    let u = 2.0 * (p % SIDE) as f64 / (SIDE - 1) as f64 - 1.0;
                    let v = 2.0 * (p / SIDE) as f64 / (SIDE - 1) as f64 - 1.0;
                    (1.0 + ((u - cx).powi(2) + (v - cy).powi(2)) / 1.5).powf(-1.5)
                })
                .collect();
            let mean = raw.iter().sum::<f64>() / raw.len() as f64;
            raw.into_iter().map(|f| f / mean).collect()
        })
        .collect()
}

/// 16-bit photo of `values` (full scale 1).
fn u16_photo(values: impl Iterator<Item = f64>) -> Photo {
    let v = values.map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16).collect();
    Photo::new(SIDE, SIDE, Channels::Gray, Samples::U16(v)).unwrap()
}

fn linear(photo: &Photo) -> Vec<f64> {
    (0..photo.pixel_count()).map(|i| photo.linear(i) as f64).collect()
}

fn mean_error(field: &Heightfield, photos: Vec<Photo>, rig: &Rig) -> f32 {
    let stack = PhotoStack::new(photos, (1..=K).map(|i| format!("{i:02}.png")).collect()).unwrap();
    let solution = solve::solve(&stack, rig, &SolveConfig::default(), &solve::NoProgress).unwrap();
    solution.normals.angular_error(&field.normals, None).unwrap().mean
}

/// The 16-bit samples of a photo `u16_photo` made.
fn u16_samples(photo: &Photo) -> &[u16] {
    let Samples::U16(v) = photo.samples() else { panic!("16-bit photo") };
    v
}

/// A session folder whose photos have the falloff, with the flats in `flats/` and a rig that
/// names them (or not): the capture reports the correction and its error drops.
#[test]
fn a_session_with_flats_in_its_rig_corrects_them() {
    let field = SkinParams::cheek(SIDE, SIDE, 4).generate().unwrap();
    let lights = RenderLight::ring(K, 45.0, Vec3::splat(INTENSITY));
    let render = RenderConfig { shadows: true, format: Quantise::Float, seed: 3, ..RenderConfig::default() };
    let uniform = skinkit_heightfield::render(&field, &lights, &render).unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("flats")).unwrap();
    let mut rig_text = String::new();
    for (i, ((photo, f), l)) in uniform.iter().zip(falloffs()).zip(&lights).enumerate() {
        let lit = u16_photo(linear(photo).into_iter().zip(&f).map(|(v, f)| v * f));
        let flat = u16_photo(f.iter().map(|f| 0.5 * INTENSITY as f64 * f));
        io::write_png(&dir.path().join(format!("{:02}.png", i + 1)), SIDE, SIDE, PngLayout::Gray16, u16_samples(&lit))
            .unwrap();
        let flat_name = format!("flats/flat-{:02}.png", i + 1);
        io::write_png(&dir.path().join(&flat_name), SIDE, SIDE, PngLayout::Gray16, u16_samples(&flat)).unwrap();
        let d = l.direction;
        rig_text += &format!(
            "[[light]]\ndirection = [{}, {}, {}]\nintensity = {INTENSITY}\nflat = \"{flat_name}\"\n",
            d.x, d.y, d.z
        );
    }
    io::write_normal_map(&dir.path().join("truth.png"), &field.normals, NormalEncoding::default(), 16).unwrap();
    let error = |rig: &str| {
        std::fs::write(dir.path().join("rig.toml"), rig).unwrap();
        let files = Session::from_dir(dir.path()).unwrap();
        assert_eq!(files.photos.len(), K, "flats in their own folder are not photos");
        let captured =
            session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress).unwrap();
        (captured.report.error_vs_truth_degrees.unwrap().mean, captured.report.corrections)
    };
    let (with, corrections) = error(&rig_text);
    assert_eq!(corrections, vec![format!("flat fields ({K} of {K} lights)")]);
    let without_flats: String = rig_text.lines().filter(|l| !l.starts_with("flat")).map(|l| format!("{l}\n")).collect();
    let (without, none) = error(&without_flats);
    assert!(none.is_empty());
    eprintln!("session with falloff (detrended): {without:.3} deg without flats, {with:.3} with");
    assert!(3.0 * with <= without, "flats: {with} against {without} without");
}

#[test]
fn flats_remove_a_strong_falloff() {
    let field = SkinParams::cheek(SIDE, SIDE, 4).generate().unwrap();
    let lights = RenderLight::ring(K, 45.0, Vec3::splat(INTENSITY));
    let render =
        RenderConfig { shadows: true, noise_sigma: 0.002, format: Quantise::Float, seed: 3, ..RenderConfig::default() };
    let uniform = skinkit_heightfield::render(&field, &lights, &render).unwrap();
    let rig_lights: Vec<Light> = lights.iter().map(|l| Light::new(l.direction, l.intensity, None).unwrap()).collect();
    let rig = Rig::new(rig_lights, "ring").unwrap();
    let falloff = falloffs();
    let lit: Vec<Photo> = uniform
        .iter()
        .zip(&falloff)
        .map(|(photo, f)| u16_photo(linear(photo).into_iter().zip(f).map(|(v, f)| v * f)))
        .collect();
    // White target photos under each light: 0.8 of the falloff, with the cosine of a flat target.
    let corrected: Vec<Photo> = lit
        .iter()
        .zip(&falloff)
        .zip(&lights)
        .enumerate()
        .map(|(i, ((photo, f), l))| {
            let cos = l.direction.normalize().z as f64;
            let target = u16_photo(f.iter().map(|f| 0.8 * cos * INTENSITY as f64 * f));
            let flat = FlatField::from_photo(&target, None, &format!("flat-{i:02}.png")).unwrap();
            correct(photo, None, Some(&flat), 0.995, &format!("{i:02}.png")).unwrap()
        })
        .collect();
    let uniform16: Vec<Photo> = uniform.iter().map(|p| u16_photo(linear(p).into_iter())).collect();
    let (without, with, even) =
        (mean_error(&field, lit, &rig), mean_error(&field, corrected, &rig), mean_error(&field, uniform16, &rig));
    eprintln!("falloff, mean error: without flats {without:.3} deg, with {with:.3}, uniform lights {even:.3}");
    assert!(3.0 * with <= without, "flats: {with} against {without} without");
    assert!(with <= 1.1 * even, "flats: {with} against {even} under uniform lights");
}

/// The rig's radial vignetting model (issue 39): its gain against the polynomial evaluated here,
/// and a cheek photographed through a vignetting lens solved with and without the model.
#[test]
fn a_vignetting_model_removes_lens_falloff() {
    let k = [-0.45f32, 0.08];
    let radial = |p: usize| {
        let c = (SIDE as f64 - 1.0) / 2.0;
        let (dx, dy) = ((p % SIDE) as f64 - c, (p / SIDE) as f64 - c);
        let r2 = (dx * dx + dy * dy) / (2.0 * c * c);
        1.0 + k[0] as f64 * r2 + k[1] as f64 * r2 * r2
    };
    let model = FlatField::vignetting(SIDE, SIDE, &k).unwrap();
    let (centre, corner) = (SIDE / 2 * SIDE + SIDE / 2, 0);
    let want = radial(corner) / radial(centre);
    let got = (model.gain()[corner] / model.gain()[centre]) as f64;
    assert!((got - want).abs() < 1e-4 * want, "corner/centre gain {got} vs {want}");
    let mean = model.gain().iter().map(|&g| g as f64).sum::<f64>() / (SIDE * SIDE) as f64;
    assert!((mean - 1.0).abs() < 1e-5, "mean gain {mean}");

    let field = SkinParams::cheek(SIDE, SIDE, 4).generate().unwrap();
    let lights = RenderLight::ring(K, 45.0, Vec3::splat(0.5));
    let render =
        RenderConfig { shadows: true, noise_sigma: 0.002, format: Quantise::Float, seed: 8, ..RenderConfig::default() };
    let uniform = skinkit_heightfield::render(&field, &lights, &render).unwrap();
    let rig_lights: Vec<Light> = lights.iter().map(|l| Light::new(l.direction, l.intensity, None).unwrap()).collect();
    let rig = Rig::new(rig_lights, "ring").unwrap();
    let vignetted: Vec<Photo> =
        uniform.iter().map(|p| u16_photo(linear(p).into_iter().enumerate().map(|(i, v)| v * radial(i)))).collect();
    let corrected: Vec<Photo> = vignetted
        .iter()
        .enumerate()
        .map(|(i, p)| correct(p, None, Some(&model), 0.995, &format!("{i:02}.png")).unwrap())
        .collect();
    let uniform16: Vec<Photo> = uniform.iter().map(|p| u16_photo(linear(p).into_iter())).collect();
    // A gain shared by every light scales each pixel's readings alike: the normals do not see it,
    // the albedo does. The gain is normalised to mean 1, so the albedo keeps a common scale:
    // measured is how far it strays from its own mean (the render's is a constant 0.7).
    let albedo_error = |photos: Vec<Photo>| {
        let stack = PhotoStack::new(photos, (1..=K).map(|i| format!("{i:02}.png")).collect()).unwrap();
        let solution = solve::solve(&stack, &rig, &SolveConfig::default(), &solve::NoProgress).unwrap();
        let solve::AlbedoMap::Gray(a) = solution.albedo else { panic!("grey photos give grey albedo") };
        let valid: Vec<f64> = a.as_slice().iter().filter(|v| **v > 0.0).map(|&v| v as f64).collect();
        let mean = valid.iter().sum::<f64>() / valid.len() as f64;
        valid.iter().map(|v| (v / mean - 1.0).abs()).sum::<f64>() / valid.len() as f64
    };
    let (without, with, even) = (albedo_error(vignetted), albedo_error(corrected), albedo_error(uniform16));
    eprintln!(
        "vignetting (corner at {want:.2} of the centre), albedo mean relative deviation: without the model {without:.4}, \
         with {with:.4}, none {even:.4}"
    );
    assert!(
        3.0 * with <= without && with <= 1.1 * even + 1e-3,
        "vignetting: {with} with, {without} without, {even} none"
    );
    // The rig file: parsed, listed among the corrections, round-tripped.
    let text = format!("vignetting = [{}, {}]\n{}", k[0], k[1], rig.to_toml_string());
    let parsed = Rig::parse(&text, "rig.toml").unwrap();
    assert_eq!(parsed.vignetting(), &k);
    assert_eq!(Rig::parse(&parsed.to_toml_string(), "again").unwrap(), parsed);
    assert_eq!(
        session::corrections(&parsed, false),
        vec![format!("vignetting model ({K} of {K} lights, those without flats)")]
    );
}
