//! Tests of the quality metrics against independent oracles and known answers.

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::pyramid::{Border, blur};
use skinkit_maps::{Grid, NormalMap};
use skinkit_synth::metrics::*;

fn uniform(n: usize, seed: u64) -> Vec<f32> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random_range(-1.0f32..1.0)).collect()
}

fn noise_grid(w: usize, h: usize, seed: u64) -> Grid<f32> {
    Grid::from_vec(w, h, uniform(w * h, seed)).unwrap()
}

/// A periodic, smooth random field: white noise blurred toroidally a few times.
fn smooth_periodic(w: usize, h: usize, seed: u64) -> Grid<f32> {
    (0..3).fold(noise_grid(w, h, seed), |g, _| blur(&g, Border::Wrap))
}

/// Oracle for W1 of step quantile functions: midpoint rule on a grid fine enough (`n m k` cells)
/// that every cell lies inside one step of both.
fn wasserstein_oracle(a: &[f32], b: &[f32]) -> f64 {
    let mut a = a.to_vec();
    let mut b = b.to_vec();
    a.sort_by(f32::total_cmp);
    b.sort_by(f32::total_cmp);
    let cells = a.len() * b.len() * 2;
    (0..cells)
        .map(|c| {
            let q = (c as f64 + 0.5) / cells as f64;
            let ia = (q * a.len() as f64) as usize;
            let ib = (q * b.len() as f64) as usize;
            (a[ia] as f64 - b[ib] as f64).abs()
        })
        .sum::<f64>()
        / cells as f64
}

#[test]
fn wasserstein_equal_sizes_is_mean_sorted_difference() {
    let a = uniform(500, 1);
    let b: Vec<f32> = uniform(500, 2).iter().map(|v| v * 0.5 + 0.2).collect();
    let mut sa = a.clone();
    let mut sb = b.clone();
    sa.sort_by(f32::total_cmp);
    sb.sort_by(f32::total_cmp);
    let expect = sa.iter().zip(&sb).map(|(x, y)| (*x as f64 - *y as f64).abs()).sum::<f64>() / 500.0;
    assert!((wasserstein_1d(&a, &b) - expect).abs() < 1e-12);
}

#[test]
fn wasserstein_different_sizes_matches_quantile_quadrature() {
    for (n, m, seed) in [(7, 3, 1), (13, 20, 2), (1, 5, 3), (64, 48, 4)] {
        let a = uniform(n, seed);
        let b: Vec<f32> = uniform(m, seed + 100).iter().map(|v| v * 2.0 - 0.3).collect();
        let got = wasserstein_1d(&a, &b);
        let expect = wasserstein_oracle(&a, &b);
        assert!((got - expect).abs() < 1e-9, "{n} vs {m}: {got} vs {expect}");
        assert!((wasserstein_1d(&b, &a) - got).abs() < 1e-12, "symmetric");
    }
    // By hand: a's quantile steps are 0,1,2,3 on quarters, b's are 0.5, 2.5 on halves.
    assert!((wasserstein_1d(&[3.0, 1.0, 0.0, 2.0], &[2.5, 0.5]) - 0.5).abs() < 1e-12);
}

#[test]
fn wasserstein_shift_and_scale() {
    let a = uniform(301, 5);
    let shifted: Vec<f32> = a.iter().map(|v| v + 0.75).collect();
    assert!((wasserstein_1d(&a, &shifted) - 0.75).abs() < 1e-6);
    // Repeating every sample twice leaves the distribution unchanged.
    let twice: Vec<f32> = a.iter().flat_map(|&v| [v + 0.25, v + 0.25]).collect();
    assert!((wasserstein_1d(&a, &twice) - 0.25).abs() < 1e-6);
    // Scaling by 2 moves each quantile x to 2x: the distance is the mean |x|.
    let scaled: Vec<f32> = a.iter().map(|v| v * 2.0).collect();
    let mean_abs = a.iter().map(|v| v.abs() as f64).sum::<f64>() / a.len() as f64;
    assert!((wasserstein_1d(&a, &scaled) - mean_abs).abs() < 1e-6);
}

#[test]
fn wasserstein_edge_cases() {
    assert_eq!(wasserstein_1d(&[], &[]), 0.0);
    assert_eq!(wasserstein_1d(&[1.0], &[]), f64::INFINITY);
    assert_eq!(wasserstein_1d(&[2.0, f32::NAN], &[2.0]), 0.0);
    assert_eq!(wasserstein_1d(&[0.5; 10], &[0.5; 3]), 0.0);
}

fn tilted(w: usize, h: usize, slope: impl Fn(usize, usize) -> (f32, f32) + Sync) -> NormalMap {
    NormalMap::from_grid(Grid::from_fn(w, h, |x, y| {
        let (sx, sy) = slope(x, y);
        Vec3::new(-sx, -sy, 1.0)
    }))
}

#[test]
fn slopes_recover_the_gradient_and_skip_invalid() {
    let mut n = tilted(4, 3, |x, y| (0.1 * x as f32, -0.2 * y as f32));
    n.set(1, 1, Vec3::ZERO);
    n.set(2, 1, Vec3::X);
    let (sx, sy) = slopes(&n);
    assert_eq!(sx.len(), 10);
    assert!((sx[3] - 0.3).abs() < 1e-5 && sy[3].abs() < 1e-6);
    assert!((sy[9] + 0.4).abs() < 1e-5 && (sx[9] - 0.3).abs() < 1e-5);
}

#[test]
fn slope_and_channel_distances() {
    let a = tilted(16, 16, |x, y| (0.05 * (x as f32 - 8.0), 0.02 * y as f32));
    let b = tilted(16, 16, |x, y| (0.05 * (x as f32 - 8.0) + 0.2, 0.02 * y as f32));
    assert!(slope_distance(&a, &a) == 0.0);
    assert!((slope_distance(&a, &b) - 0.1).abs() < 1e-5, "{}", slope_distance(&a, &b));
    let c = Grid::from_fn(8, 8, |x, y| Vec3::new(x as f32, y as f32, 0.5));
    let d = c.map(|v| *v + Vec3::new(0.3, 0.0, -0.6));
    assert!((channel_distance(&c, &d) - 0.3).abs() < 1e-6);
}

fn argmax(v: &[f64]) -> usize {
    (0..v.len()).fold(0, |best, i| if v[i] > v[best] { i } else { best })
}

#[test]
fn sinusoid_peaks_in_its_ring() {
    use std::f32::consts::TAU;
    // 8 cycles over 64 texels = 0.125 cycles/texel = a quarter of Nyquist: ring 8 of 32.
    let gx = Grid::from_fn(64, 64, |x, _| (TAU * 8.0 * x as f32 / 64.0).sin());
    let px = radial_power_spectrum(&gx, 32);
    assert_eq!(argmax(&px), 8);
    assert!((px.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    // The same frequency along y on a map of another size lands in the same ring.
    let gy = Grid::from_fn(48, 32, |_, y| (TAU * 4.0 * y as f32 / 32.0 + 0.3).cos());
    assert_eq!(argmax(&radial_power_spectrum(&gy, 32)), 8);
    // A diagonal one at (8, 8)/128: radius sqrt(2)/16 = 0.0884 cycles/texel, ring
    // floor(32 * 0.0884 / 0.5) = 5.
    let gd = Grid::from_fn(128, 128, |x, y| (TAU * 8.0 * (x + y) as f32 / 128.0).sin());
    assert_eq!(argmax(&radial_power_spectrum(&gd, 32)), 5);
}

#[test]
fn transposed_and_shifted_copies_have_the_same_spectrum() {
    let g = smooth_periodic(64, 64, 7);
    let t = Grid::from_fn(64, 64, |x, y| *g.get(y, x));
    assert!(scalar_spectrum_distance(&g, &t, 32) < 1e-9);
    let s = Grid::from_fn(64, 64, |x, y| *g.get_wrapped(x as isize + 13, y as isize - 29));
    let shifted = scalar_spectrum_distance(&g, &s, 32);
    // A different texture (white noise) is far from the smooth field, the shifted copy is not.
    let other = scalar_spectrum_distance(&g, &noise_grid(64, 64, 8), 32);
    // The Hann window weighs the shifted texels differently, so the rings fluctuate a little.
    assert!(shifted < 0.25 && other > 1.0, "shifted {shifted}, other {other}");
}

#[test]
fn white_noise_is_flat() {
    // Mean of 4 independent 256x256 spectra in 8 rings: the innermost ring holds about 800
    // frequency samples (about 150 independent ones after Hermitian symmetry and the Hann window's
    // correlation), so each ring mean is within a few percent of 1/8; allow 0.06 decades (15%).
    let mut p = [0.0; 8];
    for seed in 0..4 {
        for (t, v) in p.iter_mut().zip(radial_power_spectrum(&noise_grid(256, 256, seed), 8)) {
            *t += v / 4.0;
        }
    }
    for (i, v) in p.iter().enumerate() {
        let decades = (v * 8.0).log10().abs();
        assert!(decades < 0.06, "ring {i}: {v}");
    }
}

#[test]
fn constant_maps_are_defined() {
    let c = Grid::filled(16, 8, 0.7f32);
    let p = radial_power_spectrum(&c, 8);
    assert!(p.iter().all(|&v| v == 0.0));
    assert_eq!(scalar_spectrum_distance(&c, &Grid::filled(5, 9, -2.0), 8), 0.0);
    let textured = scalar_spectrum_distance(&c, &noise_grid(16, 8, 1), 8);
    assert!(textured.is_finite() && textured > 5.0, "{textured}");
    let flat = NormalMap::flat(8, 8);
    assert_eq!(normal_spectrum_distance(&flat, &flat, 8), 0.0);
    assert_eq!(slope_distance(&flat, &flat), 0.0);
    let s = seam_energy(&Grid::filled(4, 4, Vec3::ONE));
    assert_eq!((s.across_seam, s.interior, s.ratio), (0.0, 0.0, 1.0));
    assert!(radial_power_spectrum(&Grid::filled(1, 1, 3.0), 4).iter().all(|&v| v == 0.0));
    assert!(radial_power_spectrum(&noise_grid(1, 32, 2), 4).iter().all(|v| v.is_finite()));
}

#[test]
fn normal_spectrum_sees_the_slope_frequency() {
    use std::f32::consts::TAU;
    let n = tilted(64, 64, |x, _| (0.3 * (TAU * 8.0 * x as f32 / 64.0).sin(), 0.0));
    assert_eq!(argmax(&normal_spectrum(&n, 32)), 8);
    let m = tilted(64, 64, |_, y| (0.0, 0.3 * (TAU * 8.0 * y as f32 / 64.0).sin()));
    assert!(normal_spectrum_distance(&n, &m, 32) < 1e-6);
}

#[test]
fn seam_energy_of_periodic_and_ramp_maps() {
    use std::f32::consts::TAU;
    // Whole periods in both directions along a diagonal: the seam pairs sample every phase.
    let s = Grid::from_fn(60, 40, |x, y| (TAU * (3.0 * x as f32 / 60.0 + 2.0 * y as f32 / 40.0)).sin());
    let e = scalar_seam_energy(&s);
    assert!((e.ratio - 1.0).abs() < 0.02, "{e:?}");
    let field = smooth_periodic(96, 96, 4);
    let e = scalar_seam_energy(&field);
    assert!(e.ratio > 0.6 && e.ratio < 1.6, "{e:?}");
    let ramp = Grid::from_fn(32, 32, |x, _| Vec3::splat(x as f32 / 32.0));
    let e = seam_energy(&ramp);
    // Oracle: interior horizontal steps are 3 (1/32)^2, the wrap step 3 (31/32)^2; vertical all 0.
    let interior = (32.0 * 31.0 * 3.0 / 1024.0) / (2.0 * 32.0 * 31.0);
    let across = (32.0 * 3.0 * (31.0f64 / 32.0).powi(2)) / 64.0;
    assert!((e.interior - interior).abs() < 1e-9 && (e.across_seam - across).abs() < 1e-6, "{e:?}");
    assert!(e.ratio > 100.0);
}

#[test]
fn normal_seam_energy_skips_invalid_texels() {
    let mut n = tilted(8, 8, |_, _| (0.0, 0.0));
    n.set(7, 3, Vec3::ZERO);
    let e = normal_seam_energy(&n);
    assert_eq!((e.across_seam, e.interior, e.ratio), (0.0, 0.0, 1.0));
}

#[test]
fn copy_statistics_of_identity_and_random_maps() {
    let id = Grid::from_fn(32, 24, |x, y| [x as u32, y as u32]);
    for wrap in [false, true] {
        let s = copy_statistics(&id, (32, 24), wrap);
        assert_eq!(s, CopyStats { largest_block: 768, mean_block: 768.0, distinct_offsets: 1 });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let cells = (0..64 * 64).map(|_| [rng.random_range(0..64u32), rng.random_range(0..64u32)]).collect();
    let random = Grid::from_vec(64, 64, cells).unwrap();
    let s = copy_statistics(&random, (64, 64), true);
    assert!(s.largest_block <= 3 && s.mean_block < 1.05, "{s:?}");
    // 4096 draws from 4096 offsets: about 4096 (1 - 1/e) = 2589 distinct ones.
    let mut offsets: Vec<_> = random
        .as_slice()
        .iter()
        .enumerate()
        .map(|(i, s)| ((s[0] as i64 - (i % 64) as i64).rem_euclid(64), (s[1] as i64 - (i / 64) as i64).rem_euclid(64)))
        .collect();
    offsets.sort();
    offsets.dedup();
    assert_eq!(s.distinct_offsets, offsets.len());
    assert!((2400..2800).contains(&s.distinct_offsets), "{s:?}");
}

#[test]
fn copy_statistics_of_a_wrapped_shift() {
    // A 64x64 output copying a 32x32 exemplar shifted by (5, 7), wrapping around it.
    let shift = Grid::from_fn(64, 64, |x, y| [((x + 5) % 32) as u32, ((y + 7) % 32) as u32]);
    let s = copy_statistics(&shift, (32, 32), true);
    assert_eq!(s, CopyStats { largest_block: 4096, mean_block: 4096.0, distinct_offsets: 1 });
    // Without exemplar wrap the copy breaks where the source wraps: 3 runs per axis, the first and
    // last joined through the toroidal output, so 2 x 2 blocks of 32 x 32, 3 x 3 offsets.
    let s = copy_statistics(&shift, (32, 32), false);
    assert_eq!(s, CopyStats { largest_block: 1024, mean_block: 1024.0, distinct_offsets: 9 });
    // Two halves copied from different places form two blocks.
    let halves = Grid::from_fn(10, 4, |x, y| if x < 6 { [x as u32, y as u32] } else { [x as u32 + 20, y as u32 + 3] });
    let s = copy_statistics(&halves, (40, 40), false);
    assert_eq!(s, CopyStats { largest_block: 24, mean_block: 20.0, distinct_offsets: 2 });
    assert_eq!(copy_statistics(&Grid::filled(0, 0, [0, 0]), (4, 4), true).largest_block, 0);
}

#[test]
fn metrics_do_not_depend_on_thread_count() {
    let g = smooth_periodic(48, 40, 12);
    let a = radial_power_spectrum(&g, 16);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let b = pool.install(|| radial_power_spectrum(&g, 16));
    assert_eq!(a, b);
}

/// A colour grid of independent uniform channels.
fn color_noise(w: usize, h: usize, seed: u64) -> Grid<Vec3> {
    let v = uniform(3 * w * h, seed);
    Grid::from_vec(w, h, v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()).unwrap()
}

/// Variation ratio: scaling a map about its mean scales every channel's deviation (closed form);
/// a constant output keeps none; a constant exemplar cannot lose any.
#[test]
fn variation_ratio_has_closed_forms() {
    let ex = color_noise(40, 30, 5);
    let mean = ex.as_slice().iter().copied().sum::<Vec3>() / ex.len() as f32;
    // Channels scaled by 0.3, 0.8 and 1.5: the smallest ratio is 0.3.
    let scaled = ex.map(|v| mean + (*v - mean) * Vec3::new(0.3, 0.8, 1.5));
    assert!((variation_ratio(&scaled, &ex) - 0.3).abs() < 1e-4, "{}", variation_ratio(&scaled, &ex));
    let shifted = ex.map(|v| *v + Vec3::splat(2.0));
    assert!((variation_ratio(&shifted, &ex) - 1.0).abs() < 1e-4);
    assert_eq!(variation_ratio(&Grid::filled(8, 8, mean), &ex), 0.0);
    assert_eq!(variation_ratio(&ex, &Grid::filled(8, 8, Vec3::ONE)), 1.0);
    // A channel constant in the exemplar is left out: only the varying ones count.
    let flat_blue = ex.map(|v| Vec3::new(v.x, v.y, 0.5));
    let out = flat_blue.map(|v| Vec3::new(v.x, v.y, v.z + 0.1 * v.x));
    assert!((variation_ratio(&out, &flat_blue) - 1.0).abs() < 1e-4);
}

/// An output smaller than the exemplar is measured against the exemplar's deviation at its own
/// scale: the exemplar is a 16-texel pattern plus a different constant per 16x16 tile, so every
/// tile's deviation is the pattern's while the whole exemplar's is dominated by the steps. A
/// verbatim 16x16 crop keeps all of it (1, where the whole exemplar's deviation would give under
/// 0.5), and a half-amplitude crop keeps half.
#[test]
fn variation_ratio_of_a_small_output_is_measured_at_its_scale() {
    let pattern = |x: usize, y: usize| ((x * 7 + y * 3) % 16) as f32 / 16.0;
    let ex =
        Grid::from_fn(64, 48, |x, y| Vec3::splat(pattern(x % 16, y % 16) + 2.0 * ((x / 16) + 3 * (y / 16)) as f32));
    let crop = Grid::from_fn(16, 16, |x, y| *ex.get(x + 32, y + 16));
    assert!((variation_ratio(&crop, &ex) - 1.0).abs() < 1e-4, "{}", variation_ratio(&crop, &ex));
    let mean = crop.as_slice().iter().copied().sum::<Vec3>() / crop.len() as f32;
    let half = crop.map(|v| mean + 0.5 * (*v - mean));
    assert!((variation_ratio(&half, &ex) - 0.5).abs() < 1e-4);
    // At the exemplar's size and above, the whole exemplar's deviation: the pattern alone (a
    // 64x48 output of it) keeps a small share of the steps' deviation.
    let flat = Grid::from_fn(64, 48, |x, y| Vec3::splat(pattern(x % 16, y % 16)));
    assert!(variation_ratio(&flat, &ex) < 0.1, "{}", variation_ratio(&flat, &ex));
}

/// Slope variation: normals of slopes scaled by `s` have slope deviations scaled by `s`; invalid
/// (zero) texels are left out.
#[test]
fn slope_variation_ratio_scales_with_the_slopes() {
    let (w, h) = (32, 24);
    let (gx, gy) = (uniform(w * h, 8), uniform(w * h, 9));
    let normals = |s: f32| {
        let data = (0..w * h).map(|i| Vec3::new(-s * gx[i], -s * gy[i] * 0.5, 1.0).normalize()).collect();
        NormalMap::from_unit_grid(Grid::from_vec(w, h, data).unwrap()).unwrap()
    };
    let ex = normals(1.0);
    let r = slope_variation_ratio(&normals(0.4), &ex);
    assert!((r - 0.4).abs() < 1e-3, "{r}");
    let mut holes = normals(0.4).into_grid();
    *holes.get_mut(3, 3) = Vec3::ZERO;
    let r = slope_variation_ratio(&NormalMap::from_unit_grid(holes).unwrap(), &ex);
    assert!((r - 0.4).abs() < 0.02, "{r}");
    assert!(slope_variation_ratio(&NormalMap::flat(w, h), &ex) < 1e-6);
}

/// The histogram mismatch against closed forms: an output equal to the exemplar scores 0; one whose
/// red channel is shifted by `delta` scores `delta / sd(red) / 3` (W1 of a shift is the shift; the
/// mean over three channels); a channel the exemplar holds constant is left out; a constant
/// exemplar scores 0 whatever the output.
#[test]
fn histogram_mismatch_has_closed_forms() {
    let (w, h) = (40, 30);
    let r = uniform(w * h, 1);
    let g = uniform(w * h, 2);
    let ex = Grid::from_fn(w, h, |x, y| Vec3::new(r[y * w + x], g[y * w + x], 0.25));
    assert_eq!(channel_histogram_mismatch(&ex, &ex), 0.0);
    let delta = 0.1f32;
    let shifted = ex.map(|v| *v + Vec3::new(delta, 0.0, 0.0));
    let sd = {
        let m = r.iter().map(|&v| v as f64).sum::<f64>() / r.len() as f64;
        (r.iter().map(|&v| (v as f64 - m).powi(2)).sum::<f64>() / r.len() as f64).sqrt()
    };
    // Blue is constant in the exemplar: left out, so the mean is over red and green.
    let expected = f64::from(delta) / sd / 2.0;
    let got = channel_histogram_mismatch(&shifted, &ex);
    assert!((got - expected).abs() < 1e-5, "{got} vs {expected}");
    let flat = Grid::filled(8, 8, Vec3::splat(0.5));
    assert_eq!(channel_histogram_mismatch(&ex, &flat), 0.0);
}

/// Past the sampling limit the output is read at an even stride: a large output tiled from the
/// exemplar (so every tile holds its histogram exactly) still scores about 0, and a shifted one
/// about the shift.
#[test]
fn histogram_mismatch_samples_large_outputs_evenly() {
    let side = 64;
    let v = uniform(side * side, 3);
    let ex = Grid::from_fn(side, side, |x, y| Vec3::splat(v[y * side + x]));
    let big = Grid::from_fn(300, 250, |x, y| *ex.get(x % side, y % side));
    assert!(channel_histogram_mismatch(&big, &ex) < 0.02, "{}", channel_histogram_mismatch(&big, &ex));
    let shifted = big.map(|t| *t + Vec3::splat(0.2));
    let sd = ex.as_slice().iter().map(|t| t.x as f64).collect::<Vec<_>>();
    let m = sd.iter().sum::<f64>() / sd.len() as f64;
    let sd = (sd.iter().map(|v| (v - m).powi(2)).sum::<f64>() / sd.len() as f64).sqrt();
    let got = channel_histogram_mismatch(&shifted, &ex);
    assert!((got - 0.2 / sd).abs() < 0.02, "{got} vs {}", 0.2 / sd);
}

/// For normal maps the mismatch is over the slopes: a map against itself scores 0, against a
/// tilted copy (every slope shifted by the same amount) the shift over the slopes' deviation.
#[test]
fn slope_histogram_mismatch_reads_slopes() {
    let (w, h) = (32, 32);
    let a = uniform(w * h, 4);
    let b = uniform(w * h, 5);
    let tilted_by = |dx: f32| {
        let n = Grid::from_fn(w, h, |x, y| Vec3::new(-(0.2 * a[y * w + x] + dx), -0.2 * b[y * w + x], 1.0).normalize());
        NormalMap::from_unit_grid(n).unwrap()
    };
    let (ex, tilted) = (tilted_by(0.0), tilted_by(0.05));
    assert_eq!(slope_histogram_mismatch(&ex, &ex), 0.0);
    let (sx, _) = slopes(&ex);
    let sd = |v: &[f32]| {
        let m = v.iter().map(|&x| x as f64).sum::<f64>() / v.len() as f64;
        (v.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
    };
    // sx shifts by 0.05 (W1 = 0.05), sy does not move: the mean of 0.05 / sd(sx) and 0.
    let expected = 0.05 / sd(&sx) / 2.0;
    let got = slope_histogram_mismatch(&tilted, &ex);
    assert!((got - expected).abs() < 1e-3 * expected.max(1.0), "{got} vs {expected}");
}
