//! Camera RAW photos (issue 39): DNG, CR2, NEF, ARW and the other formats `rawloader` decodes,
//! read as linear camera values, the same for every frame: black level subtracted, divided by
//! (white level - black level), no white balance, no tone curve, no colour matrix.
//!
//! Two sizes ([`RawMode`]): `Half` bins each 2x2 Bayer cell into one RGB pixel (red, the mean of
//! the two greens, blue; no demosaicing, so no interpolated value enters the solve), `Full`
//! demosaics bilinearly (each missing colour is the mean of that colour's samples in the 3x3
//! neighbourhood, which for a Bayer mosaic is the classic bilinear interpolation).
//!
//! A RAW decoder reads hostile bytes, so three guards stand around it:
//! - the file's length is checked before it is read (a RAW file holds at most a few bytes a
//!   sensor pixel, so a file far longer than the pixel limit allows is refused unread);
//! - a metadata-only pass reads the sensor size, checked against [`Limits`] before any pixel
//!   buffer is allocated;
//! - both passes run under `catch_unwind` (the decoder indexes its input and can panic on a
//!   malformed file), and panics raised inside the decoder are kept off stderr, so a malformed
//!   file is an [`Error::Decode`] naming it, never a crash.
//!
//! Without the crate feature `raw` every RAW file is refused by name ([`Error::Unsupported`]).

use std::path::Path;

use crate::limits::ImageHeader;
use crate::{Error, Limits, Photo, Result};

pub use crate::format::RAW_EXTENSIONS;

/// Bytes a RAW file may hold per sensor pixel of the pixel limit, plus [`RAW_SLACK_BYTES`] for
/// previews and metadata: float DNGs store 4 bytes a sample, every other layout fewer.
const RAW_BYTES_PER_PIXEL: u64 = 4;
const RAW_SLACK_BYTES: u64 = 256 << 20;

/// How a Bayer mosaic becomes an RGB photo.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RawMode {
    /// Each 2x2 Bayer cell binned into one pixel (half the width and height; no interpolation).
    #[default]
    Half,
    /// Demosaiced bilinearly to the sensor's full size.
    Full,
}

impl RawMode {
    /// `half` or `full`.
    pub fn name(self) -> &'static str {
        match self {
            RawMode::Half => "half",
            RawMode::Full => "full",
        }
    }
}

/// Whether `path`'s extension says camera RAW ([`RAW_EXTENSIONS`], any case).
pub fn is_raw(path: &Path) -> bool {
    crate::format::ImageFormat::of(path) == Some(crate::format::ImageFormat::Raw)
}

/// Reads a RAW photo as linear camera RGB (float, full scale 1) in `mode`.
///
/// # Errors
/// When the file cannot be read, is too long or too large for `limits`, is not a RAW file the
/// decoder understands, or has a colour filter other than a 2x2 Bayer pattern.
pub fn read(path: &Path, limits: &Limits, mode: RawMode) -> Result<Photo> {
    let bytes = read_bounded(path, limits)?;
    decode(path, &bytes, limits, mode)
}

/// Decodes RAW `bytes`; `path` names the file in errors.
///
/// # Errors
/// As [`read`].
pub fn decode(path: &Path, bytes: &[u8], limits: &Limits, mode: RawMode) -> Result<Photo> {
    imp::decode(path, bytes, limits, mode)
}

/// The header of a RAW photo as [`read`] would decode it in `mode` (metadata only), its sensor
/// size checked against `max_pixels`.
///
/// # Errors
/// As [`read`].
pub fn header(path: &Path, max_pixels: u64, mode: RawMode) -> Result<ImageHeader> {
    let limits = Limits { max_pixels };
    let bytes = read_bounded(path, &limits)?;
    imp::header(path, &bytes, &limits, mode)
}

/// Bytes a decode of the RAW file at `path` holds besides the photo it returns (`header`, as
/// [`header`] gave it in `mode`): the file read twice (skinkit's bounded copy and the decoder's
/// own buffer) and the sensor's 16-bit samples (four a pixel at half size, one at full size).
/// A file whose length cannot be read counts as empty (reading it will then fail).
pub fn decode_cost(path: &Path, header: &ImageHeader, mode: RawMode) -> u64 {
    let file = std::fs::metadata(path).map_or(0, |m| m.len());
    let sensor = match mode {
        RawMode::Half => header.pixels().saturating_mul(4),
        RawMode::Full => header.pixels(),
    };
    file.saturating_mul(2).saturating_add(sensor.saturating_mul(2))
}

/// The file's bytes, refused unread when it is longer than a RAW file of the pixel limit can be.
fn read_bounded(path: &Path, limits: &Limits) -> Result<Vec<u8>> {
    use std::io::Read;
    let file = crate::input::open(path, crate::input::Kind::RawPhoto)?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    let max = limits.max_pixels.saturating_mul(RAW_BYTES_PER_PIXEL).saturating_add(RAW_SLACK_BYTES);
    if len > max {
        return Err(Error::decode(
            path,
            format!("{len} bytes is longer than a RAW file within the pixel limit ({max} bytes)"),
        ));
    }
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    file.take(max).read_to_end(&mut bytes).map_err(|e| Error::io(path, e))?;
    Ok(bytes)
}

#[cfg(feature = "raw")]
mod decode;
#[cfg(feature = "raw")]
use decode as imp;

#[cfg(not(feature = "raw"))]
mod imp {
    use super::*;

    fn refuse(path: &Path) -> Error {
        Error::Unsupported {
            path: path.to_owned(),
            reason: "this build has no camera RAW support (feature `raw`)".into(),
        }
    }
    pub(super) fn decode(path: &Path, _: &[u8], _: &Limits, _: RawMode) -> Result<Photo> {
        Err(refuse(path))
    }
    pub(super) fn header(path: &Path, _: &[u8], _: &Limits, _: RawMode) -> Result<ImageHeader> {
        Err(refuse(path))
    }
}

pub mod mosaic;
