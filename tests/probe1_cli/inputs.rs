//! The hostile inputs of the first probe, made in Rust: PNGs streamed row by row (a 32768 x
//! 32768 image of zeros costs a few megabytes and little memory), a PNG header claiming
//! 100000 x 100000 with nothing after it, the smallest baseline JPEG decoders accept, glTF files
//! whose accessors lie, rigs that cannot determine a normal, and seeded noise.

use std::io::Write;
use std::path::Path;

/// A seeded xorshift generator: the inputs are the same on every run.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// A `width` x `height` grey PNG of `bits` (8 or 16) whose every sample is `value`, encoded a
/// row at a time.
pub fn grey_png(path: &Path, width: u32, height: u32, bits: u8, value: u16) {
    let row: Vec<u8> = match bits {
        8 => vec![value as u8; width as usize],
        _ => (0..width).flat_map(|_| value.to_be_bytes()).collect(),
    };
    let depth = if bits == 8 { png::BitDepth::Eight } else { png::BitDepth::Sixteen };
    stream_png(path, (width, height), png::ColorType::Grayscale, depth, |_| row.clone());
}

/// A `width` x `height` 16-bit RGB PNG whose texels are `texel(x, y)`.
pub fn rgb16_png(path: &Path, width: u32, height: u32, mut texel: impl FnMut(u32, u32) -> [u16; 3]) {
    stream_png(path, (width, height), png::ColorType::Rgb, png::BitDepth::Sixteen, |y| {
        (0..width).flat_map(|x| texel(x, y)).flat_map(u16::to_be_bytes).collect()
    });
}

fn stream_png(
    path: &Path,
    (width, height): (u32, u32),
    colour: png::ColorType,
    depth: png::BitDepth,
    mut row: impl FnMut(u32) -> Vec<u8>,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut encoder = png::Encoder::new(file, width, height);
    encoder.set_color(colour);
    encoder.set_depth(depth);
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    for y in 0..height {
        stream.write_all(&row(y)).unwrap();
    }
    stream.finish().unwrap();
}

/// The first 33 bytes of a PNG: its signature and a valid IHDR claiming `width` x `height`
/// 8-bit grey, and nothing else (what a decoder must refuse from the header).
pub fn png_header_only(path: &Path, width: u32, height: u32) {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(width.to_be_bytes());
    ihdr.extend(height.to_be_bytes());
    ihdr.extend([8, 0, 0, 0, 0]);
    let mut bytes = b"\x89PNG\r\n\x1a\n".to_vec();
    bytes.extend(13u32.to_be_bytes());
    bytes.extend(&ihdr);
    bytes.extend(crc32(&ihdr).to_be_bytes());
    assert_eq!(bytes.len(), 33);
    std::fs::write(path, bytes).unwrap();
}

/// The CRC of PNG chunks (ISO 3309, reflected polynomial 0xedb88320).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xedb8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}

/// Standard luminance DC table (JPEG Annex K): how many codes of each length, then the
/// categories 0..11 they code.
const DC_BITS: [u8; 16] = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];

/// A greyscale baseline JPEG of flat 8x8 blocks of seeded levels (width and height rounded up to
/// 8): DC coefficients only, an all-ones quantisation table, the standard DC Huffman table and an
/// AC table holding only end-of-block. The smallest encoder decoders accept.
pub fn jpeg(path: &Path, width: u16, height: u16, seed: u64) {
    let codes = huffman_codes(&DC_BITS);
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let (mut bits, mut previous) = (BitWriter::default(), 0i32);
    let blocks = usize::from(height.div_ceil(8)) * usize::from(width.div_ceil(8));
    for _ in 0..blocks {
        let level = 60 + (rng.next() % 141) as i32;
        // The DC coefficient of a flat block under an all-ones table.
        let dc = 8 * (level - 128);
        let diff = dc - previous;
        previous = dc;
        let category = 32 - diff.unsigned_abs().leading_zeros();
        let (code, length) = codes[category as usize];
        bits.put(code, length);
        if category > 0 {
            let magnitude = if diff > 0 { diff } else { diff + (1 << category) - 1 };
            bits.put(magnitude as u32, category);
        }
        // End of block: the only AC symbol, code `0`.
        bits.put(0, 1);
    }
    let segment = |marker: u8, data: &[u8]| {
        let mut s = vec![0xff, marker];
        s.extend((data.len() as u16 + 2).to_be_bytes());
        s.extend(data);
        s
    };
    let mut frame = vec![8];
    frame.extend(height.to_be_bytes());
    frame.extend(width.to_be_bytes());
    frame.extend([1, 1, 0x11, 0]);
    let mut dc_table = vec![0x00];
    dc_table.extend(DC_BITS);
    dc_table.extend(0..12u8);
    let mut ac_table = vec![0x10, 1];
    ac_table.extend([0; 15]);
    ac_table.push(0);
    let mut out = vec![0xff, 0xd8];
    out.extend(segment(0xe0, b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0"));
    out.extend(segment(0xdb, &[[0u8].as_slice(), &[1; 64]].concat()));
    out.extend(segment(0xc0, &frame));
    out.extend(segment(0xc4, &dc_table));
    out.extend(segment(0xc4, &ac_table));
    out.extend(segment(0xda, &[1, 1, 0, 0, 0x3f, 0]));
    out.extend(bits.finish());
    out.extend([0xff, 0xd9]);
    std::fs::write(path, out).unwrap();
}

/// The canonical Huffman (code, length) of each symbol 0.. given the count of codes of each
/// length (JPEG Annex C).
fn huffman_codes(bits: &[u8; 16]) -> Vec<(u32, u32)> {
    let (mut codes, mut code) = (Vec::new(), 0u32);
    for (length, &count) in (1..=16).zip(bits) {
        for _ in 0..count {
            codes.push((code, length));
            code += 1;
        }
        code <<= 1;
    }
    codes
}

/// Entropy-coded bits, most significant first, a 0 stuffed after every 0xff byte.
#[derive(Default)]
struct BitWriter {
    out: Vec<u8>,
    acc: u8,
    n: u32,
}

impl BitWriter {
    fn put(&mut self, value: u32, length: u32) {
        for i in (0..length).rev() {
            self.acc = (self.acc << 1) | ((value >> i) & 1) as u8;
            self.n += 1;
            if self.n == 8 {
                self.out.push(self.acc);
                if self.acc == 0xff {
                    self.out.push(0);
                }
                (self.acc, self.n) = (0, 0);
            }
        }
    }

    /// The bytes, the last padded with ones.
    fn finish(mut self) -> Vec<u8> {
        while self.n != 0 {
            self.put(1, 1);
        }
        self.out
    }
}

/// How a glTF file lies about its buffer.
#[derive(Clone, Copy)]
pub enum GltfLie {
    /// The POSITION accessor claims a million vertices over a 36-byte view.
    Overrun,
    /// The indices' bufferView starts past the buffer's end.
    Offset,
}

/// A one-triangle glTF with an embedded buffer, lying as `lie` says.
pub fn gltf(path: &Path, lie: GltfLie) {
    let mut data: Vec<u8> =
        [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].concat().iter().flat_map(|v| v.to_le_bytes()).collect();
    data.extend([[0.0f32, 1.0], [1.0, 1.0], [0.0, 0.0]].concat().iter().flat_map(|v| v.to_le_bytes()));
    data.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    data.extend([0, 0]);
    let count = if matches!(lie, GltfLie::Overrun) { 1_000_000 } else { 3 };
    let index_offset = if matches!(lie, GltfLie::Offset) { 4096 } else { 60 };
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "buffers": [{"uri": format!("data:application/octet-stream;base64,{}", base64(&data)), "byteLength": data.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": index_offset, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    });
    std::fs::write(path, doc.to_string()).unwrap();
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let n = chunk.iter().enumerate().fold(0u32, |n, (i, &b)| n | u32::from(b) << (16 - 8 * i));
        for i in 0..4 {
            let c = if i <= chunk.len() { ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' };
            out.push(c);
        }
    }
    out
}

/// `n` seeded random bytes.
pub fn noise(path: &Path, n: usize, seed: u64) {
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    std::fs::write(path, (0..n).map(|_| rng.next() as u8).collect::<Vec<u8>>()).unwrap();
}

/// The rigs the probe fed `rig check` and `capture`.
#[derive(Clone, Copy)]
pub enum Rig {
    /// 8 lights, two directions repeated: rank 2.
    Rank2,
    /// 8 lights, all in the plane y = 0.
    Coplanar,
    /// 8 lights on an arc in the x-z plane, y alternating +-0.012: condition number near 68,
    /// over capture's limit of 50.
    NearCoplanar,
    /// 200 lights on rings, over the limit of 128.
    Lights200,
    /// A good ring of 8 naming a missing ambient frame.
    Ambient,
    /// A good ring of 8, every light positioned at (0, 0, 0), on the mold plane.
    Positions,
}

/// 8 lights evenly on a ring at 45 degrees of elevation.
fn ring() -> Vec<[f64; 3]> {
    let c = 0.5f64.sqrt();
    (0..8).map(|i| std::f64::consts::TAU * f64::from(i) / 8.0).map(|a| [a.cos() * c, a.sin() * c, c]).collect()
}

fn lights(directions: &[[f64; 3]], per_light: &str) -> String {
    directions.iter().map(|[x, y, z]| format!("[[light]]\ndirection = [{x:?}, {y:?}, {z:?}]\n{per_light}")).collect()
}

/// Writes the rig `kind` at `path`.
pub fn rig(path: &Path, kind: Rig) {
    let text = match kind {
        Rig::Rank2 => {
            let r = ring();
            lights(&[r[0], r[2]].repeat(4), "")
        }
        Rig::Coplanar => {
            let arc = (0..8).map(|i| (30.0 + 15.0 * f64::from(i)).to_radians());
            lights(&arc.map(|a| [a.cos(), 0.0, a.sin()]).collect::<Vec<_>>(), "")
        }
        Rig::NearCoplanar => {
            let arc = (0..8).map(|i| (i, (30.0 + 120.0 * f64::from(i) / 7.0).to_radians()));
            lights(
                &arc.map(|(i, a)| [a.cos(), if i % 2 == 0 { 0.012 } else { -0.012 }, a.sin()]).collect::<Vec<_>>(),
                "",
            )
        }
        Rig::Lights200 => {
            let direction = |i: u32| {
                let elevation = (25.0 + 50.0 * f64::from(i % 5) / 4.0).to_radians();
                let azimuth = std::f64::consts::TAU * f64::from(i) / 200.0;
                [elevation.cos() * azimuth.cos(), elevation.cos() * azimuth.sin(), elevation.sin()]
            };
            lights(&(0..200).map(direction).collect::<Vec<_>>(), "")
        }
        Rig::Ambient => format!("ambient = \"nope.png\"\n{}", lights(&ring(), "")),
        Rig::Positions => format!("mm_per_pixel = 0.05\n{}", lights(&ring(), "position = [0.0, 0.0, 0.0]\n")),
    };
    std::fs::write(path, text).unwrap();
}

#[test]
fn the_generators_write_what_decoders_read() {
    let tmp = tempfile::tempdir().unwrap();
    let grey = tmp.path().join("grey.png");
    grey_png(&grey, 40, 30, 16, 30000);
    let decoded = image::open(&grey).unwrap().into_luma16();
    assert_eq!((decoded.dimensions(), decoded.get_pixel(39, 29).0), ((40, 30), [30000]));
    let rgb = tmp.path().join("rgb.png");
    rgb16_png(&rgb, 3, 2, |x, y| [x as u16, y as u16, 7]);
    assert_eq!(image::open(&rgb).unwrap().into_rgb16().get_pixel(2, 1).0, [2, 1, 7]);
    let header = tmp.path().join("header.png");
    png_header_only(&header, 100_000, 100_000);
    // What a decoder reads first: the signature, then IHDR's length, type, width and height.
    let bytes = std::fs::read(&header).unwrap();
    assert_eq!(&bytes[..16], b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR");
    assert_eq!((&bytes[16..20], &bytes[20..24]), (&100_000u32.to_be_bytes()[..], &100_000u32.to_be_bytes()[..]));
    assert_eq!(u32::from_be_bytes(bytes[29..33].try_into().unwrap()), crc32(&bytes[12..29]));
    assert_eq!(crc32(b"IEND"), 0xae42_6082);
    assert_eq!(base64(b"skinkit"), "c2tpbmtpdA==");
    let gltf_path = tmp.path().join("t.gltf");
    gltf(&gltf_path, GltfLie::Overrun);
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&gltf_path).unwrap()).unwrap();
    assert_eq!(doc["accessors"][0]["count"], 1_000_000);
    // The JPEG's markers are in place; the binary's own refusal (case 1.12) checks it is JPEG.
    let jpeg_path = tmp.path().join("j.jpg");
    jpeg(&jpeg_path, 16, 16, 1);
    let bytes = std::fs::read(&jpeg_path).unwrap();
    assert_eq!((&bytes[..2], &bytes[bytes.len() - 2..]), (&[0xff, 0xd8][..], &[0xff, 0xd9][..]));
}
