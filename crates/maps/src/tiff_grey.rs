//! Grey TIFFs with extra samples (grey and alpha), which the `image` crate's TIFF decoder refuses
//! as "Multiband" (issue 42, D16). The book promises grey or RGB photos with alpha ignored, as
//! for PNG, so these are read with the `tiff` crate and the first sample of each pixel kept.

use std::io::{Read, Seek};
use std::path::Path;

use tiff::ColorType;
use tiff::decoder::{Decoder, DecodingResult};
use tiff::tags::Tag;

use crate::limits::ImageHeader;
use crate::{Channels, Error, Photo, Result, Samples};

/// `PhotometricInterpretation` of a grey image whose zero is black.
const BLACK_IS_ZERO: u32 = 1;
/// `SampleFormat` of unsigned integers (also what a file without the tag holds).
const UNSIGNED: u32 = 1;

/// A grey TIFF with extra samples: its size, bits per sample (8 or 16) and samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct GreyExtra {
    width: u32,
    height: u32,
    bits: u8,
    samples: u16,
}

impl GreyExtra {
    /// The header as [`crate::limits::image_header`] gives it (alpha counted, then dropped).
    pub(crate) fn header(&self) -> ImageHeader {
        ImageHeader {
            width: u64::from(self.width),
            height: u64::from(self.height),
            channels: u8::try_from(self.samples).unwrap_or(u8::MAX),
            alpha: true,
            sample_bytes: self.bits / 8,
        }
    }
}

/// `Some` when `reader` holds a grey (black is zero) TIFF of 8- or 16-bit unsigned samples with
/// extra samples; anything else is left to the `image` crate. `reader` is rewound.
///
/// # Errors
/// [`Error::Io`] when the reader cannot be rewound.
pub(crate) fn probe(path: &Path, reader: &mut (impl Read + Seek)) -> Result<Option<GreyExtra>> {
    let found = describe(&mut *reader);
    reader.rewind().map_err(|e| Error::io(path, e))?;
    Ok(found)
}

fn describe(reader: impl Read + Seek) -> Option<GreyExtra> {
    let mut decoder = Decoder::new(reader).ok()?;
    let ColorType::Multiband { bit_depth, num_samples } = decoder.colortype().ok()? else { return None };
    let grey = decoder.get_tag_u32(Tag::PhotometricInterpretation).ok()? == BLACK_IS_ZERO;
    // One `SampleFormat` a sample (or none: unsigned); every one must be unsigned.
    let formats = decoder.find_tag_unsigned_vec::<u32>(Tag::SampleFormat).ok()?.unwrap_or_default();
    let unsigned = formats.iter().all(|&f| f == UNSIGNED);
    let (width, height) = decoder.dimensions().ok()?;
    let fits = grey && unsigned && matches!(bit_depth, 8 | 16) && num_samples >= 2;
    fits.then_some(GreyExtra { width, height, bits: bit_depth, samples: num_samples })
}

/// Decodes the grey TIFF `found` describes, keeping the first sample of each pixel; `max_pixels`
/// is checked first.
///
/// # Errors
/// [`Error::TooLarge`] over the pixel limit; [`Error::Decode`] when the pixel data is damaged.
pub(crate) fn decode(path: &Path, reader: impl Read + Seek, found: GreyExtra, max_pixels: u64) -> Result<Photo> {
    let pixels = crate::limits::check_pixels(path, found.width.into(), found.height.into(), max_pixels)?;
    let bad = |e: tiff::TiffError| Error::decode(path, e);
    // The pixel limit was checked above; the crate's own buffer limit (256 MiB) would refuse a
    // 16-bit grey and alpha photo of 8192 x 8192 that the book accepts.
    let mut decoder = Decoder::new(reader).map_err(bad)?.with_limits(tiff::decoder::Limits::unlimited());
    let step = usize::from(found.samples);
    let samples = match decoder.read_image().map_err(bad)? {
        DecodingResult::U8(v) => Samples::U8(v.into_iter().step_by(step).collect()),
        DecodingResult::U16(v) => Samples::U16(v.into_iter().step_by(step).collect()),
        _ => return Err(Error::decode(path, "the TIFF's samples are not 8- or 16-bit unsigned integers")),
    };
    let (width, height) = (found.width as usize, found.height as usize);
    if samples.len() as u64 != pixels {
        return Err(Error::decode(path, "the TIFF holds fewer samples than its size needs"));
    }
    Photo::new(width, height, Channels::Gray, samples)
}

#[cfg(test)]
mod tests {
    use std::io::Cursor;

    use super::*;
    use crate::io::{ExrChannel, ExrOptions, Limits, decode_photo, read_photo, write_exr_channels};

    /// The reliability probe's photo (issue 42, I03): 8 x 8, 16-bit grey and unassociated alpha
    /// (`ExtraSamples` 2), one uncompressed strip.
    fn grey_alpha_tiff(grey: u16) -> Vec<u8> {
        let (w, h) = (8u32, 8u32);
        let data: Vec<u8> = (0..w * h).flat_map(|_| [grey, 65535]).flat_map(u16::to_le_bytes).collect();
        let tags: [(u16, u16, u32, u32); 11] = [
            (256, 4, 1, w),
            (257, 4, 1, h),
            (258, 3, 2, 16 | (16 << 16)),
            (259, 3, 1, 1),
            (262, 3, 1, 1),
            (273, 4, 1, 8 + 2 + 12 * 11 + 4),
            (277, 3, 1, 2),
            (278, 4, 1, h),
            (279, 4, 1, data.len() as u32),
            (338, 3, 1, 2),
            (339, 3, 2, 1 | (1 << 16)),
        ];
        let mut bytes = b"II*\0".to_vec();
        bytes.extend(8u32.to_le_bytes());
        bytes.extend((tags.len() as u16).to_le_bytes());
        for (tag, kind, count, value) in tags {
            bytes.extend(tag.to_le_bytes());
            bytes.extend(kind.to_le_bytes());
            bytes.extend(count.to_le_bytes());
            bytes.extend(value.to_le_bytes());
        }
        bytes.extend(0u32.to_le_bytes());
        bytes.extend(data);
        bytes
    }

    /// Issue 42, D16: a 16-bit grey and alpha TIFF is read as grey, alpha ignored, as the book
    /// says; its header says so too (the memory estimate reads headers first).
    #[test]
    fn probe2_d16_a_16_bit_grey_and_alpha_tiff_reads_as_grey() {
        let bytes = grey_alpha_tiff(23000);
        let photo = decode_photo(Path::new("01.tif"), Cursor::new(bytes.clone()), &Limits::default()).unwrap();
        assert_eq!((photo.width(), photo.height(), photo.channels()), (8, 8, Channels::Gray));
        assert!(matches!(photo.samples(), Samples::U16(v) if v.len() == 64 && v.iter().all(|&x| x == 23000)));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("01.tif");
        std::fs::write(&path, &bytes).unwrap();
        let header = crate::limits::image_header(&path, crate::limits::MAX_IMAGE_PIXELS).unwrap();
        assert_eq!(
            (header.width, header.height, header.channels, header.alpha, header.sample_bytes),
            (8, 8, 2, true, 2)
        );
        let tiny = Limits { max_pixels: 63 };
        assert!(matches!(decode_photo(&path, Cursor::new(bytes), &tiny), Err(Error::TooLarge { .. })));
    }

    /// Issue 42, D16: a layout skinkit does not read is refused in the book's words, never with
    /// the decoder's Debug dump (`Unknown(32)`, `Multiband { .. }`).
    #[test]
    fn probe2_d16_unsupported_layouts_are_refused_in_the_readmes_words() {
        let mut float = Cursor::new(Vec::new());
        let mut encoder = tiff::encoder::TiffEncoder::new(&mut float).unwrap();
        encoder.write_image::<tiff::encoder::colortype::Gray32Float>(4, 4, &[0.5f32; 16]).unwrap();
        let e = decode_photo(Path::new("05.tif"), Cursor::new(float.into_inner()), &Limits::default());
        let e = e.unwrap_err().to_string();
        assert!(
            e.starts_with("05.tif: unsupported image: its pixel layout is not one skinkit reads: PNG or TIFF"),
            "{e}"
        );
        assert!(!e.contains("Unknown(") && !e.contains("Multiband"), "{e}");
    }

    /// Issue 42, D16: a grey (Y only) EXR photo is refused saying which channels it needs and has.
    #[test]
    fn probe2_d16_a_grey_exr_photo_names_the_channels_it_needs() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("01.exr");
        let y = [0.5f32; 16];
        write_exr_channels(&path, 4, 4, &[ExrChannel { name: "Y", samples: &y }], &ExrOptions::default()).unwrap();
        let e = read_photo(&path, &Limits::default()).unwrap_err().to_string();
        assert!(
            e.ends_with("01.exr: unsupported image: an EXR photo or map needs R, G and B channels; this one has Y"),
            "{e}"
        );
    }
}
