//! Nearest-point partitions and random-curve boundaries, checked against independent oracles:
//! a brute-force nearest-point scan in floating point, and flood fills written here (not the
//! crate's) for the topology of every cell.

use std::collections::VecDeque;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::Grid;
use skinkit_stitch::curve::{self, CurveParams, Warp};
use skinkit_stitch::partition::{self, Partition, Rect, RegionArea, SeedPoint};

fn seed(region: usize, x: u32, y: u32) -> SeedPoint {
    SeedPoint { region, x, y }
}

/// `n` distinct random seed points, region `i % regions`.
fn random_seeds(rng: &mut ChaCha8Rng, n: usize, regions: usize, w: usize, h: usize) -> Vec<SeedPoint> {
    let mut seeds: Vec<SeedPoint> = Vec::new();
    while seeds.len() < n {
        let s = seed(seeds.len() % regions, rng.random_range(0..w as u32), rng.random_range(0..h as u32));
        if !seeds.iter().any(|t| (t.x, t.y) == (s.x, s.y)) {
            seeds.push(s);
        }
    }
    seeds
}

/// The oracle: nearest point by floating-point Euclidean distance, ties to the lowest region
/// then the lowest point index.
fn brute_nearest_region(x: usize, y: usize, seeds: &[SeedPoint]) -> usize {
    let key = |i: usize| {
        let s = seeds[i];
        let d = ((x as f64 - s.x as f64).powi(2) + (y as f64 - s.y as f64).powi(2)).sqrt();
        (d, s.region, i)
    };
    let best = (0..seeds.len()).min_by(|&a, &b| key(a).partial_cmp(&key(b)).unwrap()).unwrap();
    seeds[best].region
}

#[test]
fn nearest_partition_matches_brute_force_with_ties_to_lowest_region() {
    // Points placed symmetrically so that whole lines of texels are exact ties.
    let seeds = [seed(2, 10, 10), seed(0, 30, 10), seed(1, 20, 30), seed(3, 20, 0)];
    let p = Partition::nearest(41, 33, 4, &seeds).unwrap();
    for y in 0..33 {
        for x in 0..41 {
            assert_eq!(*p.labels().get(x, y) as usize, brute_nearest_region(x, y, &seeds), "texel ({x}, {y})");
        }
    }
    // Texel (20, 10) is equidistant from regions 2 and 0: the lower index wins.
    assert_eq!(*p.labels().get(20, 10), 0);

    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..5 {
        let seeds = random_seeds(&mut rng, 9, 4, 57, 38);
        let p = Partition::nearest(57, 38, 4, &seeds).unwrap();
        for y in 0..38 {
            for x in 0..57 {
                assert_eq!(*p.labels().get(x, y) as usize, brute_nearest_region(x, y, &seeds));
            }
        }
    }
}

#[test]
fn areas_and_synthesis_rects_match_a_scan() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let (w, h) = (70, 45);
    let seeds = random_seeds(&mut rng, 6, 3, w, h);
    let p = Partition::nearest(w, h, 3, &seeds).unwrap();
    for r in 0..3 {
        let texels: Vec<(usize, usize)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| *p.labels().get(x, y) as usize == r)
            .collect();
        let x0 = texels.iter().map(|t| t.0).min().unwrap();
        let x1 = texels.iter().map(|t| t.0).max().unwrap();
        let y0 = texels.iter().map(|t| t.1).min().unwrap();
        let y1 = texels.iter().map(|t| t.1).max().unwrap();
        let bbox = Rect { x: x0, y: y0, width: x1 - x0 + 1, height: y1 - y0 + 1 };
        assert_eq!(p.areas()[r], RegionArea { texels: texels.len(), bbox: Some(bbox) });
        let grown = p.synthesis_rect(r, 12).unwrap();
        assert_eq!(grown.x, x0.saturating_sub(12));
        assert_eq!(grown.y, y0.saturating_sub(12));
        assert_eq!(grown.x + grown.width, (x1 + 1 + 12).min(w));
        assert_eq!(grown.y + grown.height, (y1 + 1 + 12).min(h));
        let mask = p.mask(r, grown);
        let ones = mask.as_slice().iter().filter(|&&m| m == 1.0).count();
        assert_eq!(ones, texels.len(), "the grown rect holds the whole region");
    }
    assert_eq!(p.areas().iter().map(|a| a.texels).sum::<usize>(), w * h);
}

#[test]
fn coverage_restricts_the_areas_but_not_the_labels() {
    let seeds = [seed(0, 5, 5), seed(1, 25, 5)];
    let mut p = Partition::nearest(30, 10, 2, &seeds).unwrap();
    let labels = p.labels().clone();
    // Only columns 0..8 are skin: region 1 (right half) has nothing to synthesise.
    let coverage = Grid::from_fn(30, 10, |x, _| x < 8);
    p.restrict_to(&coverage).unwrap();
    assert_eq!(p.labels(), &labels);
    assert_eq!(p.areas()[0], RegionArea { texels: 80, bbox: Some(Rect { x: 0, y: 0, width: 8, height: 10 }) });
    assert_eq!(p.areas()[1], RegionArea { texels: 0, bbox: None });
    assert!(p.restrict_to(&Grid::filled(29, 10, true)).unwrap_err().to_string().contains("29x10"));
}

#[test]
fn a_region_whose_points_are_all_covered_gets_no_texels() {
    // Region 1's only point sits on region 0's point: ties go to region 0 everywhere.
    let seeds = [seed(1, 8, 8), seed(0, 8, 8), seed(2, 30, 8)];
    for curve in [CurveParams::straight(), CurveParams::new(6.0, 3)] {
        let p = Partition::build(40, 16, 3, &seeds, &curve).unwrap();
        assert_eq!(p.areas()[1], RegionArea { texels: 0, bbox: None });
        assert_eq!(p.synthesis_rect(1, 10), None);
        assert_eq!(*p.labels().get(8, 8), 0);
        assert!(p.areas()[0].texels > 0 && p.areas()[2].texels > 0);
    }
}

#[test]
fn bad_seed_points_are_refused_with_their_values() {
    let err = |w, h, n, s: &[SeedPoint]| Partition::nearest(w, h, n, s).unwrap_err().to_string();
    assert!(err(10, 10, 1, &[seed(0, 10, 3)]).contains("(10, 3) lies outside the 10x10 map"));
    assert!(err(10, 10, 1, &[seed(1, 1, 1)]).contains("names region 1 but there are 1"));
    assert!(err(10, 10, 1, &[]).contains("no seed points"));
    assert!(err(0, 10, 1, &[seed(0, 0, 0)]).contains("0x10"));
}

// ---- topology oracles -------------------------------------------------------------------------

const N4: [(i64, i64); 4] = [(1, 0), (-1, 0), (0, 1), (0, -1)];
const N8: [(i64, i64); 8] = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)];

/// Texels reachable from `start` through texels where `inside` holds, with the given steps, in a
/// `w x h` grid.
fn flood(w: i64, h: i64, start: (i64, i64), steps: &[(i64, i64)], inside: impl Fn(i64, i64) -> bool) -> usize {
    let mut seen = vec![false; (w * h) as usize];
    let mut queue = VecDeque::from([start]);
    seen[(start.1 * w + start.0) as usize] = true;
    let mut count = 0;
    while let Some((x, y)) = queue.pop_front() {
        count += 1;
        for (dx, dy) in steps {
            let (nx, ny) = (x + dx, y + dy);
            if nx >= 0 && ny >= 0 && nx < w && ny < h && !seen[(ny * w + nx) as usize] && inside(nx, ny) {
                seen[(ny * w + nx) as usize] = true;
                queue.push_back((nx, ny));
            }
        }
    }
    count
}

/// Every cell is one 4-connected piece holding its point, and has no holes: its complement,
/// padded by a ring of outside texels, is one 8-connected piece (so every part of it reaches the
/// map's edge).
fn assert_valid_cells(cells: &Grid<u16>, seeds: &[SeedPoint], what: &str) {
    let (w, h) = (cells.width() as i64, cells.height() as i64);
    let at = |x: i64, y: i64| *cells.get(x as usize, y as usize) as usize;
    for (i, s) in seeds.iter().enumerate() {
        let size = cells.as_slice().iter().filter(|&&c| c as usize == i).count();
        assert_eq!(at(s.x as i64, s.y as i64), i, "{what}: point {i} is not in its own cell");
        let reached = flood(w, h, (s.x as i64, s.y as i64), &N4, |x, y| at(x, y) == i);
        assert_eq!(reached, size, "{what}: cell {i} is in more than one piece");
        let outside = |x: i64, y: i64| x == 0 || y == 0 || x == w + 1 || y == h + 1 || at(x - 1, y - 1) != i;
        let complement = (w + 2) * (h + 2) - size as i64;
        let reached = flood(w + 2, h + 2, (0, 0), &N8, outside);
        assert_eq!(reached as i64, complement, "{what}: cell {i} has a hole");
    }
}

/// Length of all boundaries in texels by the Cauchy-Crofton formula over 4 directions of lines
/// through texel centres: `(pi / 8) (n_0 + n_90 + (n_45 + n_135) / sqrt 2)`, `n` the number of
/// label changes between neighbours along each direction. Close to isotropic (a 4-neighbour
/// count alone would call a diagonal line 41% longer than the same line turned flat).
fn boundary_length(labels: &Grid<u16>) -> f64 {
    let (w, h) = labels.size();
    let differs = |x: usize, y: usize, dx: isize, dy: isize| {
        let (nx, ny) = (x as isize + dx, y as isize + dy);
        nx >= 0
            && ny >= 0
            && (nx as usize) < w
            && (ny as usize) < h
            && labels.get(nx as usize, ny as usize) != labels.get(x, y)
    };
    let (mut axis, mut diagonal) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            axis += usize::from(differs(x, y, 1, 0)) + usize::from(differs(x, y, 0, 1));
            diagonal += usize::from(differs(x, y, 1, 1)) + usize::from(differs(x, y, -1, 1));
        }
    }
    std::f64::consts::PI / 8.0 * (axis as f64 + diagonal as f64 / std::f64::consts::SQRT_2)
}

#[test]
fn the_boundary_length_estimate_is_right_for_known_shapes() {
    // A straight line across a 200-texel map at three angles: length 200 / cos(angle).
    for (slope, length) in [(0.0, 200.0), (0.5, 200.0 * 1.25f64.sqrt()), (1.0, 200.0 * 2f64.sqrt())] {
        let labels = Grid::from_fn(200, 400, |x, y| u16::from(y as f64 > 100.0 + slope * x as f64));
        let l = boundary_length(&labels);
        assert!((l / length - 1.0).abs() < 0.1, "slope {slope}: {l} for {length}");
    }
}

fn face_seeds(w: usize, h: usize) -> Vec<SeedPoint> {
    let uv = [[0.5, 0.14], [0.27, 0.3], [0.73, 0.3], [0.5, 0.47], [0.33, 0.6], [0.67, 0.6], [0.5, 0.85]];
    uv.iter().enumerate().map(|(i, [u, v])| seed(i, (u * w as f64) as u32, (v * h as f64) as u32)).collect()
}

#[test]
fn curved_cells_are_single_pieces_without_holes_holding_their_points() {
    let (w, h) = (384, 192);
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let mut layouts = vec![face_seeds(w, h)];
    layouts.extend((0..4).map(|_| random_seeds(&mut rng, 7, 7, w, h)));
    // Dense points close together, some near edges and corners.
    layouts.push(random_seeds(&mut rng, 24, 5, w, h));
    for (l, seeds) in layouts.iter().enumerate() {
        for (amplitude, curve_seed) in [(0.0, 0), (12.0, 1), (24.0, 2), (40.0, 3)] {
            let cells = curve::curved_cells(w, h, seeds, &CurveParams::new(amplitude, curve_seed)).unwrap();
            assert_valid_cells(&cells, seeds, &format!("layout {l}, amplitude {amplitude}"));
        }
    }
}

#[test]
fn a_rough_curve_with_a_short_wavelength_stays_valid() {
    let (w, h) = (256, 160);
    let seeds = face_seeds(w, h);
    let base = CurveParams { roughness: 0.8, octaves: 6, ..CurveParams::new(10.0, 77) };
    // Just under the fold limit.
    let curve = CurveParams { wavelength: Some(base.base_wavelength() * curve::SLOPE_TARGET / 0.99), ..base };
    assert!(curve.slope_bound() < 1.0);
    let cells = curve::curved_cells(w, h, &seeds, &curve).unwrap();
    assert_valid_cells(&cells, &seeds, "rough");
}

#[test]
fn amplitude_zero_is_the_nearest_point_partition() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let (w, h) = (150, 90);
    for _ in 0..3 {
        let seeds = random_seeds(&mut rng, 8, 4, w, h);
        let curve = CurveParams { seed: 99, ..CurveParams::straight() };
        let curved = curve::curved_cells(w, h, &seeds, &curve).unwrap();
        assert_eq!(curved, partition::nearest_cells(w, h, &seeds));
        let a = Partition::build(w, h, 4, &seeds, &curve).unwrap();
        assert_eq!(a, Partition::nearest(w, h, 4, &seeds).unwrap());
    }
}

#[test]
fn curves_are_deterministic_and_depend_on_the_seed() {
    let (w, h) = (320, 160);
    let seeds = face_seeds(w, h);
    let run = |s: u64, threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| Partition::build(w, h, 7, &seeds, &CurveParams::new(20.0, s)).unwrap())
    };
    let a = run(1, 1);
    assert_eq!(a, run(1, 2), "same seed, different thread counts");
    assert_eq!(a, run(1, 1), "same seed, same thread count");
    let b = run(2, 2);
    let differ = a.labels().as_slice().iter().zip(b.labels().as_slice()).filter(|(x, y)| x != y).count();
    assert!(differ > 200, "seeds 1 and 2 differ in only {differ} texels");
}

#[test]
fn boundaries_grow_longer_with_the_amplitude() {
    let (w, h) = (512, 256);
    let seeds = face_seeds(w, h);
    // Each layer's slope stays below 1, so a curve is at most a few percent longer than the
    // straight boundary (arc length grows with the mean squared slope): the margins are small.
    let lengths: Vec<f64> = [0.0, 12.0, 48.0]
        .iter()
        .map(|&a| boundary_length(Partition::build(w, h, 7, &seeds, &CurveParams::new(a, 4)).unwrap().labels()))
        .collect();
    assert!(lengths[0] * 1.003 < lengths[1] && lengths[1] * 1.003 < lengths[2], "boundary lengths {lengths:?}");
    assert!(lengths[2] > lengths[0] * 1.01, "boundary lengths {lengths:?}");
    // A curved boundary also moves texels: more than a thin band changes label.
    let straight = Partition::nearest(w, h, 7, &seeds).unwrap();
    let curved = Partition::build(w, h, 7, &seeds, &CurveParams::new(24.0, 4)).unwrap();
    let moved = straight.labels().as_slice().iter().zip(curved.labels().as_slice()).filter(|(a, b)| a != b).count();
    assert!(moved as f64 > lengths[0] * 3.0, "only {moved} texels moved for {:.0} of boundary", lengths[0]);
}

#[test]
fn the_band_shortcut_changes_nothing() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let (w, h) = (200, 120);
    for amplitude in [0.0, 5.0, 17.0] {
        let seeds = random_seeds(&mut rng, 7, 7, w, h);
        let params = CurveParams::new(amplitude, 8);
        let fast = curve::curved_cells_unrepaired_reference(w, h, &seeds, &params, true).unwrap();
        let slow = curve::curved_cells_unrepaired_reference(w, h, &seeds, &params, false).unwrap();
        assert_eq!(fast, slow, "amplitude {amplitude}");
    }
}

#[test]
fn the_warp_keeps_its_bounds() {
    let (w, h) = (1200usize, 800usize);
    for params in [CurveParams::new(30.0, 1), CurveParams { roughness: 0.9, octaves: 5, ..CurveParams::new(12.0, 2) }] {
        let warp = Warp::new(&params, w, h).unwrap();
        assert_eq!(warp.layer_count(), params.octaves as usize);
        let bound = params.slope_bound();
        assert!(bound < 1.0);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut largest = 0.0f64;
        for _ in 0..20_000 {
            let (x, y) = (rng.random_range(-0.5..w as f64 - 0.5), rng.random_range(-0.5..h as f64 - 0.5));
            let [wx, wy] = warp.apply(x, y);
            let moved = (wx - x).hypot(wy - y);
            assert!(moved <= params.amplitude + 1e-9, "moved {moved}");
            assert!((-0.5..=w as f64 - 0.5).contains(&wx) && (-0.5..=h as f64 - 0.5).contains(&wy));
            largest = largest.max(moved);
            // Finite-difference slope of each layer along a random direction, against the bound.
            let (ex, ey) = (rng.random_range(-1.0..1.0f64), rng.random_range(-1.0..1.0f64));
            let e = 1e-3 / ex.hypot(ey).max(1e-9);
            let [vx, vy] = warp.apply(x + ex * e, y + ey * e);
            let stretch = (vx - wx).hypot(vy - wy) / (ex * e).hypot(ey * e);
            assert!(stretch <= warp.lipschitz() + 1e-6, "stretch {stretch} above {}", warp.lipschitz());
            for k in 0..warp.layer_count() {
                let d = warp.layer_displacement(k, x, y);
                let d2 = warp.layer_displacement(k, x + ex * e, y + ey * e);
                let slope = (d2[0] - d[0]).hypot(d2[1] - d[1]) / (ex * e).hypot(ey * e);
                assert!(slope <= bound + 1e-6, "layer {k}: slope {slope} above the bound {bound}");
            }
        }
        assert!(largest > 0.3 * params.amplitude, "the warp barely moves: {largest}");
        // The component normal to each edge vanishes on it, so each layer maps the map onto itself.
        for k in 0..warp.layer_count() {
            for t in [0.0, 0.37, 0.81] {
                assert_eq!(warp.layer_displacement(k, -0.5, t * h as f64)[0], 0.0);
                assert_eq!(warp.layer_displacement(k, w as f64 - 0.5, t * h as f64)[0], 0.0);
                assert_eq!(warp.layer_displacement(k, t * w as f64, -0.5)[1], 0.0);
                assert_eq!(warp.layer_displacement(k, t * w as f64, h as f64 - 0.5)[1], 0.0);
            }
        }
    }
}

#[test]
fn curve_parameters_that_could_fold_the_map_are_refused() {
    let folding = CurveParams { wavelength: Some(20.0), ..CurveParams::new(30.0, 1) };
    let msg = folding.validate().unwrap_err().to_string();
    assert!(msg.contains("could fold the map") && msg.contains("amplitude 30"), "{msg}");
    for bad in [
        CurveParams::new(-1.0, 0),
        CurveParams::new(f64::NAN, 0),
        CurveParams { octaves: 0, ..CurveParams::new(5.0, 0) },
        CurveParams { roughness: 1.5, ..CurveParams::new(5.0, 0) },
        CurveParams { wavelength: Some(0.0), ..CurveParams::new(5.0, 0) },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
        assert!(curve::curved_cells(10, 10, &[seed(0, 1, 1)], &bad).is_err());
    }
    // The automatic wavelength sits at the target.
    let auto = CurveParams::new(40.0, 0);
    assert!((auto.slope_bound() - curve::SLOPE_TARGET).abs() < 1e-12);
}

/// Timing of the full-size partition (run with `--release --ignored --nocapture`).
#[test]
#[ignore]
fn time_full_size_partition() {
    let (w, h) = (4096, 2048);
    let seeds = face_seeds(w, h);
    let start = std::time::Instant::now();
    let cells = partition::nearest_cells(w, h, &seeds);
    println!("nearest_cells: {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    let start = std::time::Instant::now();
    let _ = Partition::from_cells(&cells, &seeds, 7);
    println!("labels and areas: {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    for amplitude in [0.0, 32.0, 64.0] {
        let start = std::time::Instant::now();
        let _ = curve::curved_cells(w, h, &seeds, &CurveParams::new(amplitude, 1)).unwrap();
        println!("curved_cells, amplitude {amplitude}: {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    }
    for amplitude in [0.0, 32.0, 64.0, 128.0] {
        let params = CurveParams::new(amplitude, 1);
        let start = std::time::Instant::now();
        let p = Partition::build(w, h, 7, &seeds, &params).unwrap();
        let elapsed = start.elapsed();
        println!(
            "4096x2048, 7 regions, amplitude {amplitude}: {:.1} ms (wavelength {:.0}, boundary length {:.0})",
            elapsed.as_secs_f64() * 1e3,
            params.base_wavelength(),
            boundary_length(p.labels())
        );
    }
}

/// Writes label images to the temporary folder for a look (run with `--ignored --nocapture`).
#[test]
#[ignore]
fn write_label_images() {
    let (w, h) = (1024, 512);
    let seeds = face_seeds(w, h);
    for amplitude in [0.0, 32.0, 64.0] {
        let p = Partition::build(w, h, 7, &seeds, &CurveParams::new(amplitude, 1)).unwrap();
        let colours = [
            [230, 80, 80],
            [80, 200, 80],
            [80, 80, 230],
            [220, 200, 60],
            [200, 80, 200],
            [60, 200, 200],
            [150, 150, 150],
        ];
        let samples: Vec<u16> = p.labels().as_slice().iter().flat_map(|&l| colours[l as usize]).collect();
        let path = std::env::temp_dir().join(format!("stitch-labels-{amplitude}.png"));
        skinkit_maps::io::write_png(&path, w, h, skinkit_maps::io::PngLayout::Rgb8, &samples).unwrap();
        println!("{}: boundary {:.0}", path.display(), boundary_length(p.labels()));
    }
}
