//! Writing float RGB EXR files with the pixel gathering and the compression spread over the rayon
//! pool.
//!
//! The `exr` crate's image writer gathers every block's pixels on the calling thread and, for an
//! uncompressed file, writes them on that thread too (its parallel compressor declines
//! uncompressed layers), so a 4096x4096 float map took 0.86 s to save, one core busy (issue 12).
//! Here the header comes from the same `exr` image description, so the file is byte for byte the
//! one `exr`'s own writer produces (a test checks it), but blocks are gathered and compressed in
//! parallel batches and handed to `exr`'s chunk writer in file order, so memory stays at one
//! batch of blocks.

use std::io::{Seek, Write};

use exr::block::UncompressedBlock;
use exr::block::chunk::Chunk;
use exr::block::writer::ChunksWriter;
use exr::compression::Compression;
use exr::meta::header::Header;
use exr::prelude::{Encoding, Image, Layer, LayerAttributes, SpecificChannels, Vec2, WritableImage};
use rayon::prelude::*;

/// Rows gathered per parallel batch (whole blocks; at least one block per batch).
const BATCH_ROWS: usize = 128;

/// Writes `width x height` float RGB pixels, row `y` filled by `fill_row(y, row)`, as a scanline EXR with
/// `compression` to `out`.
///
/// # Errors
/// The `exr` crate's, as text: when a write fails or the layer is invalid (zero size).
pub(crate) fn write_rgb(
    out: impl Write + Seek,
    width: usize,
    height: usize,
    compression: Compression,
    fill_row: &(impl Fn(usize, &mut [[f32; 3]]) + Sync),
) -> Result<(), String> {
    let headers = headers(width, height, compression);
    exr::block::write(out, headers, true, |meta, writer| {
        let header = &meta.headers[0];
        let components = components(header);
        let blocks: Vec<_> = meta.enumerate_ordered_header_block_indices().collect();
        let per_batch = (BATCH_ROWS / header.compression.scan_lines_per_block()).max(1);
        for batch in blocks.chunks(per_batch) {
            let chunks: Vec<exr::error::Result<Chunk>> = batch
                .par_iter()
                .map(|(_, index)| {
                    let data = block_bytes(index.pixel_position, index.pixel_size, &components, (width, fill_row));
                    UncompressedBlock { index: *index, data }.compress_to_chunk(&meta.headers)
                })
                .collect();
            for ((in_header, _), chunk) in batch.iter().zip(chunks) {
                writer.write_chunk(*in_header, chunk?)?;
            }
        }
        Ok(())
    })
    .map_err(|e| e.to_string())
}

/// The header `exr`'s image writer would infer for an RGB f32 scanline layer (so the files match).
fn headers(width: usize, height: usize, compression: Compression) -> exr::meta::Headers {
    let channels = SpecificChannels::rgb(|_: Vec2<usize>| (0.0f32, 0.0f32, 0.0f32));
    let encoding = Encoding { compression, ..Encoding::UNCOMPRESSED };
    let layer = Layer::new((width, height), LayerAttributes::default(), encoding, channels);
    Image::from_layer(layer).write().infer_meta_data()
}

/// For each channel of the header in file order (alphabetical: B, G, R), the index of its
/// component in an `[r, g, b]` triple.
fn components(header: &Header) -> Vec<usize> {
    header
        .channels
        .list
        .iter()
        .map(|c| match c.name.to_string().as_str() {
            "R" => 0,
            "G" => 1,
            "B" => 2,
            other => unreachable!("the layer was built with R, G and B only, not {other}"),
        })
        .collect()
}

/// One block's samples as `exr` wants them before compression: per row, each channel's samples
/// in turn, native-endian f32.
fn block_bytes(
    position: Vec2<usize>,
    size: Vec2<usize>,
    components: &[usize],
    (width, fill_row): (usize, &impl Fn(usize, &mut [[f32; 3]])),
) -> Vec<u8> {
    let (x0, y0, w) = (position.x(), position.y(), size.width());
    let mut data = Vec::with_capacity(w * size.height() * components.len() * 4);
    let mut row = vec![[0.0f32; 3]; width];
    for y in y0..y0 + size.height() {
        fill_row(y, &mut row);
        for &c in components {
            data.extend(row[x0..x0 + w].iter().flat_map(|p| p[c].to_ne_bytes()));
        }
    }
    data
}

/// Float samples of one named channel, row-major.
pub struct Channel<'a> {
    pub name: &'a str,
    pub samples: &'a [f32],
}

/// How a float EXR is stored: its compression, half or full floats, and text attributes to add
/// to its header (unit, scale, what made it).
#[derive(Clone, Debug)]
pub struct ExrOptions {
    pub compression: Compression,
    /// Store 16-bit half floats (half the size; about 3 decimal digits).
    pub half: bool,
    /// `(name, text)` attributes; readers that do not know a name keep or ignore it. The `exr`
    /// crate writes them in hash-map order, which differs between processes: give one for
    /// files whose bytes must not change from run to run.
    pub attributes: Vec<(String, String)>,
    /// The OpenEXR `wrapmodes` attribute (`"periodic,periodic"` for a map that tiles).
    pub wrap_modes: Option<String>,
}

impl Default for ExrOptions {
    fn default() -> Self {
        ExrOptions { compression: Compression::Uncompressed, half: false, attributes: Vec::new(), wrap_modes: None }
    }
}

/// Writes named float channels of `width x height` samples as one scanline layer.
///
/// # Errors
/// The `exr` crate's, as text: a write failure, a channel of the wrong length or no channel.
pub(crate) fn write_channels(
    out: impl Write + Seek,
    width: usize,
    height: usize,
    channels: &[Channel],
    options: &ExrOptions,
) -> Result<(), String> {
    use exr::image::{AnyChannel, AnyChannels, FlatSamples};
    use exr::meta::attribute::{AttributeValue, Text};
    if channels.is_empty() || channels.iter().any(|c| c.samples.len() != width * height) {
        return Err(format!("{} channels for {width}x{height} samples", channels.len()));
    }
    let list = channels
        .iter()
        .map(|c| {
            let samples = if options.half {
                FlatSamples::F16(c.samples.iter().map(|&v| exr::prelude::f16::from_f32(v)).collect())
            } else {
                FlatSamples::F32(c.samples.to_vec())
            };
            AnyChannel::new(c.name, samples)
        })
        .collect();
    let mut attributes = LayerAttributes::default();
    for (name, text) in &options.attributes {
        let value = Text::new_or_none(text).ok_or_else(|| format!("attribute {name}: not a Latin-1 text"))?;
        let key = Text::new_or_none(name).ok_or_else(|| format!("attribute name {name}: not a Latin-1 text"))?;
        attributes.other.insert(key, AttributeValue::Text(value));
    }
    attributes.wrap_mode_name = options.wrap_modes.as_deref().and_then(Text::new_or_none);
    let encoding = Encoding { compression: options.compression, ..Encoding::UNCOMPRESSED };
    let layer = Layer::new((width, height), attributes, encoding, AnyChannels::sort(list));
    Image::from_layer(layer).write().to_buffered(out).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pattern(x: usize, y: usize) -> [f32; 3] {
        let v = (x * 31 + y * 17) as f32;
        [v.sin(), (v * 0.37).cos(), 1.0 / (1.0 + v)]
    }

    /// The parallel writer against `exr`'s own image writer: identical bytes for every
    /// compression (odd sizes, several batches, a partial last block).
    #[test]
    fn bytes_match_exr_image_writer() {
        let (w, h) = (37, 3 * BATCH_ROWS + 21);
        for compression in
            [Compression::Uncompressed, Compression::RLE, Compression::ZIP1, Compression::ZIP16, Compression::PIZ]
        {
            let mut ours = std::io::Cursor::new(Vec::new());
            let fill =
                |y: usize, row: &mut [[f32; 3]]| row.iter_mut().enumerate().for_each(|(x, p)| *p = pattern(x, y));
            write_rgb(&mut ours, w, h, compression, &fill).unwrap();
            let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
                let [r, g, b] = pattern(pos.x(), pos.y());
                (r, g, b)
            });
            let encoding = Encoding { compression, ..Encoding::UNCOMPRESSED };
            let image = Image::from_layer(Layer::new((w, h), LayerAttributes::default(), encoding, channels));
            let mut theirs = std::io::Cursor::new(Vec::new());
            image.write().to_buffered(&mut theirs).unwrap();
            assert!(ours.get_ref() == theirs.get_ref(), "{compression:?}: files differ");
        }
    }
}
