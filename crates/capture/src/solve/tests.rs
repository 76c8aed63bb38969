//! Unit tests of the solve's internals: the builds and paths agree bitwise.

use skinkit_maps::{Channels, Photo, Samples};

use super::chunk::{Out, Scratch};
use super::subsets::{SubsetSolve, Subsets};
use super::*;

/// A small grey stack with a few shadowed readings, and its rig (equal light intensities).
fn inputs(samples: impl Fn(usize, usize) -> Samples) -> (PhotoStack, Rig) {
    inputs_with(samples, |_| 0.9)
}

fn inputs_with(samples: impl Fn(usize, usize) -> Samples, intensity: impl Fn(usize) -> f32) -> (PhotoStack, Rig) {
    let lights: Vec<crate::Light> = (0..8)
        .map(|i| {
            let a = i as f32 * 0.785 + 0.2;
            crate::Light::new(Vec3::new(0.7 * a.cos(), 0.7 * a.sin(), 0.714), Vec3::splat(intensity(i)), None).unwrap()
        })
        .collect();
    let photos = (0..8).map(|i| Photo::new(37, 11, Channels::Gray, samples(i, 37 * 11)).unwrap()).collect();
    let stack = PhotoStack::new(photos, (0..8).map(|i| i.to_string()).collect()).unwrap();
    (stack, Rig::new(lights, "test rig").unwrap())
}

fn pseudo_random(i: usize, p: usize) -> u32 {
    let mut x = (i * 7919 + p * 104729) as u32 ^ 0x9e37_79b9;
    x ^= x << 13;
    x ^= x >> 17;
    x ^ (x << 5)
}

/// Samples of photo `i`: mostly mid-range, with zeros (dropped by the robust tests),
/// saturated values and, for floats, NaN, infinities, negative and huge values.
fn mixed_samples(kind: usize, i: usize, n: usize) -> Samples {
    let r = |p: usize| pseudo_random(i, p);
    match kind {
        0 => Samples::U16((0..n).map(|p| if r(p).is_multiple_of(9) { 0 } else { (r(p) % 60000) as u16 }).collect()),
        // Rarely dropped readings, so that most steps take the fused path in robust mode too.
        1 => Samples::U16(
            (0..n).map(|p| if r(p).is_multiple_of(97) { 65535 } else { 30000 + (r(p) % 20000) as u16 }).collect(),
        ),
        2 => Samples::U8((0..n).map(|p| if r(p).is_multiple_of(53) { 0 } else { 100 + (r(p) % 150) as u8 }).collect()),
        // Readings dropped in runs of 16 pixels (one or two lights, some saturated, some
        // runs with too few lights left), so that whole fused steps share a subset.
        4 => Samples::U16((0..n).map(|p| block_shadowed(i, p, 30000 + (r(p) % 20000) as u16, 65535)).collect()),
        // The same in floats, with a rare NaN breaking a run's common subset.
        5 => Samples::F32(
            (0..n)
                .map(|p| {
                    if r(p).is_multiple_of(89) {
                        f32::NAN
                    } else {
                        block_shadowed(i, p, 0.3 + (r(p) % 50) as f32 * 0.01, 1.5)
                    }
                })
                .collect(),
        ),
        _ => Samples::F32(
            (0..n)
                .map(|p| match r(p) % 61 {
                    0 => f32::NAN,
                    1 => f32::INFINITY,
                    2 => -0.3,
                    3 => 3e38,
                    4 => 0.0,
                    v => 0.3 + v as f32 * 0.01,
                })
                .collect(),
        ),
    }
}

/// Light `i`'s sample at pixel `p` for sample kinds 4 and 5: `lit`, or zero or `saturated`
/// depending on the run of 16 pixels.
fn block_shadowed<T: From<u8>>(i: usize, p: usize, lit: T, saturated: T) -> T {
    let run = p / 16;
    match run % 6 {
        0 => lit,
        1 | 2 if (run + i).is_multiple_of(5) => T::from(0),
        3 if i == 2 => saturated,
        4 if i < 6 => T::from(0),
        _ => lit,
    }
}

/// Solves every band with the portable and (when the CPU has it) the AVX2 build, whose
/// linear grey path is the fused kernel: same bits and the same counts.
#[test]
fn portable_and_vectorised_builds_agree_bitwise() {
    for kind in 0..6 {
        for (method, masked) in [(Method::LeastSquares, false), (Method::Robust, false), (Method::Robust, true)] {
            // Unequal intensities for the even kinds: per-light scales inside `sum r^2`.
            let intensity = |i: usize| if kind % 2 == 0 { 0.8 + 0.03 * i as f32 } else { 0.9 };
            let (mut stack, rig) = inputs_with(|i, n| mixed_samples(kind, i, n), intensity);
            if masked {
                let mask = Grid::from_fn(37, 11, |x, y| (x * 7 + y * 3) % 29 != 0);
                stack = stack.with_mask(mask).unwrap();
            }
            let config = SolveConfig { method, ..SolveConfig::default() };
            let lights = check_rig(&stack, &rig).unwrap();
            let plan = Plan::new(&stack, &rig, &config, lights, None).unwrap();
            let subsets = Subsets::new(&plan.lights, config.max_condition, config.cache_capacity);
            let n = stack.width() * stack.height();
            let band = BAND_ROWS * stack.width();
            let run = |vectorised: bool| {
                let (mut normals, mut albedo, mut conf) = (vec![Vec3::ZERO; n], vec![0.0f32; n], vec![0.0f32; n]);
                let mut scratch = Scratch::new(8, false);
                let mut stats = SolveStats::empty(8);
                for p0 in (0..n).step_by(band) {
                    let end = (p0 + band).min(n);
                    let out = Out {
                        normals: &mut normals[p0..end],
                        albedo: &mut albedo[p0..end],
                        confidence: &mut conf[p0..end],
                    };
                    stats = stats.merge(if vectorised {
                        plan.solve_band(p0, out, &mut scratch, &subsets)
                    } else {
                        plan.solve_band_portable(p0, out, &mut scratch, &subsets)
                    });
                }
                let bits: Vec<u32> =
                    normals.iter().flat_map(|v| v.to_array()).chain(albedo).chain(conf).map(f32::to_bits).collect();
                (bits, stats)
            };
            let (a, b) = (run(false), run(true));
            let what = format!("samples {kind}, {method:?}, masked {masked}");
            assert_eq!(a, b, "{what}");
            assert!(a.1.invalid_count < n / 2, "{what}");
            // The robust fit leaves out the brightest readings of the pixels least squares
            // does not explain, which on these arbitrary samples is most of them.
            assert!(method == Method::Robust || a.1.lights_used[8] > n / 4, "{what}");
            assert!(a.0.iter().all(|v| f32::from_bits(*v).is_finite()), "{what}");
        }
    }
}

/// Pixels with dropped readings solved in groups by subset ([`Plan::finish_subsets`]) get the
/// same bits as solved one at a time ([`Plan::finish_subset`]), in both builds, grey and RGB,
/// threshold and robust (whose pixels that do not agree are fitted after either).
#[test]
fn grouped_subset_solves_match_per_pixel_ones_bitwise() {
    for method in [Method::Threshold, Method::Robust] {
        grouped_subset_solves_match(method);
    }
}

fn grouped_subset_solves_match(method: Method) {
    for (kind, rgb, masked) in
        [(0, false, false), (0, false, true), (1, true, false), (2, false, false), (3, false, false), (3, true, true)]
    {
        let channels = if rgb { Channels::Rgb } else { Channels::Gray };
        let (w, h) = (37, 11);
        let per = if rgb { 3 } else { 1 };
        let photos = (0..8).map(|i| Photo::new(w, h, channels, mixed_samples(kind, i, per * w * h)).unwrap()).collect();
        let mut stack = PhotoStack::new(photos, (0..8).map(|i| i.to_string()).collect()).unwrap();
        let (_, rig) = inputs_with(|i, n| mixed_samples(kind, i, n), |i| 0.8 + 0.03 * i as f32);
        if masked {
            stack = stack.with_mask(Grid::from_fn(w, h, |x, y| (x * 7 + y * 3) % 29 != 0)).unwrap();
        }
        let config = SolveConfig { method, ..SolveConfig::default() };
        let lights = check_rig(&stack, &rig).unwrap();
        let mut plan = Plan::new(&stack, &rig, &config, lights, None).unwrap();
        assert!(plan.batch_subsets);
        let directions = plan.lights.clone();
        let subsets = Subsets::new(&directions, config.max_condition, config.cache_capacity);
        let n = w * h;
        let band = BAND_ROWS * w;
        let mut run = |grouped: bool, vectorised: bool| {
            plan.batch_subsets = grouped;
            let (mut normals, mut albedo, mut conf) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![0.0f32; n]);
            let mut scratch = Scratch::new(8, rgb);
            let mut stats = SolveStats::empty(8);
            for p0 in (0..n).step_by(band) {
                let end = (p0 + band).min(n);
                let out = Out {
                    normals: &mut normals[p0..end],
                    albedo: &mut albedo[p0..end],
                    confidence: &mut conf[p0..end],
                };
                stats = stats.merge(if vectorised {
                    plan.solve_band(p0, out, &mut scratch, &subsets)
                } else {
                    plan.solve_band_portable(p0, out, &mut scratch, &subsets)
                });
            }
            let bits: Vec<u32> =
                normals.iter().chain(&albedo).flat_map(|v| v.to_array()).chain(conf).map(f32::to_bits).collect();
            (bits, stats)
        };
        for vectorised in [false, true] {
            let (a, b) = (run(false, vectorised), run(true, vectorised));
            let what = format!("{method:?}, samples {kind}, rgb {rgb}, masked {masked}, vectorised {vectorised}");
            assert_eq!(a, b, "{what}");
            let subset_pixels: usize = a.1.lights_used[..8].iter().sum();
            assert!(subset_pixels > n / 20 && a.1.lights_used[7] > 0, "{what}: {:?}", a.1);
        }
    }
}

#[test]
fn non_finite_float_readings_give_invalid_pixels() {
    let floats = |i: usize, n: usize| {
        Samples::F32(
            (0..n)
                .map(|p| match (p, i) {
                    (0, 3) => f32::NAN,
                    (1, _) => f32::INFINITY,
                    _ => 0.4,
                })
                .collect(),
        )
    };
    for method in [Method::LeastSquares, Method::Robust] {
        let (stack, rig) = inputs(floats);
        let sol = solve(&stack, &rig, &SolveConfig { method, ..SolveConfig::default() }, &NoProgress).unwrap();
        let finite = sol.normals.as_slice().iter().all(|v| v.is_finite())
            && sol.albedo.as_gray().unwrap().as_slice().iter().all(|v| v.is_finite());
        assert!(finite && sol.confidence.as_slice().iter().all(|c| c.is_finite()), "{method:?}");
        assert_eq!(sol.normals.get(1, 0), Vec3::ZERO);
        assert!(sol.normals.get(2, 0) != Vec3::ZERO);
    }
}

#[test]
fn subset_solve_is_the_pseudo_inverse() {
    let lights = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.6, 0.0, 0.8)];
    let s = SubsetSolve::new(&lights, 0b0111, 100.0);
    assert!(s.usable && (s.condition - 1.0).abs() < 1e-12);
    assert_eq!(s.cols, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
    // Two lights cannot determine a normal; nor can three coplanar ones.
    assert!(!SubsetSolve::new(&lights, 0b0011, 100.0).usable);
    assert!(!SubsetSolve::new(&lights, 0b1101, 100.0).usable);
}
