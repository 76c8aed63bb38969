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
//! - A map larger than the device's `max_texture_dimension_2d` is halved (2x2 box, the mip
//!   filter) until it fits, with a warning naming the limit.
//!
//! # Effects
//! [`graph`] turns the scene's `effects` and lights into the pass graph: the base pass's shader
//! features (each effect a WGSL override, compiled out when absent), which light draws the one
//! shadow map (the first with `shadows = true`, and only when `shadows` is listed), which tables
//! are built (the diffuse LUT only for `preintegrated`, the shadow LUT only for
//! `shadow-scattering`, the zonal table only for `sh-ambient` over a pre-integrated diffuse) and
//! whether texture-space diffusion runs. [`plan`] lists it for people (`skinkit render
//! --explain`); [`crate::skin::setup::build`] computes it. What was asked and cannot be built (a
//! `shadows` effect with no shadow-casting light) is a note, never a silent omission.

use std::path::Path;

use glam::{Mat3, Vec3};
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{Channels, NormalEncoding};

use crate::brdf::{self, Lafortune};
use crate::frames::{self, FrameMethod};
use crate::gpu::OutputFormat as TargetFormat;
use crate::mesh::{Mesh, MeshError};
use crate::passes::{DiffuseMode, Features};
use crate::scene::{self, Albedo, Scene};
use crate::shading::{self, GreenAxis, MAX_LIGHTS, MAX_LOBES, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex};
use crate::skin::options::{Analytic, CurvatureSource};

/// Errors from turning a scene into render inputs.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The mesh could not be loaded (the message names the file).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A map could not be read (the message names the file).
    #[error("{field}: {source}")]
    Map {
        /// `normal_map.path` or `albedo`.
        field: &'static str,
        #[source]
        source: skinkit_maps::Error,
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
pub fn gpu_camera(camera: &scene::Camera, width: u32, height: u32) -> shading::Camera {
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

/// The target format and tone curve for an output file format: PNG is tone mapped (Reinhard, so
/// highlights roll off instead of clipping) and sRGB encoded; EXR stays linear.
pub fn target_for(format: scene::OutputFormat) -> (TargetFormat, ToneCurve) {
    match format {
        scene::OutputFormat::Png => (TargetFormat::Srgb8, ToneCurve::Reinhard),
        scene::OutputFormat::Exr => (TargetFormat::Hdr32, ToneCurve::None),
    }
}

/// Loads the mesh and maps of `scene`, builds the frames and the inputs of its first camera.
/// `max_texture_side` is the device limit (maps above it are halved until they fit).
///
/// # Errors
/// Unreadable or malformed mesh or maps, more lights or lobes than the pass shades.
pub fn load(scene: &Scene, scene_file: &Path, width: u32, height: u32, max_texture_side: u32) -> Result<Loaded> {
    let file = scene_file.display().to_string();
    let unsupported =
        |field: &str, reason: String| LoadError::Unsupported { file: file.clone(), field: field.into(), reason };
    if scene.lights.len() > MAX_LIGHTS {
        return Err(unsupported(
            "light",
            format!("{} lights given, the base pass shades at most {MAX_LIGHTS}", scene.lights.len()),
        ));
    }
    if scene.brdf.lobes.len() > MAX_LOBES {
        return Err(unsupported(
            "brdf.lobes",
            format!("{} lobes given, the base pass evaluates at most {MAX_LOBES}", scene.brdf.lobes.len()),
        ));
    }
    let loaded = Mesh::load(&scene.mesh)?;
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
            let encoding = NormalEncoding { green: spec.green.axis() };
            let map = io::read_normal_map(&spec.path, encoding, &limits)
                .map_err(|source| LoadError::Map { field: "normal_map.path", source })?;
            fit(Texture::from_normal_map(&map), "normal map", max_texture_side, &mut warnings)
        }
    };
    let albedo = match &scene.albedo {
        None => Texture::solid([1.0; 4]),
        Some(Albedo::Constant(c)) => Texture::solid([c.x, c.y, c.z, 1.0]),
        Some(Albedo::Map(path)) => {
            let texture = read_albedo(path, &limits).map_err(|source| LoadError::Map { field: "albedo", source })?;
            fit(texture, "albedo", max_texture_side, &mut warnings)
        }
    };
    // A constant albedo scales rho_d; with no albedo rho_d is the BRDF's own.
    let diffuse = match &scene.albedo {
        Some(_) => Vec3::ONE,
        None => scene.brdf.diffuse,
    };
    let brdf = Lafortune {
        diffuse,
        lobes: scene.brdf.lobes.iter().map(|l| brdf::Lobe { cx: l.cx, cy: l.cy, cz: l.cz, n: l.n }).collect(),
    };
    let lights = scene
        .lights
        .iter()
        .map(|light| shading::Light {
            kind: match light.kind {
                scene::LightKind::Directional { direction } => shading::LightKind::Directional { toward: direction },
                scene::LightKind::Point { position } => shading::LightKind::Point { position },
            },
            color: light.colour,
            intensity: light.intensity,
        })
        .collect();
    let inputs = RenderInputs {
        vertices,
        indices: mesh.indices.clone(),
        camera: gpu_camera(&scene.cameras[0], width, height),
        lights,
        brdf,
        normal_map,
        green: GreenAxis::Up,
        albedo,
        specular: match scene.specular {
            scene::Specular::Pixel => SpecularMode::Pixel,
            scene::Specular::Vertex => SpecularMode::Vertex,
        },
        exposure: 1.0,
        // The output decides the curve (`target_for`); callers set it.
        tone: ToneCurve::None,
        background: [0.0, 0.0, 0.0, 1.0],
    };
    Ok(Loaded { inputs, vertex_count: mesh.positions.len(), triangle_count: mesh.triangle_count(), warnings })
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
    /// Its name.
    pub name: String,
    /// What it does.
    pub what: String,
    /// Names of the resources it reads.
    pub reads: Vec<String>,
    /// Names of the resources it writes.
    pub writes: Vec<String>,
}

/// The passes and GPU resources a scene needs, in execution order.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
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

/// What a scene's effects and lights decide: the base pass's features, which light casts the
/// shadow map, which tables are built and which per-vertex data is computed. [`plan`] lists it
/// for people; [`crate::skin::setup`] builds it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Graph {
    /// The base pass's shader features.
    pub features: Features,
    /// The light whose shadow map is drawn, if any.
    pub key_light: Option<usize>,
    /// Whether the diffuse LUT is built (read by the base pass).
    pub diffuse_lut: bool,
    /// Whether the shadow-scattering LUT is built.
    pub shadow_lut: bool,
    /// Whether the skin's zonal table is built (SH ambient with a pre-integrated diffuse).
    pub zonal_table: bool,
    /// Whether per-vertex curvature is computed from the mesh.
    pub vertex_curvature: bool,
    /// Whether texture-space diffusion runs.
    pub tsd: bool,
    /// Why something asked for is not built (no shadow-casting light, extra shadow lights).
    pub notes: Vec<String>,
}

/// The pass graph of `scene`: only what its effects and lights ask for.
pub fn graph(scene: &Scene) -> Graph {
    let mut notes = Vec::new();
    let pre = &scene.skin.preintegrated;
    let diffuse = if scene.has_effect("preintegrated") {
        DiffuseMode::Lut
    } else if scene.has_effect("preintegrated-analytic") {
        match pre.analytic {
            Analytic::Own => DiffuseMode::OwnFit,
            Analytic::Blog => DiffuseMode::Blog,
        }
    } else if scene.has_effect("tsd") {
        DiffuseMode::LightMap
    } else {
        DiffuseMode::Lambert
    };
    let casters: Vec<usize> = scene.lights.iter().enumerate().filter(|(_, l)| l.shadows).map(|(i, _)| i).collect();
    let key_light = match (scene.has_effect("shadows"), casters.first()) {
        (true, Some(&key)) => {
            for &other in &casters[1..] {
                notes.push(format!("light[{other}] asks for shadows: one shadow map is drawn, for light[{key}]"));
            }
            Some(key)
        }
        (true, None) => {
            notes.push("effect `shadows`: no light has `shadows = true`, so no shadow map is drawn".into());
            None
        }
        (false, Some(_)) => {
            for &i in &casters {
                notes.push(format!(
                    "light[{i}] asks for shadows but `effects` does not list `shadows`: drawn unshadowed"
                ));
            }
            None
        }
        (false, None) => None,
    };
    let shadows = key_light.is_some();
    let shadow_scattering = shadows && scene.has_effect("shadow-scattering");
    let translucent_shadows = shadows && !scene.translucent.is_empty();
    if !shadows && !scene.translucent.is_empty() {
        notes.push("[[translucent]] casters tint only the key light's shadow map, and none is drawn".into());
    }
    let sh_ambient = scene.has_effect("sh-ambient");
    let derivative = diffuse.reads_curvature() && pre.curvature == CurvatureSource::Derivative;
    let zonal_table = sh_ambient && diffuse.reads_curvature();
    let tsd = diffuse == DiffuseMode::LightMap;
    let vertex_curvature = (diffuse.reads_curvature() && !derivative) || zonal_table || tsd;
    Graph {
        features: Features {
            diffuse,
            derivative_curvature: derivative,
            sh_ambient,
            shadows,
            shadow_scattering,
            translucent_shadows,
        },
        key_light,
        diffuse_lut: diffuse == DiffuseMode::Lut,
        shadow_lut: shadow_scattering,
        zonal_table,
        vertex_curvature,
        tsd,
        notes,
    }
}

/// The plan for `scene` drawn at `width x height` into `format`, from the loaded inputs.
///
/// # Errors
/// None today; kept fallible for effects a device cannot build.
pub fn plan(
    scene: &Scene,
    _scene_file: &Path,
    loaded: &Loaded,
    width: u32,
    height: u32,
    format: TargetFormat,
) -> Result<Plan> {
    let graph = graph(scene);
    let inputs = &loaded.inputs;
    let texture = |name: &str, t: &Texture| {
        let (bytes, levels) = mipped_bytes(t.width, t.height);
        Resource {
            name: name.into(),
            detail: format!("{}x{} Rgba16Float, {levels} mip levels", t.width, t.height),
            bytes,
        }
    };
    let table = |name: &str, w: u32, h: u32, what: &str| Resource {
        name: name.into(),
        detail: format!("{w}x{h} Rgba32Float, {what}; built on the CPU, cached by its parameters"),
        bytes: 16 * w as u64 * h as u64,
    };
    let (target_name, bytes_per_pixel) = match format {
        TargetFormat::Hdr16 => ("Rgba16Float", 8),
        TargetFormat::Hdr32 => ("Rgba32Float", 16),
        TargetFormat::Srgb8 => ("Rgba8UnormSrgb", 4),
    };
    let pixels = width as u64 * height as u64;
    let mut resources = vec![
        Resource {
            name: "vertices".into(),
            detail: format!("{} vertices x 48 B (position, normal, tangent, uv)", inputs.vertices.len()),
            bytes: 48 * inputs.vertices.len() as u64,
        },
        Resource {
            name: "indices".into(),
            detail: format!("{} triangles, u32", inputs.indices.len() / 3),
            bytes: 4 * inputs.indices.len() as u64,
        },
        Resource {
            name: "uniforms".into(),
            detail: format!("camera, {} lights, {} Lafortune lobes", inputs.lights.len(), inputs.brdf.lobes.len()),
            bytes: crate::gpu::UNIFORM_BYTES,
        },
        texture("normal map", &inputs.normal_map),
        texture("albedo", &inputs.albedo),
    ];
    let mut base_reads: Vec<String> =
        ["vertices", "indices", "uniforms", "normal map", "albedo"].map(String::from).to_vec();
    let mut passes = Vec::new();
    let skin = &scene.skin;
    if graph.vertex_curvature {
        resources.push(Resource {
            name: "per-vertex curvature".into(),
            detail: format!(
                "{} vertices x 8 B (1/r in 1/mm from the mesh's mean curvature, mm per UV unit); computed on the CPU",
                inputs.vertices.len()
            ),
            bytes: 8 * inputs.vertices.len() as u64,
        });
        base_reads.push("per-vertex curvature".into());
    }
    if graph.diffuse_lut {
        let [w, h] = skin.preintegrated.lut_size;
        let what = format!(
            "pre-integrated diffuse D(N.L, 1/r), {} normalisation, {} ring",
            skin.preintegrated.normalisation.name(),
            skin.preintegrated.domain.name()
        );
        resources.push(table("diffuse LUT", w, h, &what));
        base_reads.push("diffuse LUT".into());
    }
    if graph.zonal_table {
        let n = crate::skin::setup::ZONAL_SAMPLES as u32;
        resources.push(table("zonal table", n, 3, "the skin's SH zonal factors A_l(1/r), l = 0, 1, 2"));
        base_reads.push("zonal table".into());
    }
    if let Some(key) = graph.key_light {
        let shadow = &skin.shadow;
        let (n, filter) = if graph.shadow_lut {
            let (_, radius) = crate::passes::bounding_sphere(&inputs.vertices);
            let size = crate::skin::setup::scattering_map_size(
                shadow.map_size,
                shadow.scatter_filter,
                shadow.scatter_width_mm,
                radius * scene.mm_per_unit,
            );
            (size, shadow.scatter_filter)
        } else {
            (shadow.map_size, shadow.filter)
        };
        resources.push(Resource {
            name: "shadow map".into(),
            detail: format!("{n}x{n} Depth32Float, light[{key}], {filter}x{filter} box filter"),
            bytes: 4 * n as u64 * n as u64,
        });
        passes.push(Pass {
            name: "shadow map".into(),
            what: format!("depth of the mesh seen from light[{key}], bounding its sphere tightly"),
            reads: ["vertices", "indices", "uniforms"].map(String::from).to_vec(),
            writes: vec!["shadow map".into()],
        });
        base_reads.push("shadow map".into());
        if graph.features.translucent_shadows {
            resources.push(Resource {
                name: "shadow opacity".into(),
                detail: format!(
                    "{n}x{n} Rgba16Float: opacity of {} translucent caster(s), summed",
                    scene.translucent.len()
                ),
                bytes: 8 * n as u64 * n as u64,
            });
            passes.push(Pass {
                name: "translucent shadows".into(),
                what: "translucent casters seen from the key light, their opacity added where no opaque surface is in front"
                    .into(),
                reads: ["uniforms", "shadow map"].map(String::from).to_vec(),
                writes: vec!["shadow opacity".into()],
            });
            base_reads.push("shadow opacity".into());
        }
    }
    if graph.shadow_lut {
        let n = crate::skin::setup::SHADOW_LUT_SIDE;
        resources.push(table("shadow LUT", n, n, "shadow scattering P_S(s, w), box-filter penumbra"));
        base_reads.push("shadow LUT".into());
    }
    if graph.tsd {
        let n = skin.tsd.size;
        let map_bytes = 8 * n as u64 * n as u64;
        resources.push(Resource {
            name: "tsd depth".into(),
            detail: format!("{n}x{n} Depth32Float in texture space (culling pre-pass)"),
            bytes: 4 * n as u64 * n as u64,
        });
        for name in ["light map A", "light map B"] {
            resources.push(Resource {
                name: name.into(),
                detail: format!("{n}x{n} Rgba16Float: diffuse irradiance, kernel size in alpha"),
                bytes: map_bytes,
            });
        }
        let mut light_reads: Vec<String> =
            ["vertices", "indices", "uniforms", "normal map", "per-vertex curvature", "tsd depth"]
                .map(String::from)
                .to_vec();
        if graph.key_light.is_some() {
            light_reads.push("shadow map".into());
        }
        if let Some(path) = &skin.tsd.kernel_map {
            resources.push(Resource {
                name: "kernel map".into(),
                detail: format!("{} (per-texel blur kernel size)", path.display()),
                bytes: 0,
            });
            light_reads.push("kernel map".into());
        }
        passes.push(Pass {
            name: "tsd back-face pre-pass".into(),
            what: format!(
                "mesh at its UVs; keeps texels with N.V > -{} (frustum culling skips every TSD pass when the head is \
                 off screen)",
                skin.tsd.backface_bias
            ),
            reads: ["vertices", "indices", "uniforms"].map(String::from).to_vec(),
            writes: vec!["tsd depth".into()],
        });
        passes.push(Pass {
            name: "tsd light map".into(),
            what: "diffuse irradiance of every light into texture space (key light through the shadow map), \
                   kernel size in alpha"
                .into(),
            reads: light_reads,
            writes: vec!["light map A".into()],
        });
        for i in 0..skin.tsd.passes {
            let (from, to) = if i % 2 == 0 { ("light map A", "light map B") } else { ("light map B", "light map A") };
            let what = if i == 0 { "12-tap Poisson blur, dilating the UV borders" } else { "12-tap Poisson blur" };
            passes.push(Pass {
                name: format!("tsd blur {}", i + 1),
                what: what.into(),
                reads: vec![from.into()],
                writes: vec![to.into()],
            });
        }
        let last = if skin.tsd.passes % 2 == 0 { "light map A" } else { "light map B" };
        base_reads.push(last.into());
    }
    resources.push(Resource {
        name: "colour target".into(),
        detail: format!("{width}x{height} {target_name}"),
        bytes: bytes_per_pixel * pixels,
    });
    resources.push(Resource {
        name: "depth".into(),
        detail: format!("{width}x{height} Depth32Float"),
        bytes: 4 * pixels,
    });
    let specular = match inputs.specular {
        SpecularMode::Pixel => "per pixel",
        SpecularMode::Vertex => "per vertex (the paper's look)",
    };
    passes.push(Pass {
        name: "base".into(),
        what: format!(
            "texture-space bump mapping and the Lafortune BRDF, lobes {specular}; diffuse: {}{}{}{}",
            describe_diffuse(&graph.features),
            if graph.features.shadows { "; key light shadowed" } else { "" },
            if graph.features.shadow_scattering { " with shadow scattering" } else { "" },
            if graph.features.sh_ambient { "; order-2 SH ambient" } else { "" },
        ),
        reads: base_reads,
        writes: ["colour target", "depth"].map(String::from).to_vec(),
    });
    Ok(Plan { passes, resources, notes: graph.notes })
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
