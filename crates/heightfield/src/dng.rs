//! A minimal DNG writer for synthetic camera files (issue 39; tests and the accuracy stage): one little-endian TIFF directory holding an
//! uncompressed 16-bit Bayer mosaic with the tags a DNG reader needs to make it linear
//! (DNGVersion, CFARepeatPatternDim, CFAPattern, BlackLevel, WhiteLevel, Make and Model). No
//! preview, no colour matrices: what a lab camera's RAW holds beyond this, skinkit ignores.

/// A sensor's worth of samples and how to read them.
#[derive(Clone, Debug)]
pub struct Dng<'a> {
    pub width: u32,
    pub height: u32,
    /// Row-major samples, `width * height` of them.
    pub samples: &'a [u16],
    /// The 2x2 pattern as DNG codes it, rows concatenated: 0 red, 1 green, 2 blue (`[0, 1, 1,
    /// 2]` is RGGB).
    pub cfa: [u8; 4],
    pub black: u16,
    pub white: u16,
}

/// TIFF field types used here.
const SHORT: u16 = 3;
const LONG: u16 = 4;
const BYTE: u16 = 1;
const ASCII: u16 = 2;

/// One directory entry: tag, type, count and its value bytes (inline when 4 bytes or fewer).
struct Entry {
    tag: u16,
    kind: u16,
    count: u32,
    bytes: Vec<u8>,
}

fn short(tag: u16, v: u16) -> Entry {
    Entry { tag, kind: SHORT, count: 1, bytes: v.to_le_bytes().to_vec() }
}
fn long(tag: u16, v: u32) -> Entry {
    Entry { tag, kind: LONG, count: 1, bytes: v.to_le_bytes().to_vec() }
}
fn ascii(tag: u16, text: &str) -> Entry {
    let mut bytes = text.as_bytes().to_vec();
    bytes.push(0);
    Entry { tag, kind: ASCII, count: bytes.len() as u32, bytes }
}

/// The DNG file of `dng`, as bytes.
///
/// # Panics
/// When `samples` does not hold `width * height` values.
pub fn dng_bytes(dng: &Dng) -> Vec<u8> {
    assert_eq!(dng.samples.len(), dng.width as usize * dng.height as usize, "samples for {}x{}", dng.width, dng.height);
    let pixels: Vec<u8> = dng.samples.iter().flat_map(|v| v.to_le_bytes()).collect();
    let mut entries = vec![
        long(254, 0),
        long(256, dng.width),
        long(257, dng.height),
        short(258, 16),
        short(259, 1),
        short(262, 32803),
        ascii(271, "skinkit"),
        ascii(272, "synthetic sensor"),
        long(273, 0), // strip offset, filled in below
        short(277, 1),
        long(278, dng.height),
        long(279, pixels.len() as u32),
        Entry { tag: 33421, kind: SHORT, count: 2, bytes: [2u16, 2].iter().flat_map(|v| v.to_le_bytes()).collect() },
        Entry { tag: 33422, kind: BYTE, count: 4, bytes: dng.cfa.to_vec() },
        Entry { tag: 50706, kind: BYTE, count: 4, bytes: vec![1, 4, 0, 0] },
        long(50714, u32::from(dng.black)),
        long(50717, u32::from(dng.white)),
    ];
    let directory_len = 2 + 12 * entries.len() + 4;
    let extra_start = 8 + directory_len;
    let extra_len: usize =
        entries.iter().filter(|e| e.bytes.len() > 4).map(|e| e.bytes.len().next_multiple_of(2)).sum();
    let strip = (extra_start + extra_len) as u32;
    entries.iter_mut().find(|e| e.tag == 273).expect("strip offset").bytes = strip.to_le_bytes().to_vec();
    let mut out = b"II*\0".to_vec();
    out.extend_from_slice(&8u32.to_le_bytes());
    out.extend_from_slice(&(entries.len() as u16).to_le_bytes());
    let mut extra = Vec::new();
    for e in &entries {
        out.extend_from_slice(&e.tag.to_le_bytes());
        out.extend_from_slice(&e.kind.to_le_bytes());
        out.extend_from_slice(&e.count.to_le_bytes());
        if e.bytes.len() <= 4 {
            let mut inline = e.bytes.clone();
            inline.resize(4, 0);
            out.extend_from_slice(&inline);
        } else {
            out.extend_from_slice(&((extra_start + extra.len()) as u32).to_le_bytes());
            extra.extend_from_slice(&e.bytes);
            extra.resize(extra.len().next_multiple_of(2), 0);
        }
    }
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&extra);
    debug_assert_eq!(out.len(), strip as usize);
    out.extend_from_slice(&pixels);
    out
}

/// The DNG file of the sensor (pattern `cfa`, levels `black..white`, twice the size) that
/// recorded the linear RGB image `rgb` (`w x h`): [`mosaic_of_rgb`] written by [`dng_bytes`].
pub fn dng_of_rgb(rgb: &[[f32; 3]], w: usize, h: usize, cfa: [u8; 4], black: u16, white: u16) -> Vec<u8> {
    let samples = mosaic_of_rgb(rgb, w, h, cfa, black, white);
    dng_bytes(&Dng { width: 2 * w as u32, height: 2 * h as u32, samples: &samples, cfa, black, white })
}

/// The mosaic a sensor with pattern `cfa` records of the linear RGB image `rgb` (`w x h`, values
/// 0..1) at twice its size: each pixel becomes a 2x2 cell whose samples carry its own colours,
/// `black + v * (white - black)` rounded (so a half-size decode gives `rgb` back to within one
/// step).
pub fn mosaic_of_rgb(rgb: &[[f32; 3]], w: usize, h: usize, cfa: [u8; 4], black: u16, white: u16) -> Vec<u16> {
    let span = f32::from(white) - f32::from(black);
    let mut out = vec![0u16; 4 * w * h];
    for y in 0..2 * h {
        for x in 0..2 * w {
            let colour = cfa[(y % 2) * 2 + x % 2] as usize;
            let v = rgb[(y / 2) * w + x / 2][colour].clamp(0.0, 1.0);
            out[y * 2 * w + x] = (f32::from(black) + v * span).round() as u16;
        }
    }
    out
}
