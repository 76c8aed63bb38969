//! Reading photos (PNG, TIFF, EXR, camera RAW) and maps (PNG, TIFF, EXR) under size limits, and writing them atomically.
//!
//! Readers come in pairs: `read_*(path)` opens the file and calls `decode_*(bytes)`-style
//! functions, so tests can feed bytes. Every writer goes through [`write_atomic`]: the data lands in
//! a temporary file in the destination folder and is renamed over the target only when complete,
//! so an interrupted run never leaves a half-written output and never touches an input.
//!
//! (Over 600 lines: every reader and writer of the crate's formats, which share the format
//! detection, the limits and the atomic write; the row writers next to the whole-map ones they
//! serve.)

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;
use image::{DynamicImage, ImageDecoder, ImageReader};

use crate::encoding::{NormalEncoding, linear_to_srgb};
use crate::format::ImageFormat;
use crate::raw::RawMode;
use crate::{Channels, ColorMap, Error, Grid, NormalMap, Photo, Result, Samples, ScalarMap};

/// Upper bounds checked before any large allocation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Largest accepted `width * height`.
    pub max_pixels: u64,
}

impl Default for Limits {
    /// [`crate::limits::MAX_IMAGE_PIXELS`]: 16384 x 16384 pixels.
    fn default() -> Self {
        Limits { max_pixels: crate::limits::MAX_IMAGE_PIXELS }
    }
}

impl Limits {
    fn check(&self, path: &Path, width: u64, height: u64) -> Result<()> {
        crate::limits::check_pixels(path, width, height, self.max_pixels).map(drop)
    }
}

/// The lowercase extension of `path`, or "".
fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}

fn is_exr(path: &Path) -> bool {
    ImageFormat::of(path) == Some(ImageFormat::Exr)
}

/// The image file, opened through the input gate ([`crate::input`]) and buffered: decoders
/// stream from it rather than from a copy of the whole file in memory (for a stack of 4096x4096
/// photos that copy is a quarter of a gigabyte of fresh pages).
pub(crate) fn open_buffered(path: &Path) -> Result<std::io::BufReader<File>> {
    let file = crate::input::open(path, crate::input::Kind::Image)?;
    Ok(std::io::BufReader::with_capacity(1 << 16, file))
}

/// An EXR file through the gate, its signature and every part's size checked, rewound for the
/// decoder: one open serves the checks and the decode.
fn open_exr(path: &Path, limits: &Limits, need_rgb: bool) -> Result<std::io::BufReader<File>> {
    use std::io::Seek;
    let mut file = open_buffered(path)?;
    crate::signature::check_reader(path, &mut file)?;
    crate::limits::exr_read_size(path, &mut file, limits.max_pixels, need_rgb)?;
    file.rewind().map_err(|e| Error::io(path, e))?;
    Ok(file)
}

/// Reads a PNG, TIFF, EXR or camera RAW ([`crate::raw`], half size) photo, grey or RGB (alpha dropped), 8/16-bit or float, kept in its
/// native sample type with a linear transfer (see [`Photo::with_transfer`] for sRGB photos).
///
/// # Errors
/// When the file cannot be read, is not a supported image, or exceeds `limits`.
pub fn read_photo(path: &Path, limits: &Limits) -> Result<Photo> {
    read_photo_as(path, limits, RawMode::default())
}

/// As [`read_photo`], with camera RAW files ([`crate::raw::is_raw`]) read in `raw` mode as
/// linear float camera RGB.
///
/// # Errors
/// As [`read_photo`].
pub fn read_photo_as(path: &Path, limits: &Limits, raw: RawMode) -> Result<Photo> {
    if crate::raw::is_raw(path) {
        return crate::raw::read(path, limits, raw);
    }
    if is_exr(path) {
        let (w, h, data) = read_exr_rgb(path, limits)?;
        let samples = data.into_iter().flatten().collect();
        return Photo::new(w, h, Channels::Rgb, Samples::F32(samples));
    }
    decode_photo(path, open_buffered(path)?, limits)
}

/// Decodes a PNG or TIFF photo from `reader`; `path` names it in errors.
///
/// # Errors
/// As [`read_photo`].
pub fn decode_photo(path: &Path, mut reader: impl std::io::BufRead + std::io::Seek, limits: &Limits) -> Result<Photo> {
    // The signature first, so a grey TIFF with alpha under another format's name is refused too.
    crate::signature::check_reader(path, &mut reader)?;
    if let Some(found) = crate::tiff_grey::probe(path, &mut reader)? {
        return crate::tiff_grey::decode(path, reader, found, limits.max_pixels);
    }
    let image = decode_dynamic(path, reader, limits)?;
    photo_from_dynamic(path, image)
}

fn decode_dynamic(path: &Path, reader: impl std::io::BufRead + std::io::Seek, limits: &Limits) -> Result<DynamicImage> {
    let reader = ImageReader::new(reader).with_guessed_format().map_err(|e| Error::io(path, e))?;
    // Only PNG and TIFF reach the decoder, and only under their own names (JPEG never: D13).
    crate::signature::check(path, reader.format())?;
    let decoder = reader.into_decoder().map_err(|e| Error::image(path, e))?;
    let (w, h) = decoder.dimensions();
    limits.check(path, w as u64, h as u64)?;
    DynamicImage::from_decoder(decoder).map_err(|e| Error::image(path, e))
}

fn photo_from_dynamic(path: &Path, image: DynamicImage) -> Result<Photo> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    let (channels, samples) = match image {
        DynamicImage::ImageLuma8(b) => (Channels::Gray, Samples::U8(b.into_raw())),
        DynamicImage::ImageLuma16(b) => (Channels::Gray, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgb8(b) => (Channels::Rgb, Samples::U8(b.into_raw())),
        DynamicImage::ImageRgb16(b) => (Channels::Rgb, Samples::U16(b.into_raw())),
        DynamicImage::ImageRgb32F(b) => (Channels::Rgb, Samples::F32(b.into_raw())),
        i @ DynamicImage::ImageLumaA8(_) => (Channels::Gray, Samples::U8(i.into_luma8().into_raw())),
        i @ DynamicImage::ImageLumaA16(_) => (Channels::Gray, Samples::U16(i.into_luma16().into_raw())),
        i @ DynamicImage::ImageRgba8(_) => (Channels::Rgb, Samples::U8(i.into_rgb8().into_raw())),
        i @ DynamicImage::ImageRgba16(_) => (Channels::Rgb, Samples::U16(i.into_rgb16().into_raw())),
        i @ DynamicImage::ImageRgba32F(_) => (Channels::Rgb, Samples::F32(i.into_rgb32f().into_raw())),
        _ => {
            return Err(Error::Unsupported { path: path.to_owned(), reason: crate::error::LAYOUTS_READ.to_owned() });
        }
    };
    Photo::new(w, h, channels, samples)
}

/// Reads a normal map from PNG/TIFF (8- or 16-bit RGB, `encoding` tells green up or down) or EXR
/// (float, the same green convention). All-zero texels and NaN become invalid texels.
///
/// # Errors
/// When the file cannot be read or decoded, is not RGB, or exceeds `limits`.
pub fn read_normal_map(path: &Path, encoding: NormalEncoding, limits: &Limits) -> Result<NormalMap> {
    if is_exr(path) {
        let (w, h, data) = read_exr_rgb(path, limits)?;
        let normals = data.into_iter().map(|c| encoding.decode_float(c)).collect();
        return NormalMap::from_unit_grid(Grid::from_vec(w, h, normals)?);
    }
    let photo = decode_photo(path, open_buffered(path)?, limits)?;
    if photo.channels() != Channels::Rgb {
        return Err(Error::Unsupported {
            path: path.to_owned(),
            reason: "a normal map needs three channels (RGB)".into(),
        });
    }
    let (w, h) = (photo.width(), photo.height());
    let normals: Vec<Vec3> = match photo.samples() {
        Samples::U8(s) => {
            s.chunks_exact(3).map(|c| encoding.decode([c[0] as u32, c[1] as u32, c[2] as u32], 255)).collect()
        }
        Samples::U16(s) => {
            s.chunks_exact(3).map(|c| encoding.decode([c[0] as u32, c[1] as u32, c[2] as u32], 65535)).collect()
        }
        Samples::F32(s) => s.chunks_exact(3).map(|c| encoding.decode_float([c[0], c[1], c[2]])).collect(),
    };
    NormalMap::from_unit_grid(Grid::from_vec(w, h, normals)?)
}

/// Reads one float channel (`"Y"` of a height map, say) of the first layer of an EXR file.
///
/// # Errors
/// When the file is not an EXR within the limits or has no channel called `name`.
pub fn read_exr_channel(path: &Path, name: &str, limits: &Limits) -> Result<ScalarMap> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let file = open_exr(path, limits, false)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(file)
        .map_err(|e| Error::decode(path, e))?;
    let layer = &image.layer_data;
    let Some(channel) = layer.channel_data.list.iter().find(|c| c.name == *name) else {
        return Err(Error::InvalidParameter(format!("{}: no channel `{name}`", path.display())));
    };
    Grid::from_vec(layer.size.width(), layer.size.height(), channel.sample_data.values_as_f32().collect())
}

/// Reads the first RGB(A) layer of an EXR file as float triples (alpha ignored, missing channels 0).
fn read_exr_rgb(path: &Path, limits: &Limits) -> Result<(usize, usize, Vec<[f32; 3]>)> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let file = open_exr(path, limits, true)?;
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| (resolution.width(), vec![[0.0f32; 3]; resolution.width() * resolution.height()]),
            |(w, data): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                data[pos.y() * *w + pos.x()] = [r, g, b]
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(file)
        .map_err(|e| Error::decode(path, e))?;
    let size = image.layer_data.size;
    Ok((size.width(), size.height(), image.layer_data.channel_data.pixels.1))
}

/// Writes a file atomically: `write` fills a temporary file beside `path`, which then replaces it.
///
/// # Errors
/// When the folder is not writable, `write` fails, or the rename fails; the target is untouched.
pub fn write_atomic(path: &Path, write: impl FnOnce(&mut BufWriter<&File>) -> Result<()>) -> Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    };
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("output");
    let prefix = format!(".{name}.");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    // `make_in` with our own open: its errors are the OS's alone, where `tempfile_in` would add
    // the temporary file's name, which no message should show (issue 15, D10); errors name
    // `path`, the file the user asked for.
    let tmp = builder.make_in(&dir, open_new).map_err(|e| Error::io(path, e))?;
    {
        let mut writer = BufWriter::with_capacity(1 << 20, tmp.as_file());
        write(&mut writer)?;
        writer.flush().map_err(|e| Error::io(path, e))?;
    }
    let written = tmp.as_file().metadata().map_err(|e| Error::io(path, e))?.len();
    crate::output_set::charge_write(path, written)?;
    tmp.persist(path).map_err(|e| Error::io(path, e.error))?;
    Ok(())
}

/// Creates `path`, which must not exist, for writing: mode 0644 less the umask on Unix (outputs
/// are ordinary files; tempfile's own files are private, 0600).
fn open_new(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o644);
    options.open(path)
}

/// Pixel layouts [`write_png`] accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PngLayout {
    Gray8,
    Gray16,
    Rgb8,
    Rgb16,
}

/// Writes a PNG from samples (`u16` for 16-bit layouts, values `<= 255` for 8-bit ones),
/// atomically, with fast compression (outputs here are large; size matters less than time).
///
/// # Errors
/// When the sample count is wrong or writing fails.
pub fn write_png(path: &Path, width: usize, height: usize, layout: PngLayout, samples: &[u16]) -> Result<()> {
    let row_len = width * layout.channels();
    if samples.len() != height * row_len {
        return Err(Error::InvalidParameter(format!(
            "{}: {} samples for a {width}x{height} image",
            path.display(),
            samples.len()
        )));
    }
    write_png_rows(path, width, height, layout, PngColour::for_layout(layout), |y, row| {
        row.copy_from_slice(&samples[y * row_len..(y + 1) * row_len])
    })
}

impl PngLayout {
    /// Samples per pixel.
    pub fn channels(self) -> usize {
        match self {
            PngLayout::Gray8 | PngLayout::Gray16 => 1,
            PngLayout::Rgb8 | PngLayout::Rgb16 => 3,
        }
    }
}

/// Rows encoded per batch: filled in parallel, then compressed in order.
const PNG_BATCH_ROWS: usize = 64;

/// Writes a PNG whose rows `fill_row(y, row)` produces (interleaved samples, `u16` even for 8-bit
/// layouts), atomically, without holding the whole image in memory. Rows are produced in parallel
/// batches while deflate, which is sequential, runs on the calling thread.
///
/// # Errors
/// When writing fails.
pub fn write_png_rows(
    path: &Path,
    width: usize,
    height: usize,
    layout: PngLayout,
    colour: PngColour,
    fill_row: impl Fn(usize, &mut [u16]) + Sync,
) -> Result<()> {
    write_png_rows_info(path, width, height, layout, &PngInfo { colour, text: &[] }, fill_row)
}

/// How a PNG's samples relate to light, written into the file so that readers (OpenImageIO,
/// Blender, browsers) do not guess: a guessed sRGB curve on linear data reads it 25 % too dark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PngColour {
    /// Display-encoded sRGB (8-bit pictures, renders, previews): an `sRGB` chunk.
    Srgb,
    /// Linear samples (16-bit albedo and photos) or data that is not a colour at all (normal,
    /// height, confidence and coordinate maps): `gAMA` 1.0 with sRGB primaries in `cHRM`.
    Linear,
}

impl PngColour {
    /// The encoding `write_png` assumes for a layout: 8-bit layouts are pictures (sRGB), 16-bit
    /// ones linear.
    pub fn for_layout(layout: PngLayout) -> PngColour {
        match layout {
            PngLayout::Gray8 | PngLayout::Rgb8 => PngColour::Srgb,
            PngLayout::Gray16 | PngLayout::Rgb16 => PngColour::Linear,
        }
    }
}

/// What a PNG says about itself besides its pixels: its colour encoding and `tEXt` entries
/// (keyword, text; Latin-1 keywords of 1-79 characters, as the PNG specification asks).
#[derive(Clone, Copy, Debug)]
pub struct PngInfo<'a> {
    pub colour: PngColour,
    pub text: &'a [(String, String)],
}

/// As [`write_png_rows`], with the colour encoding and text entries of `info`.
///
/// # Errors
/// When writing fails or a text entry is not valid for PNG.
pub fn write_png_rows_info(
    path: &Path,
    width: usize,
    height: usize,
    layout: PngLayout,
    info: &PngInfo,
    fill_row: impl Fn(usize, &mut [u16]) + Sync,
) -> Result<()> {
    use rayon::prelude::*;
    let (color, depth) = match layout {
        PngLayout::Gray8 => (png::ColorType::Grayscale, png::BitDepth::Eight),
        PngLayout::Gray16 => (png::ColorType::Grayscale, png::BitDepth::Sixteen),
        PngLayout::Rgb8 => (png::ColorType::Rgb, png::BitDepth::Eight),
        PngLayout::Rgb16 => (png::ColorType::Rgb, png::BitDepth::Sixteen),
    };
    let row_len = width * layout.channels();
    let row_bytes = row_len * if depth == png::BitDepth::Sixteen { 2 } else { 1 };
    let encode_err = |e: png::EncodingError| Error::Encode { path: path.to_owned(), reason: e.to_string() };
    write_atomic(path, |out| {
        let mut encoder = png::Encoder::new(out, width as u32, height as u32);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.set_compression(png::Compression::Fast);
        describe(&mut encoder, info).map_err(encode_err)?;
        let mut writer = encoder.write_header().map_err(encode_err)?;
        let mut stream = writer.stream_writer().map_err(encode_err)?;
        let mut bytes = vec![0u8; row_bytes * PNG_BATCH_ROWS.min(height)];
        for first in (0..height).step_by(PNG_BATCH_ROWS) {
            let rows = PNG_BATCH_ROWS.min(height - first);
            bytes[..rows * row_bytes].par_chunks_mut(row_bytes.max(1)).enumerate().for_each_init(
                || vec![0u16; row_len],
                |row, (i, out)| {
                    fill_row(first + i, row);
                    match depth {
                        png::BitDepth::Sixteen => out
                            .chunks_exact_mut(2)
                            .zip(row.iter())
                            .for_each(|(o, v)| o.copy_from_slice(&v.to_be_bytes())),
                        _ => out.iter_mut().zip(row.iter()).for_each(|(o, &v)| *o = v.min(255) as u8),
                    }
                },
            );
            stream.write_all(&bytes[..rows * row_bytes]).map_err(|e| Error::io(path, e))?;
        }
        stream.finish().map_err(encode_err)?;
        Ok(())
    })
}

/// Writes the colour chunks and text entries of `info` into the header `encoder` will write.
fn describe<W: Write>(encoder: &mut png::Encoder<W>, info: &PngInfo) -> std::result::Result<(), png::EncodingError> {
    match info.colour {
        PngColour::Srgb => encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual),
        PngColour::Linear => {
            encoder.set_source_gamma(png::ScaledFloat::new(1.0));
            encoder.set_source_chromaticities(png::SourceChromaticities::new(
                (0.3127, 0.3290),
                (0.64, 0.33),
                (0.30, 0.60),
                (0.15, 0.06),
            ));
        }
    }
    for (keyword, text) in info.text {
        encoder.add_text_chunk(keyword.clone(), text.clone())?;
    }
    Ok(())
}

/// EXR compressions ([`write_exr_rgb_compressed`]).
pub use exr::compression::Compression as ExrCompression;

/// Writes float RGB triples to an uncompressed scanline EXR file, atomically.
///
/// Uncompressed on purpose: float normals carry sensor noise in every mantissa bit, so the
/// compressors buy little for their time. `cargo bench -p skinkit-maps --bench codecs` on a
/// noisy 1024x1024 normal map (2-core machine at load 10): uncompressed 18 ms; RLE 120 ms and
/// no smaller; ZIP1 0.87 s for 0.9 % less; ZIP16 0.88 s for 5.8 % less; PIZ 1.09 s for 13 % less.
///
/// # Errors
/// When writing fails.
pub fn write_exr_rgb(
    path: &Path,
    width: usize,
    height: usize,
    pixel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) -> Result<()> {
    write_exr_rgb_compressed(path, width, height, ExrCompression::Uncompressed, pixel)
}

/// Writes float RGB triples to a scanline EXR file with `compression`, atomically, gathering and
/// compressing the blocks in parallel.
///
/// # Errors
/// When writing fails.
pub fn write_exr_rgb_compressed(
    path: &Path,
    width: usize,
    height: usize,
    compression: ExrCompression,
    pixel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) -> Result<()> {
    let fill = |y: usize, row: &mut [[f32; 3]]| row.iter_mut().enumerate().for_each(|(x, p)| *p = pixel(x, y));
    write_exr_rgb_rows(path, width, height, compression, fill)
}

/// [`write_exr_rgb_compressed`] with whole rows: `fill_row(y, row)` writes row `y`'s triples (rows
/// are asked for in order, in parallel batches).
///
/// # Errors
/// When writing fails.
pub fn write_exr_rgb_rows(
    path: &Path,
    width: usize,
    height: usize,
    compression: ExrCompression,
    fill_row: impl Fn(usize, &mut [[f32; 3]]) + Sync,
) -> Result<()> {
    write_atomic(path, |out| {
        crate::exr_write::write_rgb(out, width, height, compression, &fill_row)
            .map_err(|reason| Error::Encode { path: path.to_owned(), reason })
    })
}

pub use crate::exr_write::{Channel as ExrChannel, ExrOptions};

/// Writes named float channels (`"Y"` for one grey channel, `"R"`, `"G"`, `"B"` for three) as
/// one EXR layer with the compression, sample type and header attributes of `options`,
/// atomically.
///
/// # Errors
/// When a channel's length is not `width * height`, an attribute is not Latin-1 text, or writing
/// fails.
pub fn write_exr_channels(
    path: &Path,
    width: usize,
    height: usize,
    channels: &[ExrChannel],
    options: &ExrOptions,
) -> Result<()> {
    write_atomic(path, |out| {
        crate::exr_write::write_channels(out, width, height, channels, options)
            .map_err(|reason| Error::Encode { path: path.to_owned(), reason })
    })
}

/// Writes a normal map: `.exr` as float, `.png` as 16-bit (or 8-bit with `bits == 8`) RGB, with
/// invalid texels as all-zero pixels.
///
/// # Errors
/// When the extension is not `png` or `exr`, or writing fails.
pub fn write_normal_map(path: &Path, map: &NormalMap, encoding: NormalEncoding, bits: u32) -> Result<()> {
    let (w, texels) = (map.width(), map.as_slice());
    write_normal_rows(path, map.size(), encoding, bits, |y, row| row.copy_from_slice(&texels[y * w..(y + 1) * w]))
}

/// [`write_normal_map`] of a `w x h` map whose row `y` `fill_row(y, row)` gives (rows are asked
/// for in order, in parallel batches: [`crate::stream`] feeds them as they are computed).
///
/// # Errors
/// When the extension is not `png` or `exr`, or writing fails.
pub fn write_normal_rows(
    path: &Path,
    (w, h): (usize, usize),
    encoding: NormalEncoding,
    bits: u32,
    fill_row: impl Fn(usize, &mut [Vec3]) + Sync,
) -> Result<()> {
    let texels = |y: usize| filled_row(w, y, &fill_row);
    match ImageFormat::of(path) {
        Some(ImageFormat::Exr) => write_exr_rgb_rows(path, w, h, ExrCompression::Uncompressed, |y, out| {
            out.iter_mut().zip(texels(y)).for_each(|(o, n)| *o = encoding.encode_float(n));
        }),
        Some(ImageFormat::Png) => {
            let (max, layout) = if bits == 8 { (255, PngLayout::Rgb8) } else { (65535, PngLayout::Rgb16) };
            write_png_rows(path, w, h, layout, PngColour::Linear, |y, row| {
                for (out, n) in row.chunks_exact_mut(3).zip(texels(y)) {
                    out.copy_from_slice(&encoding.encode(n, max).map(|c| c as u16));
                }
            })
        }
        _ => Err(Error::InvalidParameter(format!(
            "{}: cannot write a normal map as `.{}` (use .png or .exr)",
            path.display(),
            extension(path)
        ))),
    }
}

/// Writes a linear colour map: 8-bit sRGB PNG when `bits == 8`, else 16-bit linear PNG; values
/// clamped to `[0, 1]`. `.exr` keeps floats unclamped.
///
/// # Errors
/// When writing fails or the extension is unknown.
pub fn write_color_map(path: &Path, map: &ColorMap, bits: u32) -> Result<()> {
    let (w, texels) = (map.width(), map.as_slice());
    write_color_rows(path, map.size(), bits, |y, row| row.copy_from_slice(&texels[y * w..(y + 1) * w]))
}

/// Row `y` of `w` texels as `fill_row` gives it.
fn filled_row(w: usize, y: usize, fill_row: &impl Fn(usize, &mut [Vec3])) -> Vec<Vec3> {
    let mut row = vec![Vec3::ZERO; w];
    fill_row(y, &mut row);
    row
}

/// [`write_color_map`] of a `w x h` map whose row `y` `fill_row(y, row)` gives (see
/// [`write_normal_rows`]).
///
/// # Errors
/// When the extension is not `png` or `exr`, or writing fails.
pub fn write_color_rows(
    path: &Path,
    (w, h): (usize, usize),
    bits: u32,
    fill_row: impl Fn(usize, &mut [Vec3]) + Sync,
) -> Result<()> {
    let texels = |y: usize| filled_row(w, y, &fill_row);
    match ImageFormat::of(path) {
        Some(ImageFormat::Exr) => write_exr_rgb_rows(path, w, h, ExrCompression::Uncompressed, |y, out| {
            out.iter_mut().zip(texels(y)).for_each(|(o, c)| *o = c.to_array());
        }),
        Some(ImageFormat::Png) => {
            let layout = if bits == 8 { PngLayout::Rgb8 } else { PngLayout::Rgb16 };
            write_png_rows(path, w, h, layout, PngColour::for_layout(layout), |y, row| {
                for (out, c) in row.chunks_exact_mut(3).zip(texels(y)) {
                    out.copy_from_slice(&c.to_array().map(|v| {
                        if bits == 8 {
                            (linear_to_srgb(v) * 255.0).round() as u16
                        } else {
                            (v.clamp(0.0, 1.0) * 65535.0).round() as u16
                        }
                    }));
                }
            })
        }
        _ => Err(Error::InvalidParameter(format!(
            "{}: cannot write a colour map as `.{}`",
            path.display(),
            extension(path)
        ))),
    }
}

/// Writes a scalar map as a grey PNG, mapping `[0, 1]` to full scale (8 or 16 bits), clamped.
///
/// # Errors
/// When writing fails.
pub fn write_scalar_png(path: &Path, map: &ScalarMap, bits: u32) -> Result<()> {
    let (w, h) = map.size();
    let (max, layout) = if bits == 8 { (255.0, PngLayout::Gray8) } else { (65535.0, PngLayout::Gray16) };
    write_png_rows(path, w, h, layout, PngColour::Linear, |y, row| {
        row.iter_mut().zip(map.row(y)).for_each(|(out, &v)| *out = quantise(v, max));
    })
}

/// `v` in `[0, 1]` (clamped; NaN gives 0) scaled to `[0, max]` and rounded.
fn quantise(v: f32, max: f32) -> u16 {
    (v.clamp(0.0, 1.0) * max + 0.5) as u16
}

/// Reads a grey (or RGB, luminance taken) image as a linear scalar map in `[0, 1]`.
///
/// # Errors
/// As [`read_photo`].
pub fn read_scalar_map(path: &Path, limits: &Limits) -> Result<ScalarMap> {
    let photo = read_photo(path, limits)?;
    Grid::from_vec(photo.width(), photo.height(), photo.luminance())
}

#[cfg(test)]
mod tests;
