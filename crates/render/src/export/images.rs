//! The export's textures as PNG bytes in memory: the albedo as 8-bit sRGB (glTF's
//! `baseColorTexture` must be sRGB-encoded) and the normal map as 8- or 16-bit linear RGB in
//! glTF's normal-texture convention.
//!
//! glTF's normal textures are green-up (OpenGL: `+y` toward the top of the image) with `[-1, 1]`
//! mapped to `[0, full scale]`, and glTF puts UV `(0, 0)` at the top-left of the image: both are
//! skinkit's own conventions (maps in memory are green-up, row 0 at the top, `v = 0` at the top),
//! so texels are written as they are, with no flip. skinkit's invalid texels (0, 0, 0) have no
//! meaning in glTF, where they would decode to (-1, -1, -1); they are written as the flat normal
//! (0, 0, 1), which is how skinkit's shader draws them ("no detail").

use glam::Vec3;
use skinkit_maps::encoding::{is_valid_normal, linear_to_srgb};
use skinkit_maps::{NormalEncoding, NormalMap};

use crate::shading::Texture;

/// Bit depth of the exported normal texture.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum NormalBits {
    /// 8-bit RGB PNG: what every viewer reads (at most about 0.3 degrees of quantisation).
    #[default]
    Eight,
    /// 16-bit RGB PNG: valid PNG and accepted by the validator, but some viewers quantise it to
    /// 8 bits on upload.
    Sixteen,
}

impl NormalBits {
    /// 8 or 16.
    pub fn bits(self) -> u32 {
        match self {
            NormalBits::Eight => 8,
            NormalBits::Sixteen => 16,
        }
    }

    /// The depth for 8 or 16, else `None`.
    pub fn from_bits(bits: u32) -> Option<NormalBits> {
        match bits {
            8 => Some(NormalBits::Eight),
            16 => Some(NormalBits::Sixteen),
            _ => None,
        }
    }
}

/// A PNG in memory and what it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Png {
    /// The encoded file.
    pub bytes: Vec<u8>,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bits per channel (8 or 16).
    pub bits: u32,
}

/// The albedo (linear RGBA, alpha ignored) as an 8-bit sRGB RGB PNG.
///
/// # Errors
/// The PNG encoder's message (it fails only on sizes PNG cannot hold).
pub(crate) fn albedo_png(albedo: &Texture) -> Result<Png, String> {
    let to_byte = |v: f32| (linear_to_srgb(v) * 255.0).round() as u16;
    let samples: Vec<u16> = albedo.texels.iter().flat_map(|t| [t[0], t[1], t[2]].map(to_byte)).collect();
    encode(albedo.width, albedo.height, 8, &samples)
}

/// The normal map as a green-up RGB PNG of `bits` depth, invalid texels as the flat normal.
/// Returns the PNG and the number of invalid texels replaced.
///
/// # Errors
/// As [`albedo_png`].
pub(crate) fn normal_png(map: &NormalMap, bits: NormalBits) -> Result<(Png, usize), String> {
    let max = if bits == NormalBits::Eight { 255 } else { 65535 };
    let encoding = NormalEncoding::default();
    let mut invalid = 0usize;
    let mut samples = Vec::with_capacity(3 * map.as_slice().len());
    for &n in map.as_slice() {
        let n = if is_valid_normal(n) {
            n
        } else {
            invalid += 1;
            Vec3::Z
        };
        samples.extend(encoding.encode(n, max).map(|c| c as u16));
    }
    let png = encode(map.width() as u32, map.height() as u32, bits.bits(), &samples)?;
    Ok((png, invalid))
}

/// Encodes interleaved RGB samples (`u16` even for 8-bit) as a PNG in memory.
fn encode(width: u32, height: u32, bits: u32, samples: &[u16]) -> Result<Png, String> {
    let mut bytes = Vec::new();
    let data: Vec<u8> = match bits {
        8 => samples.iter().map(|&v| v.min(255) as u8).collect(),
        _ => samples.iter().flat_map(|v| v.to_be_bytes()).collect(),
    };
    {
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(if bits == 8 { png::BitDepth::Eight } else { png::BitDepth::Sixteen });
        encoder.set_compression(png::Compression::Fast);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(&data).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())?;
    }
    Ok(Png { bytes, width, height, bits })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decode(png: &Png) -> (png::OutputInfo, Vec<u8>) {
        let decoder = png::Decoder::new(std::io::Cursor::new(png.bytes.as_slice()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        (info, buf)
    }

    #[test]
    fn normals_are_green_up_with_invalid_texels_flat() {
        let mut map = NormalMap::from_grid(skinkit_maps::Grid::filled(2, 1, Vec3::new(0.0, 0.6, 0.8)));
        map.set(1, 0, Vec3::ZERO);
        let (png, invalid) = normal_png(&map, NormalBits::Eight).unwrap();
        assert_eq!(invalid, 1);
        let (info, px) = decode(&png);
        assert_eq!((info.width, info.bit_depth), (2, png::BitDepth::Eight));
        // +y up is green above half scale: 0.6 -> (0.8 * 255).
        assert_eq!(&px[..3], &[128, 204, 230]);
        assert_eq!(&px[3..6], &[128, 128, 255]);
        let (png16, _) = normal_png(&map, NormalBits::Sixteen).unwrap();
        let (info, px) = decode(&png16);
        assert_eq!(info.bit_depth, png::BitDepth::Sixteen);
        assert_eq!(u16::from_be_bytes([px[2], px[3]]), (0.8f32 * 65535.0 + 0.5) as u16);
    }

    #[test]
    fn albedo_is_srgb_encoded() {
        let t = Texture::from_fn(1, 1, |_, _| [0.0, 0.214, 1.0, 1.0]);
        let (_, px) = decode(&albedo_png(&t).unwrap());
        assert_eq!(px[0], 0);
        assert!((px[1] as i32 - 128).abs() <= 1, "{}", px[1]);
        assert_eq!(px[2], 255);
    }
}
