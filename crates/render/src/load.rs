//! From a validated [`Scene`] to what the passes draw: the mesh with its texture-space frames,
//! the maps as textures, lights, cameras and the BRDF, plus the plan of passes and GPU resources
//! the scene needs (`skinkit render --explain`).
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
//! - A map larger than the device's `max_texture_dimension_2d` is halved (2x2 box, the mip
//!   filter) until it fits, with a warning naming the limit.
//!
//! # Plans
//! [`plan`] lists a scene's [`PassGraph`] for people (`skinkit render --explain`): each pass of
//! the graph's ordered list with what it reads and writes, and every GPU resource with its bytes.
//! [`crate::skin::setup::build`] computes what the same graph asks for.

use std::path::Path;

use glam::{Mat3, Vec3};
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{Channels, NormalEncoding, NormalMap};

use crate::brdf::Lafortune;
use crate::frames::{self, FrameMethod};
use crate::gltf_maps;
use crate::gpu::OutputFormat as TargetFormat;
use crate::graph::{PassGraph, PassKind};
use crate::mesh::{Mesh, MeshError};
use crate::passes::{DiffuseMode, Features};
use crate::scene::{self, Albedo, NormalMapSpec, Scene};
use crate::shading::{self, GreenAxis, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex};
use crate::skin::options::TsdKernel;
use crate::skin::tsd;

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
    let mesh = loaded.mesh;
    let method = scene.normal_map.as_ref().map_or(FrameMethod::Paper, |m| m.frames);
    let tangents = frames::tangents(&mesh, method);
    let vertices = (0..mesh.positions.len())
        .map(|i| Vertex {
            position: mesh.positions[i].into(),
            normal: mesh.normals[i].into(),
            tangent: tangents[i].into(),
            uv: mesh.uvs[i].into(),
        })
        .collect();

    let limits = Limits::default();
    let normal_map = match &scene.normal_map {
        None => Texture::flat_normals(),
        Some(spec) => {
            let map = read_normal_map(scene, spec, &limits)?;
            fit(Texture::from_normal_map(&map), "normal map", max_texture_side, &mut warnings)
        }
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

/// One GPU resource a plan needs.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Resource {
    /// What it is.
    pub name: String,
    /// Format and size, for people.
    pub detail: String,
    /// Bytes on the device.
    pub bytes: u64,
}

/// One pass of a plan.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Pass {
    /// Which pass of the graph.
    pub kind: PassKind,
    /// Its name ([`PassKind::name`]).
    pub name: String,
    /// What it does.
    pub what: String,
    /// Names of the resources it reads.
    pub reads: Vec<String>,
    /// Names of the resources it writes.
    pub writes: Vec<String>,
    /// Device bytes of what it writes.
    pub bytes_written: u64,
}

/// The passes and GPU resources a scene needs, in execution order.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Plan {
    /// Passes in order.
    pub passes: Vec<Pass>,
    /// Every resource, once.
    pub resources: Vec<Resource>,
    /// What was asked for and not built, and why.
    pub notes: Vec<String>,
}

impl Plan {
    /// Total device bytes.
    pub fn bytes(&self) -> u64 {
        self.resources.iter().map(|r| r.bytes).sum()
    }
}

/// Bytes of a mip-mapped Rgba16Float texture (8 bytes a texel, a chain of halvings).
fn mipped_bytes(width: u32, height: u32) -> (u64, u32) {
    let (mut w, mut h, mut bytes, mut levels) = (width.max(1), height.max(1), 0u64, 0u32);
    loop {
        bytes += 8 * w as u64 * h as u64;
        levels += 1;
        if w == 1 && h == 1 {
            return (bytes, levels);
        }
        w = (w / 2).max(1);
        h = (h / 2).max(1);
    }
}

/// The plan of `graph` for `scene` drawn at `width x height` into `format`: every pass of the
/// graph's ordered list, what it reads and writes, and every resource with its bytes.
pub fn plan(scene: &Scene, loaded: &Loaded, graph: &PassGraph, width: u32, height: u32, format: TargetFormat) -> Plan {
    let resources = resources(scene, loaded, graph, width, height, format);
    let passes = graph
        .passes
        .iter()
        .map(|&kind| {
            let (what, reads, writes) = describe(kind, scene, loaded, graph);
            let bytes = resources.iter().filter(|r| writes.contains(&r.name)).map(|r| r.bytes).sum();
            Pass { kind, name: kind.name(), what, reads, writes, bytes_written: bytes }
        })
        .collect();
    Plan { passes, resources, notes: graph.notes.clone() }
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// What pass `kind` does, reads and writes.
fn describe(kind: PassKind, scene: &Scene, loaded: &Loaded, graph: &PassGraph) -> (String, Vec<String>, Vec<String>) {
    let key = graph.shadow.map_or(0, |s| s.light);
    match kind {
        PassKind::ShadowMap => (
            format!("depth of the mesh seen from light[{key}], bounding its sphere tightly"),
            names(&["vertices", "indices", "uniforms"]),
            names(&["shadow map"]),
        ),
        PassKind::TranslucentShadows => (
            "translucent casters seen from the key light, their opacity added where no opaque surface is in front"
                .into(),
            names(&["uniforms", "shadow map"]),
            names(&["shadow opacity"]),
        ),
        PassKind::TsdPrepass => (
            format!(
                "mesh at its UVs; keeps texels with N.V > -{} (frustum culling skips every TSD pass when the head is \
                 off screen)",
                scene.skin.tsd.backface_bias
            ),
            names(&["vertices", "indices", "uniforms"]),
            names(&["tsd depth"]),
        ),
        PassKind::TsdLightMap => {
            let mut reads =
                names(&["vertices", "indices", "uniforms", "normal map", "per-vertex curvature", "tsd depth"]);
            if graph.shadow.is_some() {
                reads.push("shadow map".into());
            }
            if scene.skin.tsd.kernel_map.is_some() {
                reads.push("kernel map".into());
            }
            let what = "diffuse irradiance of every light into texture space (key light through the shadow map), \
                        kernel size in alpha";
            (what.into(), reads, names(&[tsd::LIGHT_MAP_NAMES[0]]))
        }
        PassKind::TsdBlur(i) => {
            let kernel = graph.tsd.map_or(TsdKernel::Single, |t| t.kernel);
            let (from, to) = tsd::blur_maps(kernel, i);
            let mut reads = names(&[tsd::LIGHT_MAP_NAMES[from]]);
            let what = match (i, kernel) {
                (0, _) => "12-tap Poisson blur, dilating the UV borders".into(),
                (_, TsdKernel::Single) => "12-tap Poisson blur".into(),
                (_, TsdKernel::Gaussians) => {
                    reads.push(tsd::LIGHT_MAP_NAMES[1].into());
                    "12-tap Poisson blur by one Gaussian's increment, the weighted light map B added".to_string()
                }
            };
            (what, reads, names(&[tsd::LIGHT_MAP_NAMES[to]]))
        }
        PassKind::Base => (describe_base(loaded, graph), base_reads(graph), names(&["colour target", "depth"])),
    }
}

fn base_reads(graph: &PassGraph) -> Vec<String> {
    let mut reads = names(&["vertices", "indices", "uniforms", "normal map", "albedo"]);
    let optional = [
        (graph.vertex_curvature, "per-vertex curvature"),
        (graph.diffuse_lut, "diffuse LUT"),
        (graph.zonal_table, "zonal table"),
        (graph.shadow.is_some(), "shadow map"),
        (graph.features.translucent_shadows, "shadow opacity"),
        (graph.shadow_lut, "shadow LUT"),
    ];
    reads.extend(optional.into_iter().filter(|(on, _)| *on).map(|(_, name)| name.to_string()));
    if let Some(tsd) = graph.tsd {
        reads.push(tsd::LIGHT_MAP_NAMES[tsd::final_map(tsd.kernel, tsd.blurs)].into());
    }
    reads
}

fn describe_base(loaded: &Loaded, graph: &PassGraph) -> String {
    let specular = match loaded.inputs.specular {
        SpecularMode::Pixel => "per pixel",
        SpecularMode::Vertex => "per vertex (the paper's look)",
    };
    format!(
        "texture-space bump mapping and the Lafortune BRDF, lobes {specular}; diffuse: {}{}{}{}",
        describe_diffuse(&graph.features),
        if graph.features.shadows { "; key light shadowed" } else { "" },
        if graph.features.shadow_scattering { " with shadow scattering" } else { "" },
        if graph.features.sh_ambient { "; order-2 SH ambient" } else { "" },
    )
}

fn describe_diffuse(features: &Features) -> &'static str {
    match (features.diffuse, features.derivative_curvature) {
        (DiffuseMode::Lambert, _) => "Lambert",
        (DiffuseMode::Lut, false) => "pre-integrated LUT, per-vertex curvature, per-channel normals",
        (DiffuseMode::Lut, true) => "pre-integrated LUT, derivative curvature, per-channel normals",
        (DiffuseMode::Blog, _) => "the blog's closed-form pre-integrated curves",
        (DiffuseMode::OwnFit, _) => "our closed-form fit of the pre-integrated LUT",
        (DiffuseMode::LightMap, _) => "the blurred texture-space light map x albedo",
    }
}

/// Every GPU resource of `graph`, once.
fn resources(
    scene: &Scene,
    loaded: &Loaded,
    graph: &PassGraph,
    width: u32,
    height: u32,
    format: TargetFormat,
) -> Vec<Resource> {
    let inputs = &loaded.inputs;
    let texture = |name: &str, t: &Texture| {
        let (bytes, levels) = mipped_bytes(t.width, t.height);
        Resource {
            name: name.into(),
            detail: format!("{}x{} Rgba16Float, {levels} mip levels", t.width, t.height),
            bytes,
        }
    };
    let n_vertices = inputs.vertices.len() as u64;
    let mut out = vec![
        resource("vertices", format!("{n_vertices} vertices x 48 B (position, normal, tangent, uv)"), 48 * n_vertices),
        resource("indices", format!("{} triangles, u32", inputs.indices.len() / 3), 4 * inputs.indices.len() as u64),
        resource(
            "uniforms",
            format!("camera, {} lights, {} Lafortune lobes", inputs.lights.len(), inputs.brdf.lobes.len()),
            crate::gpu::UNIFORM_BYTES,
        ),
        texture("normal map", &inputs.normal_map),
        texture("albedo", &inputs.albedo),
    ];
    out.extend(effect_resources(scene, graph, n_vertices));
    let (target_name, bytes_per_pixel) = match format {
        TargetFormat::Hdr16 => ("Rgba16Float", 8),
        TargetFormat::Hdr32 => ("Rgba32Float", 16),
        TargetFormat::Srgb8 => ("Rgba8UnormSrgb", 4),
    };
    let pixels = width as u64 * height as u64;
    out.push(resource("colour target", format!("{width}x{height} {target_name}"), bytes_per_pixel * pixels));
    out.push(resource("depth", format!("{width}x{height} Depth32Float"), 4 * pixels));
    out
}

fn resource(name: &str, detail: String, bytes: u64) -> Resource {
    Resource { name: name.into(), detail, bytes }
}

/// A table built on the CPU: `w` x `h` Rgba32Float.
fn table(name: &str, w: u32, h: u32, what: &str) -> Resource {
    Resource {
        name: name.into(),
        detail: format!("{w}x{h} Rgba32Float, {what}; built on the CPU, cached by its parameters"),
        bytes: 16 * w as u64 * h as u64,
    }
}

/// The resources the graph's effects add: curvature, tables, the shadow map, the light maps.
fn effect_resources(scene: &Scene, graph: &PassGraph, n_vertices: u64) -> Vec<Resource> {
    let mut out = Vec::new();
    let skin = &scene.skin;
    if graph.vertex_curvature {
        let detail = format!(
            "{n_vertices} vertices x 8 B (1/r in 1/mm from the mesh's mean curvature, mm per UV unit); computed on the CPU"
        );
        out.push(resource("per-vertex curvature", detail, 8 * n_vertices));
    }
    if graph.diffuse_lut {
        let [w, h] = skin.preintegrated.lut_size;
        let what = format!(
            "pre-integrated diffuse D(N.L, 1/r), {} normalisation, {} ring",
            skin.preintegrated.normalisation.name(),
            skin.preintegrated.domain.name()
        );
        out.push(table("diffuse LUT", w, h, &what));
    }
    if graph.zonal_table {
        let n = crate::skin::sh::ZONAL_SAMPLES as u32;
        out.push(table("zonal table", n, 3, "the skin's SH zonal factors A_l(1/r), l = 0, 1, 2"));
    }
    if let Some(shadow) = graph.shadow {
        let (n, key, filter) = (shadow.size as u64, shadow.light, shadow.filter);
        let detail = format!("{n}x{n} Depth32Float, light[{key}], {filter}x{filter} box filter");
        out.push(resource("shadow map", detail, 4 * n * n));
        if graph.features.translucent_shadows {
            let casters = scene.translucent.len();
            let detail = format!("{n}x{n} Rgba16Float: opacity of {casters} translucent caster(s), summed");
            out.push(resource("shadow opacity", detail, 8 * n * n));
        }
    }
    if graph.shadow_lut {
        let n = crate::skin::shadow::SHADOW_LUT_SIDE;
        out.push(table("shadow LUT", n, n, "shadow scattering P_S(s, w), penumbra of a disc of taps"));
    }
    if let Some(tsd) = graph.tsd {
        let n = tsd.size as u64;
        out.push(resource("tsd depth", format!("{n}x{n} Depth32Float in texture space (culling pre-pass)"), 4 * n * n));
        for name in &tsd::LIGHT_MAP_NAMES[..tsd::map_count(tsd.kernel)] {
            out.push(resource(
                name,
                format!("{n}x{n} Rgba16Float: diffuse irradiance, kernel size in alpha"),
                8 * n * n,
            ));
        }
        if let Some(path) = &skin.tsd.kernel_map {
            out.push(resource("kernel map", format!("{} (per-texel blur kernel size)", path.display()), 0));
        }
    }
    out
}
