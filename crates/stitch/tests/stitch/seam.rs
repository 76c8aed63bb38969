//! The seam metric on hand-built maps whose answers are known: a hard step between two tilts, a
//! smooth ramp, identical regions; then on the spline's own output against hard labels.

use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_maps::normal::angle_degrees;
use skinkit_stitch::seam::{SeamError, measure};
use skinkit_stitch::spline::{Blend, Piece, SplineConfig, blend, piece_rect, region_bounds};

const W: usize = 64;
const H: usize = 48;

/// A fine ripple in the slopes so every interior has a gradient to compare with.
fn ripple(x: usize, y: usize) -> (f32, f32) {
    let (fx, fy) = (x as f32, y as f32);
    (0.03 * (0.9 * fx + 0.4 * fy).sin(), 0.03 * (0.5 * fx - 0.8 * fy).cos())
}

/// Normals with slopes `(sx(x) + ripple, ripple)`.
fn slopes(sx: impl Fn(usize) -> f32 + Sync) -> Grid<Vec3> {
    Grid::from_fn(W, H, |x, y| {
        let (rx, ry) = ripple(x, y);
        Vec3::new(sx(x) + rx, ry, 1.0).normalize()
    })
}

/// Left half region 0, right half region 1.
fn halves() -> Grid<u16> {
    Grid::from_fn(W, H, |x, _| u16::from(x >= W / 2))
}

/// Largest angle between 4-neighbours anywhere in the map (brute force).
fn largest_neighbour_angle(n: &Grid<Vec3>) -> f64 {
    let mut best = 0.0f64;
    for y in 0..H {
        for x in 0..W {
            if x + 1 < W {
                best = best.max(angle_degrees(*n.get(x, y), *n.get(x + 1, y)) as f64);
            }
            if y + 1 < H {
                best = best.max(angle_degrees(*n.get(x, y), *n.get(x, y + 1)) as f64);
            }
        }
    }
    best
}

#[test]
fn a_hard_step_between_two_tilts_is_a_seam() {
    let normals = slopes(|x| if x < W / 2 { 0.3 } else { -0.3 });
    let report = measure(&halves(), &normals, 2, 4).unwrap();
    assert_eq!(report.boundaries.len(), 1);
    let seam = &report.boundaries[0];
    assert_eq!(seam.regions, [0, 1]);
    assert_eq!(seam.crossings, H);
    // The step alone is 2 atan(0.3) = 33.4 degrees; the ripple moves it by at most ~3.5 degrees.
    let step = 2.0 * 0.3f64.atan().to_degrees();
    assert!((seam.max_jump_degrees - step).abs() < 3.5, "{}", seam.max_jump_degrees);
    // Forward differences put the 0.6 slope step on one of the band's 8 columns; the others see
    // the ripple's gradient g, as the interiors do: band mean = g + (0.6 - g) / 8.
    let g = 0.5 * (seam.interiors[0].mean_gradient + seam.interiors[1].mean_gradient);
    let excess = seam.band.mean_gradient - g;
    assert!((excess - (0.6 - g) / 8.0).abs() < 0.01, "{seam:?}");
    assert!(seam.gradient_ratio.unwrap() > 3.0, "{seam:?}");
    // Slopes +-0.3 in the band against the ripple alone (std about 0.03) in the interiors.
    assert!(seam.std_ratio.unwrap() > 5.0, "{seam:?}");
    // Band: 4 texels each side of the boundary; interiors 8 texels each side.
    assert_eq!((seam.band.texels, seam.interiors[0].texels, seam.interiors[1].texels), (8 * H, 8 * H, 8 * H));
    assert_eq!(report.summary.max_jump_degrees, seam.max_jump_degrees);
    assert_eq!(report.summary.mean_gradient_ratio, seam.gradient_ratio);
}

#[test]
fn a_smooth_ramp_is_no_seam() {
    // The same tilts joined by a ramp across the whole map: every texel has the same slope change.
    let normals = slopes(|x| 0.3 - 0.6 * x as f32 / (W - 1) as f32);
    let seam = &measure(&halves(), &normals, 2, 4).unwrap().boundaries[0];
    let ratio = seam.gradient_ratio.unwrap();
    assert!((0.85..1.15).contains(&ratio), "{ratio}");
    assert!(seam.max_jump_degrees < 3.0, "{}", seam.max_jump_degrees);
}

#[test]
fn identical_regions_show_no_seam() {
    let normals = slopes(|_| 0.1);
    let seam = &measure(&halves(), &normals, 2, 4).unwrap().boundaries[0];
    let ratio = seam.gradient_ratio.unwrap();
    assert!((0.85..1.15).contains(&ratio), "{ratio}");
    let std = seam.std_ratio.unwrap();
    assert!((0.7..1.4).contains(&std), "{std}");
    assert!(seam.max_jump_degrees <= largest_neighbour_angle(&normals) + 1e-6);
    assert!(seam.max_jump_degrees < 4.0, "{}", seam.max_jump_degrees);
}

#[test]
fn the_spline_hides_what_hard_labels_show() {
    // Two regions with different tilts and ripples, joined along a wavy boundary.
    let labels = Grid::from_fn(W, H, |x, y| u16::from(x as f32 >= 32.0 + 4.0 * (y as f32 * 0.3).sin()));
    let left = slopes(|_| 0.25);
    let right = Grid::from_fn(W, H, |x, y| {
        let (rx, ry) = ripple(y, x);
        Vec3::new(-0.2 + rx, 0.1 + ry, 1.0).normalize()
    });
    let levels = 4;
    let pieces: Vec<Piece> = region_bounds(&labels, 2)
        .iter()
        .zip([&left, &right])
        .map(|(b, map)| {
            let r = piece_rect(b.unwrap(), levels, W, H);
            Piece::new(r.x0, r.y0, map.crop(r.x0, r.y0, r.width, r.height).unwrap())
        })
        .collect();
    let hard = blend(&labels, &pieces, &SplineConfig::no_blend(Blend::NormalVectors)).unwrap();
    let soft = blend(&labels, &pieces, &SplineConfig { levels, blend: Blend::NormalVectors }).unwrap();
    let hard = measure(&labels, &hard, 2, 3).unwrap().summary;
    let soft = measure(&labels, &soft, 2, 3).unwrap().summary;
    eprintln!("hard labels: {hard:?}\nspline, 4 levels: {soft:?}");
    assert!(soft.max_jump_degrees < 0.5 * hard.max_jump_degrees, "{soft:?} vs {hard:?}");
    assert!(soft.mean_gradient_ratio.unwrap() < 0.5 * hard.mean_gradient_ratio.unwrap(), "{soft:?} vs {hard:?}");
}

#[test]
fn texels_of_no_region_and_invalid_normals_are_left_out() {
    let mut normals = slopes(|x| if x < W / 2 { 0.3 } else { -0.3 });
    // A third label (outside `regions`) on the top rows and a hole of invalid normals.
    let labels = Grid::from_fn(W, H, |x, y| if y < 8 { 9 } else { u16::from(x >= W / 2) });
    for y in 20..24 {
        *normals.get_mut(W / 2, y) = Vec3::ZERO;
    }
    *normals.get_mut(W / 2 - 1, 30) = Vec3::NAN;
    let report = measure(&labels, &normals, 2, 4).unwrap();
    assert_eq!(report.boundaries.len(), 1);
    // 40 labelled rows, 5 of them without a valid pair across the boundary.
    assert_eq!(report.boundaries[0].crossings, 35);
    assert!(report.summary.max_jump_degrees.is_finite());
}

#[test]
fn bad_inputs_are_refused() {
    let normals = slopes(|_| 0.0);
    let small = Grid::filled(3, 3, 0u16);
    assert!(matches!(measure(&small, &normals, 2, 4), Err(SeamError::SizeMismatch { .. })));
    assert_eq!(measure(&halves(), &normals, 2, 0), Err(SeamError::ZeroBand));
    let one = measure(&Grid::filled(W, H, 0u16), &normals, 1, 4).unwrap();
    assert!(one.boundaries.is_empty() && one.summary.mean_gradient_ratio.is_none());
}
