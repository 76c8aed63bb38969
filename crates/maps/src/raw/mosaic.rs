//! A Bayer mosaic as linear camera values, and the two ways [`crate::raw`] turns it into RGB:
//! 2x2 binning ([`Mosaic::half`]) and bilinear demosaicing ([`Mosaic::full`]). Independent of the
//! decoder, so tests feed it hand-made mosaics.

use rayon::prelude::*;

use crate::{Channels, Photo, Result, Samples};

/// A 2x2 colour filter pattern: the colour (0 red, 1 green, 2 blue) at `(row % 2, col % 2)`.
pub type Pattern = [[u8; 2]; 2];

/// The pattern a four-letter name gives (`RGGB`, `BGGR`, `GRBG`, `GBRG`: rows concatenated).
pub fn pattern(name: &str) -> Option<Pattern> {
    let colour = |c: u8| match c {
        b'R' => Some(0),
        b'G' => Some(1),
        b'B' => Some(2),
        _ => None,
    };
    let b = name.as_bytes();
    if b.len() != 4 {
        return None;
    }
    let p = [[colour(b[0])?, colour(b[1])?], [colour(b[2])?, colour(b[3])?]];
    is_bayer(&p).then_some(p)
}

/// Whether `p` holds one red, two greens and one blue.
pub fn is_bayer(p: &Pattern) -> bool {
    let mut count = [0; 3];
    p.iter().flatten().for_each(|&c| count[c as usize] += 1);
    count == [1, 2, 1]
}

/// A window of a sensor's samples with its pattern and levels.
#[derive(Clone, Debug)]
pub struct Mosaic<'a> {
    /// The sensor's samples, row-major, `stride` a row.
    pub samples: &'a [u16],
    pub stride: usize,
    /// The window (the sensor's active area): its top-left sample and size.
    pub left: usize,
    pub top: usize,
    pub width: usize,
    pub height: usize,
    /// The colour pattern relative to the window's top-left sample.
    pub pattern: Pattern,
    /// Black and white level of each colour (red, green, blue), in stored units.
    pub black: [f32; 3],
    pub white: [f32; 3],
}

impl Mosaic<'_> {
    /// The colour of window sample `(x, y)`.
    #[inline]
    fn colour(&self, x: usize, y: usize) -> usize {
        self.pattern[y % 2][x % 2] as usize
    }

    /// Window sample `(x, y)` as a linear value: `(v - black) / (white - black)`, at most 1 (a
    /// sample at the white level is saturated and stays exactly at full scale); under-black
    /// noise keeps its sign, so averages over dark areas are not biased upward.
    #[inline]
    fn level(&self, x: usize, y: usize) -> f32 {
        let c = self.colour(x, y);
        let v = f32::from(self.samples[(self.top + y) * self.stride + self.left + x]);
        ((v - self.black[c]) / (self.white[c] - self.black[c])).min(1.0)
    }

    /// One RGB pixel per 2x2 cell: red, the mean of the two greens, blue (a trailing odd row or
    /// column is dropped).
    ///
    /// # Errors
    /// When the window is smaller than one cell.
    pub fn half(&self) -> Result<Photo> {
        let (w, h) = (self.width / 2, self.height / 2);
        let mut out = vec![0.0f32; w * h * 3];
        out.par_chunks_mut((w * 3).max(1)).enumerate().for_each(|(y, row)| {
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                let mut sum = [0.0f32; 3];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (sx, sy) = (2 * x + dx, 2 * y + dy);
                    sum[self.colour(sx, sy)] += self.level(sx, sy);
                }
                px.copy_from_slice(&[sum[0], 0.5 * sum[1], sum[2]]);
            }
        });
        Photo::new(w, h, Channels::Rgb, Samples::F32(out))
    }

    /// Bilinear demosaicing to the window's full size: each colour a sample lacks is the mean of
    /// that colour's samples among its 3x3 neighbours (clipped at the borders).
    ///
    /// # Errors
    /// When the window is empty.
    pub fn full(&self) -> Result<Photo> {
        let (w, h) = (self.width, self.height);
        let mut out = vec![0.0f32; w * h * 3];
        out.par_chunks_mut((w * 3).max(1)).enumerate().for_each(|(y, row)| {
            for (x, px) in row.chunks_exact_mut(3).enumerate() {
                px.copy_from_slice(&self.demosaic(x, y));
            }
        });
        Photo::new(w, h, Channels::Rgb, Samples::F32(out))
    }

    /// The RGB value at window sample `(x, y)`: its own colour as measured, the others the mean
    /// of their samples in the 3x3 neighbourhood.
    fn demosaic(&self, x: usize, y: usize) -> [f32; 3] {
        let own = self.colour(x, y);
        let mut sum = [0.0f32; 3];
        let mut count = [0u32; 3];
        for ny in y.saturating_sub(1)..(y + 2).min(self.height) {
            for nx in x.saturating_sub(1)..(x + 2).min(self.width) {
                let c = self.colour(nx, ny);
                sum[c] += self.level(nx, ny);
                count[c] += 1;
            }
        }
        let mut rgb = [0.0; 3];
        for c in 0..3 {
            rgb[c] = if c == own { self.level(x, y) } else { sum[c] / count[c].max(1) as f32 };
        }
        rgb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mosaic of the colour planes `rgb(x, y)` sampled through `pattern`, at levels
    /// `black + v * (white - black)`.
    fn mosaic_of(w: usize, h: usize, pattern: Pattern, rgb: impl Fn(usize, usize) -> [f32; 3]) -> Vec<u16> {
        let (black, white) = (512.0, 15000.0);
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let v = rgb(x, y)[pattern[y % 2][x % 2] as usize];
                out.push((black + v * (white - black)).round() as u16);
            }
        }
        out
    }

    fn view(samples: &[u16], w: usize, h: usize, pattern: Pattern) -> Mosaic<'_> {
        Mosaic {
            samples,
            stride: w,
            left: 0,
            top: 0,
            width: w,
            height: h,
            pattern,
            black: [512.0; 3],
            white: [15000.0; 3],
        }
    }

    fn f32s(photo: &Photo) -> &[f32] {
        let Samples::F32(v) = photo.samples() else { panic!("float photo") };
        v
    }

    #[test]
    fn names_give_bayer_patterns_only() {
        assert_eq!(pattern("RGGB"), Some([[0, 1], [1, 2]]));
        assert_eq!(pattern("GBRG"), Some([[1, 2], [0, 1]]));
        assert_eq!(pattern("RGBG"), Some([[0, 1], [2, 1]]));
        assert_eq!(pattern("RRGB"), None);
        assert_eq!(pattern("RGB"), None);
    }

    /// Binning, against the plane values each cell was made from (one quantisation step of
    /// 1/14488 is the only difference).
    #[test]
    fn half_bins_each_cell_into_its_colours() {
        for name in ["RGGB", "BGGR", "GRBG", "GBRG"] {
            let p = pattern(name).unwrap();
            let plane = |x: usize, y: usize| {
                let (cx, cy) = ((x / 2) as f32, (y / 2) as f32);
                [0.1 + 0.01 * cx, 0.5 - 0.02 * cy, 0.05 * (cx + cy) / 4.0]
            };
            let raw = mosaic_of(8, 6, p, plane);
            let photo = view(&raw, 8, 6, p).half().unwrap();
            assert_eq!((photo.width(), photo.height()), (4, 3));
            for (i, px) in f32s(&photo).chunks(3).enumerate() {
                let want = plane(2 * (i % 4), 2 * (i / 4));
                for c in 0..3 {
                    assert!((px[c] - want[c]).abs() < 1e-4, "{name} pixel {i} channel {c}: {px:?} vs {want:?}");
                }
            }
        }
    }

    /// Bilinear demosaicing reproduces a linear ramp exactly away from the borders.
    #[test]
    fn full_reproduces_a_linear_ramp_inside() {
        let ramp = |x: usize, y: usize| {
            let (x, y) = (x as f32, y as f32);
            [0.1 + 0.02 * x + 0.01 * y, 0.3 + 0.01 * x - 0.02 * y + 0.2, 0.05 + 0.03 * y]
        };
        let p = pattern("GRBG").unwrap();
        let raw = mosaic_of(10, 9, p, ramp);
        let photo = view(&raw, 10, 9, p).full().unwrap();
        let v = f32s(&photo);
        for y in 1..8 {
            for x in 1..9 {
                let want = ramp(x, y);
                for c in 0..3 {
                    let got = v[(y * 10 + x) * 3 + c];
                    assert!((got - want[c]).abs() < 2e-4, "({x}, {y}) channel {c}: {got} vs {}", want[c]);
                }
            }
        }
    }

    /// Black is subtracted per colour, white normalises, and a clipped sample stays at 1.
    #[test]
    fn levels_are_per_colour_and_clip_at_white() {
        let p = pattern("RGGB").unwrap();
        let raw = [100u16, 1100, 2100, 65535];
        let m = Mosaic { black: [100.0, 100.0, 600.0], white: [1100.0, 2100.0, 4600.0], ..view(&raw, 2, 2, p) };
        let px = m.half().unwrap();
        assert_eq!(f32s(&px), &[0.0, (0.5 + 1.0) / 2.0, 1.0]);
    }

    /// A window of a larger sensor reads its own samples (the crop offsets the stride).
    #[test]
    fn a_window_reads_its_own_samples() {
        let p = pattern("RGGB").unwrap();
        let mut raw = vec![0u16; 6 * 4];
        raw[6 + 1..6 + 3].copy_from_slice(&[600, 700]);
        raw[2 * 6 + 1..2 * 6 + 3].copy_from_slice(&[800, 900]);
        let m = Mosaic {
            stride: 6,
            left: 1,
            top: 1,
            width: 2,
            height: 2,
            black: [500.0; 3],
            white: [1500.0; 3],
            ..view(&raw, 6, 4, p)
        };
        assert_eq!(f32s(&m.half().unwrap()), &[0.1, 0.25, 0.4]);
    }
}
