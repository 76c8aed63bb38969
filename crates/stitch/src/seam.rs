//! The seam metric: how visible the boundaries between regions are (Haro et al. 2001, section 4.2;
//! Wei and Levoy observed that pyramid blending alone can leave visible boundaries, so we measure).
//!
//! For every pair of 4-adjacent regions `(a, b)`, texels are sorted by their Chebyshev distance `d`
//! to the nearest boundary texel (a texel with a 4-neighbour of another region), the boundary
//! being the one of that pair: the *band* is `d < w` on both sides, the *interiors* are
//! `w <= d < 3w` on each side. In each set we measure the normal slopes `s = (nx/nz, ny/nz)`
//! ([`crate::spline::to_slope`]): the mean gradient magnitude `|grad s|` (forward differences, the
//! Frobenius norm of the 2x2 Jacobian) and the slope standard deviation
//! `sqrt(var sx + var sy)`. A seam shows as a band whose gradient (or spread) exceeds its
//! interiors': ratios near 1 mean the boundary is statistically invisible. The largest normal jump
//! is the largest angle between 4-neighbours of the two regions.
//!
//! Texels whose label is `>= regions`, or whose normal is zero or not finite, are left out.

use std::collections::{BTreeMap, VecDeque};

use glam::Vec3;
use serde::Serialize;
use skinkit_maps::Grid;
use skinkit_maps::normal::angle_degrees;

use crate::spline::to_slope;

/// Slope statistics of a set of texels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SlopeStats {
    /// Texels in the set (with a measurable gradient).
    pub texels: usize,
    /// Mean `|grad s|` per texel (slope units per texel).
    pub mean_gradient: f64,
    /// `sqrt(var sx + var sy)`.
    pub slope_std: f64,
}

/// The seam between regions `regions[0] < regions[1]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoundarySeam {
    pub regions: [u16; 2],
    /// 4-neighbour pairs across the boundary.
    pub crossings: usize,
    /// Texels within the band width of the boundary, both sides.
    pub band: SlopeStats,
    /// Texels at `w..3w` from the boundary on the side of `regions[0]` and of `regions[1]`.
    pub interiors: [SlopeStats; 2],
    /// Band mean gradient over the mean of the interiors' (`None` when they have none).
    pub gradient_ratio: Option<f64>,
    /// Band slope std over the mean of the interiors'.
    pub std_ratio: Option<f64>,
    /// Largest angle between 4-neighbours across the boundary, degrees.
    pub max_jump_degrees: f64,
    /// Mean angle between 4-neighbours across the boundary, degrees.
    pub mean_jump_degrees: f64,
}

/// All boundaries at once.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SeamSummary {
    pub boundaries: usize,
    /// Mean of the boundaries' gradient ratios, weighted by band texels.
    pub mean_gradient_ratio: Option<f64>,
    pub max_gradient_ratio: Option<f64>,
    /// Mean of the boundaries' std ratios, weighted by band texels.
    pub mean_std_ratio: Option<f64>,
    pub max_jump_degrees: f64,
    /// Mean angle across all boundaries' crossings.
    pub mean_jump_degrees: f64,
}

/// The seam metric of a map: per boundary and overall.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SeamReport {
    /// The band width `w` in texels.
    pub band_width: usize,
    pub boundaries: Vec<BoundarySeam>,
    pub summary: SeamSummary,
}

/// What [`measure`] refuses.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SeamError {
    #[error("label map is {labels:?} but the normal map is {normals:?} (width, height)")]
    SizeMismatch { labels: (usize, usize), normals: (usize, usize) },
    #[error("seam band width must be at least 1 texel")]
    ZeroBand,
}

/// Measures the seams of `normals` along the boundaries of `labels` (regions `0..regions`) with a
/// band `band` texels wide on each side.
///
/// # Errors
/// Sizes that differ, a zero band.
pub fn measure(labels: &Grid<u16>, normals: &Grid<Vec3>, regions: usize, band: usize) -> Result<SeamReport, SeamError> {
    if labels.size() != normals.size() {
        return Err(SeamError::SizeMismatch { labels: labels.size(), normals: normals.size() });
    }
    if band == 0 {
        return Err(SeamError::ZeroBand);
    }
    let valid = Grid::from_fn(labels.width(), labels.height(), |x, y| {
        let n = *normals.get(x, y);
        (*labels.get(x, y) as usize) < regions && n.is_finite() && n != Vec3::ZERO
    });
    let (nearest, jumps) = boundaries(labels, normals, &valid);
    let distances = spread(&valid, nearest, 3 * band);
    let sets = slope_sets(labels, normals, &valid, &distances, band);
    let boundaries: Vec<BoundarySeam> =
        jumps.into_iter().map(|(pair, jump)| seam(pair, &jump, sets.get(&pair).cloned().unwrap_or_default())).collect();
    let summary = summarise(&boundaries);
    Ok(SeamReport { band_width: band, boundaries, summary })
}

/// Running sums of angles across one boundary.
#[derive(Clone, Copy, Debug, Default)]
struct Jumps {
    count: usize,
    sum: f64,
    max: f64,
}

/// Boundary texels with their pair (seeds for [`spread`]) and the angles across every boundary.
#[allow(clippy::type_complexity)]
fn boundaries(
    labels: &Grid<u16>,
    normals: &Grid<Vec3>,
    valid: &Grid<bool>,
) -> (Vec<(usize, usize, [u16; 2])>, BTreeMap<[u16; 2], Jumps>) {
    let (w, h) = labels.size();
    let mut seeds = Vec::new();
    let mut jumps: BTreeMap<[u16; 2], Jumps> = BTreeMap::new();
    for y in 0..h {
        for x in 0..w {
            if !valid.get(x, y) {
                continue;
            }
            let own = *labels.get(x, y);
            let mut best: Option<[u16; 2]> = None;
            for (nx, ny) in neighbours4(x, y, w, h) {
                let other = *labels.get(nx, ny);
                if !valid.get(nx, ny) || other == own {
                    continue;
                }
                let pair = [own.min(other), own.max(other)];
                best = Some(best.map_or(pair, |b| b.min(pair)));
                if (nx, ny) > (x, y) {
                    let angle = angle_degrees(normals.get(x, y).normalize(), normals.get(nx, ny).normalize()) as f64;
                    let j = jumps.entry(pair).or_default();
                    (j.count, j.sum, j.max) = (j.count + 1, j.sum + angle, j.max.max(angle));
                }
            }
            if let Some(pair) = best {
                seeds.push((x, y, pair));
            }
        }
    }
    (seeds, jumps)
}

/// The in-map 4-neighbours of `(x, y)`: left, right, up, down.
fn neighbours4(x: usize, y: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    let cand = [(x.wrapping_sub(1), y), (x + 1, y), (x, y.wrapping_sub(1)), (x, y + 1)];
    cand.into_iter().filter(move |&(i, j)| i < w && j < h)
}

/// Chebyshev distance (8-connected breadth-first search over valid texels, up to `limit`
/// exclusive) to the nearest seed and that seed's pair; `None` beyond.
fn spread(valid: &Grid<bool>, seeds: Vec<(usize, usize, [u16; 2])>, limit: usize) -> Grid<Option<(u32, [u16; 2])>> {
    let (w, h) = valid.size();
    let mut dist: Grid<Option<(u32, [u16; 2])>> = Grid::filled(w, h, None);
    let mut queue = VecDeque::with_capacity(seeds.len());
    for (x, y, pair) in seeds {
        *dist.get_mut(x, y) = Some((0, pair));
        queue.push_back((x, y));
    }
    while let Some((x, y)) = queue.pop_front() {
        let (d, pair) = dist.get(x, y).expect("queued texels have a distance");
        if d as usize + 1 >= limit {
            continue;
        }
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                let (nx, ny) = (x.wrapping_add_signed(dx), y.wrapping_add_signed(dy));
                if nx < w && ny < h && *valid.get(nx, ny) && dist.get(nx, ny).is_none() {
                    *dist.get_mut(nx, ny) = Some((d + 1, pair));
                    queue.push_back((nx, ny));
                }
            }
        }
    }
    dist
}

/// Sums of one texel set's slopes and gradients.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    count: usize,
    gradient: f64,
    slope: [f64; 2],
    square: f64,
}

impl Sums {
    fn add(&mut self, s: Vec3, gradient: f64) {
        self.count += 1;
        self.gradient += gradient;
        self.slope[0] += s.x as f64;
        self.slope[1] += s.y as f64;
        self.square += (s.x as f64).powi(2) + (s.y as f64).powi(2);
    }

    fn stats(&self) -> SlopeStats {
        if self.count == 0 {
            return SlopeStats::default();
        }
        let n = self.count as f64;
        let mean_sq = (self.slope[0] / n).powi(2) + (self.slope[1] / n).powi(2);
        SlopeStats {
            texels: self.count,
            mean_gradient: self.gradient / n,
            slope_std: (self.square / n - mean_sq).max(0.0).sqrt(),
        }
    }
}

/// Band, interior of the first and of the second region, per pair.
type PairSums = [Sums; 3];

/// Slope statistics of every pair's band and interiors.
fn slope_sets(
    labels: &Grid<u16>,
    normals: &Grid<Vec3>,
    valid: &Grid<bool>,
    distances: &Grid<Option<(u32, [u16; 2])>>,
    band: usize,
) -> BTreeMap<[u16; 2], PairSums> {
    let (w, h) = labels.size();
    let mut sets: BTreeMap<[u16; 2], PairSums> = BTreeMap::new();
    for y in 0..h {
        for x in 0..w {
            let Some((d, pair)) = *distances.get(x, y) else { continue };
            let own = *labels.get(x, y);
            let Some(gradient) = slope_gradient(normals, valid, x, y) else { continue };
            let set = if (d as usize) < band {
                0
            } else if own == pair[0] {
                1
            } else if own == pair[1] {
                2
            } else {
                continue;
            };
            sets.entry(pair).or_default()[set].add(to_slope(*normals.get(x, y)), gradient);
        }
    }
    sets
}

/// `|grad s|` at `(x, y)` by forward differences (backward at the last column or row); `None`
/// when a neighbour it needs is not valid or the map is one texel wide or high.
fn slope_gradient(normals: &Grid<Vec3>, valid: &Grid<bool>, x: usize, y: usize) -> Option<f64> {
    let (w, h) = normals.size();
    if w < 2 || h < 2 {
        return None;
    }
    let diff = |a: (usize, usize), b: (usize, usize)| {
        (*valid.get(a.0, a.1) && *valid.get(b.0, b.1))
            .then(|| to_slope(*normals.get(b.0, b.1)) - to_slope(*normals.get(a.0, a.1)))
    };
    let dx = if x + 1 < w { diff((x, y), (x + 1, y)) } else { diff((x - 1, y), (x, y)) }?;
    let dy = if y + 1 < h { diff((x, y), (x, y + 1)) } else { diff((x, y - 1), (x, y)) }?;
    Some((dx.as_dvec3().length_squared() + dy.as_dvec3().length_squared()).sqrt())
}

/// `a / b`, `None` when `b` is not positive.
fn ratio(a: f64, b: f64) -> Option<f64> {
    (b > 0.0).then(|| a / b)
}

/// Mean of the present (non-empty) interiors' values.
fn interior_mean(interiors: &[SlopeStats; 2], value: impl Fn(&SlopeStats) -> f64) -> f64 {
    let present: Vec<f64> = interiors.iter().filter(|s| s.texels > 0).map(value).collect();
    if present.is_empty() { 0.0 } else { present.iter().sum::<f64>() / present.len() as f64 }
}

/// One boundary's seam from its jumps and sums.
fn seam(pair: [u16; 2], jump: &Jumps, sums: PairSums) -> BoundarySeam {
    let band = sums[0].stats();
    let interiors = [sums[1].stats(), sums[2].stats()];
    BoundarySeam {
        regions: pair,
        crossings: jump.count,
        band,
        interiors,
        gradient_ratio: ratio(band.mean_gradient, interior_mean(&interiors, |s| s.mean_gradient)),
        std_ratio: ratio(band.slope_std, interior_mean(&interiors, |s| s.slope_std)),
        max_jump_degrees: jump.max,
        mean_jump_degrees: if jump.count > 0 { jump.sum / jump.count as f64 } else { 0.0 },
    }
}

/// Band-weighted means and maxima over all boundaries.
fn summarise(boundaries: &[BoundarySeam]) -> SeamSummary {
    let weighted = |value: &dyn Fn(&BoundarySeam) -> Option<f64>| {
        let (sum, weight) = boundaries
            .iter()
            .filter_map(|b| value(b).map(|v| (v * b.band.texels as f64, b.band.texels as f64)))
            .fold((0.0, 0.0), |(s, w), (v, bw)| (s + v, w + bw));
        ratio(sum, weight)
    };
    let crossings: usize = boundaries.iter().map(|b| b.crossings).sum();
    let jump_sum: f64 = boundaries.iter().map(|b| b.mean_jump_degrees * b.crossings as f64).sum();
    SeamSummary {
        boundaries: boundaries.len(),
        mean_gradient_ratio: weighted(&|b| b.gradient_ratio),
        max_gradient_ratio: boundaries.iter().filter_map(|b| b.gradient_ratio).reduce(f64::max),
        mean_std_ratio: weighted(&|b| b.std_ratio),
        max_jump_degrees: boundaries.iter().map(|b| b.max_jump_degrees).fold(0.0, f64::max),
        mean_jump_degrees: if crossings > 0 { jump_sum / crossings as f64 } else { 0.0 },
    }
}
