//! Exposure brackets (issue 39): a session whose single exposure clips about 5 % of the readings
//! and buries the furrows in sensor noise, against three brackets of it merged
//! ([`skinkit_capture::bracket::merge`]): the merge has a lower mean error than any one exposure.

use std::path::Path;

use glam::Vec3;
use skinkit_capture::bracket;
use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_capture::solve::{self, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Heightfield, Quantise, RenderConfig, RenderLight, SkinParams};
use skinkit_maps::io::{self, PngLayout};
use skinkit_maps::{NormalEncoding, Photo, Samples};

const SIDE: usize = 128;
const K: usize = 8;
/// Exposure times of the brackets, a stop apart; the middle one is "the" single exposure.
const TIMES: [f32; 3] = [0.5, 1.0, 2.0];
/// Additive sensor noise, as a fraction of full scale, in every frame.
const NOISE: f32 = 0.02;
/// The share of readings the single exposure clips.
const CLIP_SHARE: f64 = 0.05;

/// The 8 photos of one exposure time, 16-bit, clipped at full scale, with their own noise.
fn exposure(field: &Heightfield, lights: &[RenderLight], time: f32, seed: u64) -> Vec<Photo> {
    let render = RenderConfig {
        shadows: true,
        exposure: time,
        noise_sigma: NOISE,
        format: Quantise::U16,
        seed,
        ..RenderConfig::default()
    };
    skinkit_heightfield::render(field, lights, &render).unwrap()
}

/// The light intensity at which the noiseless readings' top [`CLIP_SHARE`] reach full scale at
/// t = 1.
fn intensity_clipping(field: &Heightfield) -> f32 {
    let lights = RenderLight::ring(K, 45.0, Vec3::ONE);
    let render = RenderConfig { shadows: true, format: Quantise::Float, ..RenderConfig::default() };
    let photos = skinkit_heightfield::render(field, &lights, &render).unwrap();
    let mut all: Vec<f32> = photos.iter().flat_map(|p| (0..p.pixel_count()).map(|i| p.linear(i))).collect();
    all.sort_by(f32::total_cmp);
    1.0 / all[((1.0 - CLIP_SHARE) * all.len() as f64) as usize]
}

/// Mean angular error over the solved pixels, and how many pixels could not be solved.
fn mean_error(field: &Heightfield, photos: Vec<Photo>, rig: &Rig) -> (f32, usize) {
    let stack = PhotoStack::new(photos, (1..=K).map(|i| format!("{i:02}")).collect()).unwrap();
    let solution = solve::solve(&stack, rig, &SolveConfig::default(), &solve::NoProgress).unwrap();
    let e = solution.normals.angular_error(&field.normals, None).unwrap();
    (e.mean, solution.stats.invalid_count)
}

fn clipped_share(photos: &[Photo]) -> f64 {
    let total: usize = photos.iter().map(|p| p.pixel_count()).sum();
    let clipped: usize =
        photos.iter().map(|p| (0..p.pixel_count()).filter(|&i| p.samples().get(i) >= 0.995 * 65535.0).count()).sum();
    clipped as f64 / total as f64
}

#[test]
fn three_brackets_beat_every_single_exposure() {
    let field = SkinParams::cheek(SIDE, SIDE, 21).generate().unwrap();
    let lights = RenderLight::ring(K, 45.0, Vec3::splat(intensity_clipping(&field)));
    let rig_lights: Vec<Light> = lights.iter().map(|l| Light::new(l.direction, l.intensity, None).unwrap()).collect();
    let brackets: Vec<Vec<Photo>> =
        TIMES.iter().enumerate().map(|(j, &t)| exposure(&field, &lights, t, 100 + j as u64)).collect();
    let share = clipped_share(&brackets[1]);
    eprintln!("single exposure (t = 1): {:.1} % of readings clipped", 100.0 * share);
    assert!((0.03..=0.08).contains(&share), "the single exposure clips {:.1} %", 100.0 * share);
    let singles: Vec<(f32, usize)> = brackets
        .iter()
        .zip(TIMES)
        .map(|(photos, t)| {
            // A single exposure's readings scaled to t = 1: the rig's intensity times t.
            let scaled: Vec<Light> =
                rig_lights.iter().map(|l| Light::new(l.direction(), l.intensity() * t, None).unwrap()).collect();
            mean_error(&field, photos.clone(), &Rig::new(scaled, "ring").unwrap())
        })
        .collect();
    // Merged at the shortest exposure: the rig's intensity times t_min.
    let merged: Vec<Photo> = (0..K)
        .map(|i| {
            let frames: Vec<Photo> = brackets.iter().map(|b| b[i].clone()).collect();
            bracket::merge(&frames, &TIMES, 0.995, 3.0 * NOISE, &format!("light {}", i + 1)).unwrap()
        })
        .collect();
    let scaled: Vec<Light> =
        rig_lights.iter().map(|l| Light::new(l.direction(), l.intensity() * TIMES[0], None).unwrap()).collect();
    let with = mean_error(&field, merged, &Rig::new(scaled, "ring").unwrap());
    eprintln!("(mean error deg, unsolved pixels): single exposures {singles:.3?} (t = {TIMES:?}), brackets {with:.3?}");
    for ((s, invalid), t) in singles.iter().zip(TIMES) {
        assert!(with.0 < *s, "brackets {with:?} against the single exposure t = {t}: {s}");
        assert!(with.1 <= *invalid, "brackets leave {} pixels unsolved, t = {t} {invalid}", with.1);
    }
}

/// The same brackets as a session folder whose rig gives each light `exposures`: capture merges
/// them, says so, and beats the folder of the single exposure.
#[test]
fn a_rig_with_exposures_merges_the_session_brackets() {
    let field = SkinParams::cheek(SIDE, SIDE, 21).generate().unwrap();
    let lights = RenderLight::ring(K, 45.0, Vec3::splat(intensity_clipping(&field)));
    let brackets: Vec<Vec<Photo>> =
        TIMES.iter().enumerate().map(|(j, &t)| exposure(&field, &lights, t, 100 + j as u64)).collect();
    let write = |dir: &Path, frames: &[(usize, &Photo)]| {
        for (n, (_, photo)) in frames.iter().enumerate() {
            let Samples::U16(v) = photo.samples() else { panic!("16-bit render") };
            io::write_png(&dir.join(format!("{:02}.png", n + 1)), SIDE, SIDE, PngLayout::Gray16, v).unwrap();
        }
        io::write_normal_map(&dir.join("truth.png"), &field.normals, NormalEncoding::default(), 16).unwrap();
    };
    let rig = |times: Option<&[f32]>| -> String {
        let extra = times.map_or(String::new(), |t| format!("exposures = {t:?}\n"));
        lights
            .iter()
            .map(|l| {
                let d = l.direction;
                format!("[[light]]\ndirection = [{}, {}, {}]\n{extra}", d.x, d.y, d.z)
            })
            .collect()
    };
    let bracketed = tempfile::tempdir().unwrap();
    let frames: Vec<(usize, &Photo)> = (0..K).flat_map(|i| brackets.iter().map(move |b| (i, &b[i]))).collect();
    write(bracketed.path(), &frames);
    std::fs::write(bracketed.path().join("rig.toml"), rig(Some(&TIMES))).unwrap();
    let single = tempfile::tempdir().unwrap();
    let frames: Vec<(usize, &Photo)> = brackets[1].iter().enumerate().collect();
    write(single.path(), &frames);
    std::fs::write(single.path().join("rig.toml"), rig(None)).unwrap();
    let capture = |dir: &Path| {
        let files = Session::from_dir(dir).unwrap();
        session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress).unwrap().report
    };
    let (with, without) = (capture(bracketed.path()), capture(single.path()));
    assert_eq!(with.corrections, vec![format!("exposure brackets merged ({K} of {K} lights)")]);
    let mean = |r: &session::CaptureReport| r.error_vs_truth_degrees.as_ref().unwrap().mean;
    eprintln!("session (detrended): single exposure {:.3} deg, three brackets {:.3}", mean(&without), mean(&with));
    assert!(mean(&with) < mean(&without), "brackets {} against {}", mean(&with), mean(&without));
    // Brackets missing from the folder: the count names the brackets.
    std::fs::remove_file(bracketed.path().join("24.png")).unwrap();
    let e = session::capture(
        &Session::from_dir(bracketed.path()).unwrap(),
        &CaptureOptions::default(),
        &skinkit_maps::progress::NoProgress,
    )
    .map_err(|e| skinkit_maps::error::one_line(&e))
    .unwrap_err();
    assert!(e.contains("rig has 8 lights (24 photos with their brackets) but 23 photos were given"), "{e}");
}
