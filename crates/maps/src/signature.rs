//! What an image file holds, from its first bytes, against what its name says (issue 15, D13).
//!
//! Photometric stereo needs photos whose values are proportional to light. A JPEG is lossy and
//! stores sRGB-encoded 8-bit values, so a JPEG photo would be solved as if it were linear and
//! give wrong normals without a word; the workspace's image decoder can read JPEG (the glTF loader
//! enables it), so the refusal is made here, from the signature, whatever the file is called. A
//! file whose data is one supported format and whose name says another (TIFF data named `.png`)
//! is refused too: one of the two is wrong, and guessing which hides a mix-up in the export.

use std::path::Path;

use image::ImageFormat;

use crate::{Error, Result};

/// The formats skinkit reads images from, as their signatures name them.
const READ: [ImageFormat; 3] = [ImageFormat::Png, ImageFormat::Tiff, ImageFormat::OpenExr];

/// The format a file name's extension claims, if it names an image format at all.
fn named_format(path: &Path) -> Option<ImageFormat> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    match ext.as_str() {
        "jpg" | "jpeg" => Some(ImageFormat::Jpeg),
        _ => ImageFormat::from_extension(&ext),
    }
}

fn name_of(format: ImageFormat) -> &'static str {
    match format {
        ImageFormat::Png => "PNG",
        ImageFormat::Tiff => "TIFF",
        ImageFormat::OpenExr => "EXR",
        ImageFormat::Jpeg => "JPEG",
        other => other.extensions_str().first().copied().unwrap_or("an unknown format"),
    }
}

/// Checks the format `found` in the first bytes of `path` (`None`: no known signature) against
/// the formats skinkit reads and against the file's extension.
///
/// # Errors
/// [`Error::Unsupported`] for JPEG data (with the reason: photos must be linear) and for any
/// other format skinkit does not read; [`Error::Decode`] when the data is one supported format
/// and the name says another; [`Error::Decode`] when no signature is recognised.
pub(crate) fn check(path: &Path, found: Option<ImageFormat>) -> Result<()> {
    let Some(found) = found else {
        return Err(Error::decode(path, "unrecognised file signature (expected PNG, TIFF or EXR)"));
    };
    if found == ImageFormat::Jpeg {
        return Err(Error::Unsupported {
            path: path.to_owned(),
            reason: "the file holds JPEG data: JPEG is lossy and stores sRGB-encoded values, but photos \
                     and maps must be linear; export 16-bit PNG or TIFF, or float EXR"
                .into(),
        });
    }
    if !READ.contains(&found) {
        return Err(Error::Unsupported {
            path: path.to_owned(),
            reason: format!("the file holds {} data (expected PNG, TIFF or EXR)", name_of(found)),
        });
    }
    match named_format(path) {
        Some(named) if named != found => Err(Error::decode(
            path,
            format!(
                "the file holds {} data but its name says {}: rename or re-export it",
                name_of(found),
                name_of(named)
            ),
        )),
        _ => Ok(()),
    }
}

/// Checks the first bytes of `file` (opened from `path` through the input gate), then rewinds it
/// for the decoder.
///
/// # Errors
/// As [`check`], and [`Error::Io`] when the file cannot be read.
pub(crate) fn check_reader(path: &Path, file: &mut (impl std::io::Read + std::io::Seek)) -> Result<()> {
    use std::io::Read;
    let mut head = Vec::with_capacity(16);
    file.by_ref().take(16).read_to_end(&mut head).map_err(|e| Error::io(path, e))?;
    file.rewind().map_err(|e| Error::io(path, e))?;
    check(path, image::guess_format(&head).ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    const PNG: &[u8] = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR";
    const TIFF: &[u8] = b"II*\0\x08\0\0\0";
    const JPEG: &[u8] = b"\xff\xd8\xff\xe0\0\x10JFIF\0";

    fn checked(name: &str, head: &[u8]) -> Result<()> {
        check(Path::new(name), image::guess_format(head).ok())
    }

    /// Issue 15, D13: JPEG data is refused whatever its name, saying why.
    #[test]
    fn d13_jpeg_photos_are_refused_with_the_reason() {
        for name in ["03.png", "03.jpg", "03.tif", "03"] {
            let e = checked(name, JPEG).unwrap_err().to_string();
            assert!(e.starts_with(name) && e.contains("JPEG") && e.contains("linear"), "{e}");
        }
    }

    /// Issue 15, D13: a supported format under another format's name is refused, naming both.
    #[test]
    fn d13_an_extension_that_contradicts_the_data_is_refused() {
        let e = checked("a.png", TIFF).unwrap_err().to_string();
        assert!(e.contains("holds TIFF data but its name says PNG"), "{e}");
        let e = checked("a.tiff", PNG).unwrap_err().to_string();
        assert!(e.contains("holds PNG data but its name says TIFF"), "{e}");
        let e = checked("a.exr", PNG).unwrap_err().to_string();
        assert!(e.contains("holds PNG data but its name says EXR"), "{e}");
    }

    #[test]
    fn matching_or_unnamed_formats_pass() {
        checked("a.png", PNG).unwrap();
        checked("a.PNG", PNG).unwrap();
        checked("a.tif", TIFF).unwrap();
        checked("a.tiff", TIFF).unwrap();
        checked("photo", PNG).unwrap();
        checked("photo.raw16", TIFF).unwrap();
        let e = checked("a.png", b"hello, world").unwrap_err().to_string();
        assert!(e.contains("unrecognised file signature"), "{e}");
    }
}
