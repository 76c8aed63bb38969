//! [`SkinParams`]: everything that decides a synthetic skin heightfield, with presets per face
//! region.
//!
//! The presets follow the qualitative description of skin imprints in Haro, Guenter and Essa,
//! "Real-time, photo-realistic, physically based rendering of fine scale human skin structure"
//! (2001), figures 2 and 3: cheek and nose show prominent pores, the forehead fine crossing
//! furrows, the forehead edge stronger wrinkles. The numbers are plain values for a silicone mold in
//! millimetres (pores 0.05-0.15 mm in radius and 0.02-0.05 mm deep, furrows 0.5-1 mm apart), not
//! measurements.

use crate::{Error, Result};

/// Largest field [`SkinParams::validate`] accepts, in texels (16384 x 8192).
pub const MAX_TEXELS: u64 = 1 << 27;
/// Largest number of pores a field may ask for.
pub const MAX_PORES: u64 = 10_000_000;
/// Largest number of furrow lines of one family that may overlap a point (keeps evaluation cheap).
const MAX_LINES_PER_POINT: f64 = 64.0;

/// Parameters of a synthetic skin heightfield. Lengths are in millimetres.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinParams {
    /// Field width in texels.
    pub width: usize,
    /// Field height in texels.
    pub height: usize,
    /// Texel pitch: 0.02 mm makes a 21 mm mold about 1000 texels wide.
    pub mm_per_texel: f64,
    /// Seed of every random choice in the field.
    pub seed: u64,
    pub pores: PoreParams,
    /// Families of parallel furrows; several families cross.
    pub furrows: Vec<FurrowFamily>,
    pub noise: NoiseParams,
    /// A broad cap (molds from the nose are not flat); `None` for a flat mean surface.
    pub bulge: Option<Bulge>,
    /// Constant slopes `(dh/dx, dh/dy)` of a planar tilt, y up.
    pub tilt: [f64; 2],
}

/// Pores: smooth dimples `-depth * (1 - r^2/radius^2)^3` scattered by a Poisson-disc process.
#[derive(Clone, Debug, PartialEq)]
pub struct PoreParams {
    /// Mean number of pores per square millimetre (0 disables pores).
    pub density_per_mm2: f64,
    /// Mean support radius.
    pub radius_mm: f64,
    /// Mean depth; a negative depth makes bumps instead of dimples.
    pub depth_mm: f64,
    /// Relative spread of radius and depth: each is scaled by `1 + variation * U(-1, 1)`, in [0, 1).
    pub variation: f64,
    /// No two pore centres are closer than this (dart throwing gives up short of the density when
    /// the disc packing saturates).
    pub min_distance_mm: f64,
}

/// A family of parallel furrows with smooth cross-section `-depth * (1 - t^2)^3`, `t` the
/// distance to the line over half the width.
#[derive(Clone, Debug, PartialEq)]
pub struct FurrowFamily {
    /// Direction of the lines, counter-clockwise from +x (image right), in degrees.
    pub angle_deg: f64,
    /// Mean distance between neighbouring lines.
    pub spacing_mm: f64,
    /// Full width of a groove's support.
    pub width_mm: f64,
    /// Mean groove depth.
    pub depth_mm: f64,
    /// Random offset of each line as a fraction of the spacing, in [0, 0.5].
    pub jitter: f64,
    /// Amplitude of the sideways waviness of each line.
    pub waviness_mm: f64,
    /// Mean wavelength of the waviness and of the depth modulation along a line.
    pub wavelength_mm: f64,
    /// Depth modulation along a line, in [0, 1]: 0 keeps the depth constant, 1 lets a groove fade
    /// out completely between deep stretches (skin furrows come in segments).
    pub depth_variation: f64,
}

/// Fine noise: a seeded sum of random-phase plane waves with analytic derivatives.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseParams {
    /// Root-mean-square height (0 disables the noise).
    pub amplitude_mm: f64,
    /// Central wavelength; waves are drawn log-uniformly between half and twice this.
    pub scale_mm: f64,
    /// Number of waves summed.
    pub waves: usize,
}

/// A Gaussian cap `height * exp(-r^2 / (2 radius^2))` centred on the field.
#[derive(Clone, Debug, PartialEq)]
pub struct Bulge {
    pub height_mm: f64,
    /// Standard deviation of the Gaussian.
    pub radius_mm: f64,
}

impl NoiseParams {
    /// No noise.
    pub fn none() -> Self {
        NoiseParams { amplitude_mm: 0.0, scale_mm: 1.0, waves: 1 }
    }
}

impl PoreParams {
    /// No pores.
    pub fn none() -> Self {
        PoreParams { density_per_mm2: 0.0, radius_mm: 0.1, depth_mm: 0.0, variation: 0.0, min_distance_mm: 0.0 }
    }
}

impl SkinParams {
    /// A perfectly flat field: no pores, furrows, noise, bulge or tilt. Start here for custom fields.
    pub fn flat(width: usize, height: usize, mm_per_texel: f64, seed: u64) -> Self {
        SkinParams {
            width,
            height,
            mm_per_texel,
            seed,
            pores: PoreParams::none(),
            furrows: Vec::new(),
            noise: NoiseParams::none(),
            bulge: None,
            tilt: [0.0, 0.0],
        }
    }

    /// Forehead: small sparse pores, fine crossing furrows.
    pub fn forehead(width: usize, height: usize, seed: u64) -> Self {
        SkinParams {
            pores: pores(2.0, 0.05, 0.02),
            furrows: vec![furrow(15.0, 0.5, 0.08, 0.012, 0.6), furrow(125.0, 0.6, 0.07, 0.010, 0.6)],
            noise: noise(0.0015, 0.15),
            ..Self::flat(width, height, 0.02, seed)
        }
    }

    /// Forehead edge: strong roughly horizontal wrinkles over a fine crossing pattern.
    pub fn forehead_edge(width: usize, height: usize, seed: u64) -> Self {
        SkinParams {
            pores: pores(1.5, 0.05, 0.02),
            furrows: vec![
                FurrowFamily { waviness_mm: 0.08, wavelength_mm: 4.0, ..furrow(5.0, 1.0, 0.2, 0.06, 0.6) },
                furrow(70.0, 0.6, 0.07, 0.010, 0.6),
                furrow(140.0, 0.7, 0.07, 0.010, 0.6),
            ],
            noise: noise(0.0015, 0.15),
            ..Self::flat(width, height, 0.02, seed)
        }
    }

    /// Nose: large dense pores, faint furrows, a broad bulge.
    pub fn nose(width: usize, height: usize, seed: u64) -> Self {
        let flat = Self::flat(width, height, 0.02, seed);
        let sigma = 0.35 * flat.extent_mm().0.min(flat.extent_mm().1).max(flat.mm_per_texel);
        SkinParams {
            pores: pores(4.0, 0.11, 0.045),
            furrows: vec![furrow(40.0, 0.9, 0.06, 0.005, 0.8), furrow(150.0, 1.0, 0.06, 0.005, 0.8)],
            noise: noise(0.001, 0.12),
            bulge: Some(Bulge { height_mm: 0.15 * sigma, radius_mm: sigma }),
            ..flat
        }
    }

    /// Cheek: prominent pores, a weak crossing furrow pattern.
    pub fn cheek(width: usize, height: usize, seed: u64) -> Self {
        SkinParams {
            pores: pores(3.0, 0.08, 0.035),
            furrows: vec![furrow(45.0, 0.7, 0.07, 0.008, 0.7), furrow(135.0, 0.8, 0.07, 0.008, 0.7)],
            noise: noise(0.0012, 0.15),
            ..Self::flat(width, height, 0.02, seed)
        }
    }

    /// The field's size in millimetres.
    pub fn extent_mm(&self) -> (f64, f64) {
        (self.width as f64 * self.mm_per_texel, self.height as f64 * self.mm_per_texel)
    }

    /// Position in millimetres of the centre of texel `(col, row)`: the origin is the centre of the
    /// field, x grows right with `col` and y grows up, against `row`.
    pub fn texel_to_mm(&self, col: usize, row: usize) -> (f64, f64) {
        texel_to_mm(self.width, self.height, self.mm_per_texel, col, row)
    }

    /// Checks every field; the generator calls this before allocating.
    ///
    /// # Errors
    /// Names the first bad field and its value; [`Error::TooLarge`] for fields or pore counts over
    /// [`MAX_TEXELS`] or [`MAX_PORES`].
    pub fn validate(&self) -> Result<()> {
        self.validate_size()?;
        self.validate_pores()?;
        for (i, f) in self.furrows.iter().enumerate() {
            f.validate(i)?;
        }
        self.validate_noise()?;
        if let Some(b) = &self.bulge {
            finite("bulge.height_mm", b.height_mm)?;
            positive("bulge.radius_mm", b.radius_mm)?;
        }
        finite("tilt[0]", self.tilt[0])?;
        finite("tilt[1]", self.tilt[1])
    }

    fn validate_size(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid("size", format!("{}x{} has no texels", self.width, self.height)));
        }
        let texels = (self.width as u64).saturating_mul(self.height as u64);
        if texels > MAX_TEXELS {
            let what = format!("skin field of {}x{}", self.width, self.height);
            return Err(Error::TooLarge { what, requested: texels, limit: MAX_TEXELS });
        }
        positive("mm_per_texel", self.mm_per_texel)
    }

    fn validate_pores(&self) -> Result<()> {
        let p = &self.pores;
        non_negative("pores.density_per_mm2", p.density_per_mm2)?;
        if p.density_per_mm2 == 0.0 {
            return Ok(());
        }
        positive("pores.radius_mm", p.radius_mm)?;
        finite("pores.depth_mm", p.depth_mm)?;
        non_negative("pores.min_distance_mm", p.min_distance_mm)?;
        if !(0.0..1.0).contains(&p.variation) {
            return Err(Error::invalid("pores.variation", format!("{} is outside [0, 1)", p.variation)));
        }
        let (w, h) = self.extent_mm();
        let margin = 2.0 * p.radius_mm * (1.0 + p.variation);
        let count = p.density_per_mm2 * (w + margin) * (h + margin);
        if count > MAX_PORES as f64 {
            let what = format!("pore count at {} per mm^2", p.density_per_mm2);
            return Err(Error::TooLarge { what, requested: count.min(u64::MAX as f64) as u64, limit: MAX_PORES });
        }
        Ok(())
    }

    fn validate_noise(&self) -> Result<()> {
        let n = &self.noise;
        finite("noise.amplitude_mm", n.amplitude_mm)?;
        if n.amplitude_mm == 0.0 {
            return Ok(());
        }
        positive("noise.scale_mm", n.scale_mm)?;
        if !(1..=1024).contains(&n.waves) {
            return Err(Error::invalid("noise.waves", format!("{} is outside 1..=1024", n.waves)));
        }
        Ok(())
    }
}

impl FurrowFamily {
    fn validate(&self, i: usize) -> Result<()> {
        let name = |f: &str| format!("furrows[{i}].{f}");
        finite(&name("angle_deg"), self.angle_deg)?;
        positive(&name("spacing_mm"), self.spacing_mm)?;
        positive(&name("width_mm"), self.width_mm)?;
        finite(&name("depth_mm"), self.depth_mm)?;
        non_negative(&name("waviness_mm"), self.waviness_mm)?;
        positive(&name("wavelength_mm"), self.wavelength_mm)?;
        in_range(&name("jitter"), self.jitter, 0.0, 0.5)?;
        in_range(&name("depth_variation"), self.depth_variation, 0.0, 1.0)?;
        let reach = 0.5 * self.width_mm + self.waviness_mm + self.jitter * self.spacing_mm;
        if 2.0 * reach / self.spacing_mm > MAX_LINES_PER_POINT {
            let reason = format!(
                "lines {} mm apart but {} mm wide with {} mm waviness overlap more than {MAX_LINES_PER_POINT} deep",
                self.spacing_mm, self.width_mm, self.waviness_mm
            );
            return Err(Error::invalid(name("spacing_mm"), reason));
        }
        Ok(())
    }
}

pub(crate) fn texel_to_mm(width: usize, height: usize, mm_per_texel: f64, col: usize, row: usize) -> (f64, f64) {
    let x = (col as f64 - 0.5 * (width as f64 - 1.0)) * mm_per_texel;
    let y = (0.5 * (height as f64 - 1.0) - row as f64) * mm_per_texel;
    (x, y)
}

fn pores(density_per_mm2: f64, radius_mm: f64, depth_mm: f64) -> PoreParams {
    // Two maximal radii apart: neighbouring pores never overlap.
    let min_distance_mm = 2.0 * radius_mm * 1.3;
    PoreParams { density_per_mm2, radius_mm, depth_mm, variation: 0.3, min_distance_mm }
}

fn furrow(angle_deg: f64, spacing_mm: f64, width_mm: f64, depth_mm: f64, depth_variation: f64) -> FurrowFamily {
    FurrowFamily {
        angle_deg,
        spacing_mm,
        width_mm,
        depth_mm,
        jitter: 0.25,
        waviness_mm: 0.03,
        wavelength_mm: 2.0,
        depth_variation,
    }
}

fn noise(amplitude_mm: f64, scale_mm: f64) -> NoiseParams {
    NoiseParams { amplitude_mm, scale_mm, waves: 48 }
}

fn finite(field: &str, v: f64) -> Result<()> {
    if v.is_finite() { Ok(()) } else { Err(Error::invalid(field, format!("{v} is not finite"))) }
}

fn positive(field: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 { Ok(()) } else { Err(Error::invalid(field, format!("{v} is not a positive number"))) }
}

fn non_negative(field: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(field, format!("{v} is negative or not finite")))
    }
}

fn in_range(field: &str, v: f64, lo: f64, hi: f64) -> Result<()> {
    if (lo..=hi).contains(&v) { Ok(()) } else { Err(Error::invalid(field, format!("{v} is outside [{lo}, {hi}]"))) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate() {
        for p in [
            SkinParams::forehead(64, 48, 1),
            SkinParams::forehead_edge(64, 48, 1),
            SkinParams::nose(64, 48, 1),
            SkinParams::cheek(64, 48, 1),
        ] {
            p.validate().unwrap();
        }
    }

    #[test]
    fn bad_fields_are_named() {
        let mut p = SkinParams::cheek(32, 32, 0);
        p.furrows[1].spacing_mm = -1.0;
        let msg = p.validate().unwrap_err().to_string();
        assert!(msg.contains("furrows[1].spacing_mm") && msg.contains("-1"), "{msg}");
        let mut p = SkinParams::cheek(32, 32, 0);
        p.mm_per_texel = f64::NAN;
        assert!(p.validate().unwrap_err().to_string().contains("mm_per_texel"));
        let p = SkinParams::flat(100_000, 100_000, 0.02, 0);
        assert!(matches!(p.validate(), Err(Error::TooLarge { .. })));
        let p = SkinParams::flat(0, 5, 0.02, 0);
        assert!(p.validate().is_err());
    }

    #[test]
    fn texel_coordinates_centre_and_y_up() {
        let p = SkinParams::flat(3, 5, 0.5, 0);
        assert_eq!(p.texel_to_mm(1, 2), (0.0, 0.0));
        assert_eq!(p.texel_to_mm(2, 0), (0.5, 1.0));
        assert_eq!(p.texel_to_mm(0, 4), (-0.5, -1.0));
    }
}
