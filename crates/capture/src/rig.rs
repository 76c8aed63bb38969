//! Light rigs: per light a direction, an intensity and optionally a near-light position, plus the
//! checks that a rig can determine a normal at all (Haro et al. 2001, section 3: a mold is
//! photographed under k >= 3 lights of known direction).
//!
//! # Frame
//! Camera frame: x right, y up, +z toward the camera. A light direction is the unit vector from
//! the surface toward the light, so every usable light has `z > 0` (a light below the mold plane
//! cannot light it).
//!
//! # Rig files
//! A rig is a TOML file:
//! ```toml
//! name = "turntable-8"                 # optional
//! description = "one lamp, 8 positions" # optional
//! mm_per_pixel = 0.02                  # optional, size of a photo pixel on the mold
//! ambient = "ambient.png"              # optional all-lights-off frame, relative to this file
//! vignetting = [-0.3, 0.05]            # optional radial gain 1 + k1 r^2 + k2 r^4 (r = 1 in the
//!                                      # corners), divided out of lights without a flat
//!
//! [[light]]                            # one table per light, in photo order
//! direction = [0.7071, 0.0, 0.7071]    # camera frame; normalised on load
//! intensity = 1.0                      # optional (default 1.0), or [r, g, b], linear
//! position = [150.0, 0.0, 150.0]       # optional, mm, a near point light
//! flat = "flat-01.png"                 # optional flat frame (white target, this light), relative
//! exposures = [0.5, 1.0, 2.0]          # optional exposure brackets: this light's photos, in order
//! beam_axis = [-0.5, 0.0, -1.0]        # optional, near lights: the LED's axis (where it points)
//! beam_mu = 1.5                        # and its radiance falloff cos^mu about that axis
//! ```
//! Unknown keys are errors. Errors name the file and the light, numbered from 1 in file order
//! (`rig.toml: light 5: direction has zero length`); TOML syntax errors keep toml's line and
//! column. A rig needs at least 3 lights with finite values, non-zero directions with `z > 0`,
//! finite intensities `> 0`, positions (when given) above the mold plane, and directions that
//! are not coplanar.
//!
//! # Valid by construction
//! [`Light`] and [`Rig`] keep their fields private: a light is made only by [`Light::new`] (the
//! one place a direction is normalised and a light checked) and a rig only by [`Rig::new`],
//! [`Rig::parse`] / [`Rig::load`], [`Rig::turntable`] and the importers, all through one check
//! (at least 3 lights, rank 3, pixel size). So a `Rig` value can always determine a normal and
//! no solver checks it again; the photo count is checked by [`Rig::expect_photos`].
//!
//! # Conditioning
//! A rig's conditioning is computed once, when it is made ([`Rig::conditioning`]): with `L` the k x 3 matrix of
//! directions, the least-squares scaled normal `g = albedo * n` has covariance
//! `sigma^2 (L^T L)^-1` for pixel noise `sigma` (equal intensities), so coplanar lights (rank 2)
//! cannot determine a normal and a large condition number amplifies noise. For k lights evenly on
//! a ring at angle theta from the camera axis the rms tilt error of a flat patch is
//! `(sigma / albedo) sqrt(4 / (k sin^2 theta))`, and the condition number is 1 at
//! theta = 54.74 deg (docs/references.md, capture).

use std::path::{Path, PathBuf};

use glam::Vec3;
use nalgebra::{DMatrix, Matrix3};

use crate::{Error, Result};

/// Smallest ratio of smallest to largest singular value of the light matrix accepted as rank 3.
pub const COPLANAR_RATIO: f64 = 1e-3;
/// Condition number above which [`Conditioning::warning`] speaks up.
pub const WARN_CONDITION: f64 = 5.0;

/// One light of a rig, in the camera frame (x right, y up, +z toward the camera); made by
/// [`Light::new`] only, so its direction is a unit vector above the mold plane.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Unit vector from the surface toward the light.
    direction: Vec3,
    /// Linear intensity per RGB channel (a scalar intensity is splatted to all three).
    intensity: Vec3,
    /// Position of a near point light in millimetres, origin at the centre of the photographed
    /// field, when known.
    position: Option<Vec3>,
    /// A flat frame of a white target under this light ([`crate::flat`]), when the rig names one.
    flat: Option<PathBuf>,
    /// Exposure times of this light's brackets ([`crate::bracket`]); empty: one photo.
    exposures: Vec<f32>,
    /// A near LED's beam: its unit axis and the exponent `mu` of its `cos^mu` falloff.
    beam: Option<(Vec3, f32)>,
}

/// A light rig: the lights in photo order, plus optional metadata. Valid by construction (see
/// the module docs): at least 3 lights whose directions are not coplanar.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    name: Option<String>,
    description: Option<String>,
    lights: Vec<Light>,
    /// An ambient frame (all lights off), relative to the rig file's folder, to subtract.
    ambient: Option<PathBuf>,
    /// Size of a photo pixel on the mold, in millimetres, when known.
    mm_per_pixel: Option<f32>,
    /// Radial vignetting coefficients `k1, k2, ...` ([`crate::flat::FlatField::vignetting`]).
    vignetting: Vec<f32>,
    /// Of the lights' directions, computed when the rig is made.
    conditioning: Conditioning,
}

/// How well a rig's light directions determine a normal (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conditioning {
    /// Largest over smallest singular value of the k x 3 direction matrix `L` (infinite when the
    /// smallest is 0).
    pub condition_number: f64,
    /// `sqrt(trace((L^T L)^-1))`: the rms error of the scaled normal `g = albedo * n` per unit
    /// pixel noise sigma (lights of unit intensity). Infinite for a rank-deficient rig.
    pub noise_amplification: f64,
    /// `sqrt([(L^T L)^-1]_xx + [(L^T L)^-1]_yy)`: rms tilt error in radians of a flat patch
    /// (normal +z) per unit `sigma / albedo`.
    pub tilt_amplification: f64,
    /// Number of singular values above [`COPLANAR_RATIO`] times the largest.
    pub rank: usize,
}

impl Conditioning {
    /// A warning for a poorly conditioned rig (condition number above [`WARN_CONDITION`]).
    pub fn warning(&self) -> Option<String> {
        (self.condition_number > WARN_CONDITION).then(|| {
            format!(
                "poorly conditioned rig: condition number {:.1}; pixel noise is amplified {:.1}x in the normal",
                self.condition_number, self.noise_amplification
            )
        })
    }
}

impl Light {
    /// A validated light: `direction` is normalised; `intensity` is linear RGB.
    ///
    /// # Errors
    /// A reason (without location) when a value is not finite, the direction has zero length or
    /// points below the mold plane (`z <= 0`), an intensity channel is not `> 0`, or the position
    /// is not above the mold plane (`z > 0`).
    pub fn new(direction: Vec3, intensity: Vec3, position: Option<Vec3>) -> Result<Light, String> {
        let direction = unit_direction(direction)?;
        check_intensity(intensity)?;
        if let Some(p) = position {
            if !p.is_finite() {
                return Err(format!("position {} is not finite", show(p)));
            }
            if p.z <= 0.0 {
                return Err(format!("position {} is not above the mold plane (z > 0)", show(p)));
            }
        }
        Ok(Light { direction, intensity, position, flat: None, exposures: Vec::new(), beam: None })
    }

    /// Unit vector from the surface toward the light.
    pub fn direction(&self) -> Vec3 {
        self.direction
    }

    /// Linear intensity per RGB channel, each `> 0`.
    pub fn intensity(&self) -> Vec3 {
        self.intensity
    }

    /// Position of a near point light in millimetres (origin at the centre of the photographed
    /// field, `z > 0`), when known.
    pub fn position(&self) -> Option<Vec3> {
        self.position
    }

    /// The light with a flat frame (a white target under it), or none.
    pub fn with_flat(mut self, flat: Option<PathBuf>) -> Light {
        self.flat = flat;
        self
    }

    /// The flat frame of this light, when the rig names one.
    pub fn flat(&self) -> Option<&Path> {
        self.flat.as_deref()
    }

    /// The light photographed in exposure brackets of these times (empty: one photo).
    ///
    /// # Errors
    /// When a time is not finite and positive ([`crate::bracket::check_times`]).
    pub fn with_exposures(mut self, times: Vec<f32>) -> Result<Light, String> {
        crate::bracket::check_times(&times)?;
        self.exposures = times;
        Ok(self)
    }

    /// Exposure times of this light's brackets; empty when it has one photo.
    pub fn exposures(&self) -> &[f32] {
        &self.exposures
    }

    /// The light as an LED whose radiance falls off as `cos^mu` of the angle from `axis` (the
    /// direction it points; normalised here), used by the near-light solve ([`crate::near`]).
    ///
    /// # Errors
    /// When the axis is not finite or has zero length, or `mu` is not finite and `>= 0`.
    pub fn with_beam(mut self, axis: Vec3, mu: f32) -> Result<Light, String> {
        if !(axis.is_finite() && axis.length() > 0.0) {
            return Err(format!("beam_axis {} must be finite and non-zero", show(axis)));
        }
        if !(mu.is_finite() && mu >= 0.0) {
            return Err(format!("beam_mu {mu} must be finite and >= 0"));
        }
        self.beam = Some((axis.normalize(), mu));
        Ok(self)
    }

    /// The LED beam's unit axis and exponent, when the rig gives them.
    pub fn beam(&self) -> Option<(Vec3, f32)> {
        self.beam
    }

    /// Photos this light takes: one per bracket, at least one.
    pub fn photo_count(&self) -> usize {
        self.exposures.len().max(1)
    }

    /// Mean of the RGB intensity, for grey solves.
    pub fn scalar_intensity(&self) -> f32 {
        (self.intensity.x + self.intensity.y + self.intensity.z) / 3.0
    }
}

fn unit_direction(d: Vec3) -> Result<Vec3, String> {
    if !d.is_finite() {
        return Err(format!("direction {} is not finite", show(d)));
    }
    let len = d.length();
    if len == 0.0 || !len.is_normal() {
        return Err("direction has zero length".into());
    }
    // A direction already unit to f32 precision is kept bit for bit, so saved rigs round-trip.
    let unit = if (len - 1.0).abs() <= 2e-6 { d } else { d / len };
    if unit.z <= 0.0 {
        return Err(format!(
            "direction {} points below the mold plane (z <= 0): such a light cannot light the mold",
            show(d)
        ));
    }
    Ok(unit)
}

fn check_intensity(e: Vec3) -> Result<(), String> {
    if !e.is_finite() || e.min_element() <= 0.0 {
        return Err(format!("intensity {} must be finite and > 0", show(e)));
    }
    Ok(())
}

fn show(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

impl Rig {
    /// A rig of `lights` (metadata empty); `origin` names the rig in messages.
    ///
    /// # Errors
    /// [`Error::BadFile`] for fewer than 3 lights; [`Error::BadRig`] for coplanar (rank-deficient)
    /// directions, which cannot determine a normal.
    pub fn new(lights: Vec<Light>, origin: &str) -> Result<Rig> {
        if lights.len() < 3 {
            return Err(bad(origin, too_few(lights.len())));
        }
        let conditioning = conditioning_of(&lights);
        if conditioning.rank < 3 {
            return Err(Error::BadRig(format!(
                "{origin}: rig lights are coplanar (condition number {:.1e}): they cannot determine a normal; move some lights to another elevation",
                conditioning.condition_number
            )));
        }
        Ok(Rig {
            name: None,
            description: None,
            lights,
            ambient: None,
            mm_per_pixel: None,
            vignetting: Vec::new(),
            conditioning,
        })
    }

    /// The rig with a name.
    pub fn with_name(mut self, name: impl Into<String>) -> Rig {
        self.name = Some(name.into());
        self
    }

    /// The rig with a description.
    pub fn with_description(mut self, description: impl Into<String>) -> Rig {
        self.description = Some(description.into());
        self
    }

    /// The rig with an ambient frame (all lights off) to subtract, or none.
    pub fn with_ambient(mut self, ambient: Option<PathBuf>) -> Rig {
        self.ambient = ambient;
        self
    }

    /// The rig with the size of a photo pixel on the mold in millimetres, or none.
    ///
    /// # Errors
    /// [`Error::BadFile`] naming `origin` when the size is not finite and `> 0`.
    pub fn with_mm_per_pixel(mut self, mm_per_pixel: Option<f32>, origin: &str) -> Result<Rig> {
        if let Some(mm) = mm_per_pixel
            && !(mm.is_finite() && mm > 0.0)
        {
            return Err(bad(origin, format!("mm_per_pixel {mm} must be finite and > 0")));
        }
        self.mm_per_pixel = mm_per_pixel;
        Ok(self)
    }

    pub fn name(&self) -> Option<&str> {
        self.name.as_deref()
    }

    pub fn description(&self) -> Option<&str> {
        self.description.as_deref()
    }

    /// The lights in photo order (at least 3).
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Number of lights (at least 3), which is the number of photos a capture needs.
    pub fn light_count(&self) -> usize {
        self.lights.len()
    }

    /// The rig with a radial vignetting model (`k1, k2, ...`; empty: none), applied to the photos
    /// of lights without a flat frame.
    ///
    /// # Errors
    /// [`Error::BadFile`] naming `origin` when a coefficient is not finite.
    pub fn with_vignetting(mut self, k: Vec<f32>, origin: &str) -> Result<Rig> {
        if let Some(c) = k.iter().find(|c| !c.is_finite()) {
            return Err(bad(origin, format!("vignetting coefficient {c} must be finite")));
        }
        self.vignetting = k;
        Ok(self)
    }

    /// The radial vignetting coefficients (empty when the rig has no model).
    pub fn vignetting(&self) -> &[f32] {
        &self.vignetting
    }

    /// The ambient frame (all lights off) to subtract, when the rig names one.
    pub fn ambient(&self) -> Option<&Path> {
        self.ambient.as_deref()
    }

    /// Every file the rig names besides itself (its ambient frame, its lights' flat frames): what
    /// a capture with it reads.
    pub fn input_files(&self) -> Vec<&Path> {
        self.ambient().into_iter().chain(self.lights.iter().filter_map(Light::flat)).collect()
    }

    /// Size of a photo pixel on the mold in millimetres (finite, `> 0`), when known.
    pub fn mm_per_pixel(&self) -> Option<f32> {
        self.mm_per_pixel
    }

    /// Checks that `photos` photos were given for this rig: one per light, or one per bracket of
    /// a light with exposure brackets.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the counts differ.
    pub fn expect_photos(&self, photos: usize) -> Result<()> {
        let want: usize = self.lights.iter().map(Light::photo_count).sum();
        if photos != want {
            let brackets =
                if want == self.lights.len() { String::new() } else { format!(" ({want} photos with their brackets)") };
            return Err(Error::InvalidInput(format!(
                "rig has {} lights{brackets} but {photos} photos were given",
                self.lights.len()
            )));
        }
        Ok(())
    }

    /// Checks that a stack of `photos` solved readings has one per light (brackets merged).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the counts differ.
    pub fn expect_readings(&self, photos: usize) -> Result<()> {
        if photos != self.lights.len() {
            return Err(Error::InvalidInput(format!(
                "rig has {} lights but {photos} photos were given",
                self.lights.len()
            )));
        }
        Ok(())
    }

    /// Reads a rig file; the ambient frame path is resolved relative to the file's folder.
    ///
    /// # Errors
    /// [`Error::Maps`] when the input gate refuses the file or it cannot be read
    /// ([`skinkit_maps::input`]); [`Error::BadFile`] as [`Rig::parse`].
    pub fn load(path: &Path) -> Result<Rig> {
        let text = skinkit_maps::input::read_to_string(path, skinkit_maps::input::Kind::Toml)
            .map_err(skinkit_maps::Error::from)?;
        let mut rig = Rig::parse(&text, &path.display().to_string())?;
        let folder = path.parent().unwrap_or(Path::new(""));
        if let Some(ambient) = rig.ambient.take() {
            rig.ambient = Some(folder.join(ambient));
        }
        for light in &mut rig.lights {
            light.flat = light.flat.take().map(|f| folder.join(f));
        }
        Ok(rig)
    }

    /// Parses rig TOML; `origin` names the text in messages (usually the file name).
    ///
    /// # Errors
    /// [`Error::BadFile`] for TOML syntax, unknown or missing keys, and invalid values.
    pub fn parse(text: &str, origin: &str) -> Result<Rig> {
        let file: RigFile = toml::from_str(text).map_err(|e| bad(origin, e.to_string().trim_end().to_owned()))?;
        file.into_rig(origin)
    }

    /// The rig as TOML text that [`Rig::parse`] reads back to an equal rig.
    pub fn to_toml_string(&self) -> String {
        self.to_toml_relative(None)
    }

    fn to_toml_relative(&self, folder: Option<&Path>) -> String {
        let ambient = self.ambient.as_ref().map(|a| {
            let rel = folder.and_then(|f| a.strip_prefix(f).ok()).unwrap_or(a);
            rel.to_string_lossy().into_owned()
        });
        let out = RigOut {
            name: self.name.clone(),
            description: self.description.clone(),
            mm_per_pixel: self.mm_per_pixel.map(f32_to_f64),
            ambient,
            vignetting: self.vignetting.iter().map(|&k| f32_to_f64(k)).collect(),
            light: self.lights.iter().map(|l| LightOut::from_light(l, folder)).collect(),
        };
        toml::to_string(&out).expect("a rig always serialises to TOML")
    }

    /// Writes the rig atomically; an ambient path inside the target folder is written relative.
    ///
    /// # Errors
    /// [`Error::Maps`] when the file cannot be written.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = self.to_toml_relative(path.parent());
        skinkit_maps::io::write_atomic(path, |w| {
            use std::io::Write;
            w.write_all(text.as_bytes()).map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
        })?;
        Ok(())
    }

    /// `count` lights evenly on a ring: azimuth `360 i / count` degrees from +x, counter-clockwise
    /// seen from the camera; `elevation_deg` above the mold plane (90 is the camera axis).
    ///
    /// # Errors
    /// As [`Light::new`] and [`Rig::new`] ([`Error::BadFile`] naming the light, [`Error::BadRig`]
    /// for coplanar lights, e.g. an elevation of 90 degrees or fewer than 3 lights).
    pub fn turntable(count: usize, elevation_deg: f64, intensity: f32) -> Result<Rig> {
        let e = elevation_deg.to_radians();
        let lights = (0..count)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / count as f64;
                // Snap the rounding residue of cos(90 deg) and friends to zero so rig files read cleanly.
                let d = [e.cos() * a.cos(), e.cos() * a.sin(), e.sin()].map(|c| if c.abs() < 1e-12 { 0.0 } else { c });
                Light::new(Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32), Vec3::splat(intensity), None)
                    .map_err(|reason| bad(&format!("turntable-{count}: light {}", i + 1), reason))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Rig::new(lights, &format!("turntable-{count}"))?
            .with_name(format!("turntable-{count}"))
            .with_description(format!("{count} lights evenly on a ring at elevation {elevation_deg} deg")))
    }

    /// Unit light directions in photo order.
    pub fn directions(&self) -> Vec<Vec3> {
        self.lights.iter().map(|l| l.direction).collect()
    }

    /// RGB light intensities in photo order.
    pub fn intensities(&self) -> Vec<Vec3> {
        self.lights.iter().map(|l| l.intensity).collect()
    }

    /// The k x 3 matrix of light directions, one row per light, in f64.
    pub fn directions_matrix(&self) -> DMatrix<f64> {
        DMatrix::from_fn(self.lights.len(), 3, |r, c| self.lights[r].direction[c] as f64)
    }

    /// Condition number, noise amplification and rank of the direction matrix (module docs),
    /// computed when the rig was made (rank 3 always).
    pub fn conditioning(&self) -> Conditioning {
        self.conditioning
    }

    /// The rig seen in a frame whose y axis points down (image rows): negates every direction's
    /// and position's y. For light files written in image coordinates.
    pub fn flip_y(&mut self) {
        for l in &mut self.lights {
            l.direction.y = -l.direction.y;
            if let Some(p) = &mut l.position {
                p.y = -p.y;
            }
        }
        self.conditioning = conditioning_of(&self.lights);
    }
}

/// Condition number, noise amplification and rank of the directions of `lights` (the one place
/// a rig's condition number is computed).
fn conditioning_of(lights: &[Light]) -> Conditioning {
    let l = DMatrix::from_fn(lights.len(), 3, |r, c| lights[r].direction[c] as f64);
    if l.nrows() == 0 {
        return Conditioning {
            condition_number: f64::INFINITY,
            noise_amplification: f64::INFINITY,
            tilt_amplification: f64::INFINITY,
            rank: 0,
        };
    }
    let s = l.clone().svd(false, false).singular_values;
    let (max, min) = (s.max(), if s.len() < 3 { 0.0 } else { s.min() });
    let rank = s.iter().filter(|&&v| v > COPLANAR_RATIO * max).count();
    let noise = s.iter().map(|v| 1.0 / (v * v)).sum::<f64>() + if s.len() < 3 { f64::INFINITY } else { 0.0 };
    Conditioning {
        condition_number: if min > 0.0 { max / min } else { f64::INFINITY },
        noise_amplification: noise.sqrt(),
        tilt_amplification: tilt_amplification(&l),
        rank,
    }
}

/// `sqrt` of the x and y diagonal of `(L^T L)^-1`; infinite when `L^T L` is singular.
fn tilt_amplification(l: &DMatrix<f64>) -> f64 {
    let ltl = l.transpose() * l;
    let m = Matrix3::from_fn(|r, c| ltl[(r, c)]);
    match m.try_inverse() {
        Some(inv) if inv[(0, 0)] >= 0.0 && inv[(1, 1)] >= 0.0 => (inv[(0, 0)] + inv[(1, 1)]).sqrt(),
        _ => f64::INFINITY,
    }
}

fn too_few(k: usize) -> String {
    format!("rig has {k} light{}; photometric stereo needs at least 3", if k == 1 { "" } else { "s" })
}

fn bad(location: &str, reason: String) -> Error {
    Error::BadFile { location: location.to_owned(), reason }
}

mod file;
use file::{LightOut, RigFile, RigOut, f32_to_f64};

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"
name = "test"
mm_per_pixel = 0.02
ambient = "ambient.png"
[[light]]
direction = [1, 0, 1]
intensity = 2.0
[[light]]
direction = [0.0, 1.0, 1.0]
intensity = [1.0, 0.5, 0.25]
position = [0.0, 150.0, 150.0]
[[light]]
direction = [-1.0, -1.0, 1.0]
"#;

    #[test]
    fn parses_and_normalises() {
        let rig = Rig::parse(GOOD, "rig.toml").unwrap();
        assert_eq!(rig.lights.len(), 3);
        let s = std::f32::consts::FRAC_1_SQRT_2;
        assert!((rig.lights[0].direction - Vec3::new(s, 0.0, s)).length() < 1e-6);
        assert_eq!(rig.lights[0].intensity, Vec3::splat(2.0));
        assert_eq!(rig.lights[1].intensity, Vec3::new(1.0, 0.5, 0.25));
        assert_eq!(rig.lights[1].position, Some(Vec3::new(0.0, 150.0, 150.0)));
        assert_eq!(rig.lights[2].intensity, Vec3::ONE);
        assert_eq!(rig.ambient, Some(PathBuf::from("ambient.png")));
        assert_eq!(rig.mm_per_pixel, Some(0.02));
    }

    #[test]
    fn toml_round_trip_is_exact() {
        let rig = Rig::parse(GOOD, "rig.toml").unwrap();
        let again = Rig::parse(&rig.to_toml_string(), "again").unwrap();
        assert_eq!(rig, again);
    }
}
