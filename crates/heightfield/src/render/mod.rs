//! Photographs of a [`Heightfield`] under a light rig: the image formation photometric stereo
//! inverts (Haro et al. 2001, section 3, capture of the mold by shape from shading), with the
//! nuisances a real capture has.
//!
//! Per light and pixel, in linear units where 1 is the sensor's full scale:
//!
//! `value = exposure * (albedo * E * max(0, n.L) * visibility + specular + ambient) + noise`
//!
//! then clipped to `[0, 1]` and quantised by rounding. `L` points from the surface to the light
//! (camera frame, x right, y up, z toward the camera). A near point light has per-texel direction
//! `normalize(P - X)` and irradiance `E * |P|^2 / |P - X|^2`, so the field's centre (the origin, on
//! the mean plane) receives exactly `E`. `visibility` is 0 in cast shadow (when enabled) and the
//! Lambert term is 0 wherever `n.L <= 0`. The specular term is Blinn-Phong with view `(0, 0, 1)`:
//! `strength * E * max(0, n.H)^shininess`, only where the Lambert term is lit.
//!
//! Grey photos take the Rec. 709 luminance `0.2126 R + 0.7152 G + 0.0722 B` of the RGB value before
//! noise (the same weights as `Photo::luminance`). Sensor noise is Gaussian with standard deviation
//! `noise_sigma` (fraction of full scale), drawn per sample from a ChaCha8 stream keyed by
//! `(seed, light index, row)` in column then channel order, so photos do not depend on the thread
//! count.

mod sensor;
mod shadow;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use skinkit_maps::{Channels, ColorMap, Photo};

use crate::{Error, Heightfield, Result};
use sensor::Sensor;
use shadow::ShadowCaster;

/// Light index that keys the noise of [`render_ambient`] (no real rig has this many lights).
const AMBIENT_STREAM: u32 = u32::MAX;

/// One light of a rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderLight {
    /// Unit direction from the surface toward a distant light (camera frame); ignored when
    /// `position` is set.
    pub direction: Vec3,
    /// RGB irradiance (at the field's centre for a point light).
    pub intensity: Vec3,
    /// Position of a near point light in mm, origin at the field's centre, z above the mean plane.
    pub position: Option<Vec3>,
}

impl RenderLight {
    /// A distant light in `direction` (normalised here).
    pub fn directional(direction: Vec3, intensity: Vec3) -> Self {
        RenderLight { direction: direction.normalize_or_zero(), intensity, position: None }
    }

    /// A near point light at `position` (mm); `direction` is set to the direction of the centre.
    pub fn point(position: Vec3, intensity: Vec3) -> Self {
        RenderLight { direction: position.normalize_or_zero(), intensity, position: Some(position) }
    }

    /// `count` distant lights evenly spaced in azimuth (the first toward +x, counter-clockwise) at
    /// `polar_deg` from the camera axis.
    pub fn ring(count: usize, polar_deg: f32, intensity: Vec3) -> Vec<Self> {
        let (sin_p, cos_p) = polar_deg.to_radians().sin_cos();
        (0..count)
            .map(|i| {
                let azimuth = std::f32::consts::TAU * i as f32 / count as f32;
                let (s, c) = azimuth.sin_cos();
                RenderLight::directional(Vec3::new(sin_p * c, sin_p * s, cos_p), intensity)
            })
            .collect()
    }
}

/// Surface reflectance.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    Constant(Vec3),
    /// One linear RGB albedo per texel, the size of the field.
    Map(ColorMap),
}

/// Blinn-Phong highlight, the specular contamination of a real mold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Specular {
    pub strength: f32,
    pub shininess: f32,
}

/// Stored sample type of the photos.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantise {
    Float,
    U8,
    U16,
}

/// How photos are formed and stored.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderConfig {
    pub albedo: Albedo,
    /// Ray-march cast shadows over the height grid (attached shadows, `n.L <= 0`, are always dark).
    pub shadows: bool,
    pub specular: Option<Specular>,
    /// Constant radiance added to every pixel (stray light).
    pub ambient: Vec3,
    /// Standard deviation of additive Gaussian noise, as a fraction of full scale.
    pub noise_sigma: f32,
    /// Multiplier of the radiance before noise.
    pub exposure: f32,
    /// Grey (Rec. 709 luminance) or RGB.
    pub channels: Channels,
    pub format: Quantise,
    /// Seed of the sensor noise.
    pub seed: u64,
}

impl Default for RenderConfig {
    /// Grey albedo 0.7, no shadows, specular, ambient or noise, float grey photos.
    fn default() -> Self {
        RenderConfig {
            albedo: Albedo::Constant(Vec3::splat(0.7)),
            shadows: false,
            specular: None,
            ambient: Vec3::ZERO,
            noise_sigma: 0.0,
            exposure: 1.0,
            channels: Channels::Gray,
            format: Quantise::Float,
            seed: 0,
        }
    }
}

/// One photo of `field` per light.
///
/// # Errors
/// When a light has a zero or non-finite direction, position or intensity, the albedo map's size
/// differs from the field's, or a config value is not finite or negative.
pub fn render(field: &Heightfield, lights: &[RenderLight], config: &RenderConfig) -> Result<Vec<Photo>> {
    validate(field, config)?;
    let lights: Vec<Light> = lights.iter().enumerate().map(|(i, l)| Light::new(i, l)).collect::<Result<_>>()?;
    let caster = config
        .shadows
        .then(|| ShadowCaster::new(field.heights.as_slice(), field.width(), field.height(), field.mm_per_texel));
    let scene = Scene { field, config, caster: caster.as_ref() };
    lights.iter().enumerate().map(|(i, light)| scene.photo(i as u32, Some(light))).collect()
}

/// A photo with every light off: ambient light and sensor noise only (a dark frame when the ambient
/// is zero). Its noise stream differs from every lit photo's.
///
/// # Errors
/// As [`render`].
pub fn render_ambient(field: &Heightfield, config: &RenderConfig) -> Result<Photo> {
    validate(field, config)?;
    Scene { field, config, caster: None }.photo(AMBIENT_STREAM, None)
}

/// A validated light in f64.
struct Light {
    direction: DVec3,
    intensity: Vec3,
    position: Option<DVec3>,
    /// `|P|^2`, the squared distance of a point light to the field's centre.
    centre_dist_sq: f64,
}

impl Light {
    fn new(index: usize, l: &RenderLight) -> Result<Self> {
        let field = |f: &str| format!("render light {index}: {f}");
        if !l.intensity.is_finite() {
            return Err(Error::invalid(field("intensity"), format!("{} is not finite", l.intensity)));
        }
        if let Some(p) = l.position {
            if !p.is_finite() || p.length_squared() == 0.0 {
                return Err(Error::invalid(field("position"), format!("{p} is not a usable light position")));
            }
            let p = p.as_dvec3();
            let dir = p.normalize();
            return Ok(Light {
                direction: dir,
                intensity: l.intensity,
                position: Some(p),
                centre_dist_sq: p.length_squared(),
            });
        }
        let d = l.direction.as_dvec3();
        if !d.is_finite() || d.length_squared() < 1e-12 {
            return Err(Error::invalid(
                field("direction"),
                format!("{} has zero length or is not finite", l.direction),
            ));
        }
        Ok(Light { direction: d.normalize(), intensity: l.intensity, position: None, centre_dist_sq: 1.0 })
    }

    /// Unit direction toward the light and irradiance scale at surface point `x` (mm).
    #[inline]
    fn at(&self, x: DVec3) -> (DVec3, f32) {
        match self.position {
            None => (self.direction, 1.0),
            Some(p) => {
                let d = p - x;
                let dist_sq = d.length_squared().max(1e-12);
                (d / dist_sq.sqrt(), (self.centre_dist_sq / dist_sq) as f32)
            }
        }
    }
}

fn validate(field: &Heightfield, config: &RenderConfig) -> Result<()> {
    field.check()?;
    if let Albedo::Map(m) = &config.albedo
        && m.size() != field.heights.size()
    {
        let reason = format!("map is {}x{} but the field {}x{}", m.width(), m.height(), field.width(), field.height());
        return Err(Error::invalid("render config albedo", reason));
    }
    let check = |name: &str, ok: bool, v: String| {
        if ok { Ok(()) } else { Err(Error::invalid(format!("render config {name}"), v)) }
    };
    check("ambient", config.ambient.is_finite(), format!("{} is not finite", config.ambient))?;
    let sigma = config.noise_sigma;
    check("noise_sigma", sigma.is_finite() && sigma >= 0.0, format!("{sigma} is negative or not finite"))?;
    check("exposure", config.exposure.is_finite(), format!("{} is not finite", config.exposure))?;
    if let Some(s) = config.specular {
        let ok = s.strength.is_finite() && s.shininess.is_finite() && s.shininess >= 0.0;
        check("specular", ok, format!("strength {} shininess {} are not usable", s.strength, s.shininess))?;
    }
    Ok(())
}

/// Everything one photo needs.
struct Scene<'a> {
    field: &'a Heightfield,
    config: &'a RenderConfig,
    caster: Option<&'a ShadowCaster<'a>>,
}

impl Scene<'_> {
    /// Renders the photo of `light` (or of the ambient only), rows in parallel.
    fn photo(&self, stream: u32, light: Option<&Light>) -> Result<Photo> {
        let (w, h) = self.field.heights.size();
        let sensor = Sensor::new(self.config, stream);
        let n = self.config.channels.count();
        let mut values = vec![0f32; w * h * n];
        values.par_chunks_mut(w * n).enumerate().for_each(|(row, out)| {
            for col in 0..w {
                let radiance = match light {
                    Some(l) => self.radiance(col, row, l),
                    None => Vec3::ZERO,
                };
                let v = (radiance + self.config.ambient) * self.config.exposure;
                write_channels(v, self.config.channels, &mut out[col * n..(col + 1) * n]);
            }
            sensor.add_noise(row, out);
        });
        Ok(Photo::new(w, h, self.config.channels, sensor.quantise(values))?)
    }

    /// Reflected radiance of texel `(col, row)` under one light, before ambient and exposure.
    #[inline]
    fn radiance(&self, col: usize, row: usize, light: &Light) -> Vec3 {
        let n = self.field.normals.get(col, row).as_dvec3();
        let (x, y) = self.field.texel_to_mm(col, row);
        let point = DVec3::new(x, y, *self.field.heights.get(col, row) as f64);
        let (l, scale) = light.at(point);
        let cos = n.dot(l);
        if cos <= 0.0 || !self.visible(col, row, point, l, light) {
            return Vec3::ZERO;
        }
        let e = light.intensity * scale;
        let albedo = match &self.config.albedo {
            Albedo::Constant(a) => *a,
            Albedo::Map(m) => *m.get(col, row),
        };
        albedo * e * cos as f32 + self.specular(n, l) * e
    }

    fn visible(&self, col: usize, row: usize, point: DVec3, l: DVec3, light: &Light) -> bool {
        self.caster.is_none_or(|c| c.visible(col, row, point, l, light.position))
    }

    /// Blinn-Phong factor `strength * max(0, n.H)^shininess`, `H` halfway to the view `(0, 0, 1)`.
    fn specular(&self, n: DVec3, l: DVec3) -> f32 {
        let Some(s) = self.config.specular else { return 0.0 };
        let half = (l + DVec3::Z).normalize_or_zero();
        s.strength * (n.dot(half).max(0.0) as f32).powf(s.shininess)
    }
}

/// Stores an RGB value as RGB or as its Rec. 709 luminance.
#[inline]
fn write_channels(v: Vec3, channels: Channels, out: &mut [f32]) {
    match channels {
        Channels::Gray => out[0] = 0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z,
        Channels::Rgb => out.copy_from_slice(&v.to_array()),
    }
}
