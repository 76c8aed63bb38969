//! From a validated [`Scene`] to what the passes draw: the mesh with its texture-space frames,
//! the maps as textures, lights, cameras and the BRDF. What the scene's passes need on top is
//! [`crate::pass`]'s.
//!
//! # Maps
//! - The normal map is read with the file's green convention ([`skinkit_maps::io::read_normal_map`]:
//!   8/16-bit PNG or TIFF, float EXR) and kept green-up in memory, so the pass never flips.
//!   Invalid texels (all zero) read as "no detail" in the shader.
//! - The albedo is read as a photo: 8-bit files are taken as sRGB (what painted and photographed
//!   textures are), 16-bit and float files as linear (what `skinkit capture` writes). Grey albedo
//!   is spread to RGB.
//! - A map path naming a `.glb` or `.gltf` file takes the map from that file's material
//!   ([`crate::gltf_maps`]: its `baseColorTexture` as sRGB, its green-up `normalTexture`).
//! - A normal map path with `<UDIM>` in its file name names UDIM tiles: they are joined into one
//!   atlas and the mesh's UVs carried into it ([`skinkit_maps::udim`]). An albedo map cannot be
//!   tiles yet, so such a scene takes a constant albedo.
//! - A map larger than the device's `max_texture_dimension_2d` is halved (2x2 box, the mip
//!   filter) until it fits, with a warning naming the limit.

use std::path::Path;

use glam::{Mat3, Vec2, Vec3};
use skinkit_maps::io::{self, Limits};
use skinkit_maps::udim::{self, Atlas};
use skinkit_maps::{Channels, Grid, NormalEncoding, NormalMap};

use crate::brdf::Lafortune;
use crate::frames::{self, FrameMethod};
use crate::gltf_maps;
use crate::mesh::{Mesh, MeshError};
use crate::scene::{self, Albedo, NormalMapSpec, Scene};
use crate::shading::{self, GreenAxis, RenderInputs, Texture, ToneCurve, Vertex};

/// Errors from turning a scene into render inputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// A mesh could not be loaded: `scene.toml: mesh: head.obj: ...` (the scene file and its
    /// field, then the mesh error as `source()`, which names the mesh file).
    #[error("{file}: {field}")]
    Mesh {
        /// The scene file.
        file: String,
        /// `mesh` or `translucent[i].mesh`.
        field: String,
        #[source]
        error: MeshError,
    },
    /// A map could not be read: the scene file and its field, then the map error as `source()`
    /// (which names the map file).
    #[error("{file}: {field}")]
    Map {
        /// The scene file.
        file: String,
        /// `normal_map.path` or `albedo`.
        field: &'static str,
        #[source]
        error: skinkit_maps::Error,
    },
    /// A map file the scene names does not exist (yet).
    #[error("{file}: {field}: {path} does not exist{hint}")]
    Missing {
        /// The scene file.
        file: String,
        /// `normal_map.path` or `albedo`.
        field: &'static str,
        /// The missing file.
        path: String,
        /// "; make it first: COMMAND" when the scene says what makes it, else empty.
        hint: String,
    },
    /// A value the base pass cannot draw.
    #[error("{file}: {field}: {reason}")]
    Unsupported {
        /// The scene file.
        file: String,
        /// The field at fault.
        field: String,
        /// Why.
        reason: String,
    },
}

/// Result alias for this module.
pub type Result<T, E = LoadError> = std::result::Result<T, E>;

/// A scene's geometry and materials, loaded once, ready for any camera.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// Inputs with the scene's first camera (see [`Loaded::for_camera`] for the others).
    pub inputs: RenderInputs,
    /// The mesh as loaded (before frames), for reports.
    pub vertex_count: usize,
    /// Triangle count.
    pub triangle_count: usize,
    /// Notes for the user: computed normals, downscaled maps, unshadowed lights.
    pub warnings: Vec<String>,
}

impl Loaded {
    /// The inputs with `camera` and the image's aspect ratio.
    pub fn for_camera(&self, camera: &scene::Camera, width: u32, height: u32) -> RenderInputs {
        RenderInputs { camera: gpu_camera(camera, width, height), ..self.inputs.clone() }
    }
}

/// The shading camera of a scene camera for a `width x height` image.
pub(crate) fn gpu_camera(camera: &scene::Camera, width: u32, height: u32) -> shading::Camera {
    let aspect = width.max(1) as f32 / height.max(1) as f32;
    shading::Camera::look_at(camera.position, camera.target, camera.up, camera.fov_deg, aspect)
}

/// Frame `index` of `count` of a turntable around the camera's target: the eye turned about the
/// camera's up axis by `360 * index / count` degrees.
pub fn orbit(camera: &scene::Camera, index: usize, count: usize) -> scene::Camera {
    let angle = std::f32::consts::TAU * index as f32 / count.max(1) as f32;
    let turn = Mat3::from_axis_angle(camera.up, angle);
    scene::Camera { position: camera.target + turn * (camera.position - camera.target), ..*camera }
}

/// Loads the mesh and maps of `scene`, builds the frames and the inputs of its first camera.
/// `max_texture_side` is the device limit (maps above it are halved until they fit).
///
/// # Errors
/// Unreadable or malformed mesh or maps.
pub fn load(scene: &Scene, width: u32, height: u32, max_texture_side: u32) -> Result<Loaded> {
    let loaded =
        Mesh::load(&scene.mesh).map_err(|error| LoadError::Mesh { file: scene.name(), field: "mesh".into(), error })?;
    let mut warnings = loaded.warnings;
    let mut mesh = loaded.mesh;
    let method = scene.normal_map.as_ref().map_or(FrameMethod::Paper, |m| m.frames);
    let tangents = frames::tangents(&mesh, method);
    let limits = Limits::default();
    let (normals, atlas) = match &scene.normal_map {
        None => (None, None),
        Some(spec) => read_scene_normals(scene, spec, &limits).map(|(m, a)| (Some(m), a))?,
    };
    if let Some(atlas) = &atlas {
        carry_uvs(&mut mesh.uvs, atlas);
    }
    let vertices = (0..mesh.positions.len())
        .map(|i| Vertex {
            position: mesh.positions[i].into(),
            normal: mesh.normals[i].into(),
            tangent: tangents[i].into(),
            uv: mesh.uvs[i].into(),
        })
        .collect();

    let normal_map = match normals {
        None => Texture::flat_normals(),
        Some(map) => fit(Texture::from_normal_map(&map), "normal map", max_texture_side, &mut warnings),
    };
    let albedo = match &scene.albedo {
        None => Texture::solid([1.0; 4]),
        Some(Albedo::Constant(c)) => Texture::solid([c.x, c.y, c.z, 1.0]),
        Some(Albedo::Map(path)) => {
            fit(read_scene_albedo(scene, path, &limits)?, "albedo", max_texture_side, &mut warnings)
        }
    };
    // A constant albedo scales rho_d; with no albedo rho_d is the BRDF's own.
    let diffuse = match &scene.albedo {
        Some(_) => Vec3::ONE,
        None => scene.brdf.diffuse,
    };
    let brdf = Lafortune { diffuse, lobes: scene.brdf.lobes.clone() };
    let lights = scene.lights.iter().map(|l| l.light).collect();
    let inputs = RenderInputs {
        vertices,
        indices: mesh.indices.clone(),
        camera: gpu_camera(&scene.cameras[0], width, height),
        lights,
        brdf,
        normal_map,
        green: GreenAxis::Up,
        albedo,
        specular: scene.specular,
        exposure: 1.0,
        // The frame's encoding decides the curve (`crate::renderer::Encoding`), at upload.
        tone: ToneCurve::None,
        background: [0.0, 0.0, 0.0, 1.0],
    };
    Ok(Loaded { inputs, vertex_count: mesh.positions.len(), triangle_count: mesh.triangle_count(), warnings })
}

/// The scene's normal map, green-up in memory, and when its path names UDIM tiles the atlas they
/// were joined into (the mesh's UVs must be carried into it: [`carry_uvs`]).
///
/// # Errors
/// As [`read_normal_map`]; UDIM tiles with an albedo map (which cannot be tiles yet).
pub(crate) fn read_scene_normals(
    scene: &Scene,
    spec: &NormalMapSpec,
    limits: &Limits,
) -> Result<(NormalMap, Option<Atlas>)> {
    if !udim::is_pattern(&spec.path) {
        return Ok((read_normal_map(scene, spec, limits)?, None));
    }
    if let Some(Albedo::Map(path)) = &scene.albedo {
        let reason = format!(
            "{}: the normal map is UDIM tiles ({}) and an albedo map cannot be tiles yet; give a constant albedo",
            path.display(),
            spec.path.display()
        );
        return Err(LoadError::Unsupported { file: scene.name(), field: "albedo".into(), reason });
    }
    let (map, atlas) = read_tiles(scene, spec, limits)?;
    Ok((map, Some(atlas)))
}

/// The scene's normal map, green-up in memory: from its file, or from the normal texture of a
/// glTF file's material ([`crate::gltf_maps`], green-up by glTF's definition).
///
/// # Errors
/// A missing or unreadable map; `green = "down"` on a glTF file.
pub(crate) fn read_normal_map(scene: &Scene, spec: &NormalMapSpec, limits: &Limits) -> Result<NormalMap> {
    const FIELD: &str = "normal_map.path";
    exists(scene, FIELD, &spec.path, spec.made_by.as_deref())?;
    let map_error = |error| LoadError::Map { file: scene.name(), field: FIELD, error };
    if !gltf_maps::is_gltf(&spec.path) {
        return io::read_normal_map(&spec.path, NormalEncoding { green: spec.green }, limits).map_err(map_error);
    }
    if spec.green != skinkit_maps::GreenAxis::Up {
        let reason =
            format!("{}: glTF normal textures are green-up; remove `green` or say \"up\"", spec.path.display());
        return Err(LoadError::Unsupported { file: scene.name(), field: "normal_map.green".into(), reason });
    }
    gltf_maps::normal_map(&spec.path, limits).map_err(map_error)
}

/// The scene's albedo map as linear RGBA: from an image file, or from the base colour texture of
/// a glTF file's material ([`crate::gltf_maps`]).
///
/// # Errors
/// A missing or unreadable map.
pub(crate) fn read_scene_albedo(scene: &Scene, path: &Path, limits: &Limits) -> Result<Texture> {
    exists(scene, "albedo", path, None)?;
    let texture = match gltf_maps::is_gltf(path) {
        true => gltf_maps::albedo(path, limits),
        false => read_albedo(path, limits),
    };
    texture.map_err(|error| LoadError::Map { file: scene.name(), field: "albedo", error })
}

/// [`LoadError::Missing`] unless `path` exists.
fn exists(scene: &Scene, field: &'static str, path: &Path, made_by: Option<&str>) -> Result<()> {
    match path.exists() {
        true => Ok(()),
        false => Err(LoadError::Missing {
            file: scene.name(),
            field,
            path: path.display().to_string(),
            hint: made_by.map(|m| format!("; make it first: {m}")).unwrap_or_default(),
        }),
    }
}

/// Reads an albedo image as linear RGBA (8-bit as sRGB, 16-bit and float as linear).
pub(crate) fn read_albedo(path: &Path, limits: &Limits) -> skinkit_maps::Result<Texture> {
    let photo = io::read_photo(path, limits)?;
    let photo = if photo.bit_depth() == 8 { photo.with_transfer(skinkit_maps::Transfer::Srgb) } else { photo };
    let width = photo.width();
    Ok(Texture::from_fn(width as u32, photo.height() as u32, |x, y| {
        let i = y as usize * width + x as usize;
        match photo.channels() {
            Channels::Gray => {
                let g = photo.linear(i);
                [g, g, g, 1.0]
            }
            Channels::Rgb => [photo.linear(3 * i), photo.linear(3 * i + 1), photo.linear(3 * i + 2), 1.0],
        }
    }))
}

/// Halves `texture` until both sides fit `limit`, warning when it had to.
fn fit(mut texture: Texture, name: &str, limit: u32, warnings: &mut Vec<String>) -> Texture {
    let (w, h) = (texture.width, texture.height);
    while texture.width > limit.max(1) || texture.height > limit.max(1) {
        texture = texture.downsample();
    }
    if (texture.width, texture.height) != (w, h) {
        warnings.push(format!(
            "{name} is {w}x{h} but this device allows at most {limit}x{limit} (max_texture_dimension_2d): downscaled to {}x{}",
            texture.width, texture.height
        ));
    }
    texture
}

// UDIM tiles (`[normal_map] path = "normal.<UDIM>.png"`, what `skinkit face` writes for a mesh
// over several tiles): the tiles on disk joined into one atlas texture (flat normals where the
// atlas has no tile) and the mesh's UVs carried into it, so the renderer, the texture-space
// passes and the glTF export see one map over [0, 1]^2 and a bilinear fetch across a tile
// boundary reads the two tiles' neighbouring texels.

/// The tiles `spec.path` (a pattern with [`udim::TOKEN`]) names, joined into one map, and the
/// atlas they make.
///
/// # Errors
/// No tile on disk, an unreadable tile, or tiles of different sizes (each error names the
/// scene's field and the tile's file).
fn read_tiles(scene: &Scene, spec: &NormalMapSpec, limits: &Limits) -> Result<(NormalMap, Atlas)> {
    const FIELD: &str = "normal_map.path";
    let map_error = |error| LoadError::Map { file: scene.name(), field: FIELD, error };
    let files = udim::find_tiles(&spec.path).map_err(map_error)?;
    if files.is_empty() {
        let hint = format!(
            " (no file matches it with a tile number from 1001 to 1999 for {}){}",
            udim::TOKEN,
            spec.made_by.as_deref().map(|m| format!("; make it first: {m}")).unwrap_or_default()
        );
        return Err(LoadError::Missing {
            file: scene.name(),
            field: FIELD,
            path: spec.path.display().to_string(),
            hint,
        });
    }
    let mut tiles: Vec<(u32, Grid<Vec3>)> = Vec::with_capacity(files.len());
    for (number, path) in &files {
        let grid =
            io::read_normal_map(path, NormalEncoding { green: spec.green }, limits).map_err(map_error)?.into_grid();
        let (first, first_size) = tiles.first().map_or((*number, grid.size()), |(n, g)| (*n, g.size()));
        if grid.size() != first_size {
            let reason = format!(
                "{}: UDIM tile {number} is {:?} texels but tile {first} is {first_size:?}; every tile must be one size",
                path.display(),
                grid.size(),
            );
            return Err(LoadError::Unsupported { file: scene.name(), field: FIELD.into(), reason });
        }
        tiles.push((*number, grid));
    }
    let (w, h) = tiles[0].1.size();
    let numbers: Vec<u32> = tiles.iter().map(|t| t.0).collect();
    let atlas = Atlas::of_tiles(&numbers, w, h).map_err(map_error)?;
    let joined = atlas.join(&tiles, Vec3::Z).map_err(map_error)?;
    Ok((NormalMap::from_grid(joined), atlas))
}

/// The mesh's UVs carried into `atlas`'s (an affine map: the frames, computed before, keep their
/// directions).
pub(crate) fn carry_uvs(uvs: &mut [Vec2], atlas: &Atlas) {
    for uv in uvs {
        let [u, v] = atlas.to_atlas([f64::from(uv.x), f64::from(uv.y)]);
        *uv = Vec2::new(u as f32, v as f32);
    }
}
