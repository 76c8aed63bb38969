//! The scene's scattering settings: the `[preintegrated]`, `[environment]`, `[shadow]` and `[tsd]`
//! tables, each read only by the effect that names it (`effects = [...]`).
//!
//! ```toml
//! effects = ["preintegrated", "sh-ambient", "shadows", "shadow-scattering"]
//!
//! [preintegrated]               # read by preintegrated and preintegrated-analytic
//! curvature = "vertex"          # per-vertex 1/r from the mesh, or "derivative" (fwidth, per pixel)
//! curvature_scale = 1.0         # multiplies 1/r (the listing's tuneCurvature)
//! normal_blur = [1.0, 0.5, 0.25] # per channel: 0 the full normal map, 1 the blurred one
//! blur_mip = 4.0                # the blurred normal: the map's mip chain clamped at this level
//! lut_size = [256, 256]         # diffuse LUT texels (N.L x 1/r)
//! integrate = "sphere"          # over a sphere's surface; "full": the ring [-pi, pi]; "half": [-pi/2, pi/2]
//! normalisation = "2d"          # Gaussian normalisation ("1d": the listing's)
//! analytic = "own"              # preintegrated-analytic: our fit, or "blog"
//!
//! [environment]                 # read by sh-ambient; one of latlong, constant, sky + ground
//! latlong = "studio.exr"        # equirectangular, row 0 = up (+y)
//! constant = [0.2, 0.2, 0.2]
//! sky = [0.3, 0.35, 0.45]
//! ground = [0.08, 0.06, 0.05]
//! intensity = 1.0
//! zonal = "exact"               # skin zonal factors projected from the LUT, or "blog"
//!
//! [shadow]                      # read by shadows, shadow-scattering, tsd
//! map_size = 2048               # texels per side of the key light's shadow map
//! filter = 5                    # box filter: filter x filter taps (odd), a linear-ramp penumbra
//! bias = 1.5                    # depth bias in shadow-map texels
//! new_penumbra = 0.05           # shadow-scattering: the sharp penumbra's share of the filtered one
//! scatter_width_mm = 5.0        # shadow-scattering: the diameter of the disc of taps on the skin
//! scatter_taps = 64             # shadow-scattering: taps on that disc
//!
//! [tsd]                         # read by tsd (Gosselin et al. 2004; d'Eon and Luebke 2007)
//! size = 1024                   # light map texels per side
//! kernel = "gaussians"          # the profile's Gaussians per channel; "single": one kernel for all
//! passes = 1                    # Poisson blur passes (per Gaussian with "gaussians"; the first dilates)
//! kernel_map = "kernel.png"     # optional: per-texel kernel size in [0, 1), radius = a * k + b
//! kernel_scale = [3.0, 2.0]     # with kernel_map: (a, b) in texels of a 512 map (the chapter's vBlurScale)
//! curvature_gain = 0.0          # derived kernel: radius x (1 + gain_mm * 1/r); Gosselin's widening on curved skin, off (see the book)
//! backface_bias = 0.3           # the back-face pre-pass keeps texels with N.V > -0.3
//! reuse_below_px = 0            # distance culling: a head smaller than this reuses the last light map
//! ```

use std::path::PathBuf;

use glam::Vec3;
use serde::Deserialize;

use super::profile::{Domain, Normalisation};

/// Where the LUT's 1/r comes from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum CurvatureSource {
    /// Per-vertex mean curvature precomputed from the mesh, interpolated (smooth).
    #[default]
    Vertex,
    /// `length(fwidth(N)) / length(fwidth(P))` per pixel (the paper's; constant per triangle).
    Derivative,
}

/// Which closed form `preintegrated-analytic` evaluates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Analytic {
    /// Our least-squares fit to our LUT.
    #[default]
    Own,
    /// The blog's hand-fitted curves.
    Blog,
}

/// Which zonal factors `sh-ambient` uses for skin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Zonal {
    /// Projected from the diffuse response over the whole sphere, per 1/r.
    #[default]
    Exact,
    /// The blog's closed-form approximations.
    Blog,
}

/// `[preintegrated]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Preintegrated {
    /// Where 1/r comes from.
    pub curvature: CurvatureSource,
    /// Scale on 1/r.
    pub curvature_scale: f32,
    /// Per-channel blend toward the blurred normal.
    pub normal_blur: Vec3,
    /// Mip level the blurred sample is clamped at.
    pub blur_mip: f32,
    /// LUT size (N.L texels, 1/r texels).
    pub lut_size: [u32; 2],
    /// What the table integrates over: a sphere or a ring.
    pub domain: Domain,
    /// Gaussian normalisation.
    pub normalisation: Normalisation,
    /// Closed form for `preintegrated-analytic`.
    pub analytic: Analytic,
}

impl Default for Preintegrated {
    fn default() -> Self {
        Self {
            curvature: CurvatureSource::Vertex,
            curvature_scale: 1.0,
            normal_blur: Vec3::new(1.0, 0.5, 0.25),
            blur_mip: 4.0,
            lut_size: [256, 256],
            domain: Domain::default(),
            normalisation: Normalisation::TwoD,
            analytic: Analytic::Own,
        }
    }
}

/// The light `sh-ambient` projects.
#[derive(Clone, Debug, PartialEq)]
pub enum Sky {
    /// An equirectangular image, row 0 = +y.
    LatLong(PathBuf),
    /// The same radiance everywhere.
    Constant(Vec3),
    /// `sky` above the horizon blending to `ground` below, linear in the up component.
    Gradient {
        /// Radiance straight up (+y).
        sky: Vec3,
        /// Radiance straight down.
        ground: Vec3,
    },
}

/// `[environment]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Environment {
    /// What the light is.
    pub sky: Sky,
    /// Scale on it.
    pub intensity: f32,
    /// Which zonal factors.
    pub zonal: Zonal,
}

/// `[shadow]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ShadowOptions {
    /// Shadow map side.
    pub map_size: u32,
    /// Box filter side in taps (odd).
    pub filter: u32,
    /// Depth bias in texels.
    pub bias: f32,
    /// The sharp penumbra's width as a share of the filtered one (shadow scattering; a directional
    /// light's true penumbra is a step).
    pub new_penumbra: f32,
    /// With shadow scattering, the diameter (mm) of the disc of taps on the skin's tangent plane
    /// whose lit share locates the shadow edge: the scattered light is known within it. Wider
    /// reaches more of the profile's red tail but rounds the corners of a shadow (the head:
    /// relative RMSE 0.0130, 0.0121, 0.0121, 0.0134 at 3, 4, 5, 6 mm against the reference).
    pub scatter_width_mm: f32,
    /// With shadow scattering, the taps on that disc.
    pub scatter_taps: u32,
}

impl Default for ShadowOptions {
    fn default() -> Self {
        Self { map_size: 2048, filter: 5, bias: 1.5, new_penumbra: 0.05, scatter_width_mm: 5.0, scatter_taps: 64 }
    }
}

/// How texture-space diffusion blurs the light map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum TsdKernel {
    /// The profile's sum of Gaussians, each channel with its own weights (d'Eon and Luebke):
    /// the light map blurred by each Gaussian's increment in turn, widest first, the weighted
    /// irradiance added back after each (so red scatters farther than blue).
    #[default]
    Gaussians,
    /// One kernel for all three channels, of the profile's luminance variance (Gosselin); the
    /// only kind a kernel map can drive.
    Single,
}

/// `[tsd]`.
#[derive(Clone, Debug, PartialEq)]
pub struct TsdOptions {
    /// Light map side.
    pub size: u32,
    /// How the light map is blurred.
    pub kernel: TsdKernel,
    /// Blur passes (with [`TsdKernel::Gaussians`], per Gaussian).
    pub passes: u32,
    /// An artist's kernel map, if given.
    pub kernel_map: Option<PathBuf>,
    /// (a, b): with a kernel map, radius = a * k + b texels of a 512 map.
    pub kernel_scale: [f32; 2],
    /// Derived kernel: radius x (1 + gain * 1/r), gain in mm.
    pub curvature_gain: f32,
    /// Back-face pre-pass bias.
    pub backface_bias: f32,
    /// Distance culling threshold, pixels of projected head diameter (0: never).
    pub reuse_below_px: f32,
}

impl Default for TsdOptions {
    fn default() -> Self {
        Self {
            size: 1024,
            kernel: TsdKernel::Gaussians,
            passes: 1,
            kernel_map: None,
            kernel_scale: [3.0, 2.0],
            curvature_gain: 0.0,
            backface_bias: 0.3,
            reuse_below_px: 0.0,
        }
    }
}

/// Every scattering table of a scene (defaults where absent).
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SkinOptions {
    /// `[preintegrated]`.
    pub preintegrated: Preintegrated,
    /// `[environment]` (required by `sh-ambient`).
    pub environment: Option<Environment>,
    /// `[shadow]`.
    pub shadow: ShadowOptions,
    /// `[tsd]`.
    pub tsd: TsdOptions,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawPreintegrated {
    curvature: Option<CurvatureSource>,
    curvature_scale: Option<f32>,
    normal_blur: Option<[f32; 3]>,
    blur_mip: Option<f32>,
    lut_size: Option<[u32; 2]>,
    integrate: Option<Domain>,
    normalisation: Option<Normalisation>,
    analytic: Option<Analytic>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawEnvironment {
    latlong: Option<PathBuf>,
    constant: Option<[f32; 3]>,
    sky: Option<[f32; 3]>,
    ground: Option<[f32; 3]>,
    intensity: Option<f32>,
    zonal: Option<Zonal>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawShadow {
    map_size: Option<u32>,
    filter: Option<u32>,
    bias: Option<f32>,
    new_penumbra: Option<f32>,
    scatter_width_mm: Option<f32>,
    scatter_taps: Option<u32>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTsd {
    size: Option<u32>,
    kernel: Option<TsdKernel>,
    passes: Option<u32>,
    kernel_map: Option<PathBuf>,
    kernel_scale: Option<[f32; 2]>,
    curvature_gain: Option<f32>,
    backface_bias: Option<f32>,
    reuse_below_px: Option<f32>,
}

/// The raw tables as the scene file holds them.
#[derive(Default)]
pub(crate) struct RawSkin {
    pub preintegrated: Option<RawPreintegrated>,
    pub environment: Option<RawEnvironment>,
    pub shadow: Option<RawShadow>,
    pub tsd: Option<RawTsd>,
}

/// A field name and why its value is refused.
pub(crate) type Refusal = (String, String);

fn in_range(field: &str, v: f32, lo: f32, hi: f32) -> Result<f32, Refusal> {
    match v.is_finite() && v >= lo && v <= hi {
        true => Ok(v),
        false => Err((field.into(), format!("must be within [{lo}, {hi}], not {v}"))),
    }
}

fn side(field: &str, v: u32, lo: u32, hi: u32) -> Result<u32, Refusal> {
    match (lo..=hi).contains(&v) {
        true => Ok(v),
        false => Err((field.into(), format!("must be within {lo}..={hi}, not {v}"))),
    }
}

fn colour(field: &str, v: [f32; 3]) -> Result<Vec3, Refusal> {
    let v = Vec3::from(v);
    match v.is_finite() && v.cmpge(Vec3::ZERO).all() {
        true => Ok(v),
        false => Err((field.into(), format!("{v} must be finite and not negative"))),
    }
}

impl RawSkin {
    /// Validates every table; `base` resolves relative paths.
    pub(crate) fn check(self, base: &std::path::Path) -> Result<SkinOptions, Refusal> {
        Ok(SkinOptions {
            preintegrated: self.preintegrated.unwrap_or_default().check()?,
            environment: self.environment.map(|e| e.check(base)).transpose()?,
            shadow: self.shadow.unwrap_or_default().check()?,
            tsd: self.tsd.unwrap_or_default().check(base)?,
        })
    }
}

impl RawPreintegrated {
    fn check(self) -> Result<Preintegrated, Refusal> {
        let d = Preintegrated::default();
        let blur = self.normal_blur.unwrap_or(d.normal_blur.to_array());
        for (c, v) in blur.iter().enumerate() {
            in_range(&format!("preintegrated.normal_blur[{c}]"), *v, 0.0, 1.0)?;
        }
        let lut_size = self.lut_size.unwrap_or(d.lut_size);
        side("preintegrated.lut_size[0]", lut_size[0], 2, 4096)?;
        side("preintegrated.lut_size[1]", lut_size[1], 2, 4096)?;
        Ok(Preintegrated {
            curvature: self.curvature.unwrap_or(d.curvature),
            curvature_scale: in_range(
                "preintegrated.curvature_scale",
                self.curvature_scale.unwrap_or(d.curvature_scale),
                0.0,
                1e6,
            )?,
            normal_blur: Vec3::from(blur),
            blur_mip: in_range("preintegrated.blur_mip", self.blur_mip.unwrap_or(d.blur_mip), 0.0, 16.0)?,
            lut_size,
            domain: self.integrate.unwrap_or(d.domain),
            normalisation: self.normalisation.unwrap_or(d.normalisation),
            analytic: self.analytic.unwrap_or(d.analytic),
        })
    }
}

impl RawEnvironment {
    fn check(self, base: &std::path::Path) -> Result<Environment, Refusal> {
        let sky = match (self.latlong, self.constant, self.sky, self.ground) {
            (Some(path), None, None, None) => Sky::LatLong(base.join(path)),
            (None, Some(c), None, None) => Sky::Constant(colour("environment.constant", c)?),
            (None, None, Some(s), Some(g)) => {
                Sky::Gradient { sky: colour("environment.sky", s)?, ground: colour("environment.ground", g)? }
            }
            _ => {
                return Err((
                    "environment".into(),
                    "give exactly one of `latlong`, `constant`, or `sky` with `ground`".into(),
                ));
            }
        };
        Ok(Environment {
            sky,
            intensity: in_range("environment.intensity", self.intensity.unwrap_or(1.0), 0.0, 1e9)?,
            zonal: self.zonal.unwrap_or_default(),
        })
    }
}

impl RawShadow {
    fn check(self) -> Result<ShadowOptions, Refusal> {
        let d = ShadowOptions::default();
        let odd = |field: &str, v: u32| -> Result<u32, Refusal> {
            let v = side(field, v, 1, 15)?;
            match v % 2 {
                1 => Ok(v),
                _ => Err((field.into(), format!("must be odd (taps centred on the texel), not {v}"))),
            }
        };
        let filter = odd("shadow.filter", self.filter.unwrap_or(d.filter))?;
        Ok(ShadowOptions {
            map_size: side("shadow.map_size", self.map_size.unwrap_or(d.map_size), 16, 16384)?,
            filter,
            bias: in_range("shadow.bias", self.bias.unwrap_or(d.bias), 0.0, 1000.0)?,
            new_penumbra: in_range("shadow.new_penumbra", self.new_penumbra.unwrap_or(d.new_penumbra), 0.01, 1.0)?,
            scatter_width_mm: in_range(
                "shadow.scatter_width_mm",
                self.scatter_width_mm.unwrap_or(d.scatter_width_mm),
                0.1,
                1000.0,
            )?,
            scatter_taps: side("shadow.scatter_taps", self.scatter_taps.unwrap_or(d.scatter_taps), 1, 1024)?,
        })
    }
}

impl RawTsd {
    fn check(self, base: &std::path::Path) -> Result<TsdOptions, Refusal> {
        let d = TsdOptions::default();
        let scale = self.kernel_scale.unwrap_or(d.kernel_scale);
        in_range("tsd.kernel_scale[0]", scale[0], 0.0, 512.0)?;
        in_range("tsd.kernel_scale[1]", scale[1], 0.0, 512.0)?;
        // A kernel map gives one radius per texel in texels: it drives the single kernel only.
        let kernel = match (self.kernel, &self.kernel_map) {
            (Some(TsdKernel::Gaussians), Some(_)) => {
                return Err(("tsd.kernel".into(), "\"gaussians\" cannot follow a kernel_map; use \"single\"".into()));
            }
            (Some(kernel), _) => kernel,
            (None, Some(_)) => TsdKernel::Single,
            (None, None) => d.kernel,
        };
        Ok(TsdOptions {
            size: side("tsd.size", self.size.unwrap_or(d.size), 16, 16384)?,
            kernel,
            passes: side("tsd.passes", self.passes.unwrap_or(d.passes), 0, 64)?,
            kernel_map: self.kernel_map.map(|p| base.join(p)),
            kernel_scale: scale,
            curvature_gain: in_range("tsd.curvature_gain", self.curvature_gain.unwrap_or(d.curvature_gain), 0.0, 1e3)?,
            backface_bias: in_range("tsd.backface_bias", self.backface_bias.unwrap_or(d.backface_bias), 0.0, 2.0)?,
            reuse_below_px: in_range("tsd.reuse_below_px", self.reuse_below_px.unwrap_or(d.reuse_below_px), 0.0, 1e6)?,
        })
    }
}
