//! The threshold and robust solvers on photos whose shadows and saturated readings come in runs of 16 pixels
//! (as cast shadows do), which the solver handles a run or a group of pixels at a time, against
//! a naive per-pixel solve in f64 (nalgebra SVD) from the readings it should keep.

use glam::{DVec3, Vec3};
use nalgebra::{DMatrix, DVector};
use skinkit_capture::solve::{AlbedoMap, Method, NoProgress, PhotoStack, SolveConfig, solve};
use skinkit_capture::{Light, Rig};
use skinkit_maps::normal::angle_degrees;
use skinkit_maps::{Channels, Photo, Samples};

const K: usize = 8;

fn ring() -> Rig {
    let t = 40f64.to_radians();
    let lights = (0..K)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / K as f64 + 0.2;
            let d = DVec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()).as_vec3();
            Light::new(d, Vec3::ONE, None).unwrap()
        })
        .collect();
    Rig::new(lights, "test rig").unwrap()
}

/// Stored 16-bit value of light `i` at `(x, y)`: a gently tilted surface with a 1% non-Lambertian
/// ripple, zero in shadowed runs (two opposite lights), full scale in saturated runs (light 1).
fn sample(rig: &Rig, x: usize, y: usize, i: usize) -> u16 {
    let run = x / 16 + y;
    if !y.is_multiple_of(3) && (run + i).is_multiple_of(4) {
        return 0;
    }
    if run % 5 == 1 && i == 1 {
        return 65535;
    }
    let n = Vec3::new(0.2 * (x as f32 * 0.11).sin(), 0.15 * (y as f32 * 0.23).cos(), 1.0).normalize();
    let ripple = 1.0 + 0.01 * ((x * 7 + y * 13 + i * 5) as f32 * 0.37).sin();
    (0.6 * n.dot(rig.lights()[i].direction()).max(0.0) * ripple * 65535.0).round() as u16
}

/// Oracle for one pixel: `(normal, albedo, confidence, lights used)` from the readings that pass
/// the default thresholds, or `None` with the count when fewer than 3 remain. The shadow
/// threshold is `max(shadow_abs, shadow_rel * q90)`, `q90` the 90th percentile (rounded up) of
/// the unsaturated readings: with 8 lights, the brightest unsaturated one.
fn naive(rig: &Rig, raw: &[u16]) -> (Option<(DVec3, f64, f64)>, usize) {
    let config = SolveConfig::default();
    let r: Vec<f64> = raw.iter().map(|&v| v as f64 / 65535.0).collect();
    let unsaturated = |i: &usize| (raw[*i] as f64) < 0.995 * 65535.0;
    let top = (0..K).filter(unsaturated).map(|i| r[i]).fold(f64::NEG_INFINITY, f64::max);
    let threshold = (config.shadow_abs as f64).max(config.shadow_rel as f64 * top);
    let used: Vec<usize> = (0..K).filter(|&i| r[i] >= threshold && unsaturated(&i)).collect();
    if used.len() < 3 {
        return (None, used.len());
    }
    let rows = |set: &[usize]| {
        DMatrix::from_fn(set.len(), 3, |a, c| rig.lights()[set[a]].direction().normalize().as_dvec3()[c])
    };
    let condition = |m: &DMatrix<f64>| {
        let s = m.clone().svd(false, false).singular_values;
        s.max() / s.min()
    };
    let l = rows(&used);
    let b = DVector::from_iterator(used.len(), used.iter().map(|&i| r[i]));
    let g = l.clone().svd(true, true).solve(&b, 1e-12).unwrap();
    let rho2 = (&b - &l * &g).norm_squared() / b.norm_squared();
    let all: Vec<usize> = (0..K).collect();
    let weight = used.len() as f64 / K as f64 * (condition(&rows(&all)) / condition(&l)).min(1.0);
    let confidence = weight / (1.0 + rho2 / 0.01);
    let g = DVec3::new(g[0], g[1], g[2]);
    (Some((g.normalize(), g.length(), confidence)), used.len())
}

#[test]
fn runs_of_dropped_readings_match_a_naive_subset_solve() {
    let rig = ring();
    // Width 64: the fused kernel's 16-pixel steps line up with the runs; width 72: they straddle
    // them and the chunk path groups the pixels by subset.
    for w in [64, 72] {
        let h = 24;
        let photos = (0..K)
            .map(|i| {
                let v = (0..w * h).map(|p| sample(&rig, p % w, p / w, i)).collect();
                Photo::new(w, h, Channels::Gray, Samples::U16(v)).unwrap()
            })
            .collect();
        let stack = PhotoStack::new(photos, (0..K).map(|i| format!("{i}.png")).collect()).unwrap();
        let config = SolveConfig { method: Method::Threshold, ..SolveConfig::default() };
        let sol = solve(&stack, &rig, &config, &NoProgress).unwrap();
        let AlbedoMap::Gray(albedo) = &sol.albedo else { panic!("grey photos give grey albedo") };
        let mut counts = vec![0; K + 1];
        for y in 0..h {
            for x in 0..w {
                let raw: Vec<u16> = (0..K).map(|i| sample(&rig, x, y, i)).collect();
                let (want, used) = naive(&rig, &raw);
                counts[used] += 1;
                let (n, a, c) = (sol.normals.get(x, y), *albedo.get(x, y), *sol.confidence.get(x, y));
                let at = format!("width {w}, ({x}, {y}), {used} lights");
                match want {
                    None => assert!(n == Vec3::ZERO && a == 0.0 && c == 0.0, "{at}: {n} {a} {c}"),
                    Some((wn, wa, wc)) => {
                        let angle = angle_degrees(n, wn.as_vec3());
                        assert!(angle < 0.01, "{at}: normal off by {angle} deg");
                        assert!((a as f64 - wa).abs() < 1e-4 * wa, "{at}: albedo {a} vs {wa}");
                        assert!((c as f64 - wc).abs() < 1e-3, "{at}: confidence {c} vs {wc}");
                    }
                }
            }
        }
        assert_eq!(sol.stats.lights_used, counts, "width {w}");
        // Every kind of pixel occurs: all lights, and one, two or three readings dropped.
        assert!(counts[8] > 0 && counts[7] > 0 && counts[6] > 0 && counts[5] > 0, "width {w}: {counts:?}");
        // The robust solve drops the same readings, and its 2 % gate keeps every answer here
        // (the ripple leaves about 1 %), so it gives the same maps to the bit.
        let robust = solve(&stack, &rig, &SolveConfig::default(), &NoProgress).unwrap();
        assert_eq!(robust.normals, sol.normals, "width {w}");
        assert_eq!(robust.albedo, sol.albedo, "width {w}");
        assert_eq!(robust.confidence, sol.confidence, "width {w}");
    }
}
