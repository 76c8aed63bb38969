//! The peer, the `texture-synthesis` crate (Embark's multiresolution stochastic synthesis on 8-bit
//! images), fed each exemplar the way a user would: colour as 8-bit sRGB, normals as an 8-bit RGB
//! normal map. Tiling on, since skinkit's outputs tile and the energy reads windows across the
//! wrap; default parameters otherwise; the machine's threads.

use glam::Vec3;
use skinkit_maps::{Grid, NormalEncoding, NormalMap};
use texture_synthesis::image::{DynamicImage, RgbImage, RgbaImage};
use texture_synthesis::{Dims, Example, Session};

use crate::exemplars::Texels;

/// Largest 8-bit code.
const MAX_CODE: u32 = 255;

/// One peer output: its texels (decoded as the exemplar's kind) and the exemplar texel each copies.
pub struct PeerOutput {
    pub texels: Texels,
    pub coords: Grid<[u32; 2]>,
}

pub fn threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The exemplar as the 8-bit image a user would give the peer.
fn encode(texels: &Texels) -> RgbImage {
    let grid = texels.grid();
    let (w, h) = grid.size();
    let encoding = NormalEncoding::default();
    let bytes = grid
        .as_slice()
        .iter()
        .flat_map(|&v| match texels {
            Texels::Normal(_) => encoding.encode(v, MAX_CODE).map(|c| c as u8),
            Texels::Color(_) => (v * 255.0).round().clamp(Vec3::ZERO, Vec3::splat(255.0)).to_array().map(|c| c as u8),
        })
        .collect();
    RgbImage::from_raw(w as u32, h as u32, bytes).expect("buffer holds the exemplar")
}

/// Decodes an RGBA output as the exemplar's kind.
fn decode(rgba: &RgbaImage, normal: bool) -> Texels {
    let (w, h) = (rgba.width() as usize, rgba.height() as usize);
    let encoding = NormalEncoding::default();
    let texels: Vec<Vec3> = rgba
        .as_raw()
        .chunks_exact(4)
        .map(|p| {
            let rgb = [p[0], p[1], p[2]].map(u32::from);
            if normal {
                encoding.decode(rgb, MAX_CODE)
            } else {
                Vec3::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32) / 255.0
            }
        })
        .collect();
    let grid = Grid::from_vec(w, h, texels).expect("sizes match");
    if normal {
        Texels::Normal(NormalMap::from_unit_grid(grid).expect("decoded normals are unit or zero"))
    } else {
        Texels::Color(grid)
    }
}

/// The coordinate map of a peer output, from its serialised coordinate transform (native-endian
/// `u32`s: a 4-word header, two words per example, then `x, y, example` per output texel).
fn coords(generated: &texture_synthesis::GeneratedImage, width: usize, height: usize) -> Grid<[u32; 2]> {
    let mut bytes = Vec::new();
    generated.get_coordinate_transform().write(&mut bytes).expect("writes to memory");
    let words: Vec<u32> = bytes.chunks_exact(4).map(|b| u32::from_ne_bytes([b[0], b[1], b[2], b[3]])).collect();
    let examples = words[3] as usize;
    let body = &words[4 + 2 * examples..];
    let pairs = body.chunks_exact(3).map(|t| [t[0], t[1]]).collect();
    Grid::from_vec(width, height, pairs).expect("one transform per output texel")
}

/// One peer synthesis of a `width x height` output.
pub fn run(texels: &Texels, width: usize, height: usize, seed: u64) -> PeerOutput {
    let session = Session::builder()
        .add_example(Example::new(DynamicImage::ImageRgb8(encode(texels))))
        .output_size(Dims::new(width as u32, height as u32))
        .seed(seed)
        .tiling_mode(true)
        .max_thread_count(threads())
        .build()
        .expect("the peer accepts the exemplar");
    let generated = session.run(None);
    let coords = coords(&generated, width, height);
    let rgba: &RgbaImage = generated.as_ref();
    PeerOutput { texels: decode(rgba, matches!(texels, Texels::Normal(_))), coords }
}
