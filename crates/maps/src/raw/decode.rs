//! The decoder behind [`crate::raw`]: rawloader, guarded. A metadata-only pass (the decoder's
//! `dummy` mode, which reads every tag but allocates no pixel buffer) gives the sensor size,
//! checked against the limits before the real pass; both passes run under `catch_unwind`.
//!
//! rawloader over rawler (both LGPL-2.1, both pure Rust): rawloader's dependencies are five small
//! crates against rawler's two dozen (its own `image`, a JPEG XL decoder, chrono, a backtrace
//! crate), it builds with the workspace's minimum Rust, and it has the metadata-only pass the
//! size check needs. rawler reads more cameras (CR3, JPEG XL DNGs); swapping it in touches only
//! this file.

use std::panic::{self, AssertUnwindSafe};
use std::path::Path;
use std::sync::Once;

use rawloader::{RawImage, RawImageData};

use super::RawMode;
use super::mosaic::{Mosaic, Pattern, is_bayer};
use crate::limits::{ImageHeader, check_pixels};
use crate::{Error, Limits, Photo, Result};

/// What the sensor's metadata says about the part of it that is read.
struct Window {
    left: usize,
    top: usize,
    width: usize,
    height: usize,
    pattern: Pattern,
    black: [f32; 3],
    white: [f32; 3],
}

pub(super) fn header(path: &Path, bytes: &[u8], limits: &Limits, mode: RawMode) -> Result<ImageHeader> {
    let meta = guarded(path, || rawloader::decode_dummy(&mut &bytes[..]))?;
    let window = window(path, &meta, limits)?;
    let (width, height) = output_size(&window, mode);
    Ok(ImageHeader { width, height, channels: 3, alpha: false, sample_bytes: 4 })
}

pub(super) fn decode(path: &Path, bytes: &[u8], limits: &Limits, mode: RawMode) -> Result<Photo> {
    // Sizes first: the full pass allocates width * height samples from the same tags.
    window(path, &guarded(path, || rawloader::decode_dummy(&mut &bytes[..]))?, limits)?;
    let image = guarded(path, || rawloader::decode(&mut &bytes[..]))?;
    let window = window(path, &image, limits)?;
    let RawImageData::Integer(samples) = &image.data else {
        return Err(unsupported(path, "floating-point sensor data"));
    };
    if samples.len() < image.width * image.height {
        return Err(Error::decode(
            path,
            format!("camera raw: {} samples for a {}x{} sensor", samples.len(), image.width, image.height),
        ));
    }
    let mosaic = Mosaic {
        samples,
        stride: image.width,
        left: window.left,
        top: window.top,
        width: window.width,
        height: window.height,
        pattern: window.pattern,
        black: window.black,
        white: window.white,
    };
    match mode {
        RawMode::Half => mosaic.half(),
        RawMode::Full => mosaic.full(),
    }
}

/// The photo's size in `mode`.
fn output_size(window: &Window, mode: RawMode) -> (u64, u64) {
    match mode {
        RawMode::Half => ((window.width / 2) as u64, (window.height / 2) as u64),
        RawMode::Full => (window.width as u64, window.height as u64),
    }
}

/// The active area, its Bayer pattern and its levels, after checking the sensor against the
/// limits and refusing what skinkit does not read (several samples a pixel, non-Bayer filters).
fn window(path: &Path, image: &RawImage, limits: &Limits) -> Result<Window> {
    check_pixels(path, image.width as u64, image.height as u64, limits.max_pixels)?;
    if image.cpp != 1 {
        return Err(unsupported(path, &format!("{} samples a pixel (only Bayer mosaics are read)", image.cpp)));
    }
    let [top, right, bottom, left] = image.crops;
    let (width, height) = (image.width.checked_sub(left + right), image.height.checked_sub(top + bottom));
    let (Some(width), Some(height)) = (width.filter(|&w| w >= 2), height.filter(|&h| h >= 2)) else {
        return Err(Error::decode(
            path,
            format!("camera raw: crop {:?} leaves no image of {}x{}", image.crops, image.width, image.height),
        ));
    };
    let pattern = bayer(path, image)?;
    let (black, white) = levels(path, image)?;
    Ok(Window { left, top, width, height, pattern, black, white })
}

/// The 2x2 pattern of the active area.
fn bayer(path: &Path, image: &RawImage) -> Result<Pattern> {
    let cfa = image.cropped_cfa();
    let name = cfa.to_string();
    if !(cfa.width == 2 && cfa.height == 2) {
        let what = if name.is_empty() {
            "no colour filter pattern".to_owned()
        } else {
            format!("colour filter pattern {name}")
        };
        return Err(unsupported(path, &format!("{what} (only 2x2 Bayer mosaics are read)")));
    }
    let at = |r: usize, c: usize| u8::try_from(cfa.color_at(r, c)).unwrap_or(u8::MAX);
    let pattern = [[at(0, 0), at(0, 1)], [at(1, 0), at(1, 1)]];
    if !is_bayer(&pattern) {
        return Err(unsupported(
            path,
            &format!("colour filter pattern {name} (only red, green, blue Bayer mosaics are read)"),
        ));
    }
    Ok(pattern)
}

/// Black and white level of red, green and blue.
fn levels(path: &Path, image: &RawImage) -> Result<([f32; 3], [f32; 3])> {
    let black = [0, 1, 2].map(|c| f32::from(image.blacklevels[c]));
    let white = [0, 1, 2].map(|c| f32::from(image.whitelevels[c]));
    if (0..3).any(|c| white[c] <= black[c]) {
        return Err(Error::decode(
            path,
            format!("camera raw: white level {white:?} is not above black level {black:?}"),
        ));
    }
    Ok((black, white))
}

fn unsupported(path: &Path, what: &str) -> Error {
    Error::Unsupported { path: path.to_owned(), reason: format!("camera raw with {what}") }
}

/// Runs a decoder call with its panics caught and kept off stderr; either failure becomes an
/// [`Error::Decode`] naming `path`.
fn guarded<T>(path: &Path, call: impl FnOnce() -> std::result::Result<T, rawloader::RawLoaderError>) -> Result<T> {
    quiet_decoder_panics();
    match panic::catch_unwind(AssertUnwindSafe(call)) {
        Ok(Ok(value)) => Ok(value),
        Ok(Err(e)) => Err(Error::decode(path, format!("camera raw: {}", reason(&e.to_string())))),
        Err(_) => Err(Error::decode(path, "camera raw: the decoder failed on malformed data")),
    }
}

/// The decoder's message without its wrapper and bug-report footer; a caught panic reads as
/// malformed data.
fn reason(display: &str) -> String {
    let inner = display.strip_prefix("RawLoaderError: \"").and_then(|s| s.strip_suffix('"')).unwrap_or(display);
    let first = inner.lines().next().unwrap_or(inner).trim();
    if first.starts_with("Caught a panic") {
        "the decoder failed on malformed data".to_owned()
    } else {
        first.to_owned()
    }
}

/// Installs, once, a panic hook that passes every panic to the previous hook except those raised
/// inside rawloader's own source, which [`guarded`] turns into errors. rawloader catches its
/// panics itself, but the default hook would still print them (from whichever rayon thread
/// decoded the strip) before the file's error is reported.
fn quiet_decoder_panics() {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            let in_decoder = info.location().is_some_and(|l| l.file().contains("rawloader"));
            if !in_decoder {
                previous(info);
            }
        }));
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decoder_messages_lose_their_wrapper() {
        assert_eq!(reason("RawLoaderError: \"Couldn't find camera \\\"X\\\"\""), "Couldn't find camera \\\"X\\\"");
        let panicked = "RawLoaderError: \"Caught a panic while decoding.\nPlease file a bug\"";
        assert_eq!(reason(panicked), "the decoder failed on malformed data");
    }

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let path = Path::new("shot-03.dng");
        for bytes in [&b""[..], b"II*\0\x08\0\0\0", b"MM\0*\0\0\0\x08\xff\xff", b"hello, not a raw file"] {
            let e = decode(path, bytes, &Limits::default(), RawMode::Half).unwrap_err().to_string();
            assert!(e.starts_with("shot-03.dng: "), "{e}");
        }
    }
}
