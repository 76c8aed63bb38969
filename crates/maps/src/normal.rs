//! [`NormalMap`]: unit normals on a grid, with `(0, 0, 0)` for invalid texels.

use glam::Vec3;
use rayon::prelude::*;

use crate::encoding::{is_valid_normal, normalize_or_invalid};
use crate::{Error, Grid, Result};

/// A grid of unit normals (x right, y up, z out of the map). Invalid texels hold `Vec3::ZERO`.
///
/// Construction normalises every texel and turns non-finite or zero vectors into the invalid
/// marker, so a `NormalMap` never holds NaN.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMap {
    grid: Grid<Vec3>,
}

impl NormalMap {
    /// A map of `+Z` normals (a flat surface).
    pub fn flat(width: usize, height: usize) -> Self {
        NormalMap { grid: Grid::filled(width, height, Vec3::Z) }
    }

    /// Wraps a grid of vectors, normalising each and marking non-finite or zero ones invalid.
    pub fn from_grid(mut grid: Grid<Vec3>) -> Self {
        grid.as_mut_slice().par_iter_mut().for_each(|n| *n = normalize_or_invalid(*n));
        NormalMap { grid }
    }

    /// Wraps row-major vectors (see [`NormalMap::from_grid`]).
    ///
    /// # Errors
    /// When `data.len() != width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<Vec3>) -> Result<Self> {
        Ok(Self::from_grid(Grid::from_vec(width, height, data)?))
    }

    /// Wraps a grid whose texels are already unit vectors or `Vec3::ZERO` (no pass over the data).
    ///
    /// # Errors
    /// In debug builds only: when a texel is neither (a cheap sample of texels is checked).
    pub fn from_unit_grid(grid: Grid<Vec3>) -> Result<Self> {
        let step = (grid.len() / 1024).max(1);
        for (i, n) in grid.as_slice().iter().enumerate().step_by(step) {
            let ok = *n == Vec3::ZERO || (n.is_finite() && (n.length() - 1.0).abs() < 1e-3);
            if !ok {
                return Err(Error::InvalidParameter(format!("texel {i} is not a unit normal: {n}")));
            }
        }
        Ok(NormalMap { grid })
    }

    pub fn width(&self) -> usize {
        self.grid.width()
    }
    pub fn height(&self) -> usize {
        self.grid.height()
    }
    pub fn size(&self) -> (usize, usize) {
        self.grid.size()
    }
    pub fn grid(&self) -> &Grid<Vec3> {
        &self.grid
    }
    pub fn into_grid(self) -> Grid<Vec3> {
        self.grid
    }
    pub fn as_slice(&self) -> &[Vec3] {
        self.grid.as_slice()
    }
    /// The normal at `(x, y)` (`Vec3::ZERO` if invalid).
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        *self.grid.get(x, y)
    }
    /// Sets the texel at `(x, y)`, normalising `n` (or marking it invalid).
    pub fn set(&mut self, x: usize, y: usize, n: Vec3) {
        *self.grid.get_mut(x, y) = normalize_or_invalid(n);
    }
    /// Whether the texel at `(x, y)` holds a normal.
    pub fn is_valid(&self, x: usize, y: usize) -> bool {
        is_valid_normal(self.get(x, y))
    }
    /// Number of valid texels.
    pub fn valid_count(&self) -> usize {
        self.grid.as_slice().iter().filter(|n| is_valid_normal(**n)).count()
    }

    /// Angular differences in degrees to `other`, over texels valid in both (and in `mask`, when
    /// given: nonzero mask texels count).
    ///
    /// # Errors
    /// When the sizes differ.
    pub fn angular_error(&self, other: &NormalMap, mask: Option<&Grid<bool>>) -> Result<AngularStats> {
        if self.size() != other.size() || mask.is_some_and(|m| m.size() != self.size()) {
            return Err(Error::InvalidParameter(format!(
                "cannot compare a {}x{} normal map with a {}x{} one",
                self.width(),
                self.height(),
                other.width(),
                other.height()
            )));
        }
        let degrees: Vec<f32> = self
            .as_slice()
            .par_iter()
            .zip(other.as_slice())
            .enumerate()
            .filter(|(i, (a, b))| is_valid_normal(**a) && is_valid_normal(**b) && mask.is_none_or(|m| m.as_slice()[*i]))
            .map(|(_, (a, b))| angle_degrees(*a, *b))
            .collect();
        Ok(AngularStats::from_degrees(degrees))
    }
}

/// Angle between two unit vectors in degrees, accurate for tiny angles (atan2 of the cross and dot
/// products, not acos of the dot).
pub fn angle_degrees(a: Vec3, b: Vec3) -> f32 {
    let (a, b) = (a.as_dvec3(), b.as_dvec3());
    a.cross(b).length().atan2(a.dot(b)).to_degrees() as f32
}

/// Summary of angular differences, in degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct AngularStats {
    /// Number of texels compared.
    pub count: usize,
    pub mean: f32,
    pub rms: f32,
    pub median: f32,
    pub p95: f32,
    pub max: f32,
}

impl AngularStats {
    /// Statistics of a list of angles in degrees (all zero for an empty list). Linear time: the
    /// quantiles come from selection, not a full sort, so 16-megapixel maps cost milliseconds.
    pub fn from_degrees(mut degrees: Vec<f32>) -> Self {
        let count = degrees.len();
        if count == 0 {
            return AngularStats::default();
        }
        let (sum, sum_sq, max) = degrees
            .par_iter()
            .fold(|| (0.0f64, 0.0f64, f32::MIN), |(s, q, m), &d| (s + d as f64, q + (d as f64) * (d as f64), m.max(d)))
            .reduce(|| (0.0, 0.0, f32::MIN), |a, b| (a.0 + b.0, a.1 + b.1, a.2.max(b.2)));
        let mut at =
            |q: f64| *degrees.select_nth_unstable_by(((count - 1) as f64 * q).round() as usize, f32::total_cmp).1;
        let (median, p95) = (at(0.5), at(0.95));
        AngularStats {
            count,
            mean: (sum / count as f64) as f32,
            rms: (sum_sq / count as f64).sqrt() as f32,
            median,
            p95,
            max,
        }
    }
}

/// Histogram step of [`AngularStats::from_slice`], in degrees.
pub const ANGLE_BIN_DEGREES: f32 = 0.01;

/// Running sums and a histogram of angles, for [`AngularStats::from_slice`].
struct AngleHistogram {
    bins: Vec<u32>,
    count: usize,
    sum: f64,
    sum_sq: f64,
    max: f32,
}

impl AngleHistogram {
    fn new() -> Self {
        let len = (180.0 / ANGLE_BIN_DEGREES) as usize + 1;
        AngleHistogram { bins: vec![0; len], count: 0, sum: 0.0, sum_sq: 0.0, max: 0.0 }
    }
    fn add(mut self, degrees: f32) -> Self {
        let d = if degrees.is_finite() { degrees.clamp(0.0, 180.0) } else { 180.0 };
        self.bins[(d / ANGLE_BIN_DEGREES + 0.5) as usize] += 1;
        self.count += 1;
        self.sum += d as f64;
        self.sum_sq += (d as f64) * (d as f64);
        self.max = self.max.max(d);
        self
    }
    fn merge(mut self, other: Self) -> Self {
        self.bins.iter_mut().zip(&other.bins).for_each(|(a, b)| *a += b);
        self.count += other.count;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
        self.max = self.max.max(other.max);
        self
    }
    /// The angle of rank `round((count - 1) * q)`, to the bin's centre.
    fn quantile(&self, q: f64) -> f32 {
        let rank = ((self.count - 1) as f64 * q).round() as usize;
        let mut seen = 0usize;
        for (i, &n) in self.bins.iter().enumerate() {
            seen += n as usize;
            if seen > rank {
                return i as f32 * ANGLE_BIN_DEGREES;
            }
        }
        self.max
    }
}

/// Items per chunk of [`AngularStats::from_slice`]: the chunks, not the thread count, fix the order
/// in which the sums are added, so the statistics have the same bits on any number of threads.
const STATS_CHUNK: usize = 1 << 18;

impl AngularStats {
    /// Statistics of the angles `angle` gives for `items` (`None` skips an item), in `[0, 180]`
    /// degrees, computed in parallel without storing the angles: count, mean, rms and max are
    /// exact, median and p95 are rounded to [`ANGLE_BIN_DEGREES`]. For 16-megapixel maps, where
    /// sorting or selecting would dominate. Deterministic: fixed chunks merged in order.
    pub fn from_slice<T: Sync>(items: &[T], angle: impl Fn(&T) -> Option<f32> + Sync) -> Self {
        let parts: Vec<AngleHistogram> = items
            .par_chunks(STATS_CHUNK)
            .map(|chunk| chunk.iter().filter_map(&angle).fold(AngleHistogram::new(), AngleHistogram::add))
            .collect();
        let h = parts.into_iter().fold(AngleHistogram::new(), AngleHistogram::merge);
        if h.count == 0 {
            return AngularStats::default();
        }
        AngularStats {
            count: h.count,
            mean: (h.sum / h.count as f64) as f32,
            rms: (h.sum_sq / h.count as f64).sqrt() as f32,
            median: h.quantile(0.5),
            p95: h.quantile(0.95),
            max: h.max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn construction_never_keeps_nan() {
        let m = NormalMap::from_vec(3, 1, vec![Vec3::new(0.0, 0.0, 2.0), Vec3::NAN, Vec3::ZERO]).unwrap();
        assert_eq!(m.get(0, 0), Vec3::Z);
        assert_eq!(m.get(1, 0), Vec3::ZERO);
        assert_eq!(m.valid_count(), 1);
    }

    #[test]
    fn small_angles_are_accurate() {
        let a = Vec3::Z;
        let b = Vec3::new(1e-4, 0.0, 1.0).normalize();
        assert!((angle_degrees(a, b) - 1e-4f32.to_degrees()).abs() < 1e-7);
    }

    #[test]
    fn streamed_stats_agree_with_exact_ones() {
        let degrees: Vec<f32> = (0..10_000).map(|i| ((i * 7919) % 10_000) as f32 * 0.0123).collect();
        let exact = AngularStats::from_degrees(degrees.clone());
        let streamed = AngularStats::from_slice(&degrees, |&d| Some(d));
        assert_eq!(streamed.count, exact.count);
        assert!((streamed.mean - exact.mean).abs() < 1e-3);
        assert!((streamed.rms - exact.rms).abs() < 1e-3);
        assert_eq!(streamed.max, exact.max);
        assert!((streamed.median - exact.median).abs() <= ANGLE_BIN_DEGREES);
        assert!((streamed.p95 - exact.p95).abs() <= ANGLE_BIN_DEGREES);
        assert_eq!(AngularStats::from_slice(&[] as &[f32], |&d| Some(d)), AngularStats::default());
    }

    #[test]
    fn streamed_stats_have_the_same_bits_on_any_thread_count() {
        // Several chunks of values whose f64 sums depend on the order they are added in.
        let degrees: Vec<f32> =
            (0..3 * STATS_CHUNK + 12_345).map(|i| ((i as f64 * 0.618_034).fract() * 179.0) as f32).collect();
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| AngularStats::from_slice(&degrees, |&d| (d > 1.0).then_some(d)))
        };
        let one = on(1);
        assert!(one.count > 2 * STATS_CHUNK && one.count < degrees.len() && one.mean.is_finite());
        for threads in [2, 3, 8] {
            let many = on(threads);
            assert_eq!((many.mean.to_bits(), many.rms.to_bits()), (one.mean.to_bits(), one.rms.to_bits()), "{threads}");
            assert_eq!(many, one, "{threads} threads");
        }
    }

    #[test]
    fn stats_of_known_values() {
        let s = AngularStats::from_degrees(vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.count, 4);
        assert!((s.mean - 2.5).abs() < 1e-6);
        assert!((s.rms - 7.5f32.sqrt()).abs() < 1e-6);
        assert_eq!(s.max, 4.0);
    }
}
