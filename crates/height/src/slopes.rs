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

/// Texels per parallel task of the classification.
const CHUNK: usize = 1 << 16;
/// Rows per parallel task of the row passes (each task keeps its neighbours' slopes as it goes).
const ROWS: usize = 32;

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
    /// Classifies every texel of `normals` (in parallel; counts are integers, so the same at any
    /// thread count).
    pub fn from_normals(normals: &'a NormalMap) -> Slopes<'a> {
        let texels = normals.as_slice();
        let mut valid = vec![false; texels.len()];
        let counts = valid
            .par_chunks_mut(CHUNK)
            .zip(texels.par_chunks(CHUNK))
            .map(|(ok, n)| {
                let mut c = TexelCounts::default();
                for (ok, &n) in ok.iter_mut().zip(n) {
                    match classify(n) {
                        Kind::Valid { clamped } => {
                            *ok = true;
                            c.valid += 1;
                            c.clamped += clamped as usize;
                        }
                        Kind::Zero => c.zero += 1,
                        Kind::NonFinite => c.non_finite += 1,
                        Kind::BackFacing => c.back_facing += 1,
                    }
                }
                c
            })
            .reduce(TexelCounts::default, |a, b| TexelCounts {
                valid: a.valid + b.valid,
                zero: a.zero + b.zero,
                non_finite: a.non_finite + b.non_finite,
                back_facing: a.back_facing + b.back_facing,
                clamped: a.clamped + b.clamped,
            });
        let mut slopes = Slopes { normals, valid, counts, mean: (0.0, 0.0) };
        // Only a masked solve's hole fill asks for the mean slope.
        if counts.invalid() > 0 {
            slopes.mean = slopes.mean_slope();
        }
        slopes
    }

    /// The mean slope over the valid texels, summed in f64 per row and then in row order.
    fn mean_slope(&self) -> (f32, f32) {
        let w = self.width();
        let rows: Vec<(f64, f64)> = (0..self.height())
            .into_par_iter()
            .map(|y| {
                (y * w..(y + 1) * w).fold((0.0, 0.0), |(sx, sy), i| {
                    let (x, y) = self.at(i);
                    (sx + f64::from(x), sy + f64::from(y))
                })
            })
            .collect();
        let (sx, sy) = rows.iter().fold((0.0, 0.0), |a, r| (a.0 + r.0, a.1 + r.1));
        let n = self.counts.valid.max(1) as f64;
        ((sx / n) as f32, (sy / n) as f32)
    }

    /// Row `y`'s slopes, `(0, 0)` at invalid texels.
    fn row(&self, y: usize, out: &mut Vec<(f32, f32)>) {
        let w = self.width();
        out.clear();
        out.extend((y * w..(y + 1) * w).map(|i| self.at(i)));
    }

    /// The weighted target step of the edge from texel `a` (slope `sa`) to `b` (slope `sb`),
    /// along x or along rows: an edge with an invalid end, under `masked`, asks for
    /// the mean slope at [`HOLE_WEIGHT`]; otherwise every edge has weight 1 and invalid texels
    /// count as flat.
    #[inline]
    fn weighted_step(&self, a: usize, b: usize, sa: f32, sb: f32, horizontal: bool, masked: bool) -> f32 {
        if masked && !(self.valid[a] && self.valid[b]) {
            HOLE_WEIGHT * if horizontal { self.mean.0 } else { self.mean.1 }
        } else {
            0.5 * (sa + sb)
        }
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

    /// The right-hand side `D^T W g` of the normal equations: per texel, the weighted steps of
    /// the edges arriving minus those leaving. With `wraps`, edges cross the borders. Rows in
    /// parallel, each from its own and its neighbours' slopes.
    pub fn rhs(&self, wraps: bool, masked: bool) -> Vec<f32> {
        let (w, h) = (self.width(), self.height());
        let mut b = vec![0f32; w * h];
        b.par_chunks_mut(w * ROWS).enumerate().for_each(|(chunk, rows)| {
            let first = chunk * ROWS;
            let (mut up, mut cur, mut down) = (Vec::new(), Vec::new(), Vec::new());
            let above = |y: usize| {
                if y > 0 {
                    Some(y - 1)
                } else if wraps && h > 1 {
                    Some(h - 1)
                } else {
                    None
                }
            };
            let below = |y: usize| {
                if y + 1 < h {
                    Some(y + 1)
                } else if wraps && h > 1 {
                    Some(0)
                } else {
                    None
                }
            };
            above(first).inspect(|&a| self.row(a, &mut up));
            self.row(first, &mut cur);
            for (k, row) in rows.chunks_exact_mut(w).enumerate() {
                let y = first + k;
                below(y).inspect(|&d| self.row(d, &mut down));
                self.rhs_row(y, row, (above(y), &up), &cur, (below(y), &down), wraps, masked);
                std::mem::swap(&mut up, &mut cur);
                std::mem::swap(&mut cur, &mut down);
            }
        });
        b
    }

    /// One row of [`Self::rhs`], from the slopes of the row (`cur`) and its neighbours.
    #[allow(clippy::too_many_arguments)] // the row's three slope rows and the edge rules, passed once
    fn rhs_row(
        &self,
        y: usize,
        row: &mut [f32],
        (above, up): (Option<usize>, &[(f32, f32)]),
        cur: &[(f32, f32)],
        (below, down): (Option<usize>, &[(f32, f32)]),
        wraps: bool,
        masked: bool,
    ) {
        let w = row.len();
        for (x, out) in row.iter_mut().enumerate() {
            let i = y * w + x;
            let mut sum = 0.0;
            let left = if x > 0 {
                Some(x - 1)
            } else if wraps && w > 1 {
                Some(w - 1)
            } else {
                None
            };
            let right = if x + 1 < w {
                Some(x + 1)
            } else if wraps && w > 1 {
                Some(0)
            } else {
                None
            };
            if let Some(l) = left {
                sum += self.weighted_step(y * w + l, i, cur[l].0, cur[x].0, true, masked);
            }
            if let Some(r) = right {
                sum -= self.weighted_step(i, y * w + r, cur[x].0, cur[r].0, true, masked);
            }
            if let Some(a) = above {
                sum += self.weighted_step(a * w + x, i, up[x].1, cur[x].1, false, masked);
            }
            if let Some(d) = below {
                sum -= self.weighted_step(i, d * w + x, cur[x].1, down[x].1, false, masked);
            }
            *out = sum;
        }
    }

    /// The RMS residual `(h_b - h_a) - step` over the edges whose two texels are valid, and the
    /// same against the RMS step (0 for an integrable map); `h` in texel units. Summed per block
    /// of rows in f64, then in block order.
    pub fn residual(&self, h: &[f32], wraps: bool) -> (f64, f64) {
        let (w, hh) = (self.width(), self.height());
        let chunks = hh.div_ceil(ROWS);
        let rows: Vec<(f64, f64, usize)> = (0..chunks)
            .into_par_iter()
            .map(|chunk| {
                let (mut cur, mut down) = (Vec::new(), Vec::new());
                let (mut res, mut sq, mut n) = (0f64, 0f64, 0usize);
                let first = chunk * ROWS;
                self.row(first, &mut cur);
                for y in first..(first + ROWS).min(hh) {
                    let below = if y + 1 < hh {
                        Some(y + 1)
                    } else if wraps && hh > 1 {
                        Some(0)
                    } else {
                        None
                    };
                    below.inspect(|&d| self.row(d, &mut down));
                    let mut add = |a: usize, b: usize, step: f32| {
                        if self.valid[a] && self.valid[b] {
                            let r = f64::from(h[b] - h[a] - step);
                            res += r * r;
                            sq += f64::from(step) * f64::from(step);
                            n += 1;
                        }
                    };
                    for x in 0..w {
                        let i = y * w + x;
                        let right = if x + 1 < w {
                            Some(x + 1)
                        } else if wraps && w > 1 {
                            Some(0)
                        } else {
                            None
                        };
                        if let Some(r) = right {
                            add(i, y * w + r, 0.5 * (cur[x].0 + cur[r].0));
                        }
                        if let Some(d) = below {
                            add(i, d * w + x, 0.5 * (cur[x].1 + down[x].1));
                        }
                    }
                    std::mem::swap(&mut cur, &mut down);
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
