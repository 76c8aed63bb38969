//! Histogram balance (Kopf et al. 2007, section 4.3, "histogram matching"): exemplar texels whose
//! values the output already holds more often than the exemplar does are made costlier to copy.
//!
//! The occurrence penalty ([`crate::synthesis::Occurrence`]) counts copies of each exemplar texel;
//! it cannot see that the output holds too many texels of one kind (the flat middle of a broad
//! bulge, the skin between pores) when each of them is copied only a few times. Balance counts by
//! value instead: per channel, the exemplar's candidates are split into [`Bins`] of equal count by
//! rank (so the exemplar's histogram is flat by construction, whatever its distribution), and a
//! candidate whose bins the output over-fills by a share `r_c` (output share times the bin count;
//! 1 is a match) has its squared distance multiplied by `1 + mu * mean_c max(0, r_c - 1)`.

use skinkit_maps::Grid;

use crate::exemplar::ExemplarLevel;

/// Fewest candidates per bin: a level with fewer candidates than this has one bin (no balance).
const MIN_PER_BIN: usize = 16;

/// Most bins per channel.
const MAX_BINS: usize = 32;

/// Each candidate's bin per channel: its rank among the level's candidates by that channel (ties
/// by index, so a constant region spreads over several bins) times the bin count over the
/// candidate count.
pub(crate) struct Bins {
    of: Vec<[u8; 3]>,
    count: usize,
}

impl Bins {
    /// The bins of `full`'s candidates.
    pub(crate) fn new(full: &ExemplarLevel) -> Self {
        let n = full.len();
        let count = (n / MIN_PER_BIN).clamp(1, MAX_BINS);
        let texels: Vec<[f32; 3]> = (0..n).map(|i| full.texel(i).to_array()).collect();
        let mut of = vec![[0u8; 3]; n];
        let mut order: Vec<usize> = (0..n).collect();
        for c in 0..3 {
            order.sort_by(|&a, &b| texels[a][c].total_cmp(&texels[b][c]).then(a.cmp(&b)));
            for (rank, &i) in order.iter().enumerate() {
                of[i][c] = (rank * count / n) as u8;
            }
        }
        Bins { of, count }
    }

    /// The factor on each candidate's squared distance for an output whose sources are `coords`
    /// (positions that are not candidates are not counted), with strength `mu`; empty when `mu` is
    /// 0 or there is a single bin.
    pub(crate) fn weights(&self, full: &ExemplarLevel, coords: &Grid<[u32; 2]>, mu: f32) -> Vec<f32> {
        if mu <= 0.0 || self.count < 2 {
            return Vec::new();
        }
        let mut counts = vec![0u32; 3 * self.count];
        let mut total = 0u32;
        for &[x, y] in coords.as_slice() {
            if let Some(i) = full.index_of(x as isize, y as isize) {
                for (c, &b) in self.of[i].iter().enumerate() {
                    counts[c * self.count + b as usize] += 1;
                }
                total += 1;
            }
        }
        if total == 0 {
            return Vec::new();
        }
        let scale = self.count as f32 / total as f32;
        let excess: Vec<f32> = counts.iter().map(|&k| (k as f32 * scale - 1.0).max(0.0)).collect();
        self.of
            .iter()
            .map(|bins| {
                let over: f32 = bins.iter().enumerate().map(|(c, &b)| excess[c * self.count + b as usize]).sum();
                1.0 + mu * over / 3.0
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::neighbourhood::Neighbourhood;

    fn level(side: usize, texel: impl Fn(usize, usize) -> Vec3 + Sync) -> ExemplarLevel {
        let texels = Grid::from_fn(side, side, texel);
        let nb = Neighbourhood::full(3, 1, false);
        ExemplarLevel::new(texels, None, &nb, 3, true)
    }

    #[test]
    fn bins_split_candidates_into_equal_counts_per_channel() {
        let ex = level(16, |x, y| Vec3::new(x as f32, (y * 7 % 16) as f32, 0.5));
        let bins = Bins::new(&ex);
        assert_eq!(bins.count, 16);
        for c in 0..3 {
            let mut per = vec![0; bins.count];
            for b in &bins.of {
                per[b[c] as usize] += 1;
            }
            assert!(per.iter().all(|&k| k == 16), "channel {c}: {per:?}");
        }
        // Rank order: a larger x never sits in a lower bin.
        for i in 0..ex.len() {
            for j in 0..ex.len() {
                if ex.texel(i).x < ex.texel(j).x {
                    assert!(bins.of[i][0] <= bins.of[j][0]);
                }
            }
        }
    }

    #[test]
    fn weights_penalise_only_the_over_filled_bins() {
        let ex = level(16, |x, y| Vec3::new(x as f32, y as f32, (x + y) as f32));
        let bins = Bins::new(&ex);
        // An output that copies every candidate once matches the exemplar: no penalty.
        let all = Grid::from_fn(16, 16, |x, y| [x as u32, y as u32]);
        assert!(bins.weights(&ex, &all, 2.0).iter().all(|&w| w == 1.0));
        // An output of column 0 only: bin 0 of channel x holds everything (share 16 times its
        // due), so candidates of column 0 pay, and by brute force every weight is
        // 1 + mu * sum_c max(0, share_c * bins - 1) / 3.
        let column = Grid::from_fn(16, 16, |_, y| [0, y as u32]);
        let w = bins.weights(&ex, &column, 2.0);
        for i in 0..ex.len() {
            let mut over = 0.0;
            for c in 0..3 {
                // Each source (0, y) is copied 16 times.
                let same = 16 * (0..16).filter(|&y| bins.of[ex.index_of(0, y).unwrap()][c] == bins.of[i][c]).count();
                over += (same as f32 / 256.0 * 16.0 - 1.0).max(0.0);
            }
            let expected = 1.0 + 2.0 * over / 3.0;
            assert!((w[i] - expected).abs() < 1e-5, "candidate {i}: {} against {expected}", w[i]);
        }
        assert!(w[ex.index_of(0, 5).unwrap()] > 5.0);
        // Off, or a single bin: no weights.
        assert!(bins.weights(&ex, &column, 0.0).is_empty());
    }
}
