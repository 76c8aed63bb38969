//! What skinkit's test suites share, in one place: crafted image headers for the resource
//! limits' tests, a counting allocator that measures a call's peak heap, and the property tests'
//! configuration. Only `[dev-dependencies]` name this crate.

pub mod alloc;

use std::path::Path;

use proptest::test_runner::{Config, RngSeed};

/// Writes a PNG of `w x h` 8-bit grey pixels whose header is all there is: a one-byte stored
/// zlib stream as the only image data, then the end. The file is well formed up to the pixels
/// and far too short for the size it claims, so a decoder fails on it (or allocates the whole
/// image first) while a header reader needs nothing more.
///
/// # Panics
/// When the file cannot be written.
pub fn header_only_png(path: &Path, w: u32, h: u32) {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 0, 0, 0, 0]);
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend_from_slice(&13u32.to_be_bytes());
    bytes.extend_from_slice(&ihdr);
    bytes.extend_from_slice(&crc32(&ihdr).to_be_bytes());
    let idat = [b'I', b'D', b'A', b'T', 0x78, 0x01, 0x01, 0x01, 0x00, 0xFE, 0xFF, 0x00, 0x00, 0x01, 0x00, 0x01];
    bytes.extend_from_slice(&12u32.to_be_bytes());
    bytes.extend_from_slice(&idat);
    bytes.extend_from_slice(&crc32(&idat).to_be_bytes());
    bytes.extend_from_slice(&[0, 0, 0, 0, b'I', b'E', b'N', b'D', 0xAE, 0x42, 0x60, 0x82]);
    std::fs::write(path, bytes).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
}

/// CRC-32 (IEEE), bit by bit: the PNG chunk checksum.
pub fn crc32(data: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// `cases` cases from the fixed `seed`, unless `PROPTEST_CASES` / `PROPTEST_RNG_SEED` say
/// otherwise: CI runs the same cases every time, and a longer or different run is one variable
/// away.
pub fn proptest_config(cases: u32, seed: u64) -> Config {
    let from_env = Config::default();
    Config {
        cases: if std::env::var_os("PROPTEST_CASES").is_some() { from_env.cases } else { cases },
        rng_seed: if std::env::var_os("PROPTEST_RNG_SEED").is_some() {
            from_env.rng_seed
        } else {
            RngSeed::Fixed(seed)
        },
        ..from_env
    }
}

/// How far a rendered image is from a reference, per pixel: the largest channel difference over
/// the reference's brightest colour channel. The renderer's GPU tests bound `mean` and `p99`;
/// `max` is printed, not asserted, because silhouette pixels may differ fully.
#[derive(Clone, Copy, Debug)]
pub struct ImageDiff {
    pub mean: f32,
    pub p99: f32,
    pub max: f32,
    /// The reference's brightest colour channel (every error is relative to it).
    pub range: f32,
}

/// Compares two images of `channels` interleaved samples a pixel (3 or 4; the first three are
/// colour and set the range, every channel counts in the error).
///
/// # Panics
/// When the images differ in size, the reference is black or a difference is not finite.
pub fn image_diff(test: &[f32], reference: &[f32], channels: usize) -> ImageDiff {
    assert_eq!(test.len(), reference.len(), "images of different sizes");
    assert!(channels >= 3 && test.len().is_multiple_of(channels) && !test.is_empty(), "not {channels}-channel pixels");
    let range = reference.chunks_exact(channels).flat_map(|p| p[..3].iter().copied()).fold(0.0f32, f32::max);
    assert!(range > 0.0, "the reference image is black");
    let mut errors: Vec<f32> = test
        .chunks_exact(channels)
        .zip(reference.chunks_exact(channels))
        .map(|(t, r)| t.iter().zip(r).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max) / range)
        .collect();
    assert!(errors.iter().all(|e| e.is_finite()), "non-finite pixels");
    errors.sort_by(f32::total_cmp);
    let mean = errors.iter().sum::<f32>() / errors.len() as f32;
    ImageDiff { mean, p99: errors[errors.len() * 99 / 100], max: errors[errors.len() - 1], range }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_matches_the_png_specifications_check_value_and_iend() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b"IEND"), 0xAE42_6082);
    }

    #[test]
    fn a_header_only_png_claims_its_size_and_holds_no_pixels() {
        let dir = std::env::temp_dir().join(format!("skinkit-testkit-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("h.png");
        header_only_png(&path, 70000, 3);
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(&bytes[16..24], &[0, 1, 0x11, 0x70, 0, 0, 0, 3]);
        assert_eq!(bytes.len(), 8 + 25 + 24 + 12);
    }

    #[test]
    fn image_diff_is_relative_to_the_brightest_colour_channel() {
        // Two RGBA pixels; the reference's brightest colour channel is 2, alpha 5 does not count.
        let reference = [2.0, 0.0, 0.0, 5.0, 1.0, 1.0, 1.0, 5.0];
        let test = [2.0, 0.0, 0.0, 5.0, 1.0, 1.5, 1.0, 4.0];
        let d = image_diff(&test, &reference, 4);
        assert_eq!(d.range, 2.0);
        assert_eq!((d.mean, d.max), (0.25, 0.5));
        assert_eq!(image_diff(&reference, &reference, 4).max, 0.0);
    }
}
