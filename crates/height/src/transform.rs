//! Separable 2-D FFTs over a row-major grid (the periodic solve): a pass of 1-D FFTs along every
//! row, in parallel batches of rows, and a blocked parallel transpose between passes, so both
//! directions run along contiguous memory. The 1-D transforms are rustfft's.

use std::sync::Arc;

use rayon::prelude::*;
use rustfft::Fft;
use rustfft::num_complex::Complex32;

/// Rows handed to one rayon task (enough to amortise the task, few enough to balance two cores).
const ROWS_PER_TASK: usize = 16;
/// Side of the square tiles of the transpose (a tile of f32 or complex stays in L1).
const TILE: usize = 32;

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
}
