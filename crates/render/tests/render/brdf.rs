//! The Lafortune BRDF against independent computations: hand-evaluated values, reciprocity, the
//! lobe maximum found by brute force, and albedo quadrature against closed forms.

use glam::Vec3;
use skinkit_render::brdf::{LOBE_CEILING, Lafortune, Lobe, lobe_power};
use std::f64::consts::PI;

fn single_lobe(cxy: f32, cz: f32, n: f32) -> Lafortune {
    Lafortune { diffuse: Vec3::ZERO, lobes: vec![Lobe::isotropic(Vec3::splat(cxy), Vec3::splat(cz), Vec3::splat(n))] }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * b.abs().max(1e-30)
}

/// A tiny deterministic generator of unit vectors in the upper hemisphere.
fn hemisphere_samples(count: usize, seed: u64) -> Vec<Vec3> {
    let mut state = seed;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..count)
        .map(|_| {
            let z: f32 = next();
            let phi = 2.0 * std::f32::consts::PI * next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        })
        .collect()
}

#[test]
#[allow(clippy::excessive_precision)]
fn skin_set_matches_the_reference_table() {
    let skin = Lafortune::skin();
    assert_eq!(skin.lobes.len(), 3);
    assert_eq!(skin.diffuse, Vec3::new(0.428425, 0.301341, 0.331054));
    assert_eq!(skin.lobes[0].cz, Vec3::new(-1.209182, -1.462488, -1.222419));
    assert_eq!(skin.lobes[1].n, Vec3::new(3.685044, 4.266495, 4.539742));
    assert_eq!(skin.lobes[2].cx, Vec3::new(-0.998888, -1.020153, -1.027479));
    assert_eq!(skin.lobes[2].cx, skin.lobes[2].cy);
    assert_eq!(skin.lobes[2].n, Vec3::new(64.208486, 63.919687, 43.809866));
}

#[test]
fn hand_evaluated_single_lobe() {
    let brdf = single_lobe(-1.0, 1.0, 2.0);
    // Mirror pair: base = 0.6 * 0.6 + 0.8 * 0.8 = 1.
    let f = brdf.eval(Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.6, 0.0, 0.8));
    assert!((f - Vec3::ONE).abs().max_element() < 1e-6, "{f}");
    // Perpendicular azimuth: base = 0.64, squared 0.4096.
    let f = brdf.eval(Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.6, 0.8));
    assert!((f - Vec3::splat(0.4096)).abs().max_element() < 1e-6, "{f}");
    // Same side: base = -0.36 + 0.64 = 0.28.
    let f = brdf.eval(Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.6, 0.0, 0.8));
    assert!((f - Vec3::splat(0.28 * 0.28)).abs().max_element() < 1e-6, "{f}");
}

#[test]
fn hand_evaluated_skin_at_normal_incidence() {
    // l = v = z: lobe 0 has Cz < 0 (clamped to 0); lobes 1 and 2 give Cz^n; diffuse rho/pi.
    let f = Lafortune::skin().eval(Vec3::Z, Vec3::Z);
    let expected_r = 0.428425 / PI + 0.380123f64.powf(3.685044) + 0.857998f64.powf(64.208486);
    let expected_g = 0.301341 / PI + 0.410559f64.powf(4.266495) + 0.703913f64.powf(63.919687);
    let expected_b = 0.331054 / PI + 0.437367f64.powf(4.539742) + 0.573625f64.powf(43.809866);
    assert!(close(f.x as f64, expected_r, 1e-5), "{} vs {expected_r}", f.x);
    assert!(close(f.y as f64, expected_g, 1e-5), "{} vs {expected_g}", f.y);
    assert!(close(f.z as f64, expected_b, 1e-5), "{} vs {expected_b}", f.z);
}

#[test]
fn hand_evaluated_skin_grazing_lobe() {
    // l and v both near grazing on opposite sides in x: lobe 0 (Cxy < 0, Cz < 0) is active.
    let (s, c) = (0.99f64, (1.0f64 - 0.99 * 0.99).sqrt());
    let l = Vec3::new(s as f32, 0.0, c as f32);
    let v = Vec3::new(-s as f32, 0.0, c as f32);
    let f = Lafortune::skin().eval(l, v);
    let lobe = |cxy: f64, cz: f64, n: f64| (cxy * -(s * s) + cz * c * c).max(0.0).powf(n);
    let expected_r = 0.428425 / PI
        + lobe(-1.131747, -1.209182, 6.421658)
        + lobe(-0.546570, 0.380123, 3.685044)
        + lobe(-0.998888, 0.857998, 64.208486);
    assert!(close(f.x as f64, expected_r, 1e-4), "{} vs {expected_r}", f.x);
}

#[test]
fn negative_bases_give_zero_never_nan() {
    assert_eq!(lobe_power(-0.5, 3.0), 0.0);
    assert_eq!(lobe_power(-0.5, 2.0), 0.0, "an even exponent must not resurrect a negative base");
    assert_eq!(lobe_power(0.0, 0.0), 0.0);
    assert_eq!(lobe_power(f32::NAN, 2.0), 0.0);
    let f = Lafortune::skin().eval(Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 0.0, -1.0));
    assert!(f.is_finite() && f.min_element() >= 0.0, "{f}");
}

#[test]
fn exponent_10000_stays_finite() {
    let brdf = single_lobe(-1.2, 1.2, 10000.0);
    for l in hemisphere_samples(200, 1) {
        for v in [Vec3::new(-l.x, -l.y, l.z), Vec3::Z, l] {
            let f = brdf.eval(l, v);
            assert!(f.is_finite() && f.max_element() <= LOBE_CEILING, "{l} {v}: {f}");
        }
    }
    // Below the cap the value is exact: 0.9999^10000 = e^-1.00005.
    let value = lobe_power(0.9999, 10000.0) as f64;
    assert!(close(value, 0.9999f64.powf(10000.0), 1e-3), "{value}");
}

#[test]
fn grazing_directions_are_fine() {
    let skin = Lafortune::skin();
    for v in hemisphere_samples(100, 2) {
        let f = skin.eval(Vec3::X, v);
        assert!(f.is_finite() && f.min_element() >= 0.0);
        let f = skin.eval(Vec3::X, Vec3::NEG_X);
        assert!(f.is_finite());
    }
}

#[test]
fn reciprocity() {
    let skin = Lafortune::skin();
    let dirs = hemisphere_samples(64, 3);
    for &l in &dirs {
        for &v in &dirs {
            assert_eq!(skin.eval(l, v), skin.eval(v, l), "{l} {v}");
        }
    }
}

#[test]
fn single_lobe_peaks_at_the_mirror_direction() {
    let brdf = single_lobe(-1.0, 1.0, 50.0);
    let steps = 400;
    for (theta, phi) in [(0.3f32, 0.4f32), (0.9, 2.5), (1.2, -1.0)] {
        let l = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        // Brute force over a (theta, phi) grid of the hemisphere.
        let mut best = (f32::MIN, Vec3::ZERO);
        for i in 0..=steps / 4 {
            for j in 0..steps {
                let t = std::f32::consts::FRAC_PI_2 * i as f32 / (steps / 4) as f32;
                let p = 2.0 * std::f32::consts::PI * j as f32 / steps as f32;
                let v = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                let f = brdf.eval(l, v).x;
                if f > best.0 {
                    best = (f, v);
                }
            }
        }
        let mirror = Vec3::new(-l.x, -l.y, l.z);
        let angle = best.1.dot(mirror).clamp(-1.0, 1.0).acos().to_degrees();
        assert!(angle < 1.0, "l {l}: peak {} is {angle} degrees from the mirror", best.1);
    }
}

#[test]
fn albedo_quadrature_matches_closed_forms() {
    // Lambert: the albedo is rho_d whatever the incidence.
    let lambert = Lafortune::lambert(Vec3::splat(0.5));
    let a = lambert.albedo(Vec3::new(0.5, 0.0, 0.75f32.sqrt()), 128);
    assert!((a - Vec3::splat(0.5)).abs().max_element() < 1e-3, "{a}");
    // Cz-only lobe: f = (lz vz)^n, albedo = lz^n * 2 pi / (n + 2).
    let n = 8.0;
    let lobe = single_lobe(0.0, 1.0, n);
    let lz = 0.8f32;
    let l = Vec3::new(0.6, 0.0, lz);
    let expected = (lz as f64).powf(n as f64) * 2.0 * PI / (n as f64 + 2.0);
    let a = lobe.albedo(l, 256);
    assert!(close(a.x as f64, expected, 2e-3), "{} vs {expected}", a.x);
}

#[test]
fn skin_albedo_is_finite_at_several_angles() {
    let skin = Lafortune::skin();
    for degrees in [0.0f32, 30.0, 60.0, 80.0, 89.0, 90.0] {
        let t = degrees.to_radians();
        let a = skin.albedo(Vec3::new(t.sin(), 0.0, t.cos()), 256);
        eprintln!("skin albedo at {degrees} degrees: {a}");
        assert!(a.is_finite() && a.min_element() > 0.0, "{degrees}: {a}");
        // Not energy normalised, but the measured set stays well below 2 (no blow-up).
        assert!(a.max_element() < 2.0, "{degrees}: {a}");
    }
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface of index `eta` (from air)
/// at incidence `theta` (radians).
fn fresnel(theta: f64, eta: f64) -> f64 {
    let (ci, si) = (theta.cos(), theta.sin());
    let ct = (1.0 - (si / eta).powi(2)).sqrt();
    let rs = ((ci - eta * ct) / (ci + eta * ct)).powi(2);
    let rp = ((eta * ci - ct) / (eta * ci + ct)).powi(2);
    0.5 * (rs + rp)
}

/// The default lobes against the physics they were fitted to (issue 13: "check the default
/// lobes"). Skin's specular is reflection at the oily surface of the stratum corneum, index about
/// 1.4, so the lobes' directional albedo should be about the Fresnel reflectance of such an
/// interface: 2.8 % at normal incidence, rising toward grazing (Marschner et al. 1999 measured
/// skin's specular rising steeply toward grazing). It is: 3.1 / 2.3 / 2.3 % (R/G/B) at normal
/// incidence, 4.4 % at 45 degrees (Fresnel 3.7 %), 6.5 % at 60 (7.2 %), 10 % at 70 (15 %). At
/// 80 degrees the fit falls to half of the smooth interface's 37 %, as a rough surface's
/// shadowing and masking make it. So the small value at normal incidence (lobe 2 about 6e-5 at
/// l = v = n) is the data, not a transcription error: the sheen shows where light and view are
/// oblique, which is where the demo's figure 7 puts them.
#[test]
fn skin_lobes_reflect_like_the_skin_surface() {
    let lobes = Lafortune { diffuse: Vec3::ZERO, lobes: Lafortune::skin().lobes };
    let albedo = |deg: f64| {
        let t = deg.to_radians();
        lobes.albedo(Vec3::new(t.sin() as f32, 0.0, t.cos() as f32), 200)
    };
    let mut last = Vec3::ZERO;
    for deg in [0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0] {
        let a = albedo(deg);
        let f = fresnel(f64::to_radians(deg), 1.4) as f32;
        // Within a factor 1.6 of the smooth interface up to 70 degrees (the fit's own scatter
        // across channels is 1.4x at normal incidence); above half of it at 80.
        let (lo, hi) = if deg < 75.0 { (f / 1.6, f * 1.6) } else { (f / 2.5, f) };
        assert!(a.min_element() > lo && a.max_element() < hi, "{deg} deg: lobes {a}, Fresnel {f}");
        assert!(a.cmpgt(last).all(), "{deg} deg: {a} does not rise from {last}");
        last = a;
    }
}
