//! The rig file's layout as read and as written (serde), and the conversions to and from
//! [`Rig`] and [`Light`].

use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::{Light, Rig, bad};
use crate::Result;

/// Shortest decimal of an f32, as f64, so saved files read `0.70710677`, not `0.7071067690849304`.
pub(super) fn f32_to_f64(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(v as f64)
}

fn vec_out(v: Vec3) -> [f64; 3] {
    [f32_to_f64(v.x), f32_to_f64(v.y), f32_to_f64(v.z)]
}

/// The file layout as read.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RigFile {
    name: Option<String>,
    description: Option<String>,
    mm_per_pixel: Option<f64>,
    ambient: Option<String>,
    vignetting: Option<Vec<f64>>,
    #[serde(default)]
    light: Vec<LightFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightFile {
    direction: [f64; 3],
    intensity: Option<toml::Value>,
    position: Option<[f64; 3]>,
    flat: Option<String>,
    exposures: Option<Vec<f64>>,
    beam_axis: Option<[f64; 3]>,
    beam_mu: Option<f64>,
}

impl RigFile {
    pub(super) fn into_rig(self, origin: &str) -> Result<Rig> {
        let lights = self
            .light
            .into_iter()
            .enumerate()
            .map(|(i, l)| l.into_light().map_err(|reason| bad(&format!("{origin}: light {}", i + 1), reason)))
            .collect::<Result<Vec<_>>>()?;
        let mut rig = Rig::new(lights, origin)?
            .with_ambient(self.ambient.map(PathBuf::from))
            .with_mm_per_pixel(self.mm_per_pixel.map(|v| v as f32), origin)?
            .with_vignetting(self.vignetting.unwrap_or_default().into_iter().map(|k| k as f32).collect(), origin)?;
        (rig.name, rig.description) = (self.name, self.description);
        Ok(rig)
    }
}

impl LightFile {
    fn into_light(self) -> Result<Light, String> {
        let intensity = match &self.intensity {
            None => Vec3::ONE,
            Some(v) => intensity_value(v)?,
        };
        let light = Light::new(vec3(self.direction), intensity, self.position.map(vec3))?
            .with_flat(self.flat.map(PathBuf::from))
            .with_exposures(self.exposures.unwrap_or_default().into_iter().map(|t| t as f32).collect())?;
        match (self.beam_axis, self.beam_mu) {
            (None, None) => Ok(light),
            (Some(axis), Some(mu)) => light.with_beam(vec3(axis), mu as f32),
            _ => Err("beam_axis and beam_mu go together: give both or neither".into()),
        }
    }
}

fn vec3(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn intensity_value(v: &toml::Value) -> Result<Vec3, String> {
    let wrong = || format!("intensity must be a number or [r, g, b], got {v}");
    if let Some(s) = number(v) {
        return Ok(Vec3::splat(s as f32));
    }
    let arr = v.as_array().ok_or_else(wrong)?;
    let rgb: Vec<f64> = arr.iter().map(number).collect::<Option<_>>().ok_or_else(wrong)?;
    match rgb.as_slice() {
        [r, g, b] => Ok(Vec3::new(*r as f32, *g as f32, *b as f32)),
        _ => Err(wrong()),
    }
}

/// The file layout as written.
#[derive(Serialize)]
pub(super) struct RigOut {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) name: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) description: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) mm_per_pixel: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(super) ambient: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub(super) vignetting: Vec<f64>,
    pub(super) light: Vec<LightOut>,
}

#[derive(Serialize)]
pub(super) struct LightOut {
    direction: [f64; 3],
    intensity: IntensityOut,
    #[serde(skip_serializing_if = "Option::is_none")]
    position: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    flat: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    exposures: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beam_axis: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    beam_mu: Option<f64>,
}

#[derive(Serialize)]
#[serde(untagged)]
enum IntensityOut {
    Scalar(f64),
    Rgb([f64; 3]),
}

impl LightOut {
    pub(super) fn from_light(l: &Light, folder: Option<&Path>) -> LightOut {
        let e = l.intensity;
        let intensity = if e.x == e.y && e.y == e.z {
            IntensityOut::Scalar(f32_to_f64(e.x))
        } else {
            IntensityOut::Rgb(vec_out(e))
        };
        let flat = l.flat.as_ref().map(|f| {
            let rel = folder.and_then(|d| f.strip_prefix(d).ok()).unwrap_or(f);
            rel.to_string_lossy().into_owned()
        });
        let exposures = l.exposures.iter().map(|&t| f32_to_f64(t)).collect();
        LightOut {
            direction: vec_out(l.direction),
            intensity,
            position: l.position.map(vec_out),
            flat,
            exposures,
            beam_axis: l.beam.map(|(a, _)| vec_out(a)),
            beam_mu: l.beam.map(|(_, mu)| f32_to_f64(mu)),
        }
    }
}
