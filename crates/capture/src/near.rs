//! Near point lights: photometric stereo when the lamp is close enough that its direction and
//! irradiance change across the mold.
//!
//! A lamp 0.1-2 m from a 2 cm mold is not a distant light: across the field its direction turns by
//! up to a few degrees and its irradiance falls off as `1/d^2`, which biases a directional solve by
//! a smooth 2-10 degrees (docs/references.md, capture). The detrend removes most of that bias; when the
//! rig knows where its lamps are (`position` per light) and how large a pixel is (`mm_per_pixel`),
//! this module removes it at the source instead.
//!
//! Geometry: the mold is the plane z = 0, pixel `(col, row)` sits at
//! `x = (col - (W-1)/2, (H-1)/2 - row, 0) * mm_per_pixel` (origin at the photo's centre, y up), and
//! light i at `P_i` gives the unit direction `L_i(x) = (P_i - x) / |P_i - x|` and the irradiance
//! `E_i * |P_i|^2 / |P_i - x|^2` (the rig's intensity is the irradiance at the centre), times
//! `(cos t(x) / cos t(0))^mu` for an LED whose radiance falls off as `cos^mu t` about its axis
//! (`beam_axis`, `beam_mu` in the rig; issue 39), `t` the angle between the axis and the ray
//! from the LED to the point. Each pixel
//! then has its own light matrix, so instead of a cached pseudo-inverse it solves the 3x3 normal
//! equations `(sum L_i L_i^T) g = sum r_i L_i` over its usable lights, in f64. Readings are used
//! as [`crate::solve`] uses them for each method: [`Method::Threshold`] drops those under the
//! shadow rule of [`crate::readings::Shadows`] (absolute, and relative to the pixel's
//! 90th-percentile reading) or saturated; [`Method::Robust`] drops the same readings, keeps least
//! squares on the rest where its relative residual is within [`crate::robust::AGREEMENT`] and
//! otherwise runs [`crate::robust::fit_directions`] with the pixel's own directions; with
//! [`Method::LeastSquares`] every reading is used.

use glam::{DMat3, DVec3, Vec3};
use nalgebra::Matrix3;
use rayon::prelude::*;
use skinkit_maps::{Channels, ColorMap, Grid, NormalMap, ScalarMap};

use crate::readings::{self, LUMA};
use crate::robust::{self, RobustConfig};
use crate::solve::{AlbedoMap, Method, PhotoStack, Solution, SolveConfig, SolveStats};
use crate::{Error, Result, Rig};

/// Whether `rig` describes near point lights this module can use: every light has a position and
/// the rig gives the pixel size.
pub fn applies(rig: &Rig) -> bool {
    rig.mm_per_pixel().is_some() && rig.lights().iter().all(|l| l.position().is_some())
}

/// One light's position and per-channel intensity, in f64, and its LED beam when it has one.
struct NearLight {
    position: DVec3,
    intensity: DVec3,
    centre_dist_sq: f64,
    beam: Option<Beam>,
}

/// An LED's `cos^mu` beam: its unit axis, `mu`, and the beam's cosine at the field's centre.
struct Beam {
    axis: DVec3,
    mu: f64,
    centre_cos: f64,
}

impl NearLight {
    /// Unit direction toward the light from `x` and the irradiance factor relative to the centre:
    /// `|P|^2 / |P - x|^2`, times `(cos_x / cos_0)^mu` for an LED beam, `cos` the angle between
    /// the beam's axis and the ray from the LED to the point (0 outside the beam).
    fn at(&self, x: DVec3) -> (DVec3, f64) {
        let d = self.position - x;
        let dist_sq = d.length_squared().max(1e-12);
        let dir = d / dist_sq.sqrt();
        let beam = self.beam.as_ref().map_or(1.0, |b| ((-dir).dot(b.axis).max(0.0) / b.centre_cos).powf(b.mu));
        (dir, beam * self.centre_dist_sq / dist_sq)
    }
}

/// Light `i`'s beam, refused when its axis points away from the field's centre.
fn beam(i: usize, position: DVec3, beam: Option<(Vec3, f32)>) -> Result<Option<Beam>> {
    let Some((axis, mu)) = beam else { return Ok(None) };
    let axis = axis.as_dvec3();
    let centre_cos = (-position.normalize()).dot(axis);
    if !(centre_cos > 1e-3) {
        return Err(Error::InvalidInput(format!(
            "near-light solve: light {}: beam_axis points away from the field's centre (cosine {centre_cos:.3})",
            i + 1
        )));
    }
    Ok(Some(Beam { axis, mu: mu as f64, centre_cos }))
}

/// Solves `stack` under a rig of near point lights (see the module docs).
///
/// # Errors
/// [`Error::InvalidInput`] when the rig lacks `mm_per_pixel` or a light position, the photo count
/// differs from the light count, or `config` is out of range.
pub fn solve(stack: &PhotoStack, rig: &Rig, config: &SolveConfig) -> Result<Solution> {
    config.validate()?;
    let lights = near_lights(stack, rig)?;
    let pitch = rig
        .mm_per_pixel()
        .map(f64::from)
        .ok_or_else(|| Error::InvalidInput("near-light solve: the rig needs a positive mm_per_pixel".into()))?;
    let (w, h) = stack.size();
    let rgb = stack.channels() == Channels::Rgb;
    let k = lights.len();
    let mut normals = vec![Vec3::ZERO; w * h];
    let mut albedo = vec![Vec3::ZERO; w * h];
    let mut confidence = vec![0.0f32; w * h];
    let stats = normals
        .par_chunks_mut(w)
        .zip(albedo.par_chunks_mut(w))
        .zip(confidence.par_chunks_mut(w))
        .enumerate()
        .map(|(row, ((n_row, a_row), c_row))| {
            let mut stats = SolveStats::empty(k);
            let mut scratch = Pixel::new(k);
            for col in 0..w {
                let i = row * w + col;
                stats.pixels += 1;
                if stack.mask().is_some_and(|m| !m.as_slice()[i]) {
                    stats.masked_count += 1;
                    stats.invalid_count += 1;
                    continue;
                }
                let x = DVec3::new(
                    (col as f64 - (w as f64 - 1.0) / 2.0) * pitch,
                    ((h as f64 - 1.0) / 2.0 - row as f64) * pitch,
                    0.0,
                );
                match scratch.solve(stack, &lights, config, i, x, rgb) {
                    Some((n, a, c, used)) => {
                        (n_row[col], a_row[col], c_row[col]) = (n, a, c);
                        stats.lights_used[used] += 1;
                    }
                    None => stats.invalid_count += 1,
                }
            }
            stats
        })
        .reduce(|| SolveStats::empty(k), SolveStats::merge);
    let grid = |v| Grid::from_vec(w, h, v).expect("sized above");
    let albedo: ColorMap = grid(albedo);
    Ok(Solution {
        normals: NormalMap::from_unit_grid(grid(normals)).map_err(Error::Maps)?,
        albedo: if rgb { AlbedoMap::Rgb(albedo) } else { AlbedoMap::Gray(albedo.map(|a| a.x)) },
        confidence: ScalarMap::from_vec(w, h, confidence).expect("sized above"),
        stats,
        noise: None,
    })
}

/// The rig's lights as near lights, after checking them against the stack.
fn near_lights(stack: &PhotoStack, rig: &Rig) -> Result<Vec<NearLight>> {
    rig.expect_readings(stack.len())?;
    rig.lights()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            // `Light::new` keeps positions finite and above the mold plane.
            let p = l
                .position()
                .map(|p| p.as_dvec3())
                .ok_or_else(|| Error::InvalidInput(format!("near-light solve: light {} needs a position", i + 1)))?;
            Ok(NearLight {
                position: p,
                intensity: l.intensity().as_dvec3(),
                centre_dist_sq: p.length_squared(),
                beam: beam(i, p, l.beam())?,
            })
        })
        .collect()
}

/// Per-pixel working storage, reused across a row.
struct Pixel {
    dirs: Vec<DVec3>,
    /// Intensity-divided readings per channel (grey photos use channel 0).
    readings: Vec<DVec3>,
    /// Reading used for the normal (luminance of `readings` for RGB).
    value: Vec<f64>,
    usable: Vec<bool>,
}

impl Pixel {
    fn new(k: usize) -> Self {
        Pixel { dirs: vec![DVec3::ZERO; k], readings: vec![DVec3::ZERO; k], value: vec![0.0; k], usable: vec![true; k] }
    }

    /// Normal, albedo, confidence and lights used at pixel `i` (surface point `x`), or `None` when
    /// the pixel cannot be solved.
    fn solve(
        &mut self,
        stack: &PhotoStack,
        lights: &[NearLight],
        config: &SolveConfig,
        i: usize,
        x: DVec3,
        rgb: bool,
    ) -> Option<(Vec3, Vec3, f32, usize)> {
        self.read(stack, lights, config, i, x, rgb);
        if config.method == Method::Robust {
            return self.robust(config, rgb);
        }
        if config.method == Method::Threshold {
            self.drop_shadows(config);
        }
        self.least_squares(config, rgb)
    }

    /// [`Method::Robust`], the rules of the directional solve: least squares on the readings left
    /// after dropping shadowed and saturated ones when its relative residual is within
    /// [`robust::AGREEMENT`], else the robust fit (its confidence without the conditioning
    /// factor, which near lights never had).
    fn robust(&mut self, config: &SolveConfig, rgb: bool) -> Option<(Vec3, Vec3, f32, usize)> {
        let all = self.usable.clone();
        self.drop_shadows(config);
        if let Some((ls, residual)) = self.least_squares_residual(config, rgb)
            && residual <= robust::AGREEMENT as f64
        {
            return Some(ls);
        }
        let value: Vec<f32> = self.value.iter().map(|&v| v as f32).collect();
        let saturated: Vec<bool> = all.iter().map(|u| !u).collect();
        let dirs: Vec<Vec3> = self.dirs.iter().map(|d| d.as_vec3()).collect();
        let fit_config = RobustConfig {
            shadows: config.shadows(),
            min_lights: config.min_lights,
            max_condition: config.max_condition,
            ..RobustConfig::default()
        };
        let f = robust::fit_directions(&value, &saturated, &dirs, f64::INFINITY, &fit_config);
        if f.used() == 0 {
            return None;
        }
        for (j, u) in self.usable.iter_mut().enumerate() {
            *u = f.inliers >> j & 1 == 1;
        }
        let albedo = if rgb { self.rgb_albedo(f.normal.as_dvec3()).as_vec3() } else { Vec3::splat(f.albedo) };
        Some((f.normal, albedo, f.confidence, f.used()))
    }

    /// Least squares over the usable readings.
    fn least_squares(&self, config: &SolveConfig, rgb: bool) -> Option<(Vec3, Vec3, f32, usize)> {
        self.least_squares_residual(config, rgb).map(|(texel, _)| texel)
    }

    /// [`Self::least_squares`] and its relative residual `|r - L g| / |r|`.
    fn least_squares_residual(&self, config: &SolveConfig, rgb: bool) -> Option<((Vec3, Vec3, f32, usize), f64)> {
        let lights = &self.dirs;
        let used = self.usable.iter().filter(|u| **u).count();
        if used < config.min_lights {
            return None;
        }
        let (mut a, mut b) = (DMat3::ZERO, DVec3::ZERO);
        for j in (0..lights.len()).filter(|&j| self.usable[j]) {
            let l = self.dirs[j];
            a += DMat3::from_cols(l * l.x, l * l.y, l * l.z);
            b += l * self.value[j];
        }
        let condition = readings::condition_of(&Matrix3::from_column_slice(&a.to_cols_array()));
        if !(condition <= config.max_condition) {
            return None;
        }
        let g = a.inverse() * b;
        let len = g.length();
        if !readings::defines_normal(len) {
            return None;
        }
        let n = g / len;
        let albedo = if rgb { self.rgb_albedo(n) } else { DVec3::splat(len) };
        let residual = self.relative_residual(g);
        let confidence = (used as f64 / lights.len() as f64) / (1.0 + (residual / 0.1).powi(2));
        Some(((n.as_vec3(), albedo.as_vec3(), confidence as f32, used), residual))
    }

    /// Fills directions and intensity-divided readings; marks saturated or non-finite readings.
    fn read(&mut self, stack: &PhotoStack, lights: &[NearLight], config: &SolveConfig, i: usize, x: DVec3, rgb: bool) {
        let channels = if rgb { 3 } else { 1 };
        for (j, (photo, light)) in stack.photos().iter().zip(lights).enumerate() {
            let (dir, falloff) = light.at(x);
            self.dirs[j] = dir;
            let full = photo.samples().full_scale();
            let mut reading = DVec3::ZERO;
            let mut ok = true;
            let saturated_at = readings::saturation_level(config.saturation, full);
            for c in 0..channels {
                let s = i * channels + c;
                ok &= photo.samples().get(s) < saturated_at;
                let ambient = stack.ambient().map_or(0.0, |a| a.linear(s) as f64);
                reading[c] = (photo.linear(s) as f64 - ambient) / (light.intensity[c] * falloff);
            }
            let value = if rgb { reading.dot(DVec3::from(LUMA.map(f64::from))) } else { reading.x };
            ok &= value.is_finite();
            self.readings[j] = if rgb { reading } else { DVec3::splat(reading.x) };
            self.value[j] = if value.is_finite() { value } else { 0.0 };
            self.usable[j] = ok || config.method == Method::LeastSquares && value.is_finite();
        }
    }

    /// Drops readings under the absolute or the pixel-relative shadow threshold.
    fn drop_shadows(&mut self, config: &SolveConfig) {
        let mut usable: Vec<f32> =
            self.value.iter().zip(&self.usable).filter(|(_, u)| **u).map(|(v, _)| *v as f32).collect();
        // The rule's reference reading in f32, as the directional solve and the robust fit take it.
        let floor = readings::shadow_floor(config.shadows(), readings::shadow_reference(&mut usable) as f64);
        for (u, v) in self.usable.iter_mut().zip(&self.value) {
            *u &= *v >= floor;
        }
    }

    /// Per-channel least-squares albedo `sum r_ci d_i / sum d_i^2` with `d_i = n . L_i`.
    fn rgb_albedo(&self, n: DVec3) -> DVec3 {
        let (mut num, mut den) = (DVec3::ZERO, 0.0);
        for j in (0..self.dirs.len()).filter(|&j| self.usable[j]) {
            let d = n.dot(self.dirs[j]);
            num += self.readings[j] * d;
            den += d * d;
        }
        if den > 0.0 { (num / den).max(DVec3::ZERO) } else { DVec3::ZERO }
    }

    /// `|r - L g| / |r|` over the used lights.
    fn relative_residual(&self, g: DVec3) -> f64 {
        let (mut err, mut total) = (0.0, 0.0);
        for j in (0..self.dirs.len()).filter(|&j| self.usable[j]) {
            err += (self.value[j] - self.dirs[j].dot(g)).powi(2);
            total += self.value[j].powi(2);
        }
        if total > 0.0 { (err / total).sqrt() } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_light_geometry_matches_the_renderer_convention() {
        let light =
            NearLight { position: DVec3::new(0.0, 0.0, 100.0), intensity: DVec3::ONE, centre_dist_sq: 1e4, beam: None };
        let (dir, falloff) = light.at(DVec3::ZERO);
        assert_eq!((dir, falloff), (DVec3::Z, 1.0));
        let (dir, falloff) = light.at(DVec3::new(100.0, 0.0, 0.0));
        assert!((dir - DVec3::new(-1.0, 0.0, 1.0).normalize()).length() < 1e-12);
        assert!((falloff - 0.5).abs() < 1e-12);
    }
}
