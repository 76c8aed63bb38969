//! glTF 2.0 export of a scene's skin (`skinkit export gltf`): the mesh with positions, normals,
//! MikkTSpace tangents and UVs, the albedo as the material's `baseColorTexture`, the fine-scale
//! normal map as its `normalTexture`, metallic 0 and a roughness close to the scene's Lafortune
//! lobes ([`material`]), as one `.glb` or as a `.gltf` with its `.bin` and PNG files.
//!
//! # Conventions
//! glTF's conventions are skinkit's, so nothing is flipped:
//! - UV `(0, 0)` is the top-left of the image in both ([`crate::mesh`]; OBJ files are flipped
//!   when they are read);
//! - tangents are `(T, w)` with `B = cross(N, T) * w` pointing up the image (toward decreasing
//!   `v`), MikkTSpace run on OpenGL-style `(u, 1 - v)` ([`crate::frames`]): the basis glTF's
//!   green-up normal textures are made against;
//! - normal textures are green-up in both (`images`).
//!
//! glTF's unit is the metre: positions are the mesh's units times `mm_per_unit / 1000` (a scene
//! re-rendering the export says `mm_per_unit = 1000` and puts its cameras in metres). A scene
//! whose normal map was made against the paper's frames (`frames = "paper"`) is exported with
//! MikkTSpace tangents all the same, with a warning: glTF viewers use the file's tangents.
//!
//! The library builds every file in memory ([`export`]); the caller writes them (atomically).

mod document;
mod images;
pub mod material;

use std::path::Path;

use glam::Vec3;
use serde::Serialize;
use skinkit_maps::io::Limits;

use crate::frames::{self, FrameMethod};
use crate::load::LoadError;
use crate::mesh::Mesh;
use crate::scene::{Albedo, Scene};
pub use document::{Geometry, ImageSource};
pub use images::{NormalBits, Png};
pub use material::Roughness;

/// Errors of an export. Each names the scene file and the field, or what could not be encoded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The scene's mesh or a map could not be read (the scene file, its field, the input file).
    #[error(transparent)]
    Load(#[from] LoadError),
    /// A texture or the document could not be encoded.
    #[error("{file}: cannot encode {what}: {reason}")]
    Encode {
        /// The scene file.
        file: String,
        /// `the albedo texture`, `the glTF JSON`, ...
        what: String,
        /// The encoder's message.
        reason: String,
    },
}

/// Result alias for exports.
pub type Result<T, E = ExportError> = std::result::Result<T, E>;

/// The two glTF containers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Container {
    /// One binary file, the images in its buffer.
    Glb,
    /// JSON with a `.bin` buffer and PNG images beside it, named by relative URIs.
    Gltf,
}

impl Container {
    /// The container a file name's extension asks for (`.glb` or `.gltf`, any case).
    pub fn from_path(path: &Path) -> Option<Container> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "glb" => Some(Container::Glb),
            "gltf" => Some(Container::Gltf),
            _ => None,
        }
    }
}

/// What to export and how.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportOptions {
    /// GLB or glTF with side files.
    pub container: Container,
    /// The output's file stem: `head` gives `head.glb`, or `head.gltf`, `head.bin`,
    /// `head-albedo.png`, `head-normal.png`.
    pub stem: String,
    /// The normal texture's bit depth.
    pub normal_bits: NormalBits,
}

/// One output file, relative to the output's folder.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportFile {
    /// File name (no folder).
    pub name: String,
    /// Its whole content.
    pub bytes: Vec<u8>,
}

/// Size and depth of an exported texture.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TextureInfo {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Bits per channel.
    pub bits: u32,
}

/// What an export wrote, for reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ExportSummary {
    /// Vertices of the mesh (as the renderer loads it: split at UV seams).
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Metres per mesh unit the positions were scaled by.
    pub metres_per_unit: f32,
    /// The material's `baseColorFactor`.
    pub base_color_factor: [f32; 4],
    /// The material's roughness and the lobe it came from.
    pub roughness: Roughness,
    /// The albedo texture, if the scene has an albedo map.
    pub albedo: Option<TextureInfo>,
    /// The normal texture, if the scene has a normal map.
    pub normal: Option<TextureInfo>,
    /// Invalid normal-map texels written as the flat normal.
    pub invalid_normals: usize,
    /// Notes for the user.
    pub warnings: Vec<String>,
}

/// The files of an export and its summary.
#[derive(Clone, Debug, PartialEq)]
pub struct Exported {
    /// The files, the `.glb` or `.gltf` first.
    pub files: Vec<ExportFile>,
    /// What they hold.
    pub summary: ExportSummary,
}

/// The scene's inputs, read.
struct Inputs {
    mesh: Mesh,
    albedo: Option<Png>,
    normal: Option<Png>,
    invalid_normals: usize,
    warnings: Vec<String>,
}

/// Exports `scene` (its mesh, albedo, normal map and BRDF; lights and cameras are not exported).
/// `progress` is told each stage by name as it starts (`mesh`, `albedo`, `normal map`, `tangents`,
/// `assemble`), and the end of the last.
///
/// # Errors
/// A mesh or map that cannot be read (named as `skinkit render` names it), a texture or document
/// that cannot be encoded, a GLB over 4 GiB.
pub fn export(
    scene: &Scene,
    options: &ExportOptions,
    progress: &dyn skinkit_maps::progress::Progress,
) -> Result<Exported> {
    let inputs = read_inputs(scene, options, progress)?;
    progress.start("tangents", 0);
    let mesh = &inputs.mesh;
    let tangents = frames::tangents(mesh, FrameMethod::MikkTSpace);
    let metres_per_unit = scene.mm_per_unit / 1000.0;
    let positions: Vec<Vec3> = mesh.positions.iter().map(|&p| p * metres_per_unit).collect();
    let geometry = Geometry {
        positions: &positions,
        normals: &mesh.normals,
        tangents: &tangents,
        uvs: &mesh.uvs,
        indices: &mesh.indices,
    };
    let roughness = material::roughness(&scene.brdf);
    let spec = document::MaterialSpec {
        base_color_factor: material::base_color_factor(scene.albedo.as_ref(), &scene.brdf),
        roughness: roughness.roughness,
    };
    progress.start("assemble", 0);
    let files = assemble(scene, options, &geometry, &spec, &inputs)?;
    let info = |p: &Png| TextureInfo { width: p.width, height: p.height, bits: p.bits };
    let summary = ExportSummary {
        vertices: mesh.positions.len(),
        triangles: mesh.triangle_count(),
        metres_per_unit,
        base_color_factor: spec.base_color_factor,
        roughness,
        albedo: inputs.albedo.as_ref().map(info),
        normal: inputs.normal.as_ref().map(info),
        invalid_normals: inputs.invalid_normals,
        warnings: inputs.warnings,
    };
    progress.finish();
    Ok(Exported { files, summary })
}

/// Reads the mesh and maps the way [`crate::load::load`] does and encodes the maps as PNG.
fn read_inputs(
    scene: &Scene,
    options: &ExportOptions,
    progress: &dyn skinkit_maps::progress::Progress,
) -> Result<Inputs> {
    let encode_error = |what: &str, reason| ExportError::Encode { file: scene.name(), what: what.into(), reason };
    progress.start("mesh", 0);
    let loaded =
        Mesh::load(&scene.mesh).map_err(|error| LoadError::Mesh { file: scene.name(), field: "mesh".into(), error })?;
    let mut warnings = loaded.warnings;
    let mut mesh = loaded.mesh;
    let limits = Limits::default();
    progress.start("albedo", 0);
    let albedo = match &scene.albedo {
        Some(Albedo::Map(path)) => {
            let texture = crate::load::read_scene_albedo(scene, path, &limits)?;
            Some(images::albedo_png(&texture).map_err(|r| encode_error("the albedo texture", r))?)
        }
        _ => None,
    };
    progress.start("normal map", 0);
    let (normal, invalid_normals) = match &scene.normal_map {
        None => (None, 0),
        Some(spec) => {
            if spec.frames == FrameMethod::Paper {
                warnings.push(format!(
                    "{}: normal_map.frames is \"paper\" but glTF's tangents are MikkTSpace: the export's shading \
                     differs slightly from skinkit's render of this scene (say frames = \"mikktspace\" to match)",
                    scene.name()
                ));
            }
            let (map, atlas) = crate::load::read_scene_normals(scene, spec, &limits)?;
            if let Some(atlas) = &atlas {
                // glTF has no UDIM: the tiles are one texture, the UVs carried into it.
                crate::load::carry_uvs(&mut mesh.uvs, atlas);
            }
            let (png, invalid) =
                images::normal_png(&map, options.normal_bits).map_err(|r| encode_error("the normal texture", r))?;
            (Some(png), invalid)
        }
    };
    if invalid_normals > 0 {
        warnings.push(format!(
            "{}: {invalid_normals} invalid normal-map texels written as the flat normal (0, 0, 1)",
            scene.name()
        ));
    }
    Ok(Inputs { mesh, albedo, normal, invalid_normals, warnings })
}

/// The files of the container: the GLB alone, or the `.gltf`, its `.bin` and its PNGs.
fn assemble(
    scene: &Scene,
    options: &ExportOptions,
    geometry: &Geometry,
    spec: &document::MaterialSpec,
    inputs: &Inputs,
) -> Result<Vec<ExportFile>> {
    let stem = &options.stem;
    let encode_error =
        |what: &str, reason: String| ExportError::Encode { file: scene.name(), what: what.into(), reason };
    let names = [format!("{stem}-albedo.png"), format!("{stem}-normal.png")];
    let pngs = [inputs.albedo.as_ref(), inputs.normal.as_ref()];
    let image = |i: usize, name: &'static str| {
        pngs[i].map(|png| document::ImageSpec {
            name,
            source: match options.container {
                Container::Glb => ImageSource::Embedded(&png.bytes),
                Container::Gltf => ImageSource::Uri(uri_encode(&names[i])),
            },
        })
    };
    let buffer_uri = (options.container == Container::Gltf).then(|| uri_encode(&format!("{stem}.bin")));
    let (root, bin) = document::build(geometry, spec, image(0, "albedo"), image(1, "normal"), buffer_uri);
    match options.container {
        Container::Glb => {
            let json = root.to_vec().map_err(|e| encode_error("the glTF JSON", e.to_string()))?;
            let glb = gltf::Glb {
                header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
                json: json.into(),
                bin: Some(bin.into()),
            };
            let bytes = glb.to_vec().map_err(|e| encode_error("the GLB", e.to_string()))?;
            if u32::try_from(bytes.len()).is_err() {
                return Err(encode_error(
                    "the GLB",
                    format!("{} bytes is over GLB's 4 GiB limit: write .gltf", bytes.len()),
                ));
            }
            Ok(vec![ExportFile { name: format!("{stem}.glb"), bytes }])
        }
        Container::Gltf => {
            let json = root.to_vec_pretty().map_err(|e| encode_error("the glTF JSON", e.to_string()))?;
            let mut files = vec![
                ExportFile { name: format!("{stem}.gltf"), bytes: json },
                ExportFile { name: format!("{stem}.bin"), bytes: bin },
            ];
            for (name, png) in names.iter().zip(pngs) {
                files.extend(png.map(|p| ExportFile { name: name.clone(), bytes: p.bytes.clone() }));
            }
            Ok(files)
        }
    }
}

/// Percent-encodes a file name for a relative URI (RFC 3986: every byte but the unreserved ones).
fn uri_encode(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

#[cfg(test)]
mod tests;
