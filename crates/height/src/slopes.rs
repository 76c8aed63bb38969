//! [`Slopes`]: a normal map read as surface slopes, with each texel's validity, and the edge
//! equations of the integration (their right-hand side and their residual).
//!
//! Slopes are read from the normals on demand rather than stored, so that integrating an
//! 8192x8192 map holds one byte per texel here (the validity) beside the solver's buffers.

use rayon::prelude::*;
use serde::Serialize;
use skinkit_maps::{NormalMap, Vec3};

use crate::HOLE_WEIGHT;

/// Steepest slope kept, `tan(84.3 deg)`: a steeper normal (nz near 0, an infinite slope) is
/// clamped to it and counted, so one grazing texel cannot throw the surface off by thousands of
/// texels.
pub const MAX_SLOPE: f32 = 10.0;

/// Texels by what their normal said.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct TexelCounts {
    /// Usable normals.
    pub valid: usize,
    /// All-zero normals (skinkit's invalid marker: outside a mask, unsolved).
    pub zero: usize,
    /// NaN or infinite components.
    pub non_finite: usize,
    /// Normals facing away from the viewer (`nz <= 0`).
    pub back_facing: usize,
    /// Valid normals steeper than [`MAX_SLOPE`], clamped to it.
    pub clamped: usize,
}

impl TexelCounts {
    /// Texels not integrated as data.
    pub fn invalid(&self) -> usize {
        self.zero + self.non_finite + self.back_facing
    }
}

/// A normal map seen as slopes in texel units: `dh/dcol = -nx/nz`, `dh/drow = +ny/nz`.
pub struct Slopes<'a> {
    normals: &'a NormalMap,
    /// Per texel: the normal is usable.
    pub valid: Vec<bool>,
    pub counts: TexelCounts,
    /// Mean `(dh/dcol, dh/drow)` over the valid texels: the step a hole's fill asks for, so that a
    /// tilted surface is not bent flat across a hole.
    mean: (f32, f32),
}

/// Why a normal is or is not usable.
enum Kind {
    Valid { clamped: bool },
    Zero,
    NonFinite,
    BackFacing,
}

fn classify(n: Vec3) -> Kind {
    if !n.is_finite() {
        Kind::NonFinite
    } else if n == Vec3::ZERO {
        Kind::Zero
    } else if n.z <= 0.0 {
        Kind::BackFacing
    } else {
        Kind::Valid { clamped: n.x.abs() > MAX_SLOPE * n.z || n.y.abs() > MAX_SLOPE * n.z }
    }
}

impl<'a> Slopes<'a> {
    /// Classifies every texel of `normals`.
    pub fn from_normals(normals: &'a NormalMap) -> Slopes<'a> {
        let mut counts = TexelCounts::default();
        let valid = normals
            .as_slice()
            .iter()
            .map(|&n| match classify(n) {
                Kind::Valid { clamped } => {
                    counts.valid += 1;
                    counts.clamped += clamped as usize;
                    true
                }
                Kind::Zero => {
                    counts.zero += 1;
                    false
                }
                Kind::NonFinite => {
                    counts.non_finite += 1;
                    false
                }
                Kind::BackFacing => {
                    counts.back_facing += 1;
                    false
                }
            })
            .collect();
        let mut slopes = Slopes { normals, valid, counts, mean: (0.0, 0.0) };
        slopes.mean = slopes.mean_slope();
        slopes
    }

    /// The mean slope over the valid texels, summed in f64 in texel order.
    fn mean_slope(&self) -> (f32, f32) {
        let (mut sx, mut sy) = (0f64, 0f64);
        for i in (0..self.valid.len()).filter(|&i| self.valid[i]) {
            let (x, y) = self.at(i);
            sx += f64::from(x);
            sy += f64::from(y);
        }
        let n = self.counts.valid.max(1) as f64;
        ((sx / n) as f32, (sy / n) as f32)
    }

    pub fn width(&self) -> usize {
        self.normals.width()
    }

    pub fn height(&self) -> usize {
        self.normals.height()
    }

    /// `(dh/dcol, dh/drow)` at texel `i` in texel units, clamped; `(0, 0)` for an invalid texel.
    pub fn at(&self, i: usize) -> (f32, f32) {
        if !self.valid[i] {
            return (0.0, 0.0);
        }
        let n = self.normals.as_slice()[i];
        ((-n.x / n.z).clamp(-MAX_SLOPE, MAX_SLOPE), (n.y / n.z).clamp(-MAX_SLOPE, MAX_SLOPE))
    }

    /// The edge from texel `a` to its neighbour `b`: `(weight, target step)`. With `masked`, an
    /// edge with an invalid end asks for the mean slope's step at [`HOLE_WEIGHT`]; without, every
    /// edge has weight 1 and invalid texels count as flat.
    pub fn edge(&self, a: usize, b: usize, horizontal: bool, masked: bool) -> (f32, f32) {
        if masked && !(self.valid[a] && self.valid[b]) {
            return (HOLE_WEIGHT, if horizontal { self.mean.0 } else { self.mean.1 });
        }
        let (sa, sb) = (self.at(a), self.at(b));
        let step = if horizontal { 0.5 * (sa.0 + sb.0) } else { 0.5 * (sa.1 + sb.1) };
        (1.0, step)
    }

    /// The right-hand side `D^T W g` of the normal equations: per texel, the weighted steps of
    /// the edges arriving minus those leaving. With `wraps`, edges cross the borders.
    pub fn rhs(&self, wraps: bool, masked: bool) -> Vec<f32> {
        let (w, h) = (self.width(), self.height());
        let mut b = vec![0f32; w * h];
        b.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            for (x, out) in row.iter_mut().enumerate() {
                let i = y * w + x;
                let mut sum = 0.0;
                for (from, to, horizontal) in neighbours(x, y, w, h, wraps) {
                    let (weight, step) = self.edge(from, to, horizontal, masked);
                    // Arriving (`to == i`) adds the step, leaving subtracts it.
                    sum += if to == i { weight * step } else { -weight * step };
                }
                *out = sum;
            }
        });
        b
    }

    /// The RMS residual `(h_b - h_a) - step` over the edges whose two texels are valid, and the
    /// same against the RMS step (0 for an integrable map); `h` in texel units.
    pub fn residual(&self, h: &[f32], wraps: bool) -> (f64, f64) {
        let (w, hh) = (self.width(), self.height());
        let rows: Vec<(f64, f64, usize)> = (0..hh)
            .into_par_iter()
            .map(|y| {
                let (mut res, mut sq, mut n) = (0f64, 0f64, 0usize);
                for x in 0..w {
                    for (a, b, horizontal) in forward_edges(x, y, w, hh, wraps) {
                        if self.valid[a] && self.valid[b] {
                            let (_, step) = self.edge(a, b, horizontal, true);
                            let r = (h[b] - h[a] - step) as f64;
                            res += r * r;
                            sq += (step as f64) * (step as f64);
                            n += 1;
                        }
                    }
                }
                (res, sq, n)
            })
            .collect();
        let (res, sq, n) = rows.iter().fold((0.0, 0.0, 0), |t, r| (t.0 + r.0, t.1 + r.1, t.2 + r.2));
        if n == 0 {
            return (0.0, 0.0);
        }
        let rms = (res / n as f64).sqrt();
        let step = (sq / n as f64).sqrt();
        (rms, if step > 0.0 { rms / step } else { 0.0 })
    }
}

/// The (up to two) edges leaving texel `(x, y)`: to the right and downward, as `(from, to,
/// horizontal)`, wrapping when `wraps`.
pub(crate) fn forward_edges(
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    wraps: bool,
) -> impl Iterator<Item = (usize, usize, bool)> {
    let i = y * w + x;
    let right = if x + 1 < w {
        Some(i + 1)
    } else if wraps && w > 1 {
        Some(y * w)
    } else {
        None
    };
    let down = if y + 1 < h {
        Some(i + w)
    } else if wraps && h > 1 {
        Some(x)
    } else {
        None
    };
    right.map(|r| (i, r, true)).into_iter().chain(down.map(|d| (i, d, false)))
}

/// Every edge touching texel `(x, y)`, as `(from, to, horizontal)` with `from` the left or upper
/// texel: up to four.
pub(crate) fn neighbours(
    x: usize,
    y: usize,
    w: usize,
    h: usize,
    wraps: bool,
) -> impl Iterator<Item = (usize, usize, bool)> {
    let left = if x > 0 {
        Some(x - 1)
    } else if wraps && w > 1 {
        Some(w - 1)
    } else {
        None
    };
    let up = if y > 0 {
        Some(y - 1)
    } else if wraps && h > 1 {
        Some(h - 1)
    } else {
        None
    };
    let arriving =
        left.map(|lx| (y * w + lx, y * w + x, true)).into_iter().chain(up.map(|uy| (uy * w + x, y * w + x, false)));
    arriving.chain(forward_edges(x, y, w, h, wraps))
}
