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

impl std::ops::Add for TexelCounts {
    type Output = TexelCounts;

    fn add(self, o: TexelCounts) -> TexelCounts {
        TexelCounts {
            valid: self.valid + o.valid,
            zero: self.zero + o.zero,
            non_finite: self.non_finite + o.non_finite,
            back_facing: self.back_facing + o.back_facing,
            clamped: self.clamped + o.clamped,
        }
    }
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

/// `(dh/dcol, dh/drow)` of a usable normal, clamped; 0 for an unusable one (which may be NaN or
/// have `nz <= 0`: it is divided by 1 and the result dropped, without a branch).
#[inline]
fn slope_or_flat(n: Vec3, ok: bool) -> (f32, f32) {
    let inv = 1.0 / if ok { n.z } else { 1.0 };
    let (x, y) = ((-n.x * inv).clamp(-MAX_SLOPE, MAX_SLOPE), (n.y * inv).clamp(-MAX_SLOPE, MAX_SLOPE));
    if ok { (x, y) } else { (0.0, 0.0) }
}

/// The fused path's reading of a row: slopes (clamped) into `px` and `py`, and counts that are
/// exact when every normal is usable; an unusable one is counted in `non_finite` alone (the
/// caller then takes the general path, which classifies it). Branch-free, so it vectorises.
pub(crate) fn usable_row(normals: &[Vec3], px: &mut [f32], py: &mut [f32]) -> TexelCounts {
    let (mut unusable, mut clamped) = (0u32, 0u32);
    for ((n, px), py) in normals.iter().zip(px.iter_mut()).zip(py.iter_mut()) {
        let finite = n.x.abs() < f32::INFINITY && n.y.abs() < f32::INFINITY && n.z < f32::INFINITY;
        let ok = finite & (n.z > 0.0);
        unusable += u32::from(!ok);
        clamped += u32::from((n.x.abs() > MAX_SLOPE * n.z) | (n.y.abs() > MAX_SLOPE * n.z));
        let inv = 1.0 / n.z;
        *px = (-n.x * inv).clamp(-MAX_SLOPE, MAX_SLOPE);
        *py = (n.y * inv).clamp(-MAX_SLOPE, MAX_SLOPE);
    }
    let (unusable, clamped) = (unusable as usize, clamped as usize);
    TexelCounts {
        valid: normals.len() - unusable,
        non_finite: unusable,
        clamped: if unusable == 0 { clamped } else { 0 },
        ..Default::default()
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
            .reduce(TexelCounts::default, |a, b| a + b);
        let mut slopes = Slopes { normals, valid, counts, mean: (0.0, 0.0) };
        // Only a masked solve's hole fill asks for the mean slope.
        if counts.invalid() > 0 {
            slopes.mean = slopes.mean_slope();
        }
        slopes
    }

    /// The mean slope over the valid texels, summed in f64 per row and then in row order.
    fn mean_slope(&self) -> (f32, f32) {
        let rows: Vec<(f64, f64)> = (0..self.height())
            .into_par_iter()
            .map_init(Row::default, |row, y| {
                self.load(y, row);
                let sum = |s: &[f32]| s.iter().map(|&v| f64::from(v)).sum::<f64>();
                (sum(&row.px), sum(&row.py))
            })
            .collect();
        let (sx, sy) = rows.iter().fold((0.0, 0.0), |a, r| (a.0 + r.0, a.1 + r.1));
        let n = self.counts.valid.max(1) as f64;
        ((sx / n) as f32, (sy / n) as f32)
    }

    pub fn width(&self) -> usize {
        self.normals.width()
    }

    pub fn height(&self) -> usize {
        self.normals.height()
    }

    /// Row `y`'s slopes (0 at invalid texels) and validity, into `row`.
    fn load(&self, y: usize, row: &mut Row) {
        let w = self.width();
        let (normals, ok) = (&self.normals.as_slice()[y * w..][..w], &self.valid[y * w..][..w]);
        row.ok.clear();
        row.ok.extend_from_slice(ok);
        row.px.resize(w, 0.0);
        row.py.resize(w, 0.0);
        for (((n, &ok), px), py) in normals.iter().zip(ok).zip(&mut row.px).zip(&mut row.py) {
            (*px, *py) = slope_or_flat(*n, ok);
        }
    }

    /// The weighted target step of an edge whose ends have slopes `sa`, `sb` and validity `oa`,
    /// `ob`: under `masked`, an edge with an invalid end asks for the mean slope `mean` at
    /// [`HOLE_WEIGHT`]; otherwise every edge has weight 1 and invalid texels count as flat.
    #[inline]
    fn step(sa: f32, sb: f32, oa: bool, ob: bool, masked: bool, mean: f32) -> f32 {
        if masked && !(oa && ob) { HOLE_WEIGHT * mean } else { 0.5 * (sa + sb) }
    }

    /// `out[x]`: the step of the edge from texel `x` of `row` to `x + 1`; the last entry is the
    /// edge wrapping to the row's start under `wraps`, else 0.
    fn horizontal_steps(&self, row: &Row, wraps: bool, masked: bool, out: &mut Vec<f32>) {
        let (w, mean) = (row.px.len(), self.mean.0);
        out.clear();
        out.extend((1..w).map(|x| Self::step(row.px[x - 1], row.px[x], row.ok[x - 1], row.ok[x], masked, mean)));
        let wrap = wraps && w > 1;
        out.push(if wrap { Self::step(row.px[w - 1], row.px[0], row.ok[w - 1], row.ok[0], masked, mean) } else { 0.0 });
    }

    /// `out[x]`: the step of the edge from texel `x` of `up` down to texel `x` of `down`.
    fn vertical_steps(&self, up: &Row, down: &Row, masked: bool, out: &mut Vec<f32>) {
        let mean = self.mean.1;
        out.clear();
        out.extend((0..up.py.len()).map(|x| Self::step(up.py[x], down.py[x], up.ok[x], down.ok[x], masked, mean)));
    }

    /// The row below `y` (or the first row under `wraps`), if an edge goes there.
    fn below(&self, y: usize, wraps: bool) -> Option<usize> {
        let h = self.height();
        if y + 1 < h {
            Some(y + 1)
        } else if wraps && h > 1 {
            Some(0)
        } else {
            None
        }
    }

    /// The row above `y` (or the last row under `wraps`), if an edge comes from there.
    fn above(&self, y: usize, wraps: bool) -> Option<usize> {
        let h = self.height();
        if y > 0 {
            Some(y - 1)
        } else if wraps && h > 1 {
            Some(h - 1)
        } else {
            None
        }
    }

    /// The right-hand side `D^T W g` of the normal equations: per texel, the weighted steps of
    /// the edges arriving minus those leaving. With `wraps`, edges cross the borders. Blocks of
    /// rows in parallel, each carrying its rows' slopes and its last vertical steps down the block.
    pub fn rhs(&self, wraps: bool, masked: bool) -> Vec<f32> {
        let w = self.width();
        let mut b = vec![0f32; w * self.height()];
        b.par_chunks_mut(w * ROWS).enumerate().for_each(|(chunk, rows)| {
            let first = chunk * ROWS;
            let (mut cur, mut next) = (Row::default(), Row::default());
            let (mut hs, mut v_above, mut v_below) = (Vec::new(), Vec::new(), Vec::new());
            self.load(first, &mut cur);
            match self.above(first, wraps) {
                Some(a) => {
                    self.load(a, &mut next);
                    self.vertical_steps(&next, &cur, masked, &mut v_above);
                }
                None => v_above.resize(w, 0.0),
            }
            for (k, out) in rows.chunks_exact_mut(w).enumerate() {
                let y = first + k;
                match self.below(y, wraps) {
                    Some(d) => {
                        self.load(d, &mut next);
                        self.vertical_steps(&cur, &next, masked, &mut v_below);
                    }
                    None => {
                        v_below.clear();
                        v_below.resize(w, 0.0);
                    }
                }
                self.horizontal_steps(&cur, wraps, masked, &mut hs);
                let arriving_first = if wraps { hs[w - 1] } else { 0.0 };
                for (x, o) in out.iter_mut().enumerate() {
                    let arriving = if x > 0 { hs[x - 1] } else { arriving_first };
                    *o = (arriving - hs[x]) + (v_above[x] - v_below[x]);
                }
                std::mem::swap(&mut cur, &mut next);
                std::mem::swap(&mut v_above, &mut v_below);
            }
        });
        b
    }

    /// The RMS residual `(h_b - h_a) - step` over the edges whose two texels are valid, and the
    /// same against the RMS step (0 for an integrable map); `h` in units of `texel` texel widths.
    /// Summed per block of rows in f64, then in block order.
    pub fn residual(&self, h: &[f32], texel: f32, wraps: bool) -> (f64, f64) {
        let (w, hh) = (self.width(), self.height());
        let blocks: Vec<Residual> = (0..hh.div_ceil(ROWS))
            .into_par_iter()
            .map(|chunk| {
                let (mut cur, mut next) = (Row::default(), Row::default());
                let (mut steps, mut rises) = (Vec::new(), Vec::new());
                let mut sum = Residual::default();
                self.load(chunk * ROWS, &mut cur);
                for y in chunk * ROWS..((chunk + 1) * ROWS).min(hh) {
                    let row = &h[y * w..][..w];
                    self.horizontal_steps(&cur, wraps, false, &mut steps);
                    rises.clear();
                    rises.extend(row.windows(2).map(|p| (p[1] - p[0]) / texel));
                    rises.push((row[0] - row[w - 1]) / texel);
                    let edges = if wraps && w > 1 { w } else { w - 1 };
                    let right = |x: usize| if x + 1 < w { x + 1 } else { 0 };
                    sum.add_row(&rises[..edges], &steps[..edges], |x| cur.ok[x] && cur.ok[right(x)]);
                    if let Some(d) = self.below(y, wraps) {
                        self.load(d, &mut next);
                        self.vertical_steps(&cur, &next, false, &mut steps);
                        rises.clear();
                        rises.extend(h[d * w..][..w].iter().zip(row).map(|(b, a)| (b - a) / texel));
                        sum.add_row(&rises, &steps, |x| cur.ok[x] && next.ok[x]);
                        std::mem::swap(&mut cur, &mut next);
                    }
                }
                sum
            })
            .collect();
        let total = blocks.iter().fold(Residual::default(), |a, b| Residual {
            squares: a.squares + b.squares,
            steps: a.steps + b.steps,
            n: a.n + b.n,
        });
        total.rms()
    }
}

/// One row's slopes and validity (reused from row to row).
#[derive(Default)]
struct Row {
    px: Vec<f32>,
    py: Vec<f32>,
    ok: Vec<bool>,
}

/// Sums of squared residuals and steps over some edges.
#[derive(Clone, Copy, Default)]
struct Residual {
    squares: f64,
    steps: f64,
    n: usize,
}

impl Residual {
    /// Adds the edges `x` of one row for which `counts(x)`: rise `rises[x]`, step `steps[x]`.
    /// Eight running sums, added in a fixed order, so the compiler can vectorise them and the
    /// result is the same bits at any thread count.
    fn add_row(&mut self, rises: &[f32], steps: &[f32], counts: impl Fn(usize) -> bool) {
        const LANES: usize = 8;
        let (mut sq, mut st) = ([0f64; LANES], [0f64; LANES]);
        let mut n = 0;
        for (x, (&rise, &step)) in rises.iter().zip(steps).enumerate() {
            let keep = counts(x);
            let (r, s) = if keep { (f64::from(rise - step), f64::from(step)) } else { (0.0, 0.0) };
            sq[x % LANES] += r * r;
            st[x % LANES] += s * s;
            n += usize::from(keep);
        }
        self.squares += sq.iter().sum::<f64>();
        self.steps += st.iter().sum::<f64>();
        self.n += n;
    }

    /// The RMS residual, and the same against the RMS step.
    fn rms(self) -> (f64, f64) {
        if self.n == 0 {
            return (0.0, 0.0);
        }
        let rms = (self.squares / self.n as f64).sqrt();
        let step = (self.steps / self.n as f64).sqrt();
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
