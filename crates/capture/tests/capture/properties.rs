//! Property tests (proptest) of the capture kernels against independent computations:
//! - the solver against a naive per-pixel least squares (nalgebra SVD, f64) on random
//!   well-conditioned rigs, and the robust and threshold solves against the exact normal on
//!   readings that a Lambertian surface lit by every light gives;
//! - detrend: unit normals in give unit normals out, invalid texels stay invalid, an all +Z map
//!   stays +Z and any constant tilt goes to +Z.
//!
//! Case counts are kept small for CI; `PROPTEST_CASES=N` runs N cases of every property and
//! `PROPTEST_RNG_SEED=S` draws other cases than the fixed default seed.

use glam::{DVec3, Vec3};
use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use proptest::test_runner::Config;
use skinkit_capture::detrend::detrend;
use skinkit_capture::solve::{Method, NoProgress, PhotoStack, SolveConfig, solve};
use skinkit_capture::{Light, Rig};
use skinkit_maps::{Channels, Grid, NormalMap, Photo, Samples};

/// `cases` cases from this suite's fixed seed (`PROPTEST_CASES`, `PROPTEST_RNG_SEED` override).
fn config(cases: u32) -> Config {
    skinkit_testkit::proptest_config(cases, 0x5eed_ca97)
}

/// A direction at least 17 degrees above the mold plane.
fn direction() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, 0.3f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z).normalize())
}

/// 3 to 12 lights with intensities in [0.5, 2], condition number at most 20 (the solver's limit is
/// 50; rejected draws are redrawn).
fn rig() -> impl Strategy<Value = Rig> {
    prop::collection::vec((direction(), 0.5f32..2.0), 3..=12).prop_filter_map("ill-conditioned rig", |lights| {
        let lights = lights.into_iter().map(|(d, e)| Light::new(d, Vec3::splat(e), None).unwrap()).collect();
        Rig::new(lights, "random rig").ok().filter(|r| r.conditioning().condition_number <= 20.0)
    })
}

/// Least-squares `g` for `L g = r` via SVD in f64: the independent solve.
fn naive_g(l: &DMatrix<f64>, r: &DVector<f64>) -> DVector<f64> {
    l.clone().svd(true, true).solve(r, 1e-12).unwrap()
}

fn light_matrix(rig: &Rig) -> DMatrix<f64> {
    DMatrix::from_fn(rig.light_count(), 3, |i, j| rig.lights()[i].direction()[j] as f64)
}

/// Grey photos, one per light, from per-light readings (fractions of full scale); 16-bit when `u16`.
fn photos(w: usize, h: usize, readings: &[Vec<f32>], u16: bool) -> PhotoStack {
    let photos = readings
        .iter()
        .map(|v| {
            let samples = if u16 {
                Samples::U16(v.iter().map(|&x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16).collect())
            } else {
                Samples::F32(v.clone())
            };
            Photo::new(w, h, Channels::Gray, samples).unwrap()
        })
        .collect::<Vec<_>>();
    let names = (1..=photos.len()).map(|i| format!("{i:02}.png")).collect();
    PhotoStack::new(photos, names).unwrap()
}

/// A rig, a small image size and random readings in [0.05, 0.95] (no shadow, no saturation).
fn solve_case() -> impl Strategy<Value = (Rig, usize, usize, Vec<Vec<f32>>, bool)> {
    (rig(), 1usize..12, 1usize..10, any::<bool>()).prop_flat_map(|(rig, w, h, u16)| {
        let k = rig.light_count();
        let readings = prop::collection::vec(prop::collection::vec(0.05f32..0.95, w * h), k);
        (Just(rig), Just(w), Just(h), readings, Just(u16))
    })
}

proptest! {
    #![proptest_config(config(48))]

    /// Least squares gives the naive SVD solution's `g = albedo * n` at every pixel.
    #[test]
    fn least_squares_matches_a_naive_svd_solve((rig, w, h, readings, u16) in solve_case()) {
        let stack = photos(w, h, &readings, u16);
        let cfg = SolveConfig { method: Method::LeastSquares, ..SolveConfig::default() };
        let sol = solve(&stack, &rig, &cfg, &NoProgress).unwrap();
        let l = light_matrix(&rig);
        let albedo = sol.albedo.as_gray().expect("grey photos give grey albedo");
        for p in 0..w * h {
            // The solver's readings: the stored samples over full scale, divided by the intensity.
            let r = DVector::from_fn(rig.light_count(), |i, _| {
                stack.photos()[i].samples().get(p) as f64 / stack.photos()[i].samples().full_scale() as f64
                    / rig.lights()[i].intensity().x as f64
            });
            let g = naive_g(&l, &r);
            let ours = sol.normals.as_slice()[p].as_dvec3() * albedo.as_slice()[p] as f64;
            let diff = (ours - DVec3::new(g[0], g[1], g[2])).length();
            prop_assert!(diff < 2e-5 * (1.0 + g.norm()), "pixel {}: ours {} naive {}", p, ours, g);
            let n = sol.normals.as_slice()[p];
            prop_assert!((n.length() - 1.0).abs() < 1e-5, "pixel {}: normal {} is not unit", p, n);
        }
    }

    /// Readings of a Lambertian pixel lit by every light: robust and threshold give its normal.
    #[test]
    fn robust_and_threshold_recover_a_lambertian_normal(
        rig in rig(),
        normal in direction(),
        albedo in 0.2f32..0.9,
        method in prop_oneof![Just(Method::Robust), Just(Method::Threshold), Just(Method::LeastSquares)],
    ) {
        let lit = rig.lights().iter().all(|l| normal.dot(l.direction()) > 0.15);
        prop_assume!(lit && rig.lights().iter().all(|l| albedo * l.intensity().x < 0.99));
        let readings: Vec<Vec<f32>> =
            rig.lights().iter().map(|l| vec![albedo * l.intensity().x * normal.dot(l.direction()); 6]).collect();
        let sol = solve(&photos(3, 2, &readings, false), &rig, &SolveConfig { method, ..SolveConfig::default() }, &NoProgress)
            .unwrap();
        for (p, n) in sol.normals.as_slice().iter().enumerate() {
            prop_assert!((*n - normal).length() < 1e-4, "{:?} pixel {}: {} vs {}", method, p, n, normal);
            let a = sol.albedo.as_gray().unwrap().as_slice()[p];
            prop_assert!((a - albedo).abs() < 1e-4, "{:?} albedo {} vs {}", method, a, albedo);
        }
    }
}

/// A unit normal (any direction in the upper half space) or, one time in eight, invalid.
fn texel() -> impl Strategy<Value = Vec3> {
    prop_oneof![7 => direction(), 1 => Just(Vec3::ZERO)]
}

fn normal_map() -> impl Strategy<Value = NormalMap> {
    (1usize..40, 1usize..40).prop_flat_map(|(w, h)| {
        prop::collection::vec(texel(), w * h)
            .prop_map(move |v| NormalMap::from_unit_grid(Grid::from_vec(w, h, v).unwrap()).unwrap())
    })
}

proptest! {
    #![proptest_config(config(64))]

    /// Unit normals stay unit, invalid texels stay invalid, the size is kept.
    #[test]
    fn detrend_keeps_unit_normals_unit(map in normal_map(), block in 0usize..60) {
        let mut out = map.clone();
        detrend(&mut out, block);
        prop_assert_eq!(out.size(), map.size());
        for (i, (a, b)) in map.as_slice().iter().zip(out.as_slice()).enumerate() {
            if *a == Vec3::ZERO {
                prop_assert_eq!(*b, Vec3::ZERO, "texel {} was invalid", i);
            } else {
                prop_assert!(b.is_finite() && (b.length() - 1.0).abs() < 1e-5, "texel {}: {} -> {}", i, a, b);
            }
        }
        if block == 0 {
            prop_assert_eq!(out.as_slice(), map.as_slice());
        }
    }

    /// An all +Z map (with holes) stays +Z; a constant tilt goes to +Z (the window's mean is the
    /// tilt itself).
    #[test]
    fn detrend_takes_a_constant_map_to_plus_z(
        (w, h, holes) in (1usize..40, 1usize..40).prop_flat_map(|(w, h)| (Just(w), Just(h), prop::collection::vec(prop::bool::weighted(0.1), w * h))),
        tilt in direction(),
        block in 1usize..60,
    ) {
        for n in [Vec3::Z, tilt] {
            let texels = holes.iter().map(|&hole| if hole { Vec3::ZERO } else { n }).collect();
            let mut map = NormalMap::from_unit_grid(Grid::from_vec(w, h, texels).unwrap()).unwrap();
            detrend(&mut map, block);
            for (i, (hole, b)) in holes.iter().zip(map.as_slice()).enumerate() {
                let expect = if *hole { Vec3::ZERO } else { Vec3::Z };
                prop_assert!((*b - expect).length() < 1e-5, "{} texel {}: {} (block {})", n, i, b, block);
            }
        }
    }
}
