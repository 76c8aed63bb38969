//! Property tests (proptest) of the N-way multiresolution spline: joining copies of one map along
//! any labelling gives the map back (Burt and Adelson's weights add to one at every level), for
//! every blend mode, random sizes, region counts, region shapes and level counts; and a region
//! whose piece is a constant colour, surrounded by regions of the same colour, stays that colour.
//!
//! `PROPTEST_CASES=N` runs N cases of each; `PROPTEST_RNG_SEED=S` other cases than the default seed.

use glam::Vec3;
use proptest::prelude::*;
use proptest::test_runner::Config;
use skinkit_maps::Grid;
use skinkit_stitch::spline::{Blend, Piece, SplineConfig, blend, piece_rect, region_bounds};

/// `cases` cases from this suite's fixed seed (`PROPTEST_CASES`, `PROPTEST_RNG_SEED` override).
fn config(cases: u32) -> Config {
    skinkit_testkit::proptest_config(cases, 0x5eed_5711)
}

/// Labels of 1..=4 regions: each texel takes the region of the nearest of a few random seed
/// points (any region may end up with no texel, which the spline ignores).
fn labels() -> impl Strategy<Value = (Grid<u16>, usize)> {
    (4usize..72, 4usize..72, 1usize..=4).prop_flat_map(|(w, h, regions)| {
        prop::collection::vec((0..w, 0..h, 0..regions as u16), 1..8).prop_map(move |seeds| {
            let labels = Grid::from_fn(w, h, |x, y| {
                let d = |&(sx, sy, _): &(usize, usize, u16)| (sx.abs_diff(x).pow(2) + sy.abs_diff(y).pow(2), sx, sy);
                seeds.iter().min_by_key(|s| d(s)).expect("at least one seed").2
            });
            (labels, regions)
        })
    })
}

/// A map of unit normals with `z > 0` (they are valid for every blend mode) or colours.
fn map(w: usize, h: usize, normals: bool) -> impl Strategy<Value = Grid<Vec3>> {
    prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0, 0.2f32..1.0), w * h).prop_map(move |v| {
        let texels =
            v.into_iter().map(|(x, y, z)| if normals { Vec3::new(x, y, z).normalize() } else { Vec3::new(x, y, z) });
        Grid::from_vec(w, h, texels.collect()).unwrap()
    })
}

fn case() -> impl Strategy<Value = (Grid<u16>, usize, Grid<Vec3>, Blend, usize)> {
    (labels(), prop_oneof![Just(Blend::Colour), Just(Blend::NormalVectors), Just(Blend::NormalSlopes)], 1usize..=5)
        .prop_flat_map(|((labels, regions), mode, levels)| {
            let (w, h) = labels.size();
            (Just(labels), Just(regions), map(w, h, mode != Blend::Colour), Just(mode), Just(levels))
        })
}

/// The smallest valid piece of every region, cut from `map` (an empty piece for a region with no
/// texel).
fn pieces(labels: &Grid<u16>, regions: usize, map: &Grid<Vec3>, levels: usize) -> Vec<Piece> {
    let (w, h) = labels.size();
    region_bounds(labels, regions)
        .into_iter()
        .map(|bbox| match bbox {
            Some(b) => {
                let r = piece_rect(b, levels, w, h);
                Piece::new(r.x0, r.y0, map.crop(r.x0, r.y0, r.width, r.height).unwrap())
            }
            None => Piece::new(0, 0, Grid::filled(0, 0, Vec3::ZERO)),
        })
        .collect()
}

proptest! {
    #![proptest_config(config(96))]

    #[test]
    fn the_spline_of_identical_maps_is_the_map((labels, regions, map, mode, levels) in case()) {
        let out = blend(&labels, &pieces(&labels, regions, &map, levels), &SplineConfig { levels, blend: mode }).unwrap();
        prop_assert_eq!(out.size(), map.size());
        for (i, (a, b)) in out.as_slice().iter().zip(map.as_slice()).enumerate() {
            prop_assert!((*a - *b).length() < 1e-4, "{:?}, {} levels, texel {}: {} vs {}", mode, levels, i, a, b);
        }
    }

    #[test]
    fn one_colour_everywhere_stays_that_colour((labels, regions) in labels(), c in (-1.0f32..2.0, -1.0f32..2.0, -1.0f32..2.0), levels in 1usize..=6) {
        let colour = Vec3::new(c.0, c.1, c.2);
        let map = Grid::filled(labels.width(), labels.height(), colour);
        let out = blend(&labels, &pieces(&labels, regions, &map, levels), &SplineConfig { levels, blend: Blend::Colour }).unwrap();
        prop_assert!(out.as_slice().iter().all(|t| (*t - colour).length() < 1e-5));
    }
}
