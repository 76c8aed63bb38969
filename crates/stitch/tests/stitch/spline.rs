//! The N-way multiresolution spline against a naive full-map oracle (every region's pyramid over
//! the whole map, built with `skinkit_maps::pyramid`), and its promised properties: two copies of a
//! map give it back, one region is untouched, weights add to one, the blend stays local, bits do
//! not depend on the thread count, hard inputs give clear errors.

use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_maps::pyramid::{self, Border};
use skinkit_stitch::spline::{
    Blend, Piece, Rect, SplineConfig, SplineError, blend, from_slope, margin_for_levels, max_levels_for_pieces,
    piece_rect, region_bounds, region_mask_pyramid, to_slope,
};

/// Deterministic smooth-ish map: a few seeded sinusoids per channel; unit normals (z > 0) when
/// `normals`, else colours in about [-1, 2].
fn texture(w: usize, h: usize, seed: u64, normals: bool) -> Grid<Vec3> {
    let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let waves: Vec<[f32; 4]> = (0..9).map(|_| [next() * 0.9, next() * 0.9, next() * 6.3, next() * 0.4]).collect();
    let channel = move |c: usize, x: f32, y: f32| {
        waves[c * 3..c * 3 + 3].iter().map(|[fx, fy, p, a]| a * (fx * x + fy * y + p).sin()).sum::<f32>()
    };
    let tilt = Vec3::new(next() - 0.5, next() - 0.5, 0.0);
    Grid::from_fn(w, h, |x, y| {
        let (fx, fy) = (x as f32, y as f32);
        let v = Vec3::new(channel(0, fx, fy), channel(1, fx, fy), channel(2, fx, fy));
        if normals { (Vec3::new(v.x + tilt.x, v.y + tilt.y, 1.0)).normalize() } else { v + Vec3::splat(0.5) }
    })
}

/// Labels of three regions with wavy boundaries on a `w x h` map.
fn three_regions(w: usize, h: usize) -> Grid<u16> {
    Grid::from_fn(w, h, |x, y| {
        let (fx, fy) = (x as f32, y as f32);
        if fx < 0.4 * w as f32 + 5.0 * (fy * 0.2).sin() {
            0
        } else if fy < 0.5 * h as f32 + 4.0 * (fx * 0.15).cos() {
            1
        } else {
            2
        }
    })
}

/// Minimal valid pieces cut from per-region full maps.
fn pieces_from(labels: &Grid<u16>, maps: &[Grid<Vec3>], levels: usize) -> Vec<Piece> {
    let (w, h) = labels.size();
    region_bounds(labels, maps.len())
        .iter()
        .zip(maps)
        .map(|(bbox, map)| {
            let r = piece_rect(bbox.expect("every region has texels"), levels, w, h);
            Piece::new(r.x0, r.y0, map.crop(r.x0, r.y0, r.width, r.height).unwrap())
        })
        .collect()
}

/// The naive spline: each piece extended to the whole map with garbage (1e3) outside its
/// rectangle, full-map Laplacian and mask Gaussian pyramids, normalised weighted sum, collapse.
fn oracle(labels: &Grid<u16>, pieces: &[Piece], levels: usize, mode: Blend) -> Grid<Vec3> {
    let (w, h) = labels.size();
    let space = |v: Vec3| if mode == Blend::NormalSlopes { to_slope(v) } else { v };
    let mut sums: Vec<Grid<Vec3>> = pyramid::gaussian(&Grid::filled(w, h, Vec3::ZERO), levels, Border::Clamp);
    assert_eq!(sums.len(), levels, "oracle maps must allow the levels");
    let mut weights: Vec<Grid<f32>> = sums.iter().map(|g| Grid::filled(g.width(), g.height(), 0.0)).collect();
    for (r, piece) in pieces.iter().enumerate() {
        let rect = piece.rect();
        let extended = Grid::from_fn(w, h, |x, y| {
            let inside = x >= rect.x0 && x < rect.x1() && y >= rect.y0 && y < rect.y1();
            if inside { space(*piece.texels.get(x - rect.x0, y - rect.y0)) } else { Vec3::splat(1e3) }
        });
        let lap = pyramid::laplacian(&extended, levels, Border::Clamp);
        let mask = labels.map(|&l| if l as usize == r { 1.0f32 } else { 0.0 });
        let gauss = pyramid::gaussian(&mask, levels, Border::Clamp);
        for l in 0..levels {
            for (i, (s, wt)) in sums[l].as_mut_slice().iter_mut().zip(weights[l].as_mut_slice()).enumerate() {
                let m = gauss[l].as_slice()[i];
                *s += lap[l].as_slice()[i] * m;
                *wt += m;
            }
        }
    }
    for (s, wt) in sums.iter_mut().zip(&weights) {
        for (v, &m) in s.as_mut_slice().iter_mut().zip(wt.as_slice()) {
            *v = if m > 0.0 { *v / m } else { Vec3::ZERO };
        }
    }
    let out = pyramid::collapse(&sums, Border::Clamp);
    Grid::from_fn(w, h, |x, y| {
        let v = *out.get(x, y);
        match mode {
            _ if *labels.get(x, y) as usize >= pieces.len() => Vec3::ZERO,
            Blend::Colour => v,
            Blend::NormalVectors => v.normalize_or_zero(),
            Blend::NormalSlopes => from_slope(v),
        }
    })
}

fn max_diff(a: &Grid<Vec3>, b: &Grid<Vec3>) -> f32 {
    assert_eq!(a.size(), b.size());
    a.as_slice().iter().zip(b.as_slice()).map(|(p, q)| (*p - *q).abs().max_element()).fold(0.0, f32::max)
}

/// Chebyshev distance from `(x, y)` to the nearest texel of another label (brute force).
fn distance_to_other(labels: &Grid<u16>, x: usize, y: usize) -> usize {
    let own = *labels.get(x, y);
    let mut best = usize::MAX;
    for j in 0..labels.height() {
        for i in 0..labels.width() {
            if *labels.get(i, j) != own {
                best = best.min(x.abs_diff(i).max(y.abs_diff(j)));
            }
        }
    }
    best
}

#[test]
fn matches_the_full_map_oracle() {
    let (w, h) = (96, 64);
    let labels = three_regions(w, h);
    for (levels, mode) in [(3, Blend::Colour), (4, Blend::NormalVectors), (4, Blend::NormalSlopes), (2, Blend::Colour)]
    {
        let normals = mode != Blend::Colour;
        let maps: Vec<_> = (0..3).map(|r| texture(w, h, 10 + r, normals)).collect();
        let pieces = pieces_from(&labels, &maps, levels);
        let ours = blend(&labels, &pieces, &SplineConfig { levels, blend: mode }).unwrap();
        let expect = oracle(&labels, &pieces, levels, mode);
        // Same operations up to the order of a few float sums: a leak of the 1e3 garbage or a
        // misaligned level would show as errors of order 1 or more.
        let d = max_diff(&ours, &expect);
        assert!(d < 2e-5, "{levels} levels {mode:?}: {d}");
        // And the spline did blend: the result is not the hard-label composite.
        let hard = blend(&labels, &pieces, &SplineConfig::no_blend(mode)).unwrap();
        assert!(max_diff(&ours, &hard) > 1e-2, "{levels} levels {mode:?}");
    }
}

#[test]
fn two_copies_of_a_map_give_it_back() {
    let (w, h) = (96, 64);
    let labels = three_regions(w, h);
    for (mode, normals) in [(Blend::Colour, false), (Blend::NormalVectors, true), (Blend::NormalSlopes, true)] {
        let map = texture(w, h, 3, normals);
        let pieces = pieces_from(&labels, &[map.clone(), map.clone(), map.clone()], 4);
        let out = blend(&labels, &pieces, &SplineConfig { levels: 4, blend: mode }).unwrap();
        let d = max_diff(&out, &map);
        assert!(d < 1e-5, "{mode:?}: {d}");
    }
}

#[test]
fn a_single_region_is_untouched() {
    let map = texture(50, 37, 5, true);
    let labels = Grid::filled(50, 37, 0u16);
    for mode in [Blend::Colour, Blend::NormalVectors, Blend::NormalSlopes] {
        let out = blend(&labels, &[Piece::new(0, 0, map.clone())], &SplineConfig { levels: 5, blend: mode }).unwrap();
        assert_eq!(out, map, "{mode:?}");
    }
}

#[test]
fn mask_weights_add_to_one_at_every_level() {
    let (w, h) = (96, 64);
    let labels = three_regions(w, h);
    let levels = 5;
    let rects: Vec<Rect> = region_bounds(&labels, 3).iter().map(|b| piece_rect(b.unwrap(), levels, w, h)).collect();
    let pyramids: Vec<_> = (0..3).map(|r| region_mask_pyramid(&labels, r as u16, rects[r], levels)).collect();
    for l in 0..levels {
        let (lw, lh) = (w.div_ceil(1 << l), h.div_ceil(1 << l));
        let mut total = Grid::filled(lw, lh, 0.0f32);
        for (rect, pyr) in rects.iter().zip(&pyramids) {
            let g = &pyr[l];
            for y in 0..g.height() {
                for x in 0..g.width() {
                    *total.get_mut((rect.x0 >> l) + x, (rect.y0 >> l) + y) += g.get(x, y);
                }
            }
        }
        let worst = total.as_slice().iter().map(|t| (t - 1.0).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-5, "level {l}: sum of weights off by {worst}");
    }
    // Constant pieces: a partition of unity gives the constant back.
    let pieces: Vec<Piece> =
        rects.iter().map(|r| Piece::new(r.x0, r.y0, Grid::filled(r.width, r.height, Vec3::splat(0.7)))).collect();
    let out = blend(&labels, &pieces, &SplineConfig { levels, blend: Blend::Colour }).unwrap();
    assert!(max_diff(&out, &Grid::filled(w, h, Vec3::splat(0.7))) < 1e-6);
}

#[test]
fn the_blend_is_local_to_boundaries() {
    let (w, h) = (96, 64);
    let labels = three_regions(w, h);
    let levels = 3;
    let radius = margin_for_levels(levels);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, 20 + r, false)).collect();
    let pieces = pieces_from(&labels, &maps, levels);
    let ours = blend(&labels, &pieces, &SplineConfig { levels, blend: Blend::Colour }).unwrap();
    let exact = oracle(&labels, &pieces, levels, Blend::Colour);
    let (mut far, mut changed_near) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let own = *maps[*labels.get(x, y) as usize].get(x, y);
            if distance_to_other(&labels, x, y) > radius {
                far += 1;
                // Ours copies the piece bit for bit; the naive spline agrees up to rounding, so the
                // radius is not too small.
                assert_eq!(*ours.get(x, y), own, "({x}, {y})");
                assert!((*exact.get(x, y) - own).abs().max_element() < 1e-5, "({x}, {y})");
            } else if (*ours.get(x, y) - own).abs().max_element() > 1e-2 {
                changed_near += 1;
            }
        }
    }
    assert!(far > 1000 && changed_near > 100, "far {far}, changed near {changed_near}");
}

#[test]
fn bits_do_not_depend_on_the_thread_count() {
    let (w, h) = (256, 160);
    let labels = three_regions(w, h);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, 40 + r, true)).collect();
    let pieces = pieces_from(&labels, &maps, 5);
    let config = SplineConfig { levels: 5, blend: Blend::NormalVectors };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| blend(&labels, &pieces, &config).unwrap())
    };
    let (one, two, three) = (run(1), run(2), run(3));
    assert!(one == two && two == three);
}

#[test]
fn no_blend_is_the_hard_label_composite() {
    let (w, h) = (40, 30);
    let labels = three_regions(w, h);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, r, true)).collect();
    let pieces = pieces_from(&labels, &maps, 1);
    let out = blend(&labels, &pieces, &SplineConfig::no_blend(Blend::NormalVectors)).unwrap();
    assert_eq!(out, Grid::from_fn(w, h, |x, y| *maps[*labels.get(x, y) as usize].get(x, y)));
}

#[test]
fn normals_come_out_unit_and_slopes_meet_in_between() {
    // Two flat regions tilted +-0.4 in x: blended slopes pass through 0 near the boundary.
    let (w, h) = (64, 16);
    let labels = Grid::from_fn(w, h, |x, _| u16::from(x >= 32));
    let tilt = |s: f32| Grid::filled(w, h, Vec3::new(s, 0.0, 1.0).normalize());
    let pieces = pieces_from(&labels, &[tilt(0.4), tilt(-0.4)], 4);
    for mode in [Blend::NormalVectors, Blend::NormalSlopes] {
        let out = blend(&labels, &pieces, &SplineConfig { levels: 4, blend: mode }).unwrap();
        assert!(out.as_slice().iter().all(|n| (n.length() - 1.0).abs() < 1e-5), "{mode:?}");
        let row: Vec<f32> = (0..w).map(|x| to_slope(*out.get(x, 8)).x).collect();
        assert!(row.windows(2).all(|p| p[1] <= p[0] + 1e-6), "{mode:?}: slopes fall monotonically");
        assert!(row[31] > 0.0 && row[32] < 0.0 && row[31] < 0.3 && row[32] > -0.3, "{mode:?}: {row:?}");
    }
}

#[test]
fn pieces_too_small_or_misaligned_are_refused_with_the_levels_they_allow() {
    let (w, h) = (96, 64);
    let labels = three_regions(w, h);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, r, false)).collect();
    let pieces = pieces_from(&labels, &maps, 3);
    let rects: Vec<Rect> = pieces.iter().map(Piece::rect).collect();
    assert_eq!(max_levels_for_pieces(&labels, &rects), 3);
    let err = blend(&labels, &pieces, &SplineConfig { levels: 4, blend: Blend::Colour }).unwrap_err();
    let SplineError::PieceTooSmall { max_levels, .. } = err.clone() else { panic!("{err}") };
    assert_eq!(max_levels, 3);
    assert!(err.to_string().contains("at most 3 levels"), "{err}");
    // A piece shifted by one texel is misaligned for 3 levels (origin not a multiple of 4) but
    // still fine for hard labels if it covers the region.
    let mut shifted = pieces.clone();
    let r = rects[1];
    shifted[1] = Piece::new(r.x0 + 1, r.y0, maps[1].crop(r.x0 + 1, r.y0, r.width - 1, r.height).unwrap());
    let err = blend(&labels, &shifted, &SplineConfig { levels: 3, blend: Blend::Colour }).unwrap_err();
    assert!(matches!(err, SplineError::PieceTooSmall { region: 1, .. }), "{err}");
    let shifted_rects: Vec<Rect> = shifted.iter().map(Piece::rect).collect();
    let allowed = max_levels_for_pieces(&labels, &shifted_rects);
    assert!((1..3).contains(&allowed));
    assert!(blend(&labels, &shifted, &SplineConfig { levels: allowed, blend: Blend::Colour }).is_ok());
}

#[test]
fn a_map_smaller_than_the_pyramid_works_with_whole_map_pieces() {
    // 12x10 with 6 levels: the margin (124) and alignment (32) exceed the map, so pieces must be
    // the whole map; the coarsest levels are 1x1.
    let (w, h) = (12, 10);
    let labels = Grid::from_fn(w, h, |x, _| u16::from(x >= 5));
    let map = texture(w, h, 9, false);
    let pieces = vec![Piece::new(0, 0, map.clone()), Piece::new(0, 0, map.clone())];
    let out = blend(&labels, &pieces, &SplineConfig { levels: 6, blend: Blend::Colour }).unwrap();
    assert!(max_diff(&out, &map) < 1e-5);
}

#[test]
fn a_region_without_texels_is_ignored() {
    let (w, h) = (96, 64);
    let three = three_regions(w, h);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, 30 + r, true)).collect();
    // Region 1 absent: relabel its texels as 2 and give it an empty piece.
    let labels = three.map(|&l| if l == 1 { 2 } else { l });
    let mut with_empty =
        pieces_from(&labels.map(|&l| if l == 2 { 1 } else { l }), &[maps[0].clone(), maps[2].clone()], 3);
    let two = blend(&labels.map(|&l| if l == 2 { 1 } else { l }), &with_empty, &SplineConfig::new(3)).unwrap();
    with_empty.insert(1, Piece::new(0, 0, Grid::filled(0, 0, Vec3::splat(f32::NAN))));
    let out = blend(&labels, &with_empty, &SplineConfig::new(3)).unwrap();
    assert_eq!(out, two);
}

#[test]
fn non_finite_texels_are_refused_with_their_place() {
    let (w, h) = (40, 30);
    let labels = three_regions(w, h);
    let maps: Vec<_> = (0..3).map(|r| texture(w, h, r, true)).collect();
    let mut pieces = pieces_from(&labels, &maps, 2);
    let (x0, y0) = (pieces[2].x0, pieces[2].y0);
    *pieces[2].texels.get_mut(3, 1) = Vec3::new(0.0, f32::INFINITY, 1.0);
    *pieces[2].texels.get_mut(1, 2) = Vec3::NAN;
    let err = blend(&labels, &pieces, &SplineConfig::new(2)).unwrap_err();
    assert_eq!(err, SplineError::NonFinite { region: 2, x: x0 + 3, y: y0 + 1 });
}

#[test]
fn texels_of_no_region_are_zero_and_bad_parameters_are_refused() {
    let (w, h) = (40, 30);
    let labels = Grid::from_fn(w, h, |x, y| if y < 4 { 7 } else { u16::from(x >= 20) });
    let maps: Vec<_> = (0..2).map(|r| texture(w, h, r, true)).collect();
    let pieces = pieces_from(&labels, &maps, 3);
    let out = blend(&labels, &pieces, &SplineConfig::new(3)).unwrap();
    assert!((0..w).all(|x| (0..4).all(|y| *out.get(x, y) == Vec3::ZERO)));
    assert!(out.as_slice()[4 * w..].iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    let zero = blend(&labels, &pieces, &SplineConfig::new(0)).unwrap_err();
    assert!(matches!(zero, SplineError::Levels { levels: 0, .. }));
    let outside = vec![pieces[0].clone(), Piece::new(8, 0, maps[1].clone())];
    let err = blend(&labels, &outside, &SplineConfig::new(3)).unwrap_err();
    assert!(matches!(err, SplineError::PieceOutsideMap { region: 1, .. }), "{err}");
    let absurd = vec![pieces[0].clone(), Piece::new(usize::MAX - 1, 0, maps[1].clone())];
    let err = blend(&labels, &absurd, &SplineConfig::new(3)).unwrap_err();
    assert!(matches!(err, SplineError::PieceOutsideMap { region: 1, .. }), "{err}");
    let empty = blend(&Grid::filled(0, 0, 0u16), &[], &SplineConfig::new(4)).unwrap();
    assert!(empty.is_empty());
}
