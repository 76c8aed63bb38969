//! The column half of the Neumann solve after a DCT along rows (Hockney's method): for each
//! horizontal frequency `k` the rows' spectra form a column `r` with `(T + mu_k) h = r`, `T` the
//! 1-D Neumann Laplacian (tridiagonal: `1, 2, ..., 2, 1` on the diagonal, `-1` beside it). One
//! forward and one backward sweep (the Thomas algorithm) solve it, a few hundred columns at a time
//! (each row visit reads a few contiguous cache lines, and the arithmetic runs across the columns
//! in SIMD lanes), in f64 arithmetic with the intermediate `d` kept in place in f32. This replaces a DCT along each column and the two transposes that the
//! column DCTs need.
//!
//! The elimination's pivots `beta_y` depend only on `mu_k` and `y`, and converge within a few rows
//! for all but the lowest frequencies (`|gamma_y - gamma_inf|` shrinks by about `1 - 4 sqrt(mu)`
//! a row), so their inverses `gamma_y = 1 / beta_y` are tabulated once per grid until they reach
//! their fixed point in f64: about `3 w ln w` values in all, not `w h`.
//!
//! The forward sweep also gives `r . h = sum_y gamma_y d_y^2` (`T + mu = L D L^T` with
//! `D = diag(beta)`, and the forward sweep computes `d = L^-1 r`), which the integration's
//! residual needs; no copy of `r` is kept.
//!
//! `k = 0` is singular (the constant mode): its column is solved exactly by two running sums in
//! f64 after its mean is removed, and its mean height set to zero.

use rayon::prelude::*;

/// Columns whose pivots are tabulated together (sixteen f32: one cache line of a row).
const STRIP: usize = 16;

/// One strip's `gamma_y` per column: tabulated rows, then the fixed point, and the last row's own.
struct StripGammas {
    rows: Vec<[f64; STRIP]>,
    steady: [f64; STRIP],
    last: [f64; STRIP],
}

impl StripGammas {
    #[inline]
    fn at(&self, y: usize, h: usize) -> &[f64; STRIP] {
        if y + 1 == h { &self.last } else { self.rows.get(y).unwrap_or(&self.steady) }
    }
}

/// The tabulated pivots of every column of a `w x h` grid, shareable across threads.
pub(crate) struct Columns {
    w: usize,
    h: usize,
    strips: Vec<StripGammas>,
}

/// `gamma_y` of the column with eigenvalue `mu > 0`: the rows until the fixed point (at most
/// `h - 1`), the fixed point, and the last row's.
fn gammas(mu: f64, h: usize) -> (Vec<f64>, f64, f64) {
    if h == 1 {
        return (Vec::new(), 0.0, 1.0 / mu);
    }
    let mut rows = vec![1.0 / (1.0 + mu)];
    let mut g = rows[0];
    while rows.len() < h - 1 {
        let next = 1.0 / (2.0 + mu - g);
        if (next - g).abs() <= f64::EPSILON * next {
            g = next;
            break;
        }
        rows.push(next);
        g = next;
    }
    let before_last = rows.get(h - 2).copied().unwrap_or(g);
    (rows, g, 1.0 / (1.0 + mu - before_last))
}

impl Columns {
    /// Tabulates the pivots for the horizontal eigenvalues `mu_x` (one per column, `mu_x[0]`
    /// the constant mode's 0) and `h` rows.
    pub(crate) fn new(mu_x: &[f64], h: usize) -> Columns {
        let w = mu_x.len();
        let strips = (0..w.div_ceil(STRIP))
            .map(|s| {
                let columns: Vec<(Vec<f64>, f64, f64)> = (s * STRIP..w.min((s + 1) * STRIP))
                    .map(|k| if k == 0 { (Vec::new(), 0.0, 0.0) } else { gammas(mu_x[k], h) })
                    .collect();
                let len = columns.iter().map(|c| c.0.len()).max().unwrap_or(0);
                let mut strip = StripGammas { rows: vec![[0.0; STRIP]; len], steady: [0.0; STRIP], last: [0.0; STRIP] };
                for (c, (rows, steady, last)) in columns.iter().enumerate() {
                    for (y, row) in strip.rows.iter_mut().enumerate() {
                        row[c] = rows.get(y).copied().unwrap_or(*steady);
                    }
                    (strip.steady[c], strip.last[c]) = (*steady, *last);
                }
                strip
            })
            .collect();
        Columns { w, h, strips }
    }

    /// Solves every column of `b` (the rows' DCT-II spectra, row-major) in place and multiplies
    /// the result by `scale`; returns `sum_y (r_0 h_0 / 2 + sum_{k>0} r_k h_k)` of the unscaled
    /// solution `h`.
    pub(crate) fn solve(&self, b: &mut [f32], scale: f64) -> f64 {
        let (w, h) = (self.w, self.h);
        assert_eq!(b.len(), w * h, "column solve: grid size");
        // One group of columns per thread, as wide as can be: the sweeps then stream along rows.
        // The groups change only who solves which column, not its bits.
        let group = w.div_ceil(rayon::current_num_threads()).next_multiple_of(STRIP);
        let mut groups: Vec<Vec<&mut [f32]>> = (0..w.div_ceil(group)).map(|_| Vec::with_capacity(h)).collect();
        for row in b.chunks_exact_mut(w) {
            for (rows, part) in groups.iter_mut().zip(row.chunks_mut(group)) {
                rows.push(part);
            }
        }
        let energies: Vec<Vec<f64>> = groups
            .into_par_iter()
            .enumerate()
            .map(|(g, mut rows)| {
                // Column 0 is solved from its right-hand side before the sweep writes zeros over it.
                let constant = (g == 0).then(|| constant_column(&rows, scale));
                let mut energies = self.sweep(&mut rows, g * group / STRIP, scale);
                if let Some((heights, r_dot_h)) = constant {
                    rows.iter_mut().zip(heights).for_each(|(row, v)| row[0] = v);
                    energies[0] = 0.5 * r_dot_h;
                }
                energies
            })
            .collect();
        // Column by column, in order, whatever the groups.
        energies.iter().flatten().sum()
    }

    /// Solves the columns of `rows` (row segments starting at strip `first_strip`): the forward
    /// sweep leaves `d` in place (f32; the arithmetic is f64), the backward sweep the solution
    /// times `scale`. Returns each column's `sum gamma_y d_y^2`.
    fn sweep(&self, rows: &mut [&mut [f32]], first_strip: usize, scale: f64) -> Vec<f64> {
        let h = rows.len();
        let width = rows[0].len();
        let strips = &self.strips[first_strip..];
        let (mut carry, mut energy) = (vec![0f64; width], vec![0f64; width]);
        for (y, row) in rows.iter_mut().enumerate() {
            for (s, ((v, c), e)) in
                row.chunks_mut(STRIP).zip(carry.chunks_mut(STRIP)).zip(energy.chunks_mut(STRIP)).enumerate()
            {
                forward(v, strips[s].at(y, h), c, e);
            }
        }
        carry.iter_mut().for_each(|c| *c = 0.0);
        for (y, row) in rows.iter_mut().enumerate().rev() {
            for (s, (v, c)) in row.chunks_mut(STRIP).zip(carry.chunks_mut(STRIP)).enumerate() {
                backward(v, strips[s].at(y, h), c, scale);
            }
        }
        energy
    }
}

/// One row of a strip in the forward sweep: `d_y = r_y + gamma_{y-1} d_{y-1}` (the carry) written
/// over `r_y`, and `gamma_y d_y^2` added to the energy.
#[inline]
fn forward(v: &mut [f32], gamma: &[f64; STRIP], carry: &mut [f64], energy: &mut [f64]) {
    for (((v, g), c), e) in v.iter_mut().zip(gamma).zip(carry.iter_mut()).zip(energy.iter_mut()) {
        let d = f64::from(*v) + *c;
        *v = d as f32;
        *e += g * d * d;
        *c = g * d;
    }
}

/// One row of a strip in the backward sweep: `h_y = gamma_y (d_y + h_{y+1})` (the carry), written
/// over `d_y` times `scale`.
#[inline]
fn backward(v: &mut [f32], gamma: &[f64; STRIP], carry: &mut [f64], scale: f64) {
    for ((v, g), c) in v.iter_mut().zip(gamma).zip(carry.iter_mut()) {
        *c = g * (f64::from(*v) + *c);
        *v = (*c * scale) as f32;
    }
}

/// Solves the constant mode's column (column 0 of `rows`) exactly: its mean removed (no height
/// can answer it), `h_y - h_{y+1}` is the running sum of the right-hand side, and the heights'
/// mean is zero. Returns the heights times `scale` and `r . h` of the unscaled solution.
fn constant_column(rows: &[&mut [f32]], scale: f64) -> (Vec<f32>, f64) {
    let n = rows.len() as f64;
    let mean = rows.iter().map(|row| f64::from(row[0])).sum::<f64>() / n;
    let (mut step, mut height) = (0.0, 0.0);
    let mut heights = Vec::with_capacity(rows.len());
    for row in rows {
        heights.push(height);
        step += f64::from(row[0]) - mean;
        height -= step;
    }
    let centre = heights.iter().sum::<f64>() / n;
    let energy = rows.iter().zip(&heights).map(|(row, h)| (f64::from(row[0]) - mean) * (h - centre)).sum();
    (heights.iter().map(|h| ((h - centre) * scale) as f32).collect(), energy)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every column's solution against the dense system solved by Gaussian elimination, and the
    /// energy against `r . h`.
    #[test]
    fn columns_solve_the_tridiagonal_systems() {
        for (w, h) in [(5, 1), (3, 2), (37, 23), (40, 300)] {
            let mu: Vec<f64> = (0..w).map(|k| 2.0 - 2.0 * (std::f64::consts::PI * k as f64 / w as f64).cos()).collect();
            let r: Vec<f32> = (0..w * h).map(|i| ((i * 7919) % 101) as f32 / 50.0 - 1.0).collect();
            let mut b = r.clone();
            let energy = Columns::new(&mu, h).solve(&mut b, 2.0);
            let mut expected = 0.0;
            for k in 0..w {
                let column: Vec<f64> = (0..h).map(|y| f64::from(r[y * w + k])).collect();
                let solved = dense_solve(&column, mu[k]);
                for y in 0..h {
                    let got = f64::from(b[y * w + k]) / 2.0;
                    assert!(
                        (got - solved[y]).abs() < 1e-4 * (1.0 + solved[y].abs()),
                        "{w}x{h} k {k} y {y}: {got} {}",
                        solved[y]
                    );
                    expected += column[y] * solved[y] * if k == 0 { 0.5 } else { 1.0 };
                }
            }
            assert!((energy - expected).abs() < 1e-6 * (1.0 + expected.abs()), "{w}x{h}: {energy} against {expected}");
        }
    }

    /// `(T + mu) h = r` by Gaussian elimination with partial pivoting on the dense matrix; for
    /// `mu = 0` the mean of `r` is removed, `h_0 = 0` imposed in place of the last equation, and
    /// the mean of `h` removed.
    fn dense_solve(r: &[f64], mu: f64) -> Vec<f64> {
        let n = r.len();
        let mean = if mu == 0.0 { r.iter().sum::<f64>() / n as f64 } else { 0.0 };
        let mut a = vec![vec![0.0; n + 1]; n];
        for y in 0..n {
            a[y][n] = r[y] - mean;
            a[y][y] = mu + f64::from(u8::from(y > 0)) + f64::from(u8::from(y + 1 < n));
            if y > 0 {
                a[y][y - 1] = -1.0;
            }
            if y + 1 < n {
                a[y][y + 1] = -1.0;
            }
        }
        if mu == 0.0 {
            a[n - 1] = vec![0.0; n + 1];
            a[n - 1][0] = 1.0;
        }
        for i in 0..n {
            let p = (i..n).max_by(|&x, &y| a[x][i].abs().total_cmp(&a[y][i].abs())).unwrap();
            a.swap(i, p);
            for j in i + 1..n {
                let f = a[j][i] / a[i][i];
                for c in i..=n {
                    a[j][c] -= f * a[i][c];
                }
            }
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            x[i] = (a[i][n] - (i + 1..n).map(|c| a[i][c] * x[c]).sum::<f64>()) / a[i][i];
        }
        if mu == 0.0 {
            let m = x.iter().sum::<f64>() / n as f64;
            x.iter_mut().for_each(|v| *v -= m);
        }
        x
    }
}
