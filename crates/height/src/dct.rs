//! [`Dct`]: the DCT-II and DCT-III of one length through a real FFT of the same length (Makhoul,
//! 1980), so a transform costs one complex FFT of half its length. realfft does the real FFT on
//! rustfft's SIMD kernels; rustdct's own planner would take a complex FFT of the full length (or a
//! scalar split radix for powers of two).
//!
//! Conventions are rustdct's (and FFTW's REDFT10/REDFT01 halved): unnormalised DCT-II
//! `X_k = sum_n x_n cos(pi k (2n + 1) / 2N)` and DCT-III `y_n = X_0 / 2 + sum_{k>0} X_k cos(...)`,
//! so a DCT-III after a DCT-II multiplies by `N / 2`.
//!
//! With `v` the even samples of `x` in order followed by its odd samples reversed, and `V` the DFT
//! of `v`, `W_k = e^{-i pi k / 2N} V_k = X_k - i X_{N-k}`: one half-spectrum of `V` gives every
//! `X_k`. The DCT-III runs the same steps backwards.

use std::f64::consts::PI;
use std::sync::Arc;

use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::num_complex::Complex32;

/// A planned DCT-II / DCT-III pair of one length, shareable across threads.
#[derive(Clone)]
pub struct Dct {
    len: usize,
    forward: Arc<dyn RealToComplex<f32>>,
    inverse: Arc<dyn ComplexToReal<f32>>,
    /// `e^{-i pi k / 2N}` for `k` in `0..=N/2`.
    twiddles: Vec<Complex32>,
}

/// Per-thread working memory of a [`Dct`].
pub struct DctScratch {
    real: Vec<f32>,
    spectrum: Vec<Complex32>,
    fft: Vec<Complex32>,
}

impl Dct {
    /// Plans the transforms of length `len` (at least 1).
    pub fn new(len: usize) -> Dct {
        assert!(len > 0, "a DCT of length 0");
        let mut planner = RealFftPlanner::<f32>::new();
        let twiddles = (0..=len / 2)
            .map(|k| {
                let angle = -PI * k as f64 / (2 * len) as f64;
                Complex32::new(angle.cos() as f32, angle.sin() as f32)
            })
            .collect();
        Dct { len, forward: planner.plan_fft_forward(len), inverse: planner.plan_fft_inverse(len), twiddles }
    }

    /// Working memory for one thread.
    pub fn scratch(&self) -> DctScratch {
        let fft = self.forward.get_scratch_len().max(self.inverse.get_scratch_len());
        DctScratch {
            real: vec![0.0; self.len],
            spectrum: vec![Complex32::default(); self.len / 2 + 1],
            fft: vec![Complex32::default(); fft],
        }
    }

    /// The DCT-II of `x` (of this length), in place.
    pub fn dct2(&self, x: &mut [f32], s: &mut DctScratch) {
        let n = self.len;
        assert_eq!(x.len(), n, "DCT-II: length");
        let (evens, odds) = s.real.split_at_mut(n.div_ceil(2));
        for ((e, o), pair) in evens.iter_mut().zip(odds.iter_mut().rev()).zip(x.chunks_exact(2)) {
            (*e, *o) = (pair[0], pair[1]);
        }
        if n % 2 == 1 {
            evens[n / 2] = x[n - 1];
        }
        self.forward
            .process_with_scratch(&mut s.real, &mut s.spectrum, &mut s.fft)
            .expect("buffers sized by DctScratch");
        // X_k for k up to N/2 from the real parts, X_{N-k} for the rest from the imaginary ones.
        let (low, high) = x.split_at_mut(n / 2 + 1);
        for ((x, v), t) in low.iter_mut().zip(&s.spectrum).zip(&self.twiddles) {
            *x = v.re * t.re - v.im * t.im;
        }
        for ((x, v), t) in high.iter_mut().rev().zip(&s.spectrum[1..]).zip(&self.twiddles[1..]) {
            *x = -(v.re * t.im + v.im * t.re);
        }
    }

    /// The DCT-III of `x` (of this length), in place.
    pub fn dct3(&self, x: &mut [f32], s: &mut DctScratch) {
        let n = self.len;
        assert_eq!(x.len(), n, "DCT-III: length");
        // V_k = conj(t_k) (X_k - i X_{N-k}) with X_N = 0; halved, the DCT-III's factor.
        // X_{N-k} beside X_k, with X_N = 0.
        let mirrored = std::iter::once(0.0).chain(x.iter().rev().copied());
        for (((v, t), &re), im) in s.spectrum.iter_mut().zip(&self.twiddles).zip(x.iter()).zip(mirrored) {
            // 0.5 (re - i im) conj(t)
            *v = Complex32::new(0.5 * (re * t.re - im * t.im), -0.5 * (re * t.im + im * t.re));
        }
        // The DC term, and Nyquist's for an even length, are real in exact arithmetic.
        s.spectrum[0].im = 0.0;
        if n.is_multiple_of(2) {
            s.spectrum[n / 2].im = 0.0;
        }
        self.inverse
            .process_with_scratch(&mut s.spectrum, &mut s.real, &mut s.fft)
            .expect("buffers sized by DctScratch, a real DC and Nyquist term");
        let (evens, odds) = s.real.split_at(n.div_ceil(2));
        for ((pair, &e), &o) in x.chunks_exact_mut(2).zip(evens).zip(odds.iter().rev()) {
            (pair[0], pair[1]) = (e, o);
        }
        if n % 2 == 1 {
            x[n - 1] = evens[n / 2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dct2_by_definition(x: &[f32]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|k| {
                x.iter()
                    .enumerate()
                    .map(|(i, &v)| f64::from(v) * (PI * k as f64 * (2 * i + 1) as f64 / (2 * n) as f64).cos())
                    .sum()
            })
            .collect()
    }

    fn dct3_by_definition(x: &[f32]) -> Vec<f64> {
        let n = x.len();
        (0..n)
            .map(|i| {
                f64::from(x[0]) / 2.0
                    + (1..n)
                        .map(|k| f64::from(x[k]) * (PI * k as f64 * (2 * i + 1) as f64 / (2 * n) as f64).cos())
                        .sum::<f64>()
            })
            .collect()
    }

    fn signal(n: usize, seed: usize) -> Vec<f32> {
        (0..n).map(|i| (((i + seed) * 7919 + 13) % 29) as f32 / 7.0 - 2.0).collect()
    }

    /// Both transforms against their definitions (summed in f64), at even, odd, prime,
    /// power-of-two and length-1 sizes, and the round trip's factor `N / 2`.
    #[test]
    fn transforms_follow_their_definitions() {
        for n in [1, 2, 3, 4, 5, 8, 12, 17, 31, 64, 100, 128] {
            let dct = Dct::new(n);
            let mut s = dct.scratch();
            let x = signal(n, n);
            let mut y = x.clone();
            dct.dct2(&mut y, &mut s);
            let tol = 1e-4 * n as f64;
            for (k, (got, want)) in y.iter().zip(dct2_by_definition(&x)).enumerate() {
                assert!((f64::from(*got) - want).abs() < tol, "DCT-II n {n} k {k}: {got} against {want}");
            }
            let mut z = x.clone();
            dct.dct3(&mut z, &mut s);
            for (i, (got, want)) in z.iter().zip(dct3_by_definition(&x)).enumerate() {
                assert!((f64::from(*got) - want).abs() < tol, "DCT-III n {n} i {i}: {got} against {want}");
            }
            dct.dct3(&mut y, &mut s);
            for (a, b) in x.iter().zip(&y) {
                assert!((a * n as f32 / 2.0 - b).abs() < 1e-3 * n as f32, "round trip n {n}");
            }
        }
    }
}
