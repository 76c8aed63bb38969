//! The guards' figures: how much of the exemplar's variation an output kept (the collapse guard)
//! and how far its value histograms drifted from the exemplar's (the histogram guard).

use glam::Vec3;
use skinkit_maps::{Grid, NormalMap};

use super::{MIN_NZ, wasserstein_1d};

/// Below this share of the exemplar's variation an output counts as collapsed (see
/// [`variation_ratio`]).
pub const COLLAPSE_RATIO: f64 = 0.5;

/// How much of the exemplar's variation a colour output keeps: the smallest, over the channels
/// whose exemplar standard deviation is above `1e-6`, of the output's standard deviation over the
/// exemplar's. 1 when no channel varies (a constant exemplar cannot lose variation); 0 for a
/// constant output of a varied exemplar. A synthesis that regresses to one window (a blank map)
/// scores near 0; [`COLLAPSE_RATIO`] is the warning threshold.
///
/// The exemplar's deviation is taken at the output's scale (`deviation_at_scale`): an output
/// smaller than the exemplar cannot hold its longest waves, and a verbatim crop of it scores 1,
/// not the crop's share of the whole exemplar's deviation.
pub fn variation_ratio(output: &Grid<Vec3>, exemplar: &Grid<Vec3>) -> f64 {
    let value = |c: usize| move |v: &Vec3| Some(v[c]);
    let pairs = (0..3).map(|c| {
        (std_dev(output.as_slice().iter().filter_map(value(c))), deviation_at_scale(exemplar, output.size(), value(c)))
    });
    min_ratio(pairs)
}

/// The deviation of `value` over `exemplar` at the scale of an `ow x oh` output: the whole
/// exemplar's standard deviation when the output is at least as large on both axes, otherwise the
/// mean standard deviation over the exemplar's tiles of `min(ow, ew) x min(oh, eh)` texels
/// (non-overlapping, from the top-left; a partial last tile is left out).
fn deviation_at_scale(exemplar: &Grid<Vec3>, (ow, oh): (usize, usize), value: impl Fn(&Vec3) -> Option<f32>) -> f64 {
    let (ew, eh) = exemplar.size();
    let (tw, th) = (ow.clamp(1, ew.max(1)), oh.clamp(1, eh.max(1)));
    if tw >= ew && th >= eh {
        return std_dev(exemplar.as_slice().iter().filter_map(&value));
    }
    let tiles: Vec<f64> = (0..eh / th)
        .flat_map(|ty| (0..ew / tw).map(move |tx| (tx, ty)))
        .map(|(tx, ty)| {
            let rows = (ty * th..(ty + 1) * th).flat_map(|y| (tx * tw..(tx + 1) * tw).map(move |x| (x, y)));
            std_dev(rows.filter_map(|(x, y)| value(exemplar.get(x, y))))
        })
        .collect();
    tiles.iter().sum::<f64>() / tiles.len().max(1) as f64
}

/// [`variation_ratio`] for normal maps, on the slopes ([`slopes`](super::slopes)) of each axis.
pub fn slope_variation_ratio(output: &NormalMap, exemplar: &NormalMap) -> f64 {
    slope_variation_ratio_of(output.grid(), exemplar.grid())
}

/// [`slope_variation_ratio`] of normals held as plain grids (texels with `z <= MIN_NZ` left out).
pub(crate) fn slope_variation_ratio_of(output: &Grid<Vec3>, exemplar: &Grid<Vec3>) -> f64 {
    let slope = |c: usize| move |v: &Vec3| (v.z > MIN_NZ).then(|| -v[c] / v.z);
    let pairs = (0..2).map(|c| {
        (std_dev(output.as_slice().iter().filter_map(slope(c))), deviation_at_scale(exemplar, output.size(), slope(c)))
    });
    min_ratio(pairs)
}

/// Above this [`histogram_mismatch`] an output's histogram counts as drifted from the
/// exemplar's (the suite's outputs measure 0.03-0.13, the heightfield nose's 0.18-0.27 before the
/// histogram guard of [`crate::synthesize`]).
pub const HISTOGRAM_RATIO: f64 = 0.15;

/// At most this many output values enter a [`histogram_mismatch`] (an even stride through the
/// map above it): sampling moves the figure by about `1 / sqrt(65536)` = 0.004 deviations, far
/// under the guard's 0.15, and keeps its cost (two sorts) flat in the output's size.
const HISTOGRAM_SAMPLES: usize = 1 << 16;

/// How far an output's value histograms are from the exemplar's, in the exemplar's own spread:
/// the mean over the components of their [`wasserstein_1d`] distance over the exemplar's standard
/// deviation of that component. Components the exemplar holds constant (deviation under `1e-6`)
/// are left out, as are components without values; 0 when none is left.
pub fn histogram_mismatch(
    output: &Grid<Vec3>,
    exemplar: &Grid<Vec3>,
    components: usize,
    value: impl Fn(&Vec3, usize) -> Option<f32>,
) -> f64 {
    let stride = output.len().div_ceil(HISTOGRAM_SAMPLES).max(1);
    let samples: Vec<Vec<f32>> = (0..components)
        .map(|c| output.as_slice().iter().step_by(stride).filter_map(|v| value(v, c)).collect())
        .collect();
    mismatch_of_samples(&samples, exemplar, value)
}

/// [`histogram_mismatch`] of the output values sampled already, one list per component.
fn mismatch_of_samples(
    samples: &[Vec<f32>],
    exemplar: &Grid<Vec3>,
    value: impl Fn(&Vec3, usize) -> Option<f32>,
) -> f64 {
    let ratios: Vec<f64> = samples
        .iter()
        .enumerate()
        .filter_map(|(c, o)| {
            let e: Vec<f32> = exemplar.as_slice().iter().filter_map(|v| value(v, c)).collect();
            let spread = std_dev(e.iter().copied());
            let d = wasserstein_1d(o, &e);
            (spread > 1e-6 && d.is_finite()).then(|| d / spread)
        })
        .collect();
    if ratios.is_empty() { 0.0 } else { ratios.iter().sum::<f64>() / ratios.len() as f64 }
}

/// [`histogram_mismatch`] of colour maps, over r, g and b.
pub fn channel_histogram_mismatch(output: &Grid<Vec3>, exemplar: &Grid<Vec3>) -> f64 {
    histogram_mismatch(output, exemplar, 3, |v, c| Some(v[c]))
}

/// [`histogram_mismatch`] of normal maps, over the slopes `sx` and `sy` ([`slopes`](super::slopes)).
pub fn slope_histogram_mismatch(output: &NormalMap, exemplar: &NormalMap) -> f64 {
    slope_histogram_mismatch_of(output.grid(), exemplar.grid())
}

/// [`slope_histogram_mismatch`] of normals held as plain grids (texels with `z <= MIN_NZ` left out).
pub(crate) fn slope_histogram_mismatch_of(output: &Grid<Vec3>, exemplar: &Grid<Vec3>) -> f64 {
    histogram_mismatch(output, exemplar, 2, |v, c| (v.z > MIN_NZ).then(|| -v[c] / v.z))
}

/// The smallest `output / exemplar` over the pairs whose exemplar deviation is above `1e-6`.
fn min_ratio(pairs: impl Iterator<Item = (f64, f64)>) -> f64 {
    let min = pairs.filter(|&(_, e)| e > 1e-6).map(|(o, e)| o / e).fold(f64::INFINITY, f64::min);
    if min.is_finite() { min } else { 1.0 }
}

/// Population standard deviation of the finite values (0 for none), in one pass (f64 sums; the
/// values are slopes or colours, far from where the shortcut loses precision).
pub(crate) fn std_dev(values: impl Iterator<Item = f32>) -> f64 {
    let mut m = Moments::default();
    values.for_each(|v| m.add(v));
    m.deviation()
}

/// The running count, sum and sum of squares of [`std_dev`].
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    n: u64,
    sum: f64,
    squares: f64,
}

impl Moments {
    /// Counts `v` if it is finite.
    fn add(&mut self, v: f32) {
        if v.is_finite() {
            let v = f64::from(v);
            self.n += 1;
            self.sum += v;
            self.squares += v * v;
        }
    }

    fn deviation(&self) -> f64 {
        if self.n == 0 {
            return 0.0;
        }
        let mean = self.sum / self.n as f64;
        (self.squares / self.n as f64 - mean * mean).max(0.0).sqrt()
    }
}

/// The guards' figures of an output measured as its rows come, top to bottom: the same numbers,
/// bit for bit, as [`variation_ratio`] and [`channel_histogram_mismatch`] (colours) or
/// [`slope_variation_ratio`] and [`slope_histogram_mismatch`] (normals) of the whole output, since
/// it sums and samples the values in the same order.
#[derive(Clone, Debug)]
pub struct GuardMeter {
    normals: bool,
    size: (usize, usize),
    stride: usize,
    seen: usize,
    moments: [Moments; 3],
    samples: [Vec<f32>; 3],
}

impl GuardMeter {
    /// A meter of a `size` output of normals (slopes) or colours (channels).
    pub fn new(normals: bool, size: (usize, usize)) -> Self {
        let stride = (size.0 * size.1).div_ceil(HISTOGRAM_SAMPLES).max(1);
        GuardMeter { normals, size, stride, seen: 0, moments: [Moments::default(); 3], samples: Default::default() }
    }

    fn components(&self) -> usize {
        if self.normals { 2 } else { 3 }
    }

    fn value(normals: bool) -> impl Fn(&Vec3, usize) -> Option<f32> {
        move |v, c| if normals { (v.z > MIN_NZ).then(|| -v[c] / v.z) } else { Some(v[c]) }
    }

    /// Counts the next texels, in row-major order.
    pub fn add(&mut self, texels: &[Vec3]) {
        let (components, value) = (self.components(), Self::value(self.normals));
        for v in texels {
            for c in 0..components {
                if let Some(x) = value(v, c) {
                    self.moments[c].add(x);
                }
            }
        }
        let first = self.seen.next_multiple_of(self.stride) - self.seen;
        for v in texels.iter().skip(first).step_by(self.stride) {
            for c in 0..components {
                self.samples[c].extend(value(v, c));
            }
        }
        self.seen += texels.len();
    }

    /// `(variation, histogram mismatch)` against `exemplar`.
    pub fn figures(&self, exemplar: &Grid<Vec3>) -> (f64, f64) {
        let (normals, components) = (self.normals, self.components());
        let value = Self::value(normals);
        let pairs = (0..components)
            .map(|c| (self.moments[c].deviation(), deviation_at_scale(exemplar, self.size, |v| value(v, c))));
        let histogram = mismatch_of_samples(&self.samples[..components], exemplar, Self::value(normals));
        (min_ratio(pairs), histogram)
    }
}

#[cfg(test)]
mod tests {
    /// The one-pass deviation against a hand computation; non-finite values are skipped.
    #[test]
    fn std_dev_is_the_population_deviation_of_the_finite_values() {
        let v = [1.0f32, 3.0, f32::NAN, 5.0, 7.0, f32::INFINITY];
        assert!((super::std_dev(v.iter().copied()) - 5.0f64.sqrt()).abs() < 1e-12);
        assert_eq!(super::std_dev(std::iter::empty()), 0.0);
    }

    /// The meter fed in uneven bands gives the whole-output figures bit for bit, for colours and
    /// normals (invalid texels among them), at a size where the histogram samples a stride.
    #[test]
    fn the_meter_gives_the_whole_output_figures() {
        use super::*;
        let (w, h) = (301, 250);
        let texel = |x: usize, y: usize| {
            let t = (x * 7 + y * 13) as f32;
            if (x + y).is_multiple_of(97) { Vec3::ZERO } else { Vec3::new(0.3 * t.sin(), 0.2 * (0.7 * t).cos(), 0.9) }
        };
        let output = Grid::from_fn(w, h, texel);
        let exemplar = Grid::from_fn(40, 30, |x, y| texel(3 * x + 1, 2 * y));
        for normals in [false, true] {
            let mut meter = GuardMeter::new(normals, (w, h));
            for rows in [0..1, 1..100, 100..101, 101..250] {
                meter.add(&output.as_slice()[rows.start * w..rows.end * w]);
            }
            let whole = if normals {
                (slope_variation_ratio_of(&output, &exemplar), slope_histogram_mismatch_of(&output, &exemplar))
            } else {
                (variation_ratio(&output, &exemplar), channel_histogram_mismatch(&output, &exemplar))
            };
            let (v, m) = meter.figures(&exemplar);
            assert_eq!((v.to_bits(), m.to_bits()), (whole.0.to_bits(), whole.1.to_bits()), "normals {normals}");
            assert!(v > 0.1 && m.is_finite());
        }
        assert!(w * h > HISTOGRAM_SAMPLES, "the histogram samples a stride");
    }
}
