//! Scene files (TOML): the mesh and its scale, the albedo and normal maps, the Lafortune skin BRDF
//! (Haro et al. 2001, section 5.2), lights, cameras, the output and the effects to build.
//!
//! Unknown keys are errors everywhere (a misspelt `intesity` must not silently become the
//! default). Relative paths are taken against the scene file's folder. Validation happens once,
//! here: a [`Scene`] holds only values the renderer can use (finite, unit directions, exponents
//! above zero, a field of view inside (0, 180) degrees, at most [`MAX_LIGHTS`] lights and
//! `MAX_LOBES` lobes, effects the rules of [`crate::effect`] allow). Every error names the file
//! and the field (`light[1].direction`). The scene deserialises into the shading types
//! ([`Light`], [`Lafortune`], [`SpecularMode`]); it keeps its file for later messages.
//!
//! ```toml
//! mesh = "head.obj"
//! mm_per_unit = 1.0             # how long one mesh unit is, in millimetres (curvature needs it)
//! albedo = "albedo.png"         # or a constant linear RGB: [0.6, 0.45, 0.4]; absent: brdf.diffuse
//!                               # (a .glb/.gltf here or in normal_map.path: crate::gltf_maps)
//! specular = "pixel"            # or "vertex" (the paper's per-vertex specular look)
//! effects = ["shadows"]         # crate::effect::Effect names; their settings: skin::options
//!
//! [normal_map]
//! path = "face-normals.png"
//! green = "up"                  # "up" (OpenGL, glTF, Blender) or "down" (DirectX, Unreal)
//! frames = "paper"              # or "mikktspace"
//! made_by = "scripts/demo"      # optional: what makes the file, named when it is missing
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

use skinkit_maps::GreenAxis;

use crate::brdf::{Lafortune, Lobe};
use crate::effect::{self, Effect};
use crate::frames::FrameMethod;
use crate::shading::{Light, LightKind, MAX_LIGHTS, MAX_LOBES, SpecularMode};
use crate::skin::options::{
    Environment, RawEnvironment, RawPreintegrated, RawShadow, RawSkin, RawTsd, SkinOptions, Sky,
};

/// Largest output side accepted, in pixels.
pub const MAX_OUTPUT_SIDE: u32 = 16384;

/// What a scene without `mm_per_unit` is told: the mesh's units are not in the file (OBJ has
/// none; glTF says metres, but face-mesh exports often are not).
pub const MISSING_MM_PER_UNIT: &str = "missing: how long one mesh unit is, in millimetres (1 for a \
     mesh in mm, 10 in cm, 1000 in metres, as glTF and Blender's default are); skinkit cannot tell \
     from the mesh, and pores, curvature and scattering are sized by it";

/// Errors from reading a scene file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read.
    #[error("{file}")]
    Io {
        file: String,
        #[source]
        error: std::io::Error,
    },
    /// The input gate refused the file or could not read it ([`skinkit_maps::input`]).
    #[error(transparent)]
    Input(#[from] skinkit_maps::input::InputError),
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
    /// The scene file itself (named in later messages).
    pub file: PathBuf,
    /// The mesh file (OBJ, glTF, GLB), resolved against the scene's folder.
    pub mesh: PathBuf,
    /// Millimetres per mesh unit.
    pub mm_per_unit: f32,
    /// The albedo; `None` means the BRDF's diffuse `rho_d` everywhere.
    pub albedo: Option<Albedo>,
    /// The fine-scale normal map, if any.
    pub normal_map: Option<NormalMapSpec>,
    /// The Lafortune skin BRDF (`rho_d` and lobes; default [`Lafortune::skin`]).
    pub brdf: Lafortune,
    /// Where the specular lobes are evaluated.
    pub specular: SpecularMode,
    /// Lights, one to [`MAX_LIGHTS`].
    pub lights: Vec<SceneLight>,
    /// Cameras, at least one (a render makes one image per camera).
    pub cameras: Vec<Camera>,
    /// Output size and optional path.
    pub output: Output,
    /// The effects, in file order, without repeats, allowed by `effect::check_rules`.
    pub effects: Vec<Effect>,
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
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(&effect)
    }

    /// The scene file, for messages.
    pub fn name(&self) -> String {
        self.file.display().to_string()
    }

    /// Every file the scene reads, each with what it is for messages: the scene itself, its
    /// meshes and maps, and the skin options' environment image and kernel map. The one list an
    /// output check compares against, so that a new input cannot be missed.
    pub fn input_files(&self) -> Vec<(String, PathBuf)> {
        let mut inputs =
            vec![("the scene".to_owned(), self.file.clone()), ("the scene's mesh".to_owned(), self.mesh.clone())];
        if let Some(Albedo::Map(p)) = &self.albedo {
            inputs.push(("the scene's albedo".to_owned(), p.clone()));
        }
        let normals = self.normal_map.iter().flat_map(|n| skinkit_maps::udim::files(&n.path));
        inputs.extend(normals.map(|p| ("the scene's normal map".to_owned(), p)));
        inputs.extend(self.translucent.iter().map(|t| ("a translucent mesh of the scene".to_owned(), t.mesh.clone())));
        if let Some(Environment { sky: Sky::LatLong(p), .. }) = &self.skin.environment {
            inputs.push(("the scene's environment image".to_owned(), p.clone()));
        }
        if let Some(p) = &self.skin.tsd.kernel_map {
            inputs.push(("the scene's TSD kernel map".to_owned(), p.clone()));
        }
        inputs
    }
}

/// A light of the scene: what the shaders light with, and whether it asks for the shadow map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneLight {
    /// Where, which colour, how bright.
    pub light: Light,
    /// `shadows = true`: the light may draw the key shadow map.
    pub shadows: bool,
}

/// Albedo: a map (linear after decoding) or a constant linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// An image, resolved against the scene's folder.
    Map(PathBuf),
    /// The same linear RGB everywhere, each channel in [0, 1].
    Constant(Vec3),
}

/// The normal map and how to read it.
#[derive(Clone, Debug, PartialEq)]
pub struct NormalMapSpec {
    /// The image, resolved against the scene's folder.
    pub path: PathBuf,
    /// Green-channel convention of the file.
    pub green: GreenAxis,
    /// Tangent basis the map was made against.
    pub frames: FrameMethod,
    /// The command that makes the file (named when the file is missing, e.g. on a fresh clone).
    pub made_by: Option<String>,
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
        match skinkit_maps::format::ImageFormat::of(path)? {
            skinkit_maps::format::ImageFormat::Png => Some(OutputFormat::Png),
            skinkit_maps::format::ImageFormat::Exr => Some(OutputFormat::Exr),
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
        let text = skinkit_maps::input::read_to_string(path, skinkit_maps::input::Kind::Toml)?;
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
        Checker { file, base }.scene(raw, origin)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    mesh: PathBuf,
    /// Optional here so that its absence is named as such (serde's "missing field" points at
    /// line 1, column 1 of the file, issue 41).
    mm_per_unit: Option<f32>,
    albedo: Option<RawAlbedo>,
    normal_map: Option<RawNormalMap>,
    brdf: Option<RawBrdf>,
    #[serde(default)]
    specular: SpecularMode,
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
    green: Option<String>,
    #[serde(default)]
    frames: FrameMethod,
    made_by: Option<String>,
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
    fn scene(&self, raw: RawScene, origin: &Path) -> Result<Scene> {
        let mm_per_unit = raw.mm_per_unit.ok_or_else(|| self.invalid("mm_per_unit", MISSING_MM_PER_UNIT))?;
        let mm_per_unit = self.positive("mm_per_unit", mm_per_unit)?;
        let effects = self.effects(&raw.effects)?;
        let skin = RawSkin {
            preintegrated: raw.preintegrated,
            environment: raw.environment,
            shadow: raw.shadow,
            tsd: raw.tsd,
        }
        .check(self.base)
        .map_err(|(field, reason)| self.invalid(field, reason))?;
        effect::check_rules(&effects, skin.environment.is_some())
            .map_err(|(field, reason)| self.invalid(field, reason))?;
        Ok(Scene {
            file: origin.to_owned(),
            mesh: self.base.join(&raw.mesh),
            mm_per_unit,
            albedo: raw.albedo.map(|a| self.albedo(a)).transpose()?,
            normal_map: raw.normal_map.map(|n| self.normal_map(n)).transpose()?,
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

    fn normal_map(&self, raw: RawNormalMap) -> Result<NormalMapSpec> {
        let green = match raw.green {
            None => GreenAxis::Up,
            Some(g) => g.parse().map_err(|reason: String| self.invalid("normal_map.green", reason))?,
        };
        Ok(NormalMapSpec { path: self.base.join(raw.path), green, frames: raw.frames, made_by: raw.made_by })
    }

    fn brdf(&self, raw: Option<RawBrdf>) -> Result<Lafortune> {
        let skin = Lafortune::skin();
        let Some(raw) = raw else { return Ok(skin) };
        let diffuse = match raw.diffuse {
            Some(d) => self.in_range3("brdf.diffuse", d, 0.0, 1.0)?,
            None => skin.diffuse,
        };
        let lobes: Vec<Lobe> = match raw.lobes {
            Some(lobes) => lobes.iter().enumerate().map(|(i, l)| self.lobe(i, l)).collect::<Result<_>>()?,
            None => skin.lobes,
        };
        if lobes.len() > MAX_LOBES {
            let reason = format!("{} lobes given, the base pass evaluates at most {MAX_LOBES}", lobes.len());
            return Err(self.invalid("brdf.lobes", reason));
        }
        Ok(Lafortune { diffuse, lobes })
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

    fn lights(&self, raw: &[RawLight]) -> Result<Vec<SceneLight>> {
        if raw.is_empty() {
            return Err(self.invalid("light", "the scene has no [[light]]"));
        }
        if raw.len() > MAX_LIGHTS {
            let reason = format!("{} lights given, the base pass shades at most {MAX_LIGHTS}", raw.len());
            return Err(self.invalid("light", reason));
        }
        raw.iter().enumerate().map(|(i, l)| self.light(i, l)).collect()
    }

    fn light(&self, i: usize, raw: &RawLight) -> Result<SceneLight> {
        let name = |key: &str| format!("light[{i}].{key}");
        let kind = match (raw.kind, raw.direction, raw.position) {
            (RawLightKind::Directional, Some(d), None) => {
                LightKind::Directional { toward: self.unit(&name("direction"), d)? }
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
        Ok(SceneLight { light: Light { kind, color: colour, intensity }, shadows: raw.shadows })
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

    fn effects(&self, raw: &[String]) -> Result<Vec<Effect>> {
        let mut out: Vec<Effect> = Vec::new();
        for (i, name) in raw.iter().enumerate() {
            let Some(effect) = Effect::from_name(name) else {
                let reason = format!("unknown effect `{name}` (known: {})", Effect::known_names());
                return Err(self.invalid(format!("effects[{i}]"), reason));
            };
            if out.contains(&effect) {
                return Err(self.invalid(format!("effects[{i}]"), format!("`{name}` is listed twice")));
            }
            out.push(effect);
        }
        Ok(out)
    }
}
