//! A glTF file's material textures as a scene's maps: a scene whose `albedo` or `normal_map.path`
//! names a `.glb` or `.gltf` file takes that map from the file's first material (what
//! [`crate::export`] writes), so an exported head re-renders from the one file:
//!
//! ```toml
//! mesh = "head.glb"
//! mm_per_unit = 1000.0          # glTF positions are metres
//! albedo = "head.glb"           # the material's baseColorTexture (times its baseColorFactor)
//! [normal_map]
//! path = "head.glb"             # the material's normalTexture (green-up, as glTF defines it)
//! frames = "mikktspace"         # the tangent basis glTF's normal textures are made against
//! ```
//!
//! Images are read from a buffer view (GLB or `.gltf` alike) or a relative file URI, decoded as
//! skinkit decodes map files (PNG or TIFF; JPEG and data URIs are refused with the reason), under
//! the same size limits. The base colour texture is sRGB by glTF's definition whatever its depth.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use skinkit_maps::io::{self, Limits};
use skinkit_maps::{Channels, Grid, NormalEncoding, NormalMap, Photo, Samples, Transfer};

use crate::shading::Texture;

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case).
pub(crate) fn is_gltf(path: &Path) -> bool {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    matches!(ext.as_deref(), Some("gltf" | "glb"))
}

/// Which texture of the material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Slot {
    BaseColor,
    Normal,
}

impl Slot {
    fn name(self) -> &'static str {
        match self {
            Slot::BaseColor => "baseColorTexture",
            Slot::Normal => "normalTexture",
        }
    }
}

/// The base colour of `path`'s first material as linear RGBA (the texture decoded as sRGB, times
/// the material's `baseColorFactor`).
///
/// # Errors
/// An unreadable file, no material or no base colour texture, an unreadable image; the message
/// names the file, the material's texture and the image.
pub fn albedo(path: &Path, limits: &Limits) -> skinkit_maps::Result<Texture> {
    let (photo, factor) = image(path, Slot::BaseColor, limits)?;
    let photo = photo.with_transfer(Transfer::Srgb);
    let width = photo.width();
    Ok(Texture::from_fn(width as u32, photo.height() as u32, |x, y| {
        let i = y as usize * width + x as usize;
        let rgb = match photo.channels() {
            Channels::Gray => [photo.linear(i); 3],
            Channels::Rgb => [photo.linear(3 * i), photo.linear(3 * i + 1), photo.linear(3 * i + 2)],
        };
        [rgb[0] * factor[0], rgb[1] * factor[1], rgb[2] * factor[2], 1.0]
    }))
}

/// The normal texture of `path`'s first material, green-up (glTF's convention), all-zero texels
/// invalid as in skinkit's own maps.
///
/// # Errors
/// As [`albedo`], and a normal texture that is not RGB.
pub fn normal_map(path: &Path, limits: &Limits) -> skinkit_maps::Result<NormalMap> {
    let (photo, _) = image(path, Slot::Normal, limits)?;
    let named = image_name(path, Slot::Normal);
    if photo.channels() != Channels::Rgb {
        let reason = "a normal map needs three channels (RGB)".into();
        return Err(skinkit_maps::Error::Unsupported { path: named, reason });
    }
    let encoding = NormalEncoding::default();
    let normals = match photo.samples() {
        Samples::U8(s) => s.chunks_exact(3).map(|c| encoding.decode([c[0], c[1], c[2]].map(u32::from), 255)).collect(),
        Samples::U16(s) => {
            s.chunks_exact(3).map(|c| encoding.decode([c[0], c[1], c[2]].map(u32::from), 65535)).collect()
        }
        Samples::F32(s) => s.chunks_exact(3).map(|c| encoding.decode_float([c[0], c[1], c[2]])).collect(),
    };
    NormalMap::from_unit_grid(Grid::from_vec(photo.width(), photo.height(), normals)?)
}

/// How errors name an image inside a glTF file: `head.glb: normalTexture`.
fn image_name(path: &Path, slot: Slot) -> PathBuf {
    PathBuf::from(format!("{}: {}", path.display(), slot.name()))
}

/// The decoded image of `slot` in `path`'s first material, and the material's base colour factor.
fn image(path: &Path, slot: Slot, limits: &Limits) -> skinkit_maps::Result<(Photo, [f32; 4])> {
    let named = image_name(path, slot);
    let refuse = |reason: String| skinkit_maps::Error::Unsupported { path: named.clone(), reason };
    let io_error = |error| skinkit_maps::Error::Io { path: path.to_owned(), error };
    let bytes = skinkit_maps::input::read(path, skinkit_maps::input::Kind::Mesh)?;
    let gltf = crate::mesh::source::parse_gltf(&bytes).map_err(|reason| {
        io_error(std::io::Error::new(std::io::ErrorKind::InvalidData, format!("not a readable glTF file: {reason}")))
    })?;
    let material = gltf.document.materials().next().ok_or_else(|| refuse("the file has no material".into()))?;
    let pbr = material.pbr_metallic_roughness();
    let texture = match slot {
        Slot::BaseColor => pbr.base_color_texture().map(|t| t.texture()),
        Slot::Normal => material.normal_texture().map(|t| t.texture()),
    };
    let texture =
        texture.ok_or_else(|| refuse(format!("material {} has no {}", material_label(&material), slot.name())))?;
    let base = path.parent().unwrap_or(Path::new("."));
    let photo = match texture.source().source() {
        gltf::image::Source::View { view, .. } => {
            let data = view_bytes(&gltf, &view, base).map_err(refuse)?;
            io::decode_photo(&named, Cursor::new(data), limits)?
        }
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
            return Err(refuse("images in data URIs are not read: use a GLB or an image file".into()));
        }
        gltf::image::Source::Uri { uri, .. } => io::read_photo(&base.join(uri_path(uri).map_err(refuse)?), limits)?,
    };
    Ok((photo, pbr.base_color_factor()))
}

fn material_label(material: &gltf::Material) -> String {
    match (material.index(), material.name()) {
        (Some(i), Some(name)) => format!("{i} (`{name}`)"),
        (Some(i), None) => i.to_string(),
        (None, _) => "(default)".into(),
    }
}

/// The bytes of a buffer view: from the GLB's binary chunk or an external buffer file (read
/// through the input gate, [`skinkit_maps::input`]).
fn view_bytes(gltf: &gltf::Gltf, view: &gltf::buffer::View, base: &Path) -> Result<Vec<u8>, String> {
    crate::mesh::source::check_gltf_buffer_uris(&gltf.document)?;
    let buffer = view.buffer();
    let external;
    let data: &[u8] = match buffer.source() {
        gltf::buffer::Source::Bin => gltf.blob.as_deref().ok_or("the GLB has no binary chunk")?,
        gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
            return Err("buffers in data URIs are not read: use a GLB or a .bin file".into());
        }
        gltf::buffer::Source::Uri(uri) => {
            let file = base.join(uri_path(uri)?);
            external = skinkit_maps::input::read(&file, skinkit_maps::input::Kind::GltfBuffer)
                .map_err(|e| format!("buffer {}: {e}", buffer.index()))?;
            &external
        }
    };
    let (start, length) = (view.offset(), view.length());
    let end = start.checked_add(length).filter(|&end| end <= data.len()).ok_or_else(|| {
        format!(
            "bufferView {} (bytes {start}..{}) lies past the end of its buffer ({} bytes)",
            view.index(),
            start.saturating_add(length),
            data.len()
        )
    })?;
    Ok(data[start..end].to_vec())
}

/// A relative URI as a path: percent-escapes decoded; absolute and scheme URIs refused.
fn uri_path(uri: &str) -> Result<PathBuf, String> {
    let decoded = crate::mesh::source::percent_decode(uri)
        .ok_or_else(|| format!("uri `{uri}`: its percent-encoding is not UTF-8"))?;
    if decoded.contains("://") || Path::new(&decoded).is_absolute() {
        return Err(format!("uri `{uri}`: only relative file URIs are read"));
    }
    Ok(PathBuf::from(decoded))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_relative_file_uris_are_read() {
        assert_eq!(uri_path("maps/head%20normal.png").unwrap(), PathBuf::from("maps/head normal.png"));
        assert!(uri_path("/etc/passwd").unwrap_err().contains("only relative file URIs"));
        assert!(uri_path("https://example.invalid/a.png").unwrap_err().contains("only relative file URIs"));
        assert!(uri_path("%FF.png").unwrap_err().contains("not UTF-8"));
        assert!(is_gltf(Path::new("a/HEAD.GLB")) && is_gltf(Path::new("h.gltf")) && !is_gltf(Path::new("h.png")));
    }

    #[test]
    fn a_file_that_is_not_gltf_is_named_with_the_reason() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.glb");
        std::fs::write(&path, b"not a glTF file").unwrap();
        let error = skinkit_maps::error::one_line(&albedo(&path, &Limits::default()).unwrap_err());
        assert!(error.contains("x.glb: not a readable glTF file"), "{error}");
    }
}
