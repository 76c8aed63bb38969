//! Separable 2-D transforms over a row-major grid: a pass of 1-D transforms along every row, in
//! parallel batches of rows, and a blocked parallel transpose between passes, so both directions
//! run along contiguous memory. The 1-D transforms are rustdct's and rustfft's.

use std::sync::Arc;

use rayon::prelude::*;
use rustdct::TransformType2And3;
use rustfft::Fft;
use rustfft::num_complex::Complex32;

/// Rows handed to one rayon task (enough to amortise the task, few enough to balance two cores).
const ROWS_PER_TASK: usize = 16;
/// Side of the square tiles of the transpose (a tile of f32 or complex stays in L1).
const TILE: usize = 32;

/// A DCT-II/III of `len`: through rustfft's (SIMD) FFT for every length past the smallest, since
/// rustdct's planner takes a scalar split-radix recursion for powers of two, 2.5x slower than
/// SciPy on a 4096x4096 solve where this is faster.
pub fn plan_dct(len: usize) -> Arc<dyn TransformType2And3<f32>> {
    if len < 16 {
        return rustdct::DctPlanner::new().plan_dct2(len);
    }
    let fft = rustfft::FftPlanner::new().plan_fft_forward(len);
    Arc::new(rustdct::algorithm::Type2And3ConvertToFft::new(fft))
}

/// DCT-II (`inverse == false`) or DCT-III of every row of `data` (rows of `len`), unnormalised:
/// DCT-III after DCT-II multiplies by `len / 2`.
pub fn dct_rows(data: &mut [f32], len: usize, dct: &Arc<dyn TransformType2And3<f32>>, inverse: bool) {
    let scratch = dct.get_scratch_len();
    data.par_chunks_mut(len * ROWS_PER_TASK).for_each_init(
        || vec![0f32; scratch],
        |scratch, rows| {
            for row in rows.chunks_exact_mut(len) {
                if inverse {
                    dct.process_dct3_with_scratch(row, scratch);
                } else {
                    dct.process_dct2_with_scratch(row, scratch);
                }
            }
        },
    );
}

/// The FFT `fft` (forward or inverse, unnormalised) of every row of `data` (rows of its length).
pub fn fft_rows(data: &mut [Complex32], fft: &Arc<dyn Fft<f32>>) {
    let len = fft.len();
    let scratch = fft.get_inplace_scratch_len();
    data.par_chunks_mut(len * ROWS_PER_TASK)
        .for_each_init(|| vec![Complex32::default(); scratch], |scratch, rows| fft.process_with_scratch(rows, scratch));
}

/// Writes the transpose of `src` (`h` rows of `w`) into `dst` (`w` rows of `h`), in parallel
/// bands of destination rows, tile by tile.
pub fn transpose<T: Copy + Send + Sync>(src: &[T], w: usize, h: usize, dst: &mut [T]) {
    assert_eq!(src.len(), w * h, "transpose: source size");
    assert_eq!(dst.len(), w * h, "transpose: destination size");
    if w == 0 || h == 0 {
        return;
    }
    dst.par_chunks_mut(h * TILE).enumerate().for_each(|(band, out)| {
        let x0 = band * TILE;
        let cols = out.len() / h;
        for y0 in (0..h).step_by(TILE) {
            for y in y0..(y0 + TILE).min(h) {
                let row = &src[y * w + x0..y * w + x0 + cols];
                for (dx, &v) in row.iter().enumerate() {
                    out[dx * h + y] = v;
                }
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use rustdct::DctPlanner;

    #[test]
    fn transpose_matches_index_swap() {
        for (w, h) in [(1, 1), (3, 70), (70, 3), (33, 65), (64, 64)] {
            let src: Vec<u32> = (0..(w * h) as u32).collect();
            let mut dst = vec![0; w * h];
            transpose(&src, w, h, &mut dst);
            for y in 0..h {
                for x in 0..w {
                    assert_eq!(dst[x * h + y], src[y * w + x], "{w}x{h} at ({x}, {y})");
                }
            }
        }
    }

    /// rustdct's DCT-II against the definition `X_k = sum x_n cos(pi k (2n + 1) / 2N)`, and the
    /// DCT-III round trip's factor `N / 2` that the Poisson solve relies on.
    #[test]
    fn dct_rows_follow_the_definition() {
        let len = 12;
        let x: Vec<f32> = (0..len * 3).map(|i| ((i * 7919) % 13) as f32 - 6.0).collect();
        let dct = DctPlanner::new().plan_dct2(len);
        let mut y = x.clone();
        dct_rows(&mut y, len, &dct, false);
        for (row_in, row_out) in x.chunks(len).zip(y.chunks(len)) {
            for (k, &out) in row_out.iter().enumerate() {
                let exact: f64 = row_in
                    .iter()
                    .enumerate()
                    .map(|(n, &v)| {
                        v as f64 * (std::f64::consts::PI * k as f64 * (2 * n + 1) as f64 / (2 * len) as f64).cos()
                    })
                    .sum();
                assert!((out as f64 - exact).abs() < 1e-4, "k {k}: {out} against {exact}");
            }
        }
        dct_rows(&mut y, len, &dct, true);
        for (a, b) in x.iter().zip(&y) {
            assert!((a * len as f32 / 2.0 - b).abs() < 1e-3);
        }
    }
}
