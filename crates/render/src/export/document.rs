//! The glTF document of an export (written with the `gltf` crate's JSON types, `gltf-json`): one
//! buffer, one mesh of one triangle primitive (POSITION, NORMAL, TANGENT, TEXCOORD_0, u32
//! indices), one material, up to two textures sharing one repeating, mip-mapped sampler, one node
//! and one scene.
//!
//! The buffer holds the vertex attributes, each in its own tightly packed view, then the indices,
//! then (in a GLB) the PNG images, every view starting on a 4-byte boundary as the specification
//! asks. In a `.gltf` the images are files beside it, named by relative, percent-encoded URIs.

use glam::{Vec2, Vec3, Vec4};
use gltf::json::{self, validation::Checked::Valid, validation::USize64};

/// The vertex and index data of the one primitive (positions already in metres).
pub struct Geometry<'a> {
    /// Positions, metres.
    pub positions: &'a [Vec3],
    /// Unit normals.
    pub normals: &'a [Vec3],
    /// Unit tangents with the handedness in `w` (glTF's rule: `B = cross(N, T) * w`).
    pub tangents: &'a [Vec4],
    /// Texture coordinates, `(0, 0)` at the top-left of the image.
    pub uvs: &'a [Vec2],
    /// Three indices per triangle, counter-clockwise seen from outside.
    pub indices: &'a [u32],
}

/// The material's numbers and which images it samples.
pub(crate) struct MaterialSpec {
    /// Linear RGBA multiplying the base colour texture (or standing for it).
    pub base_color_factor: [f32; 4],
    /// glTF `roughnessFactor`.
    pub roughness: f32,
}

/// Where an image's bytes go: into the buffer (GLB) or into a file beside the JSON (`.gltf`).
pub enum ImageSource<'a> {
    /// Bytes stored in the buffer, in their own view.
    Embedded(&'a [u8]),
    /// A relative URI (already percent-encoded).
    Uri(String),
}

/// One texture of the material.
pub(crate) struct ImageSpec<'a> {
    /// The image's name in the document.
    pub name: &'static str,
    /// Where its PNG is.
    pub source: ImageSource<'a>,
}

/// The document and the buffer it describes. `buffer_uri` is `None` for a GLB (the buffer is the
/// binary chunk) and the `.bin` file's URI for a `.gltf`.
pub fn build(
    geometry: &Geometry,
    material: &MaterialSpec,
    albedo: Option<ImageSpec>,
    normal: Option<ImageSpec>,
    buffer_uri: Option<String>,
) -> (json::Root, Vec<u8>) {
    let mut root = json::Root {
        asset: json::Asset { generator: Some(format!("skinkit {}", env!("CARGO_PKG_VERSION"))), ..Default::default() },
        ..Default::default()
    };
    let mut bin = Vec::new();
    let buffer = json::Index::new(0);
    let primitive = primitive(&mut root, &mut bin, buffer, geometry);
    let sampler = (albedo.is_some() || normal.is_some()).then(|| root.push(repeating_sampler()));
    let texture = |root: &mut json::Root, bin: &mut Vec<u8>, spec: ImageSpec| {
        let image = push_image(root, bin, buffer, spec);
        root.push(json::Texture { name: None, sampler, source: image, extensions: None, extras: Default::default() })
    };
    let albedo = albedo.map(|spec| texture(&mut root, &mut bin, spec));
    let normal = normal.map(|spec| texture(&mut root, &mut bin, spec));
    let material = root.push(skin_material(material, albedo, normal));
    finish_scene(&mut root, json::mesh::Primitive { material: Some(material), ..primitive });
    pad4(&mut bin);
    root.push(json::Buffer {
        byte_length: USize64::from(bin.len()),
        name: None,
        uri: buffer_uri,
        extensions: None,
        extras: Default::default(),
    });
    (root, bin)
}

/// The mesh's accessors and the primitive reading them (no material yet).
fn primitive(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    g: &Geometry,
) -> json::mesh::Primitive {
    use json::accessor::Type;
    let vertex = Some(json::buffer::Target::ArrayBuffer);
    let (min, max) = bounds(g.positions);
    let floats = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let positions = floats(&g.positions.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    let normals = floats(&g.normals.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    let tangents = floats(&g.tangents.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    let uvs = floats(&g.uvs.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>());
    let n = g.positions.len();
    let mut attribute = |bytes: &[u8], type_, bounds: Option<(Vec3, Vec3)>| {
        let view = push_view(root, bin, buffer, bytes, vertex);
        let accessor = float_accessor(view, n, type_, bounds);
        root.push(accessor)
    };
    let position = attribute(&positions, Type::Vec3, Some((min, max)));
    let normal = attribute(&normals, Type::Vec3, None);
    let tangent = attribute(&tangents, Type::Vec4, None);
    let uv = attribute(&uvs, Type::Vec2, None);
    let index_bytes: Vec<u8> = g.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
    let view = push_view(root, bin, buffer, &index_bytes, Some(json::buffer::Target::ElementArrayBuffer));
    let indices = root.push(json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(g.indices.len()),
        component_type: Valid(json::accessor::GenericComponentType(json::accessor::ComponentType::U32)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(Type::Scalar),
        min: None,
        max: None,
        name: None,
        normalized: false,
        sparse: None,
    });
    let attributes = [
        (json::mesh::Semantic::Positions, position),
        (json::mesh::Semantic::Normals, normal),
        (json::mesh::Semantic::Tangents, tangent),
        (json::mesh::Semantic::TexCoords(0), uv),
    ];
    json::mesh::Primitive {
        attributes: attributes.into_iter().map(|(s, a)| (Valid(s), a)).collect(),
        extensions: None,
        extras: Default::default(),
        indices: Some(indices),
        material: None,
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    }
}

/// An f32 accessor of `count` elements over `view`; `bounds` gives POSITION its required min/max.
fn float_accessor(
    view: json::Index<json::buffer::View>,
    count: usize,
    type_: json::accessor::Type,
    bounds: Option<(Vec3, Vec3)>,
) -> json::Accessor {
    let value = |v: Vec3| json::Value::from(v.to_array().to_vec());
    json::Accessor {
        buffer_view: Some(view),
        byte_offset: None,
        count: USize64::from(count),
        component_type: Valid(json::accessor::GenericComponentType(json::accessor::ComponentType::F32)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(type_),
        min: bounds.map(|(min, _)| value(min)),
        max: bounds.map(|(_, max)| value(max)),
        name: None,
        normalized: false,
        sparse: None,
    }
}

/// Componentwise bounds (zero for an empty list; the exporter never passes one).
fn bounds(points: &[Vec3]) -> (Vec3, Vec3) {
    match points.first() {
        None => (Vec3::ZERO, Vec3::ZERO),
        Some(&first) => points.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
    }
}

/// Appends `bytes` to the buffer on a 4-byte boundary and adds a view of them.
fn push_view(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    bytes: &[u8],
    target: Option<json::buffer::Target>,
) -> json::Index<json::buffer::View> {
    pad4(bin);
    let offset = bin.len();
    bin.extend_from_slice(bytes);
    root.push(json::buffer::View {
        buffer,
        byte_length: USize64::from(bytes.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        name: None,
        target: target.map(Valid),
        extensions: None,
        extras: Default::default(),
    })
}

fn pad4(bin: &mut Vec<u8>) {
    bin.resize(bin.len().next_multiple_of(4), 0);
}

fn push_image(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    buffer: json::Index<json::Buffer>,
    spec: ImageSpec,
) -> json::Index<json::Image> {
    let (buffer_view, mime_type, uri) = match spec.source {
        ImageSource::Embedded(bytes) => {
            let view = push_view(root, bin, buffer, bytes, None);
            (Some(view), Some(json::image::MimeType("image/png".into())), None)
        }
        ImageSource::Uri(uri) => (None, None, Some(uri)),
    };
    root.push(json::Image {
        buffer_view,
        mime_type,
        name: Some(spec.name.into()),
        uri,
        extensions: None,
        extras: Default::default(),
    })
}

/// Linear filtering with trilinear mip-maps and repeat addressing: how skinkit samples its maps.
fn repeating_sampler() -> json::texture::Sampler {
    json::texture::Sampler {
        mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
        min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
        wrap_s: Valid(json::texture::WrappingMode::Repeat),
        wrap_t: Valid(json::texture::WrappingMode::Repeat),
        ..Default::default()
    }
}

fn skin_material(
    spec: &MaterialSpec,
    albedo: Option<json::Index<json::Texture>>,
    normal: Option<json::Index<json::Texture>>,
) -> json::Material {
    let info = |index| json::texture::Info { index, tex_coord: 0, extensions: None, extras: Default::default() };
    json::Material {
        name: Some("skin".into()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(spec.base_color_factor),
            base_color_texture: albedo.map(info),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(spec.roughness),
            ..Default::default()
        },
        normal_texture: normal.map(|index| json::material::NormalTexture {
            index,
            scale: 1.0,
            tex_coord: 0,
            extensions: None,
            extras: Default::default(),
        }),
        ..Default::default()
    }
}

/// The mesh of `primitive`, its node and the default scene.
fn finish_scene(root: &mut json::Root, primitive: json::mesh::Primitive) {
    let mesh = root.push(json::Mesh {
        extensions: None,
        extras: Default::default(),
        name: Some("skin".into()),
        primitives: vec![primitive],
        weights: None,
    });
    let node = root.push(json::Node { mesh: Some(mesh), name: Some("skin".into()), ..Default::default() });
    let scene = root.push(json::Scene { extensions: None, extras: Default::default(), name: None, nodes: vec![node] });
    root.scene = Some(scene);
}
