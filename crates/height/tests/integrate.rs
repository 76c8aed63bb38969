//! The integrators against exact heights (synthetic heightfields whose heights the `heightfield`
//! crate knows), against a brute-force least-squares solve on small grids, and on hard inputs.

mod support;

use skinkit_height::compare::error_share;
use skinkit_height::{Error, HOLE_WEIGHT, HeightOptions, Integrator, Scale, integrate};
use skinkit_heightfield::{HeightSample, Heightfield, SkinParams};
use skinkit_maps::{NormalMap, Vec3};
use support::{brute_force, wave_field};

fn options(integrator: Integrator, scale: Scale) -> HeightOptions {
    HeightOptions { integrator: Some(integrator), scale, ..HeightOptions::default() }
}

/// Each integrator is the least-squares minimiser of its edge equations: the same heights as a
/// Gauss-Seidel solve of the normal equations run to convergence in f64.
#[test]
fn each_integrator_solves_its_least_squares_problem() {
    let field = SkinParams::forehead(11, 9, 3).generate().unwrap();
    let mut normals = field.normals.clone();
    normals.set(4, 4, Vec3::ZERO);
    normals.set(5, 4, Vec3::ZERO);
    for (integrator, wraps, masked) in
        [(Integrator::Periodic, true, false), (Integrator::Neumann, false, false), (Integrator::Masked, false, true)]
    {
        let opts = HeightOptions { tolerance: 1e-9, max_iterations: 2000, ..options(integrator, Scale::Texels) };
        let ours = integrate(&normals, &opts).unwrap();
        let exact = brute_force(&normals, wraps, masked, HOLE_WEIGHT as f64);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let (m1, m2) = (mean(&ours.map.as_slice().iter().map(|&v| v as f64).collect::<Vec<_>>()), mean(&exact));
        for (i, (&a, &b)) in ours.map.as_slice().iter().zip(&exact).enumerate() {
            assert!(((a as f64 - m1) - (b - m2)).abs() < 2e-4, "{integrator:?} texel {i}: {a} against {b}");
        }
    }
}

/// A periodic field (whole waves across the map) comes back within 1 % of its RMS, and its
/// height tiles: the step across the wrap seam is no larger than the steps inside.
#[test]
fn periodic_integration_recovers_a_wrapping_field_that_tiles() {
    let field = wave_field(128, 96, 0.05, true);
    let h = integrate(&field.normals, &options(Integrator::Periodic, Scale::MmPerTexel(0.05))).unwrap();
    assert_eq!(h.report.unit, "mm");
    let err = error_share(&h.map, &field.heights, None, false);
    assert!(err < 0.01, "error {err} of the RMS height");
    let (w, hh) = h.map.size();
    let step = |x0: usize, x1: usize| {
        let s: f64 = (0..hh).map(|y| (h.map.get(x1, y) - h.map.get(x0, y)) as f64).map(|d| d * d).sum();
        (s / hh as f64).sqrt()
    };
    let seam = step(w - 1, 0);
    let interior: Vec<f64> = (0..w - 1).map(|x| step(x, x + 1)).collect();
    let max = interior.iter().cloned().fold(0.0, f64::max);
    assert!(seam <= max, "seam step {seam} over the largest interior step {max}");
}

/// A field that does not wrap (a tilted skin patch with furrows and pores): Neumann recovers it
/// within 2 % of its RMS after removing the best plane, where a periodic solve bends it.
#[test]
fn neumann_integration_recovers_a_rectangle_without_a_bowl() {
    let mut params = SkinParams::forehead(160, 120, 5);
    params.tilt = [0.05, -0.03];
    // Finer than the forehead's own 0.02 mm, so pores span several texels: the test is about the
    // boundary, not the discretisation error of near-Nyquist detail.
    params.mm_per_texel = 0.005;
    let field = params.generate().unwrap();
    let scale = Scale::MmPerTexel(field.mm_per_texel);
    let neumann = integrate(&field.normals, &options(Integrator::Neumann, scale)).unwrap();
    let periodic = integrate(&field.normals, &options(Integrator::Periodic, scale)).unwrap();
    let (en, ep) =
        (error_share(&neumann.map, &field.heights, None, true), error_share(&periodic.map, &field.heights, None, true));
    assert!(en < 0.02, "neumann error {en}");
    assert!(ep > 5.0 * en, "periodic error {ep} should be far worse than neumann's {en} on a tilted patch");
    assert_eq!(Integrator::choose(false, 0), Integrator::Neumann);
}

/// Holes (a disc and a band of invalid texels, the valid part connected) neither pull the surface nor leave NaN: the masked
/// solve is within 3 % of the RMS over the valid texels; treating the holes as flat data is not.
#[test]
fn masked_integration_ignores_holes() {
    let mut params = SkinParams::forehead(128, 128, 9);
    params.mm_per_texel = 0.005;
    let field = params.generate().unwrap();
    let mut normals = field.normals.clone();
    let mut valid = vec![true; 128 * 128];
    for y in 0..128 {
        for x in 0..128 {
            let disc = (x as f64 - 40.0).powi(2) + (y as f64 - 60.0).powi(2) < 400.0;
            if disc || ((90..96).contains(&x) && (15..110).contains(&y)) {
                normals.set(x, y, Vec3::ZERO);
                valid[y * 128 + x] = false;
            }
        }
    }
    let scale = Scale::MmPerTexel(field.mm_per_texel);
    let masked = integrate(&normals, &HeightOptions { scale, ..HeightOptions::default() }).unwrap();
    assert_eq!(masked.report.integrator, Integrator::Masked, "a map with holes chooses the masked solve");
    assert!(masked.map.as_slice().iter().all(|v| v.is_finite()));
    let flat = integrate(&normals, &options(Integrator::Neumann, scale)).unwrap();
    let em = error_share(&masked.map, &field.heights, Some(&valid), true);
    let ef = error_share(&flat.map, &field.heights, Some(&valid), true);
    assert!(em < 0.03, "masked error {em} (after {:?} iterations)", masked.report.iterations);
    assert!(ef > 2.0 * em, "flat-filled holes {ef} against masked {em}");
}

/// Signs and rows: a surface rising to the right and toward the top of the picture (row 0) gives
/// heights that rise the same way, in millimetres through the scale.
#[test]
fn a_plane_comes_back_with_its_signs_and_scale() {
    let (sx, sy) = (0.2, 0.1);
    let field =
        Heightfield::from_fn(40, 30, 0.5, |x, y| HeightSample { height: sx * x + sy * y, gradient: [sx, sy].into() })
            .unwrap();
    let h = integrate(&field.normals, &options(Integrator::Neumann, Scale::MmPerTexel(0.5))).unwrap();
    let dx = h.map.get(39, 15) - h.map.get(0, 15);
    let dy = h.map.get(20, 0) - h.map.get(20, 29);
    assert!((dx as f64 - sx * 39.0 * 0.5).abs() < 1e-3, "rise to the right {dx}");
    assert!((dy as f64 - sy * 29.0 * 0.5).abs() < 1e-3, "rise toward row 0 {dy}");
    assert!(h.report.residual_relative < 1e-4);
}

/// NaN, zero-length and back-facing normals are counted and integrated around, never into NaN;
/// a map with no usable normal is refused.
#[test]
fn bad_normals_are_counted_not_integrated() {
    let mut normals = NormalMap::flat(16, 16);
    normals.set(1, 1, Vec3::new(f32::NAN, 0.0, 1.0));
    normals.set(2, 2, Vec3::ZERO);
    normals.set(3, 3, Vec3::new(0.0, 0.6, -0.8));
    normals.set(4, 4, Vec3::new(1.0, 0.0, 1e-9));
    let h = integrate(&normals, &HeightOptions::default()).unwrap();
    let t = h.report.texels;
    // `NormalMap::set` already turns a NaN normal into the invalid (zero) marker.
    assert_eq!((t.non_finite, t.zero, t.back_facing, t.clamped, t.valid), (0, 2, 1, 1, 253));
    assert!(h.map.as_slice().iter().all(|v| v.is_finite()));
    for integrator in [Integrator::Periodic, Integrator::Neumann, Integrator::Masked] {
        let h = integrate(&normals, &options(integrator, Scale::Texels)).unwrap();
        assert!(h.map.as_slice().iter().all(|v| v.is_finite()), "{integrator:?}");
    }
    let mut dead = NormalMap::flat(4, 4);
    (0..4).for_each(|y| (0..4).for_each(|x| dead.set(x, y, Vec3::ZERO)));
    assert!(matches!(integrate(&dead, &HeightOptions::default()), Err(Error::NoValidTexel { texels: 16 })));
    assert!(Scale::from_mm(Some(-1.0)).is_err() && Scale::from_mm(Some(f64::NAN)).is_err());
}

/// 16-bit quantised normals (what a PNG holds) still integrate to within 2 % on a wrapping field.
#[test]
fn quantised_normals_integrate() {
    let field = wave_field(96, 96, 0.05, true);
    let q = |c: f32| ((c * 0.5 + 0.5) * 65535.0).round() / 65535.0 * 2.0 - 1.0;
    let grid = field.normals.grid().map(|n| Vec3::new(q(n.x), q(n.y), q(n.z)));
    let normals = NormalMap::from_grid(grid);
    let h = integrate(&normals, &options(Integrator::Periodic, Scale::MmPerTexel(0.05))).unwrap();
    let err = error_share(&h.map, &field.heights, None, false);
    assert!(err < 0.02, "error {err}");
}

/// The same bits on one thread and on four, for every integrator.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let field = SkinParams::forehead(70, 50, 2).generate().unwrap();
    let mut normals = field.normals.clone();
    (10..20).for_each(|x| normals.set(x, 20, Vec3::ZERO));
    // With holes every integrator takes its general path; without, Neumann takes the fused one.
    for (map, integrator) in [
        (&normals, Integrator::Periodic),
        (&normals, Integrator::Neumann),
        (&normals, Integrator::Masked),
        (&field.normals, Integrator::Neumann),
    ] {
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| integrate(map, &options(integrator, Scale::Texels)).unwrap())
        };
        let (a, b) = (run(1), run(4));
        let same = a.map.as_slice().iter().zip(b.map.as_slice()).all(|(x, y)| x.to_bits() == y.to_bits());
        assert!(same, "{integrator:?}");
        let report = |h: &skinkit_height::Height| (h.report.residual_rms.to_bits(), h.report.rms.to_bits());
        assert_eq!(report(&a), report(&b), "{integrator:?}");
    }
}
