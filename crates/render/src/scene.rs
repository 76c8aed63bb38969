//! Scene files (TOML): the mesh and its scale, the albedo and normal maps, the Lafortune skin BRDF
//! (Haro et al. 2001, section 5.2), lights, cameras, the output and the effects to build.
//!
//! Unknown keys are errors everywhere (a misspelt `intesity` must not silently become the
//! default). Relative paths are taken against the scene file's folder. Validation happens once,
//! here: a [`Scene`] holds only values the renderer can use (finite, unit directions, exponents
//! above zero, a field of view inside (0, 180) degrees). Every error names the file and the field
//! (`light[1].direction`).
//!
//! ```toml
//! mesh = "head.obj"
//! mm_per_unit = 1.0             # how long one mesh unit is, in millimetres (curvature needs it)
//! albedo = "albedo.png"         # or a constant linear RGB: [0.6, 0.45, 0.4]; absent: brdf.diffuse
//! specular = "pixel"            # or "vertex" (the paper's per-vertex specular look)
//! effects = ["shadows"]         # names from KNOWN_EFFECTS; their settings: skin::options
//!
//! [normal_map]
//! path = "face-normals.png"
//! green = "up"                  # "up" (OpenGL, glTF, Blender) or "down" (DirectX, Unreal)
//! frames = "paper"              # or "mikktspace"
//!
//! [brdf]                        # both keys optional: default_diffuse(), default_lobes()
//! diffuse = [0.43, 0.30, 0.33]
//! lobes = [{ cxy = [-1.0, -1.0, -1.0], cz = [0.9, 0.7, 0.6], n = [64.0, 64.0, 44.0] }]
//!
//! [[light]]
//! kind = "directional"          # direction points from the surface toward the light
//! direction = [0.3, 0.5, 1.0]
//! colour = [1.0, 1.0, 1.0]      # default white
//! intensity = 3.0               # default 1
//! shadows = true                # default false
//!
//! [[camera]]
//! position = [0.0, 0.0, 600.0]
//! target = [0.0, 0.0, 0.0]
//! up = [0.0, 1.0, 0.0]          # default +y
//! fov_deg = 30.0                # default 30
//!
//! [[translucent]]               # optional: tints the key light's shadow map, not drawn itself
//! mesh = "lens.obj"
//! opacity = [0.6, 0.3, 0.2]     # per channel, in [0, 1]
//!
//! [output]
//! size = [1024, 1024]           # default 1024 x 1024
//! path = "render.png"           # optional; .png (sRGB 8-bit) or .exr (linear HDR)
//! ```

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::Deserialize;

use crate::frames::FrameMethod;
use crate::skin::options::{RawEnvironment, RawPreintegrated, RawShadow, RawSkin, RawTsd, SkinOptions};

/// Effect names a scene may list (see [`crate::load::graph`] for what each builds and
/// [`crate::skin::options`] for their settings): `preintegrated` (the LUT), `preintegrated-analytic`
/// (a closed form), `sh-ambient` (order-2 SH environment light), `shadows` (the key light's shadow
/// map), `shadow-scattering` (the penumbra LUT), `tsd` (texture-space diffusion). One of
/// `preintegrated`, `preintegrated-analytic` and `tsd` at most.
pub const KNOWN_EFFECTS: &[&str] =
    &["preintegrated", "preintegrated-analytic", "sh-ambient", "shadows", "shadow-scattering", "tsd"];

/// Largest output side accepted, in pixels.
pub const MAX_OUTPUT_SIDE: u32 = 16384;

/// Errors from reading a scene file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    /// Not valid TOML, an unknown key, or a value of the wrong type (the TOML parser's message
    /// names the key and line).
    #[error("{file}: {message}")]
    Syntax { file: String, message: String },
    /// A value the renderer cannot use.
    #[error("{file}: {field}: {reason}")]
    Invalid { file: String, field: String, reason: String },
}

/// Result alias for scene reading.
pub type Result<T, E = SceneError> = std::result::Result<T, E>;

/// A validated scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The mesh file (OBJ, glTF, GLB), resolved against the scene's folder.
    pub mesh: PathBuf,
    /// Millimetres per mesh unit.
    pub mm_per_unit: f32,
    /// The albedo; `None` means the BRDF's diffuse `rho_d` everywhere.
    pub albedo: Option<Albedo>,
    /// The fine-scale normal map, if any.
    pub normal_map: Option<NormalMapSpec>,
    /// The Lafortune skin BRDF.
    pub brdf: Brdf,
    /// Where the specular lobes are evaluated.
    pub specular: Specular,
    /// Lights, at least one.
    pub lights: Vec<Light>,
    /// Cameras, at least one (a render makes one image per camera).
    pub cameras: Vec<Camera>,
    /// Output size and optional path.
    pub output: Output,
    /// Effect names, each from [`KNOWN_EFFECTS`], in file order, without repeats.
    pub effects: Vec<String>,
    /// The scattering tables (`[preintegrated]`, `[environment]`, `[shadow]`, `[tsd]`).
    pub skin: SkinOptions,
    /// Translucent shadow casters (`[[translucent]]`): they tint the key light's shadow map
    /// (Gosselin et al.'s translucent shadows) and are not drawn themselves.
    pub translucent: Vec<Translucent>,
}

/// A translucent shadow caster.
#[derive(Clone, Debug, PartialEq)]
pub struct Translucent {
    /// Its mesh, resolved against the scene's folder.
    pub mesh: PathBuf,
    /// Opacity per channel in [0, 1] (light through it keeps `1 - opacity`).
    pub opacity: Vec3,
}

impl Scene {
    /// Whether the scene lists `effect`.
    pub fn has_effect(&self, effect: &str) -> bool {
        self.effects.iter().any(|e| e == effect)
    }
}

/// Albedo: a map (linear after decoding) or a constant linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// An image, resolved against the scene's folder.
    Map(PathBuf),
    /// The same linear RGB everywhere, each channel in [0, 1].
    Constant(Vec3),
}

/// Which way a normal map's green channel points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Green {
    /// Green grows toward the top of the image (OpenGL, glTF, Blender).
    #[default]
    Up,
    /// Green grows toward the bottom (DirectX, Unreal).
    Down,
}

impl Green {
    /// The `maps` crate's name for it (what its readers take).
    pub fn axis(self) -> skinkit_maps::GreenAxis {
        match self {
            Green::Up => skinkit_maps::GreenAxis::Up,
            Green::Down => skinkit_maps::GreenAxis::Down,
        }
    }
}

/// The normal map and how to read it.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMapSpec {
    /// The image, resolved against the scene's folder.
    pub path: PathBuf,
    /// Green-channel convention of the file.
    pub green: Green,
    /// Tangent basis the map was made against.
    pub frames: FrameMethod,
}

/// One Lafortune lobe: `[Cx ux vx + Cy uy vy + Cz uz vz]^n` per RGB channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lobe {
    /// `Cx` per channel.
    pub cx: Vec3,
    /// `Cy` per channel.
    pub cy: Vec3,
    /// `Cz` per channel.
    pub cz: Vec3,
    /// Exponent per channel, above zero.
    pub n: Vec3,
}

/// Diffuse albedo and Lafortune lobes.
#[derive(Clone, Debug, PartialEq)]
pub struct Brdf {
    /// `rho_d` per channel, in [0, 1].
    pub diffuse: Vec3,
    /// The lobes (may be empty: diffuse only).
    pub lobes: Vec<Lobe>,
}

impl Default for Brdf {
    fn default() -> Self {
        Brdf { diffuse: default_diffuse(), lobes: default_lobes() }
    }
}

/// The skin `rho_d` of the pbrt-v1 skin material (REFERENCE.md, "Rendering").
pub fn default_diffuse() -> Vec3 {
    Vec3::new(0.428425, 0.301341, 0.331054)
}

/// The 3-lobe Lafortune skin set of the pbrt-v1 skin material (REFERENCE.md, "Rendering"),
/// `Cx = Cy = Cxy`. Lobe 0 has a negative `Cz`: a grazing lobe relying on the clamp at zero.
#[allow(clippy::excessive_precision)] // The table's digits, as published.
pub fn default_lobes() -> Vec<Lobe> {
    let lobe = |cxy: [f32; 3], cz: [f32; 3], n: [f32; 3]| Lobe {
        cx: Vec3::from(cxy),
        cy: Vec3::from(cxy),
        cz: Vec3::from(cz),
        n: Vec3::from(n),
    };
    vec![
        lobe([-1.131747, -1.016939, -0.966018], [-1.209182, -1.462488, -1.222419], [6.421658, 3.699932, 3.524889]),
        lobe([-0.546570, -0.643533, -0.638934], [0.380123, 0.410559, 0.437367], [3.685044, 4.266495, 4.539742]),
        lobe([-0.998888, -1.020153, -1.027479], [0.857998, 0.703913, 0.573625], [64.208486, 63.919687, 43.809866]),
    ]
}

/// Where the specular lobes are evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Specular {
    /// Per pixel against the normal map (the default).
    #[default]
    Pixel,
    /// Per vertex, interpolated (the look the paper's hardware forced).
    Vertex,
}

/// A light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Directional or point, with its direction or position.
    pub kind: LightKind,
    /// Linear RGB colour, non-negative.
    pub colour: Vec3,
    /// Scale on the colour, non-negative.
    pub intensity: f32,
    /// Whether the light casts shadows.
    pub shadows: bool,
}

/// Light geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// At infinity; the unit direction from the surface toward the light.
    Directional { direction: Vec3 },
    /// At a point, in mesh units.
    Point { position: Vec3 },
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position, mesh units.
    pub position: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Unit up hint, not parallel to the view direction.
    pub up: Vec3,
    /// Vertical field of view in degrees, inside (0, 180).
    pub fov_deg: f32,
}

/// Output image size and optional path.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// Width and height in pixels.
    pub size: [u32; 2],
    /// Where to write, resolved against the scene's folder (the command line may override).
    pub path: Option<PathBuf>,
}

/// Output file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    /// 8-bit sRGB PNG.
    Png,
    /// Linear HDR OpenEXR.
    Exr,
}

impl OutputFormat {
    /// The format for a path's extension (case-insensitive), if supported.
    pub fn from_path(path: &Path) -> Option<OutputFormat> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "png" => Some(OutputFormat::Png),
            "exr" => Some(OutputFormat::Exr),
            _ => None,
        }
    }
}

impl Scene {
    /// Reads and validates a scene file.
    ///
    /// # Errors
    /// Unreadable file, TOML syntax, unknown keys, wrong types, invalid values.
    pub fn load(path: &Path) -> Result<Scene> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| SceneError::Io { file: path.display().to_string(), source })?;
        Scene::parse(&text, path)
    }

    /// Parses and validates scene text; `origin` is the scene file's path (its folder resolves
    /// relative paths; it names the file in errors).
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn parse(text: &str, origin: &Path) -> Result<Scene> {
        let file = origin.display().to_string();
        let raw: RawScene =
            toml::from_str(text).map_err(|e| SceneError::Syntax { file: file.clone(), message: e.to_string() })?;
        let base = origin.parent().unwrap_or(Path::new(""));
        Checker { file, base }.scene(raw)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    mesh: PathBuf,
    mm_per_unit: f32,
    albedo: Option<RawAlbedo>,
    normal_map: Option<RawNormalMap>,
    brdf: Option<RawBrdf>,
    #[serde(default)]
    specular: Specular,
    #[serde(default)]
    light: Vec<RawLight>,
    #[serde(default)]
    camera: Vec<RawCamera>,
    output: Option<RawOutput>,
    #[serde(default)]
    effects: Vec<String>,
    preintegrated: Option<RawPreintegrated>,
    environment: Option<RawEnvironment>,
    shadow: Option<RawShadow>,
    tsd: Option<RawTsd>,
    #[serde(default)]
    translucent: Vec<RawTranslucent>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTranslucent {
    mesh: PathBuf,
    opacity: [f32; 3],
}

#[derive(Deserialize)]
#[serde(untagged)]
enum RawAlbedo {
    Map(PathBuf),
    Constant([f32; 3]),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNormalMap {
    path: PathBuf,
    #[serde(default)]
    green: Green,
    #[serde(default)]
    frames: FrameMethod,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBrdf {
    diffuse: Option<[f32; 3]>,
    lobes: Option<Vec<RawLobe>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLobe {
    cxy: Option<[f32; 3]>,
    cx: Option<[f32; 3]>,
    cy: Option<[f32; 3]>,
    cz: [f32; 3],
    n: [f32; 3],
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
enum RawLightKind {
    Directional,
    Point,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    kind: RawLightKind,
    direction: Option<[f32; 3]>,
    position: Option<[f32; 3]>,
    colour: Option<[f32; 3]>,
    intensity: Option<f32>,
    #[serde(default)]
    shadows: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: [f32; 3],
    target: [f32; 3],
    up: Option<[f32; 3]>,
    fov_deg: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    size: Option<[u32; 2]>,
    path: Option<PathBuf>,
}

/// Turns raw values into a [`Scene`], naming the file and field in every error.
struct Checker<'a> {
    file: String,
    base: &'a Path,
}

impl Checker<'_> {
    fn scene(&self, raw: RawScene) -> Result<Scene> {
        let mm_per_unit = self.positive("mm_per_unit", raw.mm_per_unit)?;
        let effects = self.effects(&raw.effects)?;
        let skin = RawSkin {
            preintegrated: raw.preintegrated,
            environment: raw.environment,
            shadow: raw.shadow,
            tsd: raw.tsd,
        }
        .check(self.base)
        .map_err(|(field, reason)| self.invalid(field, reason))?;
        self.effect_rules(&effects, &skin)?;
        Ok(Scene {
            mesh: self.base.join(&raw.mesh),
            mm_per_unit,
            albedo: raw.albedo.map(|a| self.albedo(a)).transpose()?,
            normal_map: raw.normal_map.map(|n| NormalMapSpec {
                path: self.base.join(n.path),
                green: n.green,
                frames: n.frames,
            }),
            brdf: self.brdf(raw.brdf)?,
            specular: raw.specular,
            lights: self.lights(&raw.light)?,
            cameras: self.cameras(&raw.camera)?,
            output: self.output(raw.output)?,
            effects,
            skin,
            translucent: raw
                .translucent
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    let opacity = self.in_range3(&format!("translucent[{i}].opacity"), t.opacity, 0.0, 1.0)?;
                    Ok(Translucent { mesh: self.base.join(&t.mesh), opacity })
                })
                .collect::<Result<_>>()?,
        })
    }

    /// Effects that contradict each other or lack what they read.
    fn effect_rules(&self, effects: &[String], skin: &SkinOptions) -> Result<()> {
        let has = |e: &str| effects.iter().any(|x| x == e);
        let diffuse: Vec<&str> =
            ["preintegrated", "preintegrated-analytic", "tsd"].into_iter().filter(|e| has(e)).collect();
        if diffuse.len() > 1 {
            let reason = format!("`{}` each decide the diffuse term: list one", diffuse.join("` and `"));
            return Err(self.invalid("effects", reason));
        }
        if has("shadow-scattering") && !has("shadows") {
            return Err(self.invalid("effects", "`shadow-scattering` filters the shadow map: list `shadows` too"));
        }
        if has("sh-ambient") && skin.environment.is_none() {
            return Err(self.invalid("environment", "`sh-ambient` needs an [environment] table"));
        }
        Ok(())
    }

    fn invalid(&self, field: impl Into<String>, reason: impl Into<String>) -> SceneError {
        SceneError::Invalid { file: self.file.clone(), field: field.into(), reason: reason.into() }
    }

    fn finite3(&self, field: &str, v: [f32; 3]) -> Result<Vec3> {
        let v = Vec3::from(v);
        match v.is_finite() {
            true => Ok(v),
            false => Err(self.invalid(field, format!("{v} is not finite"))),
        }
    }

    fn positive(&self, field: &str, x: f32) -> Result<f32> {
        match x.is_finite() && x > 0.0 {
            true => Ok(x),
            false => Err(self.invalid(field, format!("must be a finite number above 0, not {x}"))),
        }
    }

    fn in_range3(&self, field: &str, v: [f32; 3], lo: f32, hi: f32) -> Result<Vec3> {
        let v = self.finite3(field, v)?;
        match v.cmpge(Vec3::splat(lo)).all() && v.cmple(Vec3::splat(hi)).all() {
            true => Ok(v),
            false => Err(self.invalid(field, format!("{v} has a channel outside [{lo}, {hi}]"))),
        }
    }

    fn unit(&self, field: &str, v: [f32; 3]) -> Result<Vec3> {
        let v = self.finite3(field, v)?;
        v.try_normalize().ok_or_else(|| self.invalid(field, format!("{v} has zero length")))
    }

    fn albedo(&self, raw: RawAlbedo) -> Result<Albedo> {
        Ok(match raw {
            RawAlbedo::Map(p) => Albedo::Map(self.base.join(p)),
            RawAlbedo::Constant(c) => Albedo::Constant(self.in_range3("albedo", c, 0.0, 1.0)?),
        })
    }

    fn brdf(&self, raw: Option<RawBrdf>) -> Result<Brdf> {
        let Some(raw) = raw else { return Ok(Brdf::default()) };
        let diffuse = match raw.diffuse {
            Some(d) => self.in_range3("brdf.diffuse", d, 0.0, 1.0)?,
            None => default_diffuse(),
        };
        let lobes = match raw.lobes {
            Some(lobes) => lobes.iter().enumerate().map(|(i, l)| self.lobe(i, l)).collect::<Result<_>>()?,
            None => default_lobes(),
        };
        Ok(Brdf { diffuse, lobes })
    }

    fn lobe(&self, i: usize, raw: &RawLobe) -> Result<Lobe> {
        let name = |key: &str| format!("brdf.lobes[{i}].{key}");
        let (cx, cy) = match (raw.cxy, raw.cx, raw.cy) {
            (Some(cxy), None, None) => (cxy, cxy),
            (None, Some(cx), Some(cy)) => (cx, cy),
            _ => return Err(self.invalid(name("cxy"), "give either `cxy` or both `cx` and `cy`")),
        };
        let n = self.finite3(&name("n"), raw.n)?;
        if !n.cmpgt(Vec3::ZERO).all() {
            return Err(self.invalid(name("n"), format!("exponents must be above 0, not {n}")));
        }
        Ok(Lobe {
            cx: self.finite3(&name("cx"), cx)?,
            cy: self.finite3(&name("cy"), cy)?,
            cz: self.finite3(&name("cz"), raw.cz)?,
            n,
        })
    }

    fn lights(&self, raw: &[RawLight]) -> Result<Vec<Light>> {
        if raw.is_empty() {
            return Err(self.invalid("light", "the scene has no [[light]]"));
        }
        raw.iter().enumerate().map(|(i, l)| self.light(i, l)).collect()
    }

    fn light(&self, i: usize, raw: &RawLight) -> Result<Light> {
        let name = |key: &str| format!("light[{i}].{key}");
        let kind = match (raw.kind, raw.direction, raw.position) {
            (RawLightKind::Directional, Some(d), None) => {
                LightKind::Directional { direction: self.unit(&name("direction"), d)? }
            }
            (RawLightKind::Point, None, Some(p)) => LightKind::Point { position: self.finite3(&name("position"), p)? },
            (RawLightKind::Directional, _, _) => {
                return Err(
                    self.invalid(name("direction"), "a directional light takes `direction` (and no `position`)")
                );
            }
            (RawLightKind::Point, _, _) => {
                return Err(self.invalid(name("position"), "a point light takes `position` (and no `direction`)"));
            }
        };
        let colour = self.in_range3(&name("colour"), raw.colour.unwrap_or([1.0; 3]), 0.0, f32::MAX)?;
        let intensity = raw.intensity.unwrap_or(1.0);
        if !(intensity.is_finite() && intensity >= 0.0) {
            return Err(self.invalid(name("intensity"), format!("must be finite and not negative, not {intensity}")));
        }
        Ok(Light { kind, colour, intensity, shadows: raw.shadows })
    }

    fn cameras(&self, raw: &[RawCamera]) -> Result<Vec<Camera>> {
        if raw.is_empty() {
            return Err(self.invalid("camera", "the scene has no [[camera]]"));
        }
        raw.iter().enumerate().map(|(i, c)| self.camera(i, c)).collect()
    }

    fn camera(&self, i: usize, raw: &RawCamera) -> Result<Camera> {
        let name = |key: &str| format!("camera[{i}].{key}");
        let position = self.finite3(&name("position"), raw.position)?;
        let target = self.finite3(&name("target"), raw.target)?;
        let view = (target - position)
            .try_normalize()
            .ok_or_else(|| self.invalid(name("target"), "the target is the camera position"))?;
        let up = self.unit(&name("up"), raw.up.unwrap_or([0.0, 1.0, 0.0]))?;
        if up.cross(view).length() < 1e-4 {
            return Err(self.invalid(name("up"), format!("{up} is parallel to the view direction")));
        }
        let fov_deg = raw.fov_deg.unwrap_or(30.0);
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(self.invalid(name("fov_deg"), format!("{fov_deg} is outside (0, 180) degrees")));
        }
        Ok(Camera { position, target, up, fov_deg })
    }

    fn output(&self, raw: Option<RawOutput>) -> Result<Output> {
        let raw = raw.unwrap_or(RawOutput { size: None, path: None });
        let size = raw.size.unwrap_or([1024, 1024]);
        if size.iter().any(|&s| s == 0 || s > MAX_OUTPUT_SIDE) {
            let reason = format!("{}x{} is outside 1..={MAX_OUTPUT_SIDE} per side", size[0], size[1]);
            return Err(self.invalid("output.size", reason));
        }
        let path = raw.path.map(|p| self.base.join(p));
        if let Some(p) = &path
            && OutputFormat::from_path(p).is_none()
        {
            return Err(self.invalid("output.path", format!("{}: expected a .png or .exr file", p.display())));
        }
        Ok(Output { size, path })
    }

    fn effects(&self, raw: &[String]) -> Result<Vec<String>> {
        let mut out: Vec<String> = Vec::new();
        for (i, name) in raw.iter().enumerate() {
            if !KNOWN_EFFECTS.contains(&name.as_str()) {
                let reason = format!("unknown effect `{name}` (known: {})", KNOWN_EFFECTS.join(", "));
                return Err(self.invalid(format!("effects[{i}]"), reason));
            }
            if out.contains(name) {
                return Err(self.invalid(format!("effects[{i}]"), format!("`{name}` is listed twice")));
            }
            out.push(name.clone());
        }
        Ok(out)
    }
}
