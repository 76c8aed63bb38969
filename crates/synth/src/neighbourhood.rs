//! Wei-Levoy neighbourhoods flattened into feature vectors (Wei and Levoy 2000, section 3).
//!
//! A feature vector holds, 3 floats per texel, first the causal part of the `N x N` window at the
//! current level (the `(N*N - 1) / 2` texels before the centre in scanline order: full rows above,
//! then the texels left of the centre), then, when a coarser level exists, the full `M x M` window
//! of that level centred on `(x / 2, y / 2)`, in row-major order.

use glam::Vec3;

/// The offsets of one neighbourhood shape.
#[derive(Clone, Debug)]
pub struct Neighbourhood {
    causal: Vec<[isize; 2]>,
    parent: Vec<[isize; 2]>,
}

impl Neighbourhood {
    /// A causal `n x n` window, joined with a full `m x m` coarser window when `has_parent`.
    pub fn new(n: usize, m: usize, has_parent: bool) -> Self {
        let r = (n / 2) as isize;
        let causal = (-r..=0).flat_map(|dy| (-r..=r).map(move |dx| [dx, dy])).take_while(|&o| o != [0, 0]).collect();
        let pr = (m / 2) as isize;
        let parent = if has_parent {
            (-pr..=pr).flat_map(|dy| (-pr..=pr).map(move |dx| [dx, dy])).collect()
        } else {
            Vec::new()
        };
        Neighbourhood { causal, parent }
    }

    /// A full (non-causal) `n x n` window, centre included, joined with a full `m x m` coarser
    /// window when `has_parent`: the shape k-coherence sets are built with (Tong et al. 2002).
    pub fn full(n: usize, m: usize, has_parent: bool) -> Self {
        let r = (n / 2) as isize;
        let mut nb = Neighbourhood::new(n, m, has_parent);
        nb.causal = (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| [dx, dy])).collect();
        nb
    }

    /// Offsets `[dx, dy]` of the current-level texels (the causal ones, or the whole window for
    /// [`Self::full`]), in feature order.
    pub fn causal(&self) -> &[[isize; 2]] {
        &self.causal
    }

    /// Offsets of the coarser-level texels around `(x / 2, y / 2)`, in feature order (empty at the
    /// coarsest level).
    pub fn parent(&self) -> &[[isize; 2]] {
        &self.parent
    }

    /// Length of the feature vector in floats.
    pub fn dim(&self) -> usize {
        3 * (self.causal.len() + self.parent.len())
    }

    /// Writes the feature vector of texel `(x, y)` into `out` (length [`Self::dim`]); `current`
    /// and `coarser` read texels at the current and at the coarser level and do their own
    /// border addressing.
    pub fn gather(
        &self,
        x: isize,
        y: isize,
        current: impl Fn(isize, isize) -> Vec3,
        coarser: impl Fn(isize, isize) -> Vec3,
        out: &mut [f32],
    ) {
        debug_assert_eq!(out.len(), self.dim());
        let (px, py) = (x.div_euclid(2), y.div_euclid(2));
        let texels = self
            .causal
            .iter()
            .map(|&[dx, dy]| current(x + dx, y + dy))
            .chain(self.parent.iter().map(|&[dx, dy]| coarser(px + dx, py + dy)));
        for (slot, t) in out.chunks_exact_mut(3).zip(texels) {
            slot.copy_from_slice(&t.to_array());
        }
    }
}

/// Lanes of a squared distance's partial sums ([`Lanes`]).
pub const LANES: usize = 8;

/// The partial sums of a squared distance: float `j` of a feature adds to lane `j % LANES`, and
/// [`Lanes::total`] adds the lanes in one fixed order. Every distance in the crate goes through
/// it, so every caller gets the same bits for the same pair, and the compiler can keep the lanes
/// in SIMD registers (a single running sum cannot be reordered, and ran one float at a time).
#[derive(Debug, Clone, Copy, Default)]
pub struct Lanes([f32; LANES]);

impl Lanes {
    /// Adds `(a - b)^2` of the floats of `a` and `b`, which start at a multiple of [`LANES`].
    #[inline]
    pub fn add(&mut self, a: &[f32], b: &[f32]) {
        let (full_a, rest_a) = a.as_chunks::<LANES>();
        let (full_b, rest_b) = b.as_chunks::<LANES>();
        for (x, y) in full_a.iter().zip(full_b) {
            for l in 0..LANES {
                let d = x[l] - y[l];
                self.0[l] += d * d;
            }
        }
        for (l, (p, q)) in rest_a.iter().zip(rest_b).enumerate() {
            self.0[l] += (p - q) * (p - q);
        }
    }

    /// Adds `(a - b)^2` for float `j` (at lane `j % LANES`) only.
    #[inline]
    pub fn add_one(&mut self, j: usize, a: f32, b: f32) {
        self.0[j % LANES] += (a - b) * (a - b);
    }

    /// The sum of the lanes, pairwise in a fixed order.
    #[inline]
    pub fn total(&self) -> f32 {
        let l = &self.0;
        ((l[0] + l[1]) + (l[2] + l[3])) + ((l[4] + l[5]) + (l[6] + l[7]))
    }
}

/// Squared L2 distance, summed in [`Lanes`] (so every caller gets the same bits).
pub fn distance2(a: &[f32], b: &[f32]) -> f32 {
    let mut lanes = Lanes::default();
    lanes.add(a, b);
    lanes.total()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn causal_window_is_the_texels_before_the_centre() {
        let nb = Neighbourhood::new(5, 3, true);
        assert_eq!(nb.causal().len(), 12);
        assert_eq!(nb.causal()[0], [-2, -2]);
        assert_eq!(nb.causal()[11], [-1, 0]);
        assert_eq!(nb.parent().len(), 9);
        assert_eq!(nb.dim(), 3 * 21);
        assert_eq!(Neighbourhood::new(3, 3, false).dim(), 12);
        let full = Neighbourhood::full(5, 3, true);
        assert_eq!(full.causal().len(), 25);
        assert_eq!(full.causal()[12], [0, 0]);
        assert_eq!(full.dim(), 3 * 34);
    }

    #[test]
    fn gather_reads_both_levels_in_order() {
        let nb = Neighbourhood::new(3, 1, true);
        let mut out = vec![0.0; nb.dim()];
        nb.gather(5, 3, |x, y| Vec3::new(x as f32, y as f32, 0.0), |x, y| Vec3::new(x as f32, y as f32, 1.0), &mut out);
        let expect = [4., 2., 0., 5., 2., 0., 6., 2., 0., 4., 3., 0., 2., 1., 1.];
        assert_eq!(out, expect);
    }
}
