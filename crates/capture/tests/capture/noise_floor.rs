//! The robust solve under sensor noise (issue 39): it measures the image's noise floor, widens
//! its agreement gate to it, and so stays within 2 % of least squares' mean error on a noisy
//! mold, while keeping its gains where cast shadows and highlights break Lambert's law.

use glam::Vec3;
use skinkit_capture::solve::{self, Method, PhotoStack, Solution, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Heightfield, Quantise, RenderConfig, RenderLight, SkinParams, Specular};

const SIDE: usize = 128;

fn field() -> Heightfield {
    SkinParams::cheek(SIDE, SIDE, 3).generate().unwrap()
}

/// Photos of `field` under a ring of `k` lights 45 degrees off axis, and the rig.
fn session(field: &Heightfield, k: usize, noise: f32, effects: bool) -> (PhotoStack, Rig) {
    let lights = RenderLight::ring(k, 45.0, Vec3::ONE);
    let render = RenderConfig {
        shadows: effects,
        specular: effects.then_some(Specular { strength: 0.05, shininess: 40.0 }),
        noise_sigma: noise,
        format: Quantise::U16,
        seed: 7,
        ..RenderConfig::default()
    };
    let photos = skinkit_heightfield::render(field, &lights, &render).unwrap();
    let stack = PhotoStack::new(photos, (1..=k).map(|i| format!("{i:02}.png")).collect()).unwrap();
    let rig_lights: Vec<Light> = lights.iter().map(|l| Light::new(l.direction, l.intensity, None).unwrap()).collect();
    (stack, Rig::new(rig_lights, "ring").unwrap())
}

fn solve(stack: &PhotoStack, rig: &Rig, method: Method) -> Solution {
    solve::solve(stack, rig, &SolveConfig { method, ..SolveConfig::default() }, &solve::NoProgress).unwrap()
}

fn mean_error(solution: &Solution, field: &Heightfield) -> f32 {
    solution.normals.angular_error(&field.normals, None).unwrap().mean
}

/// The measured sigma is the rendered one (Gaussian, as a share of full scale), within 10 %.
#[test]
fn the_noise_floor_is_the_sensor_noise() {
    let field = field();
    for noise in [0.01f32, 0.04] {
        let (stack, rig) = session(&field, 8, noise, false);
        let floor = solve(&stack, &rig, Method::Robust).noise.expect("8 lights give a noise floor");
        assert!((floor.sigma / noise - 1.0).abs() < 0.1, "noise {noise}: measured {}", floor.sigma);
        assert!(floor.gate > 0.02, "noise {noise}: gate {}", floor.gate);
    }
}

/// Noise-free photos keep the 2 % gate; least squares and threshold measure none.
#[test]
fn clean_photos_keep_the_fixed_gate() {
    let field = field();
    let (stack, rig) = session(&field, 8, 0.0, true);
    let floor = solve(&stack, &rig, Method::Robust).noise.unwrap();
    assert_eq!(floor.gate, skinkit_capture::robust::AGREEMENT);
    assert!(floor.sigma < 2e-3, "{}", floor.sigma);
    assert!(solve(&stack, &rig, Method::LeastSquares).noise.is_none());
}

/// With shadows and highlights at 2 and 4 % noise (where the fixed 2 % gate lost to it),
/// robust is within 2 % of least squares at 4 and 8 lights; without noise it beats it.
#[test]
fn robust_holds_against_least_squares_under_noise() {
    let field = field();
    for (k, noise) in [(4, 0.02f32), (8, 0.02), (8, 0.04)] {
        let (stack, rig) = session(&field, k, noise, true);
        let ls = mean_error(&solve(&stack, &rig, Method::LeastSquares), &field);
        let robust = mean_error(&solve(&stack, &rig, Method::Robust), &field);
        assert!(robust <= 1.02 * ls, "{k} lights, noise {noise}: robust {robust} against least squares {ls}");
    }
    let (stack, rig) = session(&field, 8, 0.0, true);
    let ls = mean_error(&solve(&stack, &rig, Method::LeastSquares), &field);
    let robust = mean_error(&solve(&stack, &rig, Method::Robust), &field);
    assert!(robust < 0.95 * ls, "noise-free: robust {robust} against least squares {ls}");
}
