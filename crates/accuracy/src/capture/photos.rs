//! Capture from the lab's own photos (issue 39): exposure brackets against a single exposure,
//! and camera RAW (half-size DNG) against the same photos as 16-bit TIFF.
//!
//! Brackets: 8 lights, 2 % additive sensor noise in every frame, the single exposure (t = 1) set
//! so 5 % of its noiseless readings reach full scale; brackets at t = 0.5, 1, 2 merged
//! ([`skinkit_capture::bracket::merge`]); time of the merge and the solve.
//! RAW: the mold's RGB photos under 8 lights (0.5 % noise) as 16-bit samples, and as DNGs of a
//! sensor twice the size (RGGB, black 512, white 16383) decoded at half size; time of the
//! solve, plus the decoding for the DNGs.

use std::path::Path;

use glam::Vec3;
use skinkit_capture::bracket;
use skinkit_capture::solve::{self, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::dng::dng_of_rgb;
use skinkit_heightfield::{Heightfield, Quantise, RenderConfig, RenderLight};
use skinkit_maps::raw::{self, RawMode};
use skinkit_maps::{Channels, Limits, NormalMap, Photo, Samples};

use super::POLAR_DEG;
use crate::choice::{Choice, knobs, metrics};
use crate::timing::median_of;
use crate::{Config, Result};

const K: usize = 8;
/// The cases, in report order.
pub const CASES: [&str; 4] = ["single exposure", "three brackets", "16-bit TIFF", "DNG, half size"];
const TIMES: [f32; 3] = [0.5, 1.0, 2.0];
const BRACKET_NOISE: f32 = 0.02;

/// One case's error and time.
pub fn choice(field: &Heightfield, case: &str, config: &Config) -> Result<Choice> {
    let (normals, seconds, noise) = match case {
        "single exposure" | "three brackets" => {
            let photos = brackets(field, config.seed)?;
            let (n, s) = median_of(config.runs(), || solve_brackets(field, &photos, case == "three brackets"));
            (n?, s, BRACKET_NOISE)
        }
        _ => {
            let (n, s) = median_of(config.runs(), || solve_raw(field, case == "DNG, half size", config.seed));
            (n?, s, 0.005)
        }
    };
    let stats = normals.angular_error(&field.normals, None)?;
    let pixels = (field.width() * field.height()).max(1) as f64;
    let invalid = 100.0 * (pixels - normals.valid_count() as f64) / pixels;
    Ok(Choice::timed(
        &format!("photos: {case}"),
        case,
        knobs(&[("lights", K.to_string()), ("noise", noise.to_string()), ("photos", case.to_owned())]),
        metrics(&[
            ("mean angular error (deg)", stats.mean as f64),
            ("p95 angular error (deg)", stats.p95 as f64),
            ("invalid pixels (%)", invalid),
        ]),
        seconds,
        config.runs(),
    ))
}

fn ring(intensity: Vec3) -> Vec<RenderLight> {
    RenderLight::ring(K, POLAR_DEG, intensity)
}

fn rig_of(lights: &[RenderLight], scale: f32) -> Result<Rig> {
    let rig_lights = lights
        .iter()
        .map(|l| Light::new(l.direction, l.intensity * scale, None))
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(skinkit_capture::Error::InvalidInput)?;
    Ok(Rig::new(rig_lights, "ring of 8")?)
}

/// The light intensity at which 5 % of the noiseless readings reach full scale at t = 1.
fn clipping_intensity(field: &Heightfield) -> Result<f32> {
    let render = RenderConfig { shadows: true, format: Quantise::Float, ..RenderConfig::default() };
    let photos = skinkit_heightfield::render(field, &ring(Vec3::ONE), &render)?;
    let mut all: Vec<f32> = photos.iter().flat_map(|p| (0..p.pixel_count()).map(|i| p.linear(i))).collect();
    all.sort_by(f32::total_cmp);
    Ok(1.0 / all[(0.95 * all.len() as f64) as usize].max(1e-6))
}

/// The photos at each of [`TIMES`] (16-bit, clipped, their own noise), and the intensity.
fn brackets(field: &Heightfield, seed: u64) -> Result<(Vec<Vec<Photo>>, f32)> {
    let intensity = clipping_intensity(field)?;
    let mut out = Vec::with_capacity(TIMES.len());
    for (j, &t) in TIMES.iter().enumerate() {
        let render = RenderConfig {
            shadows: true,
            exposure: t,
            noise_sigma: BRACKET_NOISE,
            format: Quantise::U16,
            seed: seed + 100 + j as u64,
            ..RenderConfig::default()
        };
        out.push(skinkit_heightfield::render(field, &ring(Vec3::splat(intensity)), &render)?);
    }
    Ok((out, intensity))
}

fn names() -> Vec<String> {
    (1..=K).map(|i| format!("{i:02}")).collect()
}

/// The single exposure (t = 1) or the three brackets merged, solved.
fn solve_brackets(field: &Heightfield, (photos, intensity): &(Vec<Vec<Photo>>, f32), merge: bool) -> Result<NormalMap> {
    let lights = ring(Vec3::splat(*intensity));
    let config = SolveConfig::default();
    let (stack, rig) = if merge {
        let mut merged = Vec::with_capacity(K);
        for i in 0..K {
            let frames: Vec<Photo> = photos.iter().map(|b| b[i].clone()).collect();
            merged.push(bracket::merge(
                &frames,
                &TIMES,
                config.saturation,
                bracket::FLOOR,
                &format!("light {}", i + 1),
            )?);
        }
        (PhotoStack::new(merged, names())?, rig_of(&lights, TIMES[0])?)
    } else {
        (PhotoStack::new(photos[1].clone(), names())?, rig_of(&lights, 1.0)?)
    };
    debug_assert_eq!(stack.width(), field.width());
    Ok(solve::solve(&stack, &rig, &config, &solve::NoProgress)?.normals)
}

/// The RGB photos as 16-bit samples, or written as DNGs and decoded at half size, solved.
fn solve_raw(field: &Heightfield, dng: bool, seed: u64) -> Result<NormalMap> {
    let intensity = Vec3::new(0.42, 0.36, 0.27);
    let render = RenderConfig {
        shadows: true,
        noise_sigma: 0.005,
        channels: Channels::Rgb,
        format: Quantise::Float,
        seed,
        ..RenderConfig::default()
    };
    let lights = ring(intensity);
    let rendered = skinkit_heightfield::render(field, &lights, &render)?;
    let (w, h) = (field.width(), field.height());
    let mut photos = Vec::with_capacity(K);
    for (i, photo) in rendered.iter().enumerate() {
        let Samples::F32(v) = photo.samples() else { unreachable!("float render") };
        photos.push(if dng {
            let rgb: Vec<[f32; 3]> = v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            let file = dng_of_rgb(&rgb, w, h, [0, 1, 1, 2], 512, 16383);
            raw::decode(Path::new(&format!("{:02}.dng", i + 1)), &file, &Limits::default(), RawMode::Half)?
        } else {
            let q = v.iter().map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16).collect();
            Photo::new(w, h, Channels::Rgb, Samples::U16(q))?
        });
    }
    let stack = PhotoStack::new(photos, names())?;
    Ok(solve::solve(&stack, &rig_of(&lights, 1.0)?, &SolveConfig::default(), &solve::NoProgress)?.normals)
}

#[cfg(test)]
mod tests {
    use super::*;
    use skinkit_heightfield::SkinParams;

    /// Brackets beat the single exposure; the half-size DNG matches the 16-bit TIFF within 0.1
    /// degrees mean error.
    #[test]
    fn brackets_beat_one_exposure_and_raw_matches_tiff() {
        let config = Config { quick: true, seed: 2, samples: std::path::PathBuf::new() };
        let field = SkinParams::cheek(96, 96, 2).generate().unwrap();
        let e = |case| choice(&field, case, &config).unwrap().metric("mean angular error (deg)").unwrap();
        let (single, merged, tiff, dng) = (e(CASES[0]), e(CASES[1]), e(CASES[2]), e(CASES[3]));
        eprintln!("single {single:.3}, brackets {merged:.3}; TIFF {tiff:.4}, DNG {dng:.4}");
        assert!(merged < single, "brackets {merged} against {single}");
        assert!((dng - tiff).abs() < 0.1, "DNG {dng} against TIFF {tiff}");
    }
}
