//! Fine noise: a sum of random plane waves `A sqrt(2/N) sum cos(k_i . p + phi_i)` (root-mean-square
//! height `A`), whose gradient is the exact sum of the waves' derivatives.
//!
//! Rasterising uses `cos(a + b) = cos a cos b - sin a sin b` with `a = k_x x + phi` tabulated per
//! column and `b = k_y y` per row, so a texel costs a few multiplies per wave instead of a sine.
//! Tables are padded to a multiple of [`LANES`] waves with zero entries (which add nothing) and
//! summed in that many independent lanes, which the compiler turns into vector code; the lane
//! order is fixed, so results do not depend on the machine's thread count.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::HeightSample;
use crate::params::NoiseParams;

/// Accumulator lanes of the tabulated sum.
const LANES: usize = 4;

pub(crate) struct Waves {
    /// Wave vectors, padded with zeros to a multiple of `LANES`.
    kx: Vec<f64>,
    ky: Vec<f64>,
    phase: Vec<f64>,
    /// Number of real (unpadded) waves.
    count: usize,
    amplitude: f64,
}

impl Waves {
    /// Draws the waves (none when the amplitude is 0).
    pub(crate) fn new(p: &NoiseParams, rng: &mut ChaCha8Rng) -> Self {
        let count = if p.amplitude_mm == 0.0 { 0 } else { p.waves };
        let padded = count.div_ceil(LANES) * LANES;
        let (mut kx, mut ky, mut phase) = (vec![0.0; padded], vec![0.0; padded], vec![0.0; padded]);
        for i in 0..count {
            let wavelength = p.scale_mm * 2f64.powf(rng.random_range(-1.0..1.0));
            let (sin, cos) = rng.random_range(0.0..std::f64::consts::TAU).sin_cos();
            let k = std::f64::consts::TAU / wavelength;
            (kx[i], ky[i]) = (k * cos, k * sin);
            phase[i] = rng.random_range(0.0..std::f64::consts::TAU);
        }
        let amplitude = if count == 0 { 0.0 } else { p.amplitude_mm * (2.0 / count as f64).sqrt() };
        Waves { kx, ky, phase, count, amplitude }
    }

    /// Length of a column or row table: sines then cosines of every padded wave.
    pub(crate) fn table_len(&self) -> usize {
        2 * self.kx.len()
    }

    /// Height and gradient at `(x, y)` (mm).
    pub(crate) fn eval(&self, x: f64, y: f64) -> HeightSample {
        let mut s = HeightSample::default();
        for i in 0..self.count {
            let (sin, cos) = (self.kx[i] * x + self.ky[i] * y + self.phase[i]).sin_cos();
            s.height += cos;
            s.gradient.x -= self.kx[i] * sin;
            s.gradient.y -= self.ky[i] * sin;
        }
        s.scaled(self.amplitude)
    }

    /// Appends the column table at `x`: sines, then cosines, of `k_x x + phi` (zeros for padding).
    pub(crate) fn column_table(&self, x: f64, out: &mut Vec<f64>) {
        let (sin, cos): (Vec<f64>, Vec<f64>) = self.angles(|i| self.kx[i] * x + self.phase[i]).unzip();
        out.extend(sin);
        out.extend(cos);
    }

    /// The row table at `y`: sines, then cosines, of `k_y y` (zeros for padding).
    pub(crate) fn row_table(&self, y: f64) -> Vec<f64> {
        let (sin, cos): (Vec<f64>, Vec<f64>) = self.angles(|i| self.ky[i] * y).unzip();
        [sin, cos].concat()
    }

    fn angles(&self, angle: impl Fn(usize) -> f64) -> impl Iterator<Item = (f64, f64)> {
        (0..self.kx.len()).map(move |i| if i < self.count { angle(i).sin_cos() } else { (0.0, 0.0) })
    }

    /// The same as [`Waves::eval`] from tabulated column and row parts.
    #[inline]
    pub(crate) fn eval_tables(&self, column: &[f64], row: &[f64]) -> HeightSample {
        let n = self.kx.len();
        let (sa, ca) = column.split_at(n);
        let (sb, cb) = row.split_at(n);
        let (mut h, mut gx, mut gy) = ([0.0; LANES], [0.0; LANES], [0.0; LANES]);
        let parts = lanes(sa).zip(lanes(ca)).zip(lanes(sb).zip(lanes(cb))).zip(lanes(&self.kx).zip(lanes(&self.ky)));
        for (((sa, ca), (sb, cb)), (kx, ky)) in parts {
            for l in 0..LANES {
                let cos = ca[l] * cb[l] - sa[l] * sb[l];
                let sin = sa[l] * cb[l] + ca[l] * sb[l];
                h[l] += cos;
                gx[l] -= kx[l] * sin;
                gy[l] -= ky[l] * sin;
            }
        }
        let sum = |v: [f64; LANES]| (v[0] + v[1]) + (v[2] + v[3]);
        let s = HeightSample { height: sum(h), gradient: glam::DVec2::new(sum(gx), sum(gy)) };
        s.scaled(self.amplitude)
    }
}

/// `v` as consecutive fixed-size lanes (the length is a multiple of `LANES`).
fn lanes(v: &[f64]) -> impl Iterator<Item = [f64; LANES]> + '_ {
    v.chunks_exact(LANES).map(|c| c.try_into().expect("chunks are LANES long"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec2;
    use rand::SeedableRng;

    #[test]
    fn tables_agree_with_direct_evaluation_and_rms_is_amplitude() {
        let p = NoiseParams { amplitude_mm: 0.01, scale_mm: 0.2, waves: 64 };
        let w = Waves::new(&p, &mut ChaCha8Rng::seed_from_u64(3));
        let mut sum_sq = 0.0;
        let n = 200;
        for i in 0..n {
            let pt = DVec2::new(i as f64 * 0.173 - 7.0, (i * i % 97) as f64 * 0.31 - 11.0);
            let mut col = Vec::new();
            w.column_table(pt.x, &mut col);
            let a = w.eval(pt.x, pt.y);
            let b = w.eval_tables(&col, &w.row_table(pt.y));
            assert!((a.height - b.height).abs() < 1e-12);
            assert!((a.gradient - b.gradient).length() < 1e-10);
            sum_sq += a.height * a.height;
        }
        let rms = (sum_sq / n as f64).sqrt();
        assert!((rms / 0.01 - 1.0).abs() < 0.25, "rms {rms}");
    }
}
