//! The photometric-stereo solver against synthetic photos rendered here (exact Lambert on an
//! analytic surface) and against a naive per-pixel least-squares solve (nalgebra SVD).

use glam::{DVec3, Vec3};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_capture::solve::{AlbedoMap, Method, NoProgress, PhotoStack, Solution, SolveConfig, solve, solve_into};
use skinkit_capture::{Error, Light, Rig};
use skinkit_maps::normal::angle_degrees;
use skinkit_maps::progress::Step;
use skinkit_maps::{Channels, Grid, Photo, Samples, Transfer};

/// `k` lights evenly on a ring `theta` degrees from the camera axis.
fn ring(k: usize, theta: f64) -> Rig {
    let t = theta.to_radians();
    let lights = (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64 + 0.3;
            let d = DVec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()).as_vec3();
            Light::new(d, Vec3::ONE, None).unwrap()
        })
        .collect();
    Rig::new(lights, "test rig").unwrap()
}

/// Normals of a sum of Gaussian bumps, tilts up to ~35 deg (row index grows against y).
fn bumps(w: usize, h: usize) -> Grid<Vec3> {
    let centres = [(0.3, 0.3, 0.12), (0.7, 0.4, 0.1), (0.45, 0.75, 0.15), (0.8, 0.8, 0.08)];
    Grid::from_fn(w, h, |x, y| {
        let (u, v) = (x as f64 / w as f64, y as f64 / h as f64);
        let (mut zu, mut zv) = (0.0, 0.0);
        for (cu, cv, s) in centres {
            let e = (-((u - cu).powi(2) + (v - cv).powi(2)) / (2.0 * s * s)).exp() * 0.08;
            zu += -e * (u - cu) / (s * s);
            zv += -e * (v - cv) / (s * s);
        }
        // v grows downward, so dz/dy = -dz/dv.
        DVec3::new(-zu, zv, 1.0).normalize().as_vec3()
    })
}

/// Linear readings (full scale 1) of `albedo * E_i * max(0, n . L_i)` per light, grey.
fn render(normals: &Grid<Vec3>, albedo: f32, rig: &Rig) -> Vec<Vec<f32>> {
    rig.lights()
        .iter()
        .map(|l| normals.as_slice().iter().map(|n| albedo * l.intensity().x * n.dot(l.direction()).max(0.0)).collect())
        .collect()
}

fn float_photos(w: usize, h: usize, values: Vec<Vec<f32>>) -> Vec<Photo> {
    values.into_iter().map(|v| Photo::new(w, h, Channels::Gray, Samples::F32(v)).unwrap()).collect()
}

fn u16_photos(w: usize, h: usize, values: Vec<Vec<f32>>) -> Vec<Photo> {
    let q = |v: f32| (v.clamp(0.0, 1.0) * 65535.0).round() as u16;
    values
        .into_iter()
        .map(|v| Photo::new(w, h, Channels::Gray, Samples::U16(v.into_iter().map(q).collect())).unwrap())
        .collect()
}

fn stack(photos: Vec<Photo>) -> PhotoStack {
    let names = (1..=photos.len()).map(|i| format!("{i:02}.png")).collect();
    PhotoStack::new(photos, names).unwrap()
}

fn config(method: Method) -> SolveConfig {
    SolveConfig { method, ..SolveConfig::default() }
}

fn run(photos: Vec<Photo>, rig: &Rig, method: Method) -> Solution {
    solve(&stack(photos), rig, &config(method), &NoProgress).unwrap()
}

/// Mean angle in degrees over texels where `keep` holds.
fn mean_error(sol: &Solution, truth: &Grid<Vec3>, keep: impl Fn(usize) -> bool) -> f64 {
    let errors: Vec<f64> = (0..truth.len())
        .filter(|&i| keep(i))
        .map(|i| angle_degrees(sol.normals.as_slice()[i], truth.as_slice()[i]) as f64)
        .collect();
    assert!(errors.len() > 100, "too few texels compared");
    errors.iter().sum::<f64>() / errors.len() as f64
}

fn lit_by_all(truth: &Grid<Vec3>, rig: &Rig) -> impl Fn(usize) -> bool {
    let t = truth.clone();
    let lights: Vec<Vec3> = rig.lights().iter().map(|l| l.direction()).collect();
    move |i| lights.iter().all(|l| t.as_slice()[i].dot(*l) > 0.1)
}

fn gaussian(rng: &mut ChaCha8Rng) -> f32 {
    // Box-Muller.
    let (u, v): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random());
    ((-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()) as f32
}

#[test]
fn noise_free_photos_give_exact_normals() {
    let (w, h) = (96, 80);
    let rig = ring(8, 45.0);
    let truth = bumps(w, h);
    let keep = lit_by_all(&truth, &rig);
    for method in [Method::LeastSquares, Method::Robust] {
        let f = run(float_photos(w, h, render(&truth, 0.7, &rig)), &rig, method);
        let q = run(u16_photos(w, h, render(&truth, 0.7, &rig)), &rig, method);
        let (ef, eq) = (mean_error(&f, &truth, &keep), mean_error(&q, &truth, &keep));
        println!("{method:?}: float {ef:.5} deg, u16 {eq:.5} deg");
        assert!(ef < 0.05 && eq < 0.05, "{method:?}: {ef} {eq}");
        let i = (0..truth.len()).find(|&i| keep(i)).unwrap();
        assert!((f.albedo.as_gray().expect("grey photos, grey albedo").as_slice()[i] - 0.7).abs() < 1e-4);
        assert_eq!(f.albedo.get(i % w, i / w), Vec3::splat(f.albedo.as_gray().unwrap().as_slice()[i]));
        assert!(f.confidence.as_slice()[i] > 0.99);
    }
}

#[test]
fn robust_and_least_squares_agree_when_nothing_is_dropped() {
    let (w, h) = (70, 9);
    let rig = ring(8, 40.0);
    let flat = Grid::filled(w, h, Vec3::new(0.1, -0.2, 1.0).normalize());
    let photos = u16_photos(w, h, render(&flat, 0.5, &rig));
    let ls = run(photos.clone(), &rig, Method::LeastSquares);
    let robust = run(photos, &rig, Method::Robust);
    for (a, b) in ls.normals.as_slice().iter().zip(robust.normals.as_slice()) {
        assert!((*a - *b).length() < 1e-6, "{a} {b}");
    }
    assert_eq!(robust.stats.lights_used[8], w * h);
}

/// Least-squares `g` for `A g = b` via SVD, in f64.
fn naive_g(a: &DMatrix<f64>, b: &DVector<f64>) -> DVector<f64> {
    a.clone().svd(true, true).solve(b, 1e-12).unwrap()
}

#[test]
fn least_squares_matches_naive_solve_on_random_inputs() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let k = 7;
    let lights: Vec<Light> = (0..k)
        .map(|_| {
            let d = Vec3::new(rng.random_range(-0.7..0.7), rng.random_range(-0.7..0.7), rng.random_range(0.4..1.0))
                .normalize();
            Light::new(d, Vec3::splat(rng.random_range(0.5..2.0)), None).unwrap()
        })
        .collect();
    let rig = Rig::new(lights, "test rig").unwrap();
    let (w, h) = (23, 17);
    let values: Vec<Vec<f32>> = (0..k).map(|_| (0..w * h).map(|_| rng.random_range(0.05..1.0)).collect()).collect();
    // The solver's problem: least squares on the intensity-divided readings, `L g = I / E`.
    let l = DMatrix::from_fn(k, 3, |i, j| rig.lights()[i].direction()[j] as f64);
    for photos in [float_photos(w, h, values.clone()), u16_photos(w, h, values.clone())] {
        let scale = if photos[0].bit_depth() == 16 { 65535.0 } else { 1.0 };
        let sol = solve(&stack(photos.clone()), &rig, &config(Method::LeastSquares), &NoProgress).unwrap();
        for p in 0..w * h {
            let r = DVector::from_fn(k, |i, _| {
                photos[i].samples().get(p) as f64 / scale / rig.lights()[i].intensity().x as f64
            });
            let g = naive_g(&l, &r);
            let ours = sol.normals.as_slice()[p].as_dvec3() * sol.albedo.as_gray().unwrap().as_slice()[p] as f64;
            let diff = (ours - DVec3::new(g[0], g[1], g[2])).length();
            assert!(diff < 1e-5 * (1.0 + g.norm()), "pixel {p}: {ours} vs {g}");
            // Confidence: the residual factor of the naive fit (all lights used, cond factor 1).
            let rho2 = (&l * &g - &r).norm_squared() / r.norm_squared();
            let expect = 1.0 / (1.0 + rho2 / 0.01);
            assert!(
                (sol.confidence.as_slice()[p] as f64 - expect).abs() < 2e-3,
                "pixel {p}: {} vs {expect}",
                sol.confidence.as_slice()[p]
            );
        }
    }
}

#[test]
fn noise_matches_the_predicted_tilt_error() {
    let (w, h) = (256, 256);
    let (k, theta, sigma) = (8, 45.0f64, 0.01f32);
    let rig = ring(k, theta);
    let flat = Grid::filled(w, h, Vec3::Z);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let values: Vec<Vec<f32>> = render(&flat, 1.0, &rig)
        .into_iter()
        .map(|v| v.into_iter().map(|x| x + sigma * gaussian(&mut rng)).collect())
        .collect();
    let predicted = (sigma as f64 * (4.0 / (k as f64 * theta.to_radians().sin().powi(2))).sqrt()).to_degrees();
    for method in [Method::LeastSquares, Method::Robust] {
        let sol = run(float_photos(w, h, values.clone()), &rig, method);
        let stats = sol.normals.angular_error(&skinkit_maps::NormalMap::flat(w, h), None).unwrap();
        println!("{method:?}: rms {:.4} deg, predicted {predicted:.4} deg", stats.rms);
        assert_eq!(stats.count, w * h);
        assert!((stats.rms as f64 / predicted - 1.0).abs() < 0.15, "{method:?}: {} vs {predicted}", stats.rms);
    }
}

/// Bumps rendered under a ring, with each reading zeroed (occluded) with probability `p`.
fn shadowed(w: usize, h: usize, rig: &Rig, p: f64, seed: u64) -> (Grid<Vec3>, Vec<Vec<f32>>) {
    let truth = bumps(w, h);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut values = render(&truth, 0.8, rig);
    for px in 0..w * h {
        for v in values.iter_mut() {
            if rng.random_bool(p) {
                v[px] = 0.0;
            }
        }
    }
    (truth, values)
}

#[test]
fn robust_beats_least_squares_under_cast_shadows() {
    let (w, h) = (80, 64);
    let rig = ring(8, 45.0);
    let (truth, values) = shadowed(w, h, &rig, 0.15, 9);
    let keep = lit_by_all(&truth, &rig);
    let ls = run(u16_photos(w, h, values.clone()), &rig, Method::LeastSquares);
    let robust = run(u16_photos(w, h, values), &rig, Method::Robust);
    let valid = |s: &Solution, i: usize| s.normals.as_slice()[i] != Vec3::ZERO;
    let (e_ls, e_robust) = (
        mean_error(&ls, &truth, |i| keep(i) && valid(&ls, i)),
        mean_error(&robust, &truth, |i| keep(i) && valid(&robust, i)),
    );
    println!("cast shadows: least squares {e_ls:.3} deg, robust {e_robust:.4} deg");
    assert!(e_robust < 0.1 && e_ls > 3.0 && e_robust * 20.0 < e_ls);
    // Pixels that lost lights are still solved, with less confidence than fully lit ones.
    assert!(robust.stats.lights_used[5] > 0 && robust.stats.lights_used[8] > 0);
    let conf = |i: usize| robust.confidence.as_slice()[i];
    assert!((0..w * h).any(|i| keep(i) && valid(&robust, i) && conf(i) < 0.8));
    assert!((0..w * h).any(|i| keep(i) && conf(i) > 0.99));
}

#[test]
fn results_do_not_depend_on_thread_count() {
    let (w, h) = (67, 45);
    let rig = ring(8, 45.0);
    let (_, values) = shadowed(w, h, &rig, 0.2, 3);
    let st = stack(u16_photos(w, h, values));
    let with = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| solve(&st, &rig, &SolveConfig::default(), &NoProgress).unwrap())
    };
    let (a, b) = (with(1), with(2));
    let bits = |s: &Solution| {
        let n: Vec<u32> = s.normals.as_slice().iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect();
        let c: Vec<u32> = s.confidence.as_slice().iter().map(|v| v.to_bits()).collect();
        (n, c)
    };
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.albedo, b.albedo);
    assert_eq!(a.stats, b.stats);
}

#[test]
fn ninety_six_lights_with_a_tiny_cache() {
    let (w, h) = (48, 40);
    let lights = [30.0, 50.0, 70.0].iter().flat_map(|&t| ring(32, t).lights().to_vec()).collect();
    let rig = Rig::new(lights, "96 lights").unwrap();
    let (truth, values) = shadowed(w, h, &rig, 0.1, 21);
    let keep = |i: usize| truth.as_slice()[i].z > 0.95;
    let st = stack(u16_photos(w, h, values));
    let small = SolveConfig { cache_capacity: 3, ..SolveConfig::default() };
    let large = SolveConfig { cache_capacity: 1 << 20, ..SolveConfig::default() };
    let a = solve(&st, &rig, &small, &NoProgress).unwrap();
    let b = solve(&st, &rig, &large, &NoProgress).unwrap();
    assert_eq!(a.normals, b.normals);
    assert_eq!(a.confidence, b.confidence);
    // Pixels facing the camera see every unshadowed light; the dropped ones are exactly the zeros.
    let e = mean_error(&a, &truth, |i| keep(i) && a.normals.as_slice()[i] != Vec3::ZERO);
    println!("96 lights: mean error {e:.4} deg, invalid {}", a.stats.invalid_count);
    assert!(e < 0.1);
}

#[test]
fn rgb_photos_give_rgb_albedo() {
    let (w, h) = (40, 30);
    let lights = (ring(6, 50.0).lights().iter().enumerate())
        .map(|(i, l)| Light::new(l.direction(), Vec3::new(1.0, 0.8 + 0.05 * i as f32, 1.2), None).unwrap())
        .collect();
    let rig = Rig::new(lights, "rgb").unwrap();
    let truth = bumps(w, h);
    let albedo = Vec3::new(0.6, 0.4, 0.25);
    let photos: Vec<Photo> = rig
        .lights()
        .iter()
        .map(|l| {
            let samples = truth
                .as_slice()
                .iter()
                .flat_map(|n| (albedo * l.intensity() * n.dot(l.direction()).max(0.0)).to_array())
                .map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16)
                .collect();
            Photo::new(w, h, Channels::Rgb, Samples::U16(samples)).unwrap()
        })
        .collect();
    let keep = lit_by_all(&truth, &rig);
    for method in [Method::LeastSquares, Method::Robust] {
        let sol = run(photos.clone(), &rig, method);
        assert!(mean_error(&sol, &truth, &keep) < 0.05);
        let i = (0..w * h).find(|&i| keep(i)).unwrap();
        let rgb = sol.albedo.as_rgb().expect("rgb photos, rgb albedo");
        assert!((rgb.as_slice()[i] - albedo).abs().max_element() < 1e-3, "{}", rgb.as_slice()[i]);
        assert_eq!(sol.albedo.get(i % w, i / w), rgb.as_slice()[i]);
    }
}

/// `solve_into` gives the bits of a fresh `solve` whether it reuses the output maps (same size and
/// kind) or has to replace them (another size, or RGB maps reused for grey photos and back).
#[test]
fn solve_into_reuses_or_replaces_maps_with_the_same_results() {
    let rig = ring(8, 45.0);
    let grey = |w, h| u16_photos(w, h, render(&bumps(w, h), 0.6, &rig));
    let rgb = |w: usize, h: usize| {
        let photos = grey(w, h).into_iter().map(|p| {
            let Samples::U16(v) = p.samples() else { unreachable!() };
            let samples = v.iter().flat_map(|&x| [x, x / 2, x / 3]).collect();
            Photo::new(w, h, Channels::Rgb, Samples::U16(samples)).unwrap()
        });
        photos.collect::<Vec<_>>()
    };
    for method in [Method::LeastSquares, Method::Robust] {
        let cfg = config(method);
        let fresh_grey = solve(&stack(grey(31, 9)), &rig, &cfg, &NoProgress).unwrap();
        let fresh_rgb = solve(&stack(rgb(31, 9)), &rig, &cfg, &NoProgress).unwrap();
        assert!(matches!(fresh_grey.albedo, AlbedoMap::Gray(_)) && matches!(fresh_rgb.albedo, AlbedoMap::Rgb(_)));
        let same = |a: &Solution, b: &Solution| {
            a.normals == b.normals && a.albedo == b.albedo && a.confidence == b.confidence && a.stats == b.stats
        };
        // Reused in place: a solution of the same stack, and one of a differently sized stack.
        let mut out = fresh_grey.clone();
        solve_into(&stack(grey(31, 9)), &rig, &cfg, &NoProgress, &mut out).unwrap();
        assert!(same(&out, &fresh_grey), "{method:?}");
        let mut out = solve(&stack(grey(12, 40)), &rig, &cfg, &NoProgress).unwrap();
        solve_into(&stack(grey(31, 9)), &rig, &cfg, &NoProgress, &mut out).unwrap();
        assert!(same(&out, &fresh_grey), "{method:?}");
        // Kind switches both ways.
        let mut out = fresh_rgb.clone();
        solve_into(&stack(grey(31, 9)), &rig, &cfg, &NoProgress, &mut out).unwrap();
        assert!(same(&out, &fresh_grey), "{method:?}");
        solve_into(&stack(rgb(31, 9)), &rig, &cfg, &NoProgress, &mut out).unwrap();
        assert!(same(&out, &fresh_rgb), "{method:?}");
        assert_eq!(fresh_rgb.albedo.to_color_map().get(3, 4), &fresh_rgb.albedo.get(3, 4));
        assert_eq!(fresh_grey.albedo.to_color_map().get(3, 4), &fresh_grey.albedo.get(3, 4));
        assert_eq!(fresh_grey.albedo.size(), (31, 9));
    }
}

#[test]
fn srgb_photos_are_linearised() {
    let (w, h) = (40, 30);
    let rig = ring(8, 45.0);
    let truth = bumps(w, h);
    let encode = |v: f32| (skinkit_maps::encoding::linear_to_srgb(v) * 255.0).round() as u8;
    let photos = render(&truth, 0.8, &rig)
        .into_iter()
        .map(|v| {
            Photo::new(w, h, Channels::Gray, Samples::U8(v.into_iter().map(encode).collect()))
                .unwrap()
                .with_transfer(Transfer::Srgb)
        })
        .collect();
    let sol = run(photos, &rig, Method::LeastSquares);
    let e = mean_error(&sol, &truth, lit_by_all(&truth, &rig));
    println!("8-bit sRGB: mean error {e:.3} deg");
    // 8-bit quantisation limits the accuracy; without linearisation the error is several degrees.
    assert!(e < 0.5);
}

#[test]
fn ambient_frame_is_subtracted() {
    let (w, h) = (30, 20);
    let rig = ring(8, 45.0);
    let truth = bumps(w, h);
    let ambient: Vec<f32> = (0..w * h).map(|i| 0.05 + 0.1 * (i % 7) as f32 / 7.0).collect();
    let lit: Vec<Vec<f32>> =
        render(&truth, 0.6, &rig).into_iter().map(|v| v.iter().zip(&ambient).map(|(a, b)| a + b).collect()).collect();
    let amb = u16_photos(w, h, vec![ambient]).pop().unwrap();
    for method in [Method::LeastSquares, Method::Robust] {
        let st = stack(u16_photos(w, h, lit.clone())).with_ambient(amb.clone(), "dark.png").unwrap();
        let sol = solve(&st, &rig, &config(method), &NoProgress).unwrap();
        assert!(mean_error(&sol, &truth, lit_by_all(&truth, &rig)) < 0.05);
    }
}

#[test]
fn mask_excludes_texels() {
    let (w, h) = (30, 20);
    let rig = ring(8, 45.0);
    let truth = bumps(w, h);
    let mask = Grid::from_fn(w, h, |x, _| x >= 10);
    let st = stack(u16_photos(w, h, render(&truth, 0.6, &rig))).with_mask(mask).unwrap();
    let sol = solve(&st, &rig, &SolveConfig::default(), &NoProgress).unwrap();
    assert_eq!(sol.stats.masked_count, 10 * h);
    assert_eq!(sol.stats.invalid_count, 10 * h);
    assert_eq!(sol.normals.get(3, 5), Vec3::ZERO);
    assert_eq!(*sol.confidence.get(3, 5), 0.0);
    assert!(sol.normals.get(20, 5) != Vec3::ZERO);
}

#[test]
fn hard_pixels_are_invalid_never_nan() {
    let rig = ring(8, 45.0);
    let n = Vec3::new(0.2, 0.1, 1.0).normalize();
    let reading = |l: &Light| 0.5 * n.dot(l.direction()).max(0.0);
    // Pixels: 0 normal, 1 all black, 2 only two lit, 3 six saturated, 4 one saturated, 5 zero albedo.
    let values: Vec<Vec<f32>> = rig
        .lights()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            vec![
                reading(l),
                0.0,
                if i < 2 { reading(l) } else { 0.0 },
                if i < 6 { 1.0 } else { reading(l) },
                if i == 0 { 1.0 } else { reading(l) },
                0.0,
            ]
        })
        .collect();
    for method in [Method::LeastSquares, Method::Robust] {
        let sol = run(u16_photos(6, 1, values.clone()), &rig, method);
        let albedo = sol.albedo.to_color_map();
        let all_finite = sol.normals.as_slice().iter().chain(albedo.as_slice()).all(|v| v.is_finite());
        assert!(all_finite && sol.confidence.as_slice().iter().all(|c| c.is_finite() && (0.0..=1.0).contains(c)));
        assert!(angle_degrees(sol.normals.get(0, 0), n) < 0.05);
        for px in [1, 5] {
            assert_eq!(sol.normals.get(px, 0), Vec3::ZERO, "{method:?} pixel {px}");
            assert_eq!(*sol.confidence.get(px, 0), 0.0);
        }
        if method == Method::Robust {
            assert_eq!(sol.normals.get(2, 0), Vec3::ZERO);
            assert_eq!(sol.normals.get(3, 0), Vec3::ZERO);
            assert!(angle_degrees(sol.normals.get(4, 0), n) < 0.05);
            assert!(*sol.confidence.get(4, 0) < *sol.confidence.get(0, 0));
            assert_eq!(sol.stats.invalid_count, 4);
        }
    }
    // A 1x1 image.
    let one = run(u16_photos(1, 1, rig.lights().iter().map(|l| vec![reading(l)]).collect()), &rig, Method::Robust);
    assert!(angle_degrees(one.normals.get(0, 0), n) < 0.05);
}

#[test]
fn bad_rigs_and_stacks_are_refused() {
    let (w, h) = (4, 3);
    let photos = |k| float_photos(w, h, vec![vec![0.5; w * h]; k]);
    // Coplanar: every light on the great circle through x and z.
    // (A rig is valid by construction: coplanar lights and two lights are refused by `Rig::new`.)
    let coplanar =
        (0..8).map(|i| 0.3 + 0.3 * i as f32).map(|a| Light::new(Vec3::new(a.cos(), 0.0, a.sin()), Vec3::ONE, None));
    let err = Rig::new(coplanar.map(Result::unwrap).collect(), "coplanar").unwrap_err();
    assert!(matches!(err, Error::BadRig(_)), "{err}");
    let two = ring(8, 45.0).lights()[..2].to_vec();
    assert!(matches!(Rig::new(two, "two"), Err(Error::BadFile { .. })));
    // A condition number above the solver's bound is refused by the solve.
    let narrow = SolveConfig { max_condition: 1.5, ..SolveConfig::default() };
    let err = solve(&stack(photos(8)), &ring(8, 20.0), &narrow, &NoProgress).unwrap_err();
    assert!(matches!(err, Error::BadRig(_)), "{err}");
    let err = solve(&stack(photos(7)), &ring(8, 45.0), &SolveConfig::default(), &NoProgress).unwrap_err();
    assert_eq!(err.to_string(), "rig has 8 lights but 7 photos were given");
    let mut mixed = photos(3);
    mixed[2] = Photo::new(5, 3, Channels::Gray, Samples::F32(vec![0.0; 15])).unwrap();
    let err = PhotoStack::new(mixed, vec!["a/01.png".into(), "a/02.png".into(), "a/03.png".into()]).unwrap_err();
    assert_eq!(err.to_string(), "photo 3 (a/03.png) is 5x3 but photo 1 (a/01.png) is 4x3");
    let mut depths = photos(3);
    depths[1] = Photo::new(w, h, Channels::Gray, Samples::U8(vec![0; w * h])).unwrap();
    assert!(matches!(PhotoStack::new(depths, vec!["1".into(), "2".into(), "3".into()]), Err(Error::InvalidInput(_))));
    assert!(stack(photos(3)).with_mask(Grid::filled(3, 3, true)).is_err());
    let bad = SolveConfig { min_lights: 2, ..SolveConfig::default() };
    assert!(bad.validate().is_err());
    assert!(SolveConfig { shadow_rel: 1.5, ..SolveConfig::default() }.validate().is_err());
    assert!(SolveConfig::default().validate().is_ok());
}

#[test]
fn progress_reaches_one() {
    let rig = ring(8, 45.0);
    let seen = std::sync::Mutex::new(Vec::new());
    let st = stack(float_photos(10, 40, render(&bumps(10, 40), 0.5, &rig)));
    let record = |step: Step<'_>| seen.lock().unwrap().push(format!("{step:?}"));
    solve(&st, &rig, &SolveConfig::default(), &record).unwrap();
    let seen = seen.into_inner().unwrap();
    // One stage of the image's 40 rows, every row told once, from whichever thread solved it.
    assert_eq!(seen.first().map(String::as_str), Some("Start { name: \"solve\", len: 40 }"));
    assert_eq!(seen.last().map(String::as_str), Some("Finish"));
    let rows: u64 =
        seen.iter().filter_map(|s| s.strip_prefix("Advance(")?.strip_suffix(')')?.parse::<u64>().ok()).sum();
    assert_eq!(rows, 40);
}
