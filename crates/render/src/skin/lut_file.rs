//! The pre-integrated tables ([`super::lut`], [`super::shadow`]) as float RGB OpenEXR files, with
//! their definitions in header attributes so another engine can read one without guessing.
//!
//! Pixels are 32-bit float R, G, B, uncompressed, row 0 of the image = row 0 of the table (the
//! top). Attributes (all in the layer header):
//!
//! | name | type | value |
//! | --- | --- | --- |
//! | `skinkit.table` | text | `diffuse` or `shadow` |
//! | `skinkit.x`, `skinkit.y` | text | what the columns and rows hold |
//! | `skinkit.cache_key` | text | the spec's cache key |
//! | `skinkit.profile` | text | the diffusion profile |
//! | `skinkit.normalisation` | text | `2d` or `1d` (diffuse) |
//! | `skinkit.domain` | text | `full` or `half` (diffuse) |
//! | `skinkit.inv_r_min`, `skinkit.inv_r_max` | f32 | curvature range, 1/mm (diffuse) |
//! | `skinkit.filter` | text | `disc` (shadow: the lit share of a disc of taps on the skin) |
//! | `skinkit.new_penumbra` | f32 | new penumbra width / filtered width (shadow) |
//! | `skinkit.w_min_mm`, `skinkit.w_max_mm` | f32 | penumbra width range, mm (shadow) |
//! | `skinkit.profile_slice` | text | `marginal` (shadow) |
//!
//! Files are written atomically ([`skinkit_maps::io::write_atomic`]). Readers come in a pair:
//! [`read`] loads a file and calls [`decode`] on its bytes; [`LutImage::into_diffuse`] and
//! [`LutImage::into_shadow`] turn what was read back into a table with its spec.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use exr::meta::attribute::{AttributeValue, Text};
use exr::prelude::{
    Encoding, Image, Layer, LayerAttributes, ReadChannels, ReadLayers, SpecificChannels, Vec2, WritableImage,
};

use super::lut::{DiffuseLut, DiffuseLutSpec, MAX_SIDE};
use super::profile::{Domain, Normalisation};
use super::shadow::{ShadowLut, ShadowLutSpec};

/// Errors reading or writing a table file; messages name the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LutFileError {
    /// Writing failed (the folder, the encoder or the rename); the target is untouched.
    #[error(transparent)]
    Write(#[from] skinkit_maps::Error),
    /// The file could not be read.
    #[error("{path}")]
    Io {
        path: String,
        #[source]
        error: std::io::Error,
    },
    /// The input gate refused the file or could not read it ([`skinkit_maps::input`]).
    #[error(transparent)]
    Input(#[from] skinkit_maps::input::InputError),
    /// Not an RGB float EXR this module can read.
    #[error("{path}: not a readable table: {reason}")]
    Decode { path: String, reason: String },
    /// Sides beyond the table limit, refused before decoding pixels.
    #[error("{path}: {width}x{height} is larger than a table may be ({max} per side)")]
    TooLarge { path: String, width: usize, height: usize, max: u32 },
}

/// One header attribute of a table file.
#[derive(Debug, Clone, PartialEq)]
pub enum LutAttribute {
    /// A text attribute.
    Text(String),
    /// A 32-bit float attribute.
    F32(f32),
}

/// A table file read back: its pixels and its `skinkit.*` attributes.
#[derive(Debug, Clone, PartialEq)]
pub struct LutImage {
    pub width: usize,
    pub height: usize,
    /// Row-major RGB, row 0 at the top.
    pub texels: Vec<[f32; 3]>,
    /// Every attribute whose name starts with `skinkit.` (other types are skipped).
    pub attributes: BTreeMap<String, LutAttribute>,
}

impl LutImage {
    /// The text attribute `name`, if present with that type.
    pub fn text(&self, name: &str) -> Option<&str> {
        match self.attributes.get(name) {
            Some(LutAttribute::Text(t)) => Some(t),
            _ => None,
        }
    }

    /// The float attribute `name`, if present with that type.
    pub fn float(&self, name: &str) -> Option<f32> {
        match self.attributes.get(name) {
            Some(LutAttribute::F32(v)) => Some(*v),
            _ => None,
        }
    }

    /// The texel at column `i`, row `j`.
    pub fn texel(&self, i: usize, j: usize) -> [f32; 3] {
        self.texels[j * self.width + i]
    }

    /// The diffuse table this file holds, its spec read back from the attributes (so a renderer
    /// can load a cached build and check its [`DiffuseLut::cache_key`]); `name` appears in errors.
    ///
    /// # Errors
    /// When `skinkit.table` is not `diffuse`, an attribute is missing or unknown, or the spec it
    /// gives does not validate.
    pub fn into_diffuse(self, name: &str) -> Result<DiffuseLut, LutFileError> {
        self.expect_table("diffuse", name)?;
        let normalisation = match self.required_text("skinkit.normalisation", name)? {
            "2d" => Normalisation::TwoD,
            "1d" => Normalisation::OneD,
            other => return Err(decode_error(name, format!("unknown skinkit.normalisation `{other}`"))),
        };
        let domain = match self.required_text("skinkit.domain", name)? {
            "full" => Domain::Full,
            "half" => Domain::Half,
            "sphere" => Domain::Sphere,
            other => return Err(decode_error(name, format!("unknown skinkit.domain `{other}`"))),
        };
        let (width, height) = (self.width as u32, self.height as u32);
        let inv_r_min = self.required_float("skinkit.inv_r_min", name)?;
        let inv_r_max = self.required_float("skinkit.inv_r_max", name)?;
        let spec = DiffuseLutSpec { width, height, normalisation, domain, inv_r_min, inv_r_max };
        spec.validate().map_err(|e| decode_error(name, e))?;
        Ok(DiffuseLut { spec, texels: self.texels })
    }

    /// The shadow table this file holds, its spec read back from the attributes.
    ///
    /// # Errors
    /// As [`LutImage::into_diffuse`], for `skinkit.table = shadow`.
    pub fn into_shadow(self, name: &str) -> Result<ShadowLut, LutFileError> {
        self.expect_table("shadow", name)?;
        let spec = ShadowLutSpec {
            width: self.width as u32,
            height: self.height as u32,
            w_min_mm: self.required_float("skinkit.w_min_mm", name)?,
            w_max_mm: self.required_float("skinkit.w_max_mm", name)?,
            new_penumbra: self.required_float("skinkit.new_penumbra", name)?,
        };
        spec.validate().map_err(|e| decode_error(name, e))?;
        Ok(ShadowLut { spec, texels: self.texels })
    }

    fn expect_table(&self, table: &str, name: &str) -> Result<(), LutFileError> {
        match self.required_text("skinkit.table", name)? {
            t if t == table => Ok(()),
            other => Err(decode_error(name, format!("holds a {other} table, not a {table} table"))),
        }
    }

    fn required_text(&self, attribute: &str, name: &str) -> Result<&str, LutFileError> {
        self.text(attribute).ok_or_else(|| decode_error(name, format!("no text attribute {attribute}")))
    }

    fn required_float(&self, attribute: &str, name: &str) -> Result<f32, LutFileError> {
        self.float(attribute).ok_or_else(|| decode_error(name, format!("no f32 attribute {attribute}")))
    }
}

fn decode_error(name: &str, reason: impl ToString) -> LutFileError {
    LutFileError::Decode { path: name.to_owned(), reason: reason.to_string() }
}

/// The attributes [`write_diffuse`] stores for `lut`.
pub fn diffuse_attributes(lut: &DiffuseLut) -> BTreeMap<String, LutAttribute> {
    let s = &lut.spec;
    let mut a = common_attributes("diffuse", &lut.cache_key());
    text(&mut a, "x", "n_dot_l = 2 u - 1 at column centres u = (i + 0.5) / width; sample at u = n_dot_l * 0.5 + 0.5");
    text(
        &mut a,
        "y",
        "inv_r (1/mm) = inv_r_min + j (inv_r_max - inv_r_min) / (height - 1) at row centres, row 0 at the top",
    );
    text(&mut a, "normalisation", s.normalisation.name());
    text(&mut a, "domain", s.domain.name());
    float(&mut a, "inv_r_min", s.inv_r_min);
    float(&mut a, "inv_r_max", s.inv_r_max);
    text(&mut a, "equation", "Penner-Borshukov 2011 eq. 1.1, clamped cosine, denominator with the same r");
    a
}

/// The attributes [`write_shadow`] stores for `lut`.
pub fn shadow_attributes(lut: &ShadowLut) -> BTreeMap<String, LutAttribute> {
    let s = &lut.spec;
    let mut a = common_attributes("shadow", &lut.cache_key());
    text(&mut a, "x", "shadow value s = (i + 0.5) / width at column centres; sample at u = s");
    text(
        &mut a,
        "y",
        "penumbra width w (mm) = w_min_mm + j (w_max_mm - w_min_mm) / (height - 1) at row centres, row 0 at the top",
    );
    text(&mut a, "filter", "disc");
    text(
        &mut a,
        "penumbra",
        "P(t) = 1 - (acos t - t sqrt(1 - t^2)) / pi, edge at t w / 2 from the disc's centre; new penumbra a linear ramp; ends stretched to 0 and 1",
    );
    text(&mut a, "profile_slice", "marginal");
    float(&mut a, "new_penumbra", s.new_penumbra);
    float(&mut a, "w_min_mm", s.w_min_mm);
    float(&mut a, "w_max_mm", s.w_max_mm);
    text(&mut a, "equation", "Penner-Borshukov 2011 sec. 1.6, P_S(s, w) = int P'(P^-1(s) w / 2 + x) R1(x) dx");
    a
}

fn common_attributes(table: &str, cache_key: &str) -> BTreeMap<String, LutAttribute> {
    let mut a = BTreeMap::new();
    text(&mut a, "table", table);
    text(&mut a, "cache_key", cache_key);
    text(&mut a, "profile", "d'Eon-Luebke 2007 sum of 6 Gaussians (green weight 0.336)");
    a
}

fn text(map: &mut BTreeMap<String, LutAttribute>, name: &str, value: &str) {
    map.insert(format!("skinkit.{name}"), LutAttribute::Text(value.to_owned()));
}

fn float(map: &mut BTreeMap<String, LutAttribute>, name: &str, value: f32) {
    map.insert(format!("skinkit.{name}"), LutAttribute::F32(value));
}

/// Writes a diffuse table as a float RGB EXR with its definitions (module docs), atomically.
///
/// # Errors
/// When the folder is not writable or encoding fails.
pub fn write_diffuse(path: &Path, lut: &DiffuseLut) -> Result<(), LutFileError> {
    let (w, h) = (lut.spec.width as usize, lut.spec.height as usize);
    write(path, w, h, &lut.texels, &diffuse_attributes(lut))
}

/// Writes a shadow table as a float RGB EXR with its definitions (module docs), atomically.
///
/// # Errors
/// When the folder is not writable or encoding fails.
pub fn write_shadow(path: &Path, lut: &ShadowLut) -> Result<(), LutFileError> {
    let (w, h) = (lut.spec.width as usize, lut.spec.height as usize);
    write(path, w, h, &lut.texels, &shadow_attributes(lut))
}

fn write(
    path: &Path,
    width: usize,
    height: usize,
    texels: &[[f32; 3]],
    attributes: &BTreeMap<String, LutAttribute>,
) -> Result<(), LutFileError> {
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in attributes {
        let value = match value {
            LutAttribute::Text(t) => AttributeValue::Text(exr_text(t)),
            LutAttribute::F32(v) => AttributeValue::F32(*v),
        };
        layer_attributes.other.insert(exr_text(name), value);
    }
    let channels = SpecificChannels::rgb(|pos: Vec2<usize>| {
        let [r, g, b] = texels[pos.y() * width + pos.x()];
        (r, g, b)
    });
    let layer = Layer::new((width, height), layer_attributes, Encoding::UNCOMPRESSED, channels);
    let image = Image::from_layer(layer);
    skinkit_maps::io::write_atomic(path, |out| {
        image
            .write()
            .to_buffered(out)
            .map_err(|e| skinkit_maps::Error::Encode { path: path.to_owned(), reason: e.to_string() })
    })?;
    Ok(())
}

/// Our attribute texts are ASCII; anything else is replaced rather than panicking.
fn exr_text(s: &str) -> Text {
    let ascii: String = s.chars().map(|c| if c.is_ascii() { c } else { '?' }).collect();
    Text::new_or_panic(ascii)
}

/// Reads a table file written by [`write_diffuse`] or [`write_shadow`].
///
/// # Errors
/// When the file cannot be read, is not an RGB EXR, or is larger than [`MAX_SIDE`] per side.
pub fn read(path: &Path) -> Result<LutImage, LutFileError> {
    let name = path.display().to_string();
    let bytes = skinkit_maps::input::read(path, skinkit_maps::input::Kind::SkinTable)?;
    decode(&bytes, &name)
}

/// Decodes the bytes of a table file; `name` appears in errors.
///
/// # Errors
/// As [`read`].
pub fn decode(bytes: &[u8], name: &str) -> Result<LutImage, LutFileError> {
    let bad = |e: exr::error::Error| LutFileError::Decode { path: name.to_owned(), reason: e.to_string() };
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(bad)?;
    if meta.headers.is_empty() {
        return Err(LutFileError::Decode { path: name.to_owned(), reason: "no layer".to_owned() });
    }
    // Every part, not only the first: the reader may allocate for any of them.
    for header in &meta.headers {
        let (width, height) = (header.layer_size.width(), header.layer_size.height());
        if width > MAX_SIDE as usize || height > MAX_SIDE as usize {
            return Err(LutFileError::TooLarge { path: name.to_owned(), width, height, max: MAX_SIDE });
        }
    }
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.width(), vec![[0.0f32; 3]; size.width() * size.height()]),
            |(w, data): &mut (usize, Vec<[f32; 3]>), pos, (r, g, b): (f32, f32, f32)| {
                data[pos.y() * *w + pos.x()] = [r, g, b]
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(bad)?;
    let layer = &image.layer_data;
    let attributes =
        layer.attributes.other.iter().chain(image.attributes.other.iter()).filter_map(skinkit_attribute).collect();
    let size = layer.size;
    Ok(LutImage { width: size.width(), height: size.height(), texels: layer.channel_data.pixels.1.clone(), attributes })
}

fn skinkit_attribute((name, value): (&Text, &AttributeValue)) -> Option<(String, LutAttribute)> {
    let name = name.to_string();
    if !name.starts_with("skinkit.") {
        return None;
    }
    match value {
        AttributeValue::Text(t) => Some((name, LutAttribute::Text(t.to_string()))),
        AttributeValue::F32(v) => Some((name, LutAttribute::F32(*v))),
        _ => None,
    }
}
