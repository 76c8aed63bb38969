//! The robust fit against least squares on synthetic non-Lambertian molds rendered here: a
//! furrowed, bumpy heightfield with a Blinn-Phong specular lobe, cast shadows (rays marched over
//! the heightfield toward each light) and inter-reflection in the furrows (light from the facing
//! walls, growing with how enclosed the point is). Each case prints its mean errors; run with
//! `--nocapture` to see the table the README quotes.

use glam::Vec3;
use skinkit_capture::robust::{Estimator, Lights, RobustConfig, fit_pixel};
use skinkit_maps::normal::angle_degrees;

const SIZE: usize = 96;
const ALBEDO: f32 = 0.55;

/// Height in pixels: furrows along y (period 24 px, 8 px deep, walls up to 46 deg) and two bumps.
fn height(x: f32, y: f32) -> f32 {
    let furrow = 4.0 * (std::f32::consts::TAU * x / 24.0).cos();
    let bump = |cx: f32, cy: f32, s: f32, a: f32| a * (-((x - cx).powi(2) + (y - cy).powi(2)) / (2.0 * s * s)).exp();
    furrow + bump(30.0, 40.0, 14.0, 8.0) + bump(70.0, 65.0, 10.0, 6.0)
}

fn normal(x: f32, y: f32) -> Vec3 {
    let d = 1e-2;
    let hx = (height(x + d, y) - height(x - d, y)) / (2.0 * d);
    let hy = (height(x, y + d) - height(x, y - d)) / (2.0 * d);
    Vec3::new(-hx, -hy, 1.0).normalize()
}

/// Whether the ray from the surface at `(x, y)` toward `l` passes under the heightfield.
fn shadowed(x: f32, y: f32, l: Vec3) -> bool {
    let flat = (l.x * l.x + l.y * l.y).sqrt();
    if flat < 1e-6 {
        return false;
    }
    let (h0, rise) = (height(x, y), l.z / flat);
    (1..200).map(|t| t as f32 * 0.5).any(|t| height(x + t * l.x / flat, y + t * l.y / flat) > h0 + t * rise + 1e-3)
}

/// Fraction of 16 directions at 30 deg elevation blocked by the heightfield (how enclosed).
fn enclosure(x: f32, y: f32) -> f32 {
    let e = 30f32.to_radians();
    let blocked = (0..16)
        .filter(|&i| {
            let a = std::f32::consts::TAU * i as f32 / 16.0;
            shadowed(x, y, Vec3::new(e.cos() * a.cos(), e.cos() * a.sin(), e.sin()))
        })
        .count();
    blocked as f32 / 16.0
}

#[derive(Clone, Copy, Debug)]
struct Effects {
    specular: bool,
    cast_shadows: bool,
    interreflection: bool,
}

/// Reading of the point `(x, y)` under light `l` (intensity 1), clipped at full scale 1.
fn reading(x: f32, y: f32, l: Vec3, fx: Effects, enclosed: f32) -> (f32, bool) {
    let n = normal(x, y);
    let lit = !(fx.cast_shadows && shadowed(x, y, l));
    let mut v = if lit { ALBEDO * n.dot(l).max(0.0) } else { 0.0 };
    if fx.specular && lit && n.dot(l) > 0.0 {
        let half = (l + Vec3::Z).normalize();
        v += 0.6 * n.dot(half).max(0.0).powf(40.0);
    }
    if fx.interreflection {
        // The walls around the point, lit as a flat surface would be, send back part of it.
        v += 0.5 * ALBEDO * ALBEDO * l.z.max(0.0) * enclosed;
    }
    (v.min(1.0), v >= 1.0)
}

/// Golden-angle spiral of `k` lights over the cap within `max_deg` of the camera axis.
fn spiral(k: usize, max_deg: f32) -> Vec<Vec3> {
    let cos_max = max_deg.to_radians().cos();
    (0..k)
        .map(|i| {
            let z = 1.0 - (1.0 - cos_max) * (i as f32 + 0.5) / k as f32;
            let (a, s) = (i as f32 * 2.399_963, (1.0 - z * z).sqrt());
            Vec3::new(s * a.cos(), s * a.sin(), z)
        })
        .collect()
}

fn ring(k: usize, deg: f32) -> Vec<Vec3> {
    let t = deg.to_radians();
    (0..k)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / k as f32 + 0.3;
            Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
        })
        .collect()
}

fn least_squares(r: &[f32], lights: &[Vec3]) -> Vec3 {
    let m = nalgebra::DMatrix::from_fn(lights.len(), 3, |i, j| lights[i][j] as f64);
    let b = nalgebra::DVector::from_iterator(r.len(), r.iter().map(|&v| v as f64));
    let g = m.svd(true, true).solve(&b, 1e-12).unwrap();
    Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32).normalize_or_zero()
}

/// Mean error (degrees) of least squares and of each estimator over the mold's pixels.
fn errors(lights: &[Vec3], fx: Effects) -> (f32, Vec<f32>) {
    let estimators = [Estimator::Trimmed, Estimator::Cauchy, Estimator::L1];
    let fitted = Lights::new(lights).unwrap();
    let (mut ls, mut robust) = (0.0f64, vec![0.0f64; estimators.len()]);
    let mut count = 0;
    for y in (4..SIZE - 4).step_by(2) {
        for x in (4..SIZE - 4).step_by(2) {
            let (x, y) = (x as f32, y as f32);
            let enclosed = if fx.interreflection { enclosure(x, y) } else { 0.0 };
            let (r, sat): (Vec<f32>, Vec<bool>) = lights.iter().map(|&l| reading(x, y, l, fx, enclosed)).unzip();
            let truth = normal(x, y);
            ls += angle_degrees(least_squares(&r, lights), truth) as f64;
            for (sum, &estimator) in robust.iter_mut().zip(&estimators) {
                let config = RobustConfig { estimator, ..RobustConfig::default() };
                let fit = fit_pixel(&r, &sat, &fitted, &config);
                // An invalid pixel counts as 90 deg wrong, so rejecting everything cannot win.
                *sum += if fit.used() == 0 { 90.0 } else { angle_degrees(fit.normal, truth) as f64 };
            }
            count += 1;
        }
    }
    let mean = |s: f64| (s / count as f64) as f32;
    let robust: Vec<f32> = robust.into_iter().map(mean).collect();
    println!(
        "{:>3} lights {fx:?}: least squares {:.2}, trimmed {:.2}, Cauchy {:.2}, L1 {:.2} deg",
        lights.len(),
        mean(ls),
        robust[0],
        robust[1],
        robust[2]
    );
    (mean(ls), robust)
}

const LAMBERT: Effects = Effects { specular: false, cast_shadows: false, interreflection: false };

#[test]
fn attached_shadows_only_is_exact() {
    for lights in [ring(8, 45.0), spiral(96, 55.0)] {
        let (_, robust) = errors(&lights, LAMBERT);
        assert!(robust.iter().all(|&e| e < 0.05), "{robust:?}");
    }
}

#[test]
fn cast_shadows_robust_far_below_least_squares() {
    let fx = Effects { cast_shadows: true, ..LAMBERT };
    for lights in [ring(8, 45.0), ring(10, 50.0), spiral(96, 55.0)] {
        let (ls, robust) = errors(&lights, fx);
        assert!(robust[0] < 0.25 * ls, "least squares {ls}, trimmed {}", robust[0]);
    }
}

#[test]
fn specular_lobe_is_rejected() {
    let fx = Effects { specular: true, ..LAMBERT };
    for lights in [ring(10, 50.0), spiral(96, 55.0)] {
        let (ls, robust) = errors(&lights, fx);
        assert!(robust[0] < 0.5 * ls, "least squares {ls}, trimmed {}", robust[0]);
    }
}

#[test]
fn all_effects_together_robust_below_least_squares() {
    let fx = Effects { specular: true, cast_shadows: true, interreflection: true };
    for lights in [ring(8, 45.0), ring(10, 50.0), spiral(96, 55.0)] {
        let (ls, robust) = errors(&lights, fx);
        assert!(robust[0] < ls, "least squares {ls}, trimmed {}", robust[0]);
    }
}
