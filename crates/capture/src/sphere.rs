//! Light calibration from photos of a sphere, one photo per light (what `skinkit rig from-sphere`
//! runs). Haro et al. (2001, section 3) need known light directions; a sphere in the mold's place
//! shows every normal at once, so each light can be read off it.
//!
//! * Mirror (chrome) sphere: per photo the highlight is the intensity-weighted centroid of the
//!   bright blob around the brightest pixel on the sphere (weights `I - t` above a threshold `t`
//!   halfway between the sphere's median and the peak), so it is sub-pixel. The sphere normal
//!   there is `n = ((x - cx)/r, -(y - cy)/r, sqrt(1 - ...))` (image rows grow downward, against
//!   +y); with an orthographic view `v = (0, 0, 1)` the light is `L = 2 (n . v) n - v`.
//! * Matte (Lambertian) sphere: per photo the least-squares fit of `I = b . n` over the lit
//!   sphere pixels, dropping pixels with `b . n <= 0.05 |b|` (the attached shadow) and refitting
//!   until the set is stable. The direction is `b / |b|`; `|b|` (per RGB channel: the scale of
//!   `d . n` fitted to that channel) is the light's relative intensity, normalised so its mean
//!   over the lights is 1 per channel (which also cancels a tinted sphere's colour).
//! * Both: directions from the mirror sphere, intensities from the matte one; the angle between
//!   the two directions is reported per light as a consistency check.
//!
//! Pixel coordinates: column `x`, row `y`, pixel centres at integer coordinates. The sphere is
//! given as a [`Circle`], a mask, or found automatically ([`Locate::Auto`]): the per-pixel
//! maximum over all photos is thresholded (Otsu's threshold on its histogram), the largest
//! 4-connected bright blob is taken as the sphere and grown over its dim rim (down to a tenth of
//! the way from the background's median to the blob's), and the circle is its centroid with the radius
//! of a disk of equal area (`sqrt(area / pi)`); this needs the sphere brighter than its
//! background in some photo (a matte sphere always is; a chrome sphere in a dark room may only
//! show its highlights: then give the circle or a mask). Photos are read as linear luminance
//! ([`Photo::luminance`]). Lights are numbered from 1 in messages, as photos are.

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use skinkit_maps::{Grid, Photo};

use crate::rig::{Light, Rig};
use crate::{Error, Result};

/// Matte pixels with `b . n` at or below this fraction of `|b|` count as shadowed.
const SHADOW_COS: f64 = 0.05;
/// Matte fits use pixels inside this fraction of the radius (the rim blends with the background).
const MATTE_RIM: f64 = 0.97;
/// A highlight must be this many times brighter than the sphere's median.
const HIGHLIGHT_CONTRAST: f32 = 1.5;
/// Smallest sphere radius in pixels accepted.
const MIN_RADIUS: f64 = 3.0;

/// A sphere's outline in pixels (centre column and row, radius).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Circle {
    pub cx: f64,
    pub cy: f64,
    pub radius: f64,
}

/// How to find the sphere in the photos.
#[derive(Clone, Debug, PartialEq)]
pub enum Locate {
    /// Threshold the per-pixel maximum of the photos and take the largest bright blob.
    Auto,
    /// A known outline.
    Circle(Circle),
    /// A mask of the sphere's pixels (the photos' size); the circle is fitted from its area.
    Mask(Grid<bool>),
}

/// What the calibration saw for one light.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct LightReport {
    /// Mirror: the highlight centroid `[x, y]` in pixels.
    pub highlight: Option<[f64; 2]>,
    /// Mirror: rms radius of the highlight blob in pixels (large: a blurred or doubled highlight).
    pub highlight_spread: Option<f64>,
    /// Matte: rms residual of the Lambert fit over the lit pixels, relative to their mean.
    pub lambert_rms: Option<f64>,
    /// Matte: number of lit pixels used by the fit.
    pub lit_pixels: Option<usize>,
    /// Both: angle in degrees between the mirror and matte directions.
    pub mirror_matte_angle_deg: Option<f64>,
}

/// A calibrated rig with the circles used and per-light diagnostics.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    pub rig: Rig,
    pub mirror_circle: Option<Circle>,
    pub matte_circle: Option<Circle>,
    pub lights: Vec<LightReport>,
}

impl Circle {
    /// The sphere normal seen at pixel `(x, y)` (y up, z toward the camera), or `None` outside.
    pub fn normal_at(&self, x: f64, y: f64) -> Option<DVec3> {
        let nx = (x - self.cx) / self.radius;
        let ny = -(y - self.cy) / self.radius;
        let s = nx * nx + ny * ny;
        (s <= 1.0).then(|| DVec3::new(nx, ny, (1.0 - s).sqrt()))
    }

    /// The pixel where the sphere has normal `n` (inverse of [`Circle::normal_at`]).
    pub fn pixel_of(&self, n: DVec3) -> [f64; 2] {
        [self.cx + self.radius * n.x, self.cy - self.radius * n.y]
    }

    /// The circle of a mask: its centroid and the radius of a disk of equal area.
    ///
    /// # Errors
    /// [`Error::Calibration`] when the mask has fewer pixels than a disk of radius 3.
    pub fn from_mask(mask: &Grid<bool>) -> Result<Circle> {
        let (mut n, mut sx, mut sy) = (0usize, 0f64, 0f64);
        for (i, _) in mask.as_slice().iter().enumerate().filter(|(_, m)| **m) {
            n += 1;
            sx += (i % mask.width()) as f64;
            sy += (i / mask.width()) as f64;
        }
        let radius = (n as f64 / std::f64::consts::PI).sqrt();
        if radius < MIN_RADIUS {
            return Err(Error::Calibration(format!("no sphere found: the sphere mask has {n} pixels")));
        }
        Ok(Circle { cx: sx / n as f64, cy: sy / n as f64, radius })
    }

    fn validate(&self) -> Result<()> {
        if !(self.cx.is_finite() && self.cy.is_finite() && self.radius.is_finite() && self.radius >= MIN_RADIUS) {
            return Err(Error::InvalidInput(format!(
                "sphere circle ({}, {}) radius {} must be finite with radius >= {MIN_RADIUS} px",
                self.cx, self.cy, self.radius
            )));
        }
        Ok(())
    }

    /// Pixels `(index, normal)` whose centres lie within `fraction * radius`, in row-major order.
    fn pixels(&self, w: usize, h: usize, fraction: f64) -> Vec<(usize, DVec3)> {
        let r = self.radius * fraction;
        let clip = |lo: f64, hi: f64, n: usize| {
            (lo.floor().max(0.0) as usize, (hi.ceil().max(-1.0) as usize).min(n.saturating_sub(1)))
        };
        let (x0, x1) = clip(self.cx - r, self.cx + r, w);
        let (y0, y1) = clip(self.cy - r, self.cy + r, h);
        let mut out = Vec::new();
        for y in y0..=y1.max(y0) {
            for x in x0..=x1.max(x0) {
                let (dx, dy) = (x as f64 - self.cx, y as f64 - self.cy);
                if x < w && y < h && dx * dx + dy * dy <= r * r {
                    out.extend(self.normal_at(x as f64, y as f64).map(|n| (y * w + x, n)));
                }
            }
        }
        out
    }
}

/// Light directions (unit intensities) from mirror-sphere photos, one per light.
///
/// # Errors
/// [`Error::InvalidInput`] for no photos or photos of different sizes; [`Error::Calibration`]
/// naming the photo when no sphere or no highlight is found or a highlight implies a light at or
/// below the mold plane; [`Error::BadFile`] when the result is not a valid rig (fewer than 3).
pub fn mirror(photos: &[Photo], locate: &Locate) -> Result<Calibration> {
    let (w, h) = photo_size(photos, "mirror")?;
    let lum = luminances(photos);
    let circle = locate_sphere(&lum, w, h, locate, "mirror")?;
    let found = mirror_directions(&lum, w, h, &circle)?;
    let lights = found.iter().map(|(d, _)| (*d, Vec3::ONE)).collect();
    let reports = found.into_iter().map(|(_, r)| r).collect();
    finish(lights, reports, Some(circle), None, "mirror sphere")
}

/// Light directions and relative intensities from matte-sphere photos, one per light.
///
/// # Errors
/// As [`mirror`], with "not lit" instead of "no highlight".
pub fn matte(photos: &[Photo], locate: &Locate) -> Result<Calibration> {
    let (w, h) = photo_size(photos, "matte")?;
    let lum = luminances(photos);
    let circle = locate_sphere(&lum, w, h, locate, "matte")?;
    let pixels = circle.pixels(w, h, MATTE_RIM);
    let mut lights = Vec::with_capacity(photos.len());
    let mut reports = Vec::with_capacity(photos.len());
    for (i, photo) in photos.iter().enumerate() {
        let fit = fit_lambert(&lum[i], &pixels, i)?;
        let direction = fit.b.normalize();
        lights.push((direction, channel_scales(photo, &pixels, direction, i)?));
        reports.push(LightReport { lambert_rms: Some(fit.rms), lit_pixels: Some(fit.lit), ..LightReport::default() });
    }
    normalise_intensities(&mut lights);
    finish(lights, reports, None, Some(circle), "matte sphere")
}

/// Directions from mirror-sphere photos and intensities from matte-sphere photos of the same
/// lights (same count and order; the two spheres may sit in different places).
///
/// # Errors
/// As [`mirror`] and [`matte`]; [`Error::InvalidInput`] when the photo counts differ.
pub fn mirror_and_matte(
    mirror_photos: &[Photo],
    mirror_locate: &Locate,
    matte_photos: &[Photo],
    matte_locate: &Locate,
) -> Result<Calibration> {
    if mirror_photos.len() != matte_photos.len() {
        return Err(Error::InvalidInput(format!(
            "{} mirror-sphere photos but {} matte-sphere photos: one of each per light",
            mirror_photos.len(),
            matte_photos.len()
        )));
    }
    let from_mirror = mirror(mirror_photos, mirror_locate)?;
    let (w, h) = photo_size(matte_photos, "matte")?;
    let lum = luminances(matte_photos);
    let circle = locate_sphere(&lum, w, h, matte_locate, "matte")?;
    let pixels = circle.pixels(w, h, MATTE_RIM);
    let mut lights = Vec::with_capacity(matte_photos.len());
    let mut reports = from_mirror.lights;
    for (i, photo) in matte_photos.iter().enumerate() {
        let direction = from_mirror.rig.lights()[i].direction().as_dvec3();
        let fit = fit_lambert(&lum[i], &pixels, i)?;
        let report = &mut reports[i];
        report.lambert_rms = Some(fit.rms);
        report.lit_pixels = Some(fit.lit);
        report.mirror_matte_angle_deg = Some(direction.angle_between(fit.b.normalize()).to_degrees());
        lights.push((direction, channel_scales(photo, &pixels, direction, i)?));
    }
    normalise_intensities(&mut lights);
    finish(lights, reports, from_mirror.mirror_circle, Some(circle), "mirror and matte spheres")
}

fn finish(
    lights: Vec<(DVec3, Vec3)>,
    reports: Vec<LightReport>,
    mirror_circle: Option<Circle>,
    matte_circle: Option<Circle>,
    what: &str,
) -> Result<Calibration> {
    let lights = lights
        .into_iter()
        .enumerate()
        .map(|(i, (d, e))| {
            Light::new(d.as_vec3(), e, None).map_err(|r| Error::Calibration(format!("photo {}: {r}", i + 1)))
        })
        .collect::<Result<Vec<_>>>()?;
    let rig = Rig::new(lights, what)?
        .with_name("sphere-calibration")
        .with_description(format!("light directions from a {what}"));
    Ok(Calibration { rig, mirror_circle, matte_circle, lights: reports })
}

fn photo_size(photos: &[Photo], what: &str) -> Result<(usize, usize)> {
    let first = photos.first().ok_or_else(|| Error::InvalidInput(format!("no {what}-sphere photos")))?;
    let size = (first.width(), first.height());
    for (i, p) in photos.iter().enumerate() {
        if (p.width(), p.height()) != size {
            return Err(Error::InvalidInput(format!(
                "{what}-sphere photo {} is {}x{} but photo 1 is {}x{}",
                i + 1,
                p.width(),
                p.height(),
                size.0,
                size.1
            )));
        }
    }
    Ok(size)
}

fn luminances(photos: &[Photo]) -> Vec<Vec<f32>> {
    photos.par_iter().map(|p| p.luminance()).collect()
}

fn locate_sphere(lum: &[Vec<f32>], w: usize, h: usize, locate: &Locate, what: &str) -> Result<Circle> {
    let circle = match locate {
        Locate::Circle(c) => *c,
        Locate::Mask(m) if m.size() != (w, h) => {
            return Err(Error::InvalidInput(format!(
                "the {what}-sphere mask is {}x{} but the photos are {w}x{h}",
                m.width(),
                m.height()
            )));
        }
        Locate::Mask(m) => Circle::from_mask(m)?,
        Locate::Auto => Circle::from_mask(&auto_mask(lum, w, h, what)?)?,
    };
    circle.validate()?;
    Ok(circle)
}

/// The largest 4-connected blob of the per-pixel maximum above Otsu's threshold.
fn auto_mask(lum: &[Vec<f32>], w: usize, h: usize, what: &str) -> Result<Grid<bool>> {
    let max_image: Vec<f32> = (0..w * h).map(|i| lum.iter().map(|l| l[i]).fold(0.0, f32::max)).collect();
    let no_sphere = || {
        Error::Calibration(format!(
            "no {what} sphere found: the photos have no bright blob; give the sphere's circle or a mask"
        ))
    };
    let t = otsu_threshold(&max_image).ok_or_else(no_sphere)?;
    let bright: Vec<bool> = max_image.iter().map(|&v| v > t).collect();
    let core = largest_component(&bright, w, h);
    if core.is_empty() {
        return Err(no_sphere());
    }
    // Otsu's cut can fall inside a matte sphere's dim rim: grow the blob down to a tenth of the
    // way from the background level to the sphere's median, so the circle is not pulled inward.
    let background = median(&mut (0..w * h).filter(|&i| !bright[i]).map(|i| max_image[i]).collect::<Vec<_>>());
    let sphere = median(&mut core.iter().map(|&i| max_image[i]).collect::<Vec<_>>());
    let low = background + 0.1 * (sphere - background);
    let mut seen = vec![false; w * h];
    let blob = flood(core[0], w, h, &mut seen, |i| max_image[i] > low, false);
    let mut mask = vec![false; w * h];
    for i in blob {
        mask[i] = true;
    }
    Ok(Grid::from_vec(w, h, mask)?)
}

/// Otsu's threshold over 256 bins between the minimum and maximum; `None` for a flat image.
fn otsu_threshold(values: &[f32]) -> Option<f32> {
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let (lo, hi) = finite.fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !(hi > lo) {
        return None;
    }
    let bin = |v: f32| (((v - lo) / (hi - lo) * 255.0) as usize).min(255);
    let mut hist = [0f64; 256];
    values.iter().filter(|v| v.is_finite()).for_each(|&v| hist[bin(v)] += 1.0);
    let total: f64 = hist.iter().sum();
    let sum_all: f64 = hist.iter().enumerate().map(|(i, c)| i as f64 * c).sum();
    let (mut w0, mut sum0, mut best, mut best_k) = (0.0, 0.0, -1.0, 0);
    for (k, c) in hist.iter().enumerate().take(255) {
        w0 += c;
        sum0 += k as f64 * c;
        let w1 = total - w0;
        if w0 == 0.0 || w1 == 0.0 {
            continue;
        }
        let between = w0 * w1 * (sum0 / w0 - (sum_all - sum0) / w1).powi(2);
        if between > best {
            best = between;
            best_k = k;
        }
    }
    Some(lo + (best_k as f32 + 1.0) / 256.0 * (hi - lo))
}

/// Indices of the largest 4-connected set of `true` pixels (first found wins ties).
fn largest_component(on: &[bool], w: usize, h: usize) -> Vec<usize> {
    let mut seen = vec![false; on.len()];
    let mut best = Vec::new();
    for start in 0..on.len() {
        if on[start] && !seen[start] {
            let blob = flood(start, w, h, &mut seen, |i| on[i], false);
            if blob.len() > best.len() {
                best = blob;
            }
        }
    }
    best
}

/// Pixels connected to `start` (4- or 8-connected) where `inside` holds; marks them `seen`.
fn flood(
    start: usize,
    w: usize,
    h: usize,
    seen: &mut [bool],
    inside: impl Fn(usize) -> bool,
    diagonal: bool,
) -> Vec<usize> {
    let mut blob = vec![start];
    seen[start] = true;
    let mut next = 0;
    while next < blob.len() {
        let i = blob[next];
        next += 1;
        let (x, y) = ((i % w) as isize, (i / w) as isize);
        for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1), (-1, -1), (1, -1), (-1, 1), (1, 1)]
            .into_iter()
            .take(if diagonal { 8 } else { 4 })
        {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                continue;
            }
            let j = ny as usize * w + nx as usize;
            if !seen[j] && inside(j) {
                seen[j] = true;
                blob.push(j);
            }
        }
    }
    blob
}

/// Per photo the mirror-reflected light direction and its report.
fn mirror_directions(lum: &[Vec<f32>], w: usize, h: usize, circle: &Circle) -> Result<Vec<(DVec3, LightReport)>> {
    let pixels = circle.pixels(w, h, 1.0);
    lum.par_iter()
        .enumerate()
        .map(|(i, l)| {
            let hl = find_highlight(l, w, h, &pixels, i)?;
            let d = reflect_light(circle, hl.x, hl.y, i)?;
            Ok((
                d,
                LightReport {
                    highlight: Some([hl.x, hl.y]),
                    highlight_spread: Some(hl.spread),
                    ..LightReport::default()
                },
            ))
        })
        .collect()
}

struct Highlight {
    x: f64,
    y: f64,
    spread: f64,
}

/// The weighted centroid of the blob around the brightest sphere pixel (module docs).
fn find_highlight(lum: &[f32], w: usize, h: usize, pixels: &[(usize, DVec3)], photo: usize) -> Result<Highlight> {
    let mut values: Vec<f32> = pixels.iter().map(|&(i, _)| sanitize(lum[i])).collect();
    let (peak_at, peak) = pixels
        .iter()
        .map(|&(i, _)| (i, sanitize(lum[i])))
        .fold((usize::MAX, 0.0f32), |best, c| if c.1 > best.1 { c } else { best });
    let median = median(&mut values);
    if peak_at == usize::MAX || peak <= HIGHLIGHT_CONTRAST * median {
        return Err(Error::Calibration(format!(
            "photo {}: no highlight found on the mirror sphere (brightest {peak:.3}, median {median:.3})",
            photo + 1
        )));
    }
    let t = median + 0.5 * (peak - median);
    let mut on_sphere = vec![false; w * h];
    pixels.iter().for_each(|&(i, _)| on_sphere[i] = true);
    let mut seen = vec![false; w * h];
    let blob = flood(peak_at, w, h, &mut seen, |i| on_sphere[i] && sanitize(lum[i]) > t, true);
    Ok(weighted_centroid(&blob, lum, w, t))
}

fn weighted_centroid(blob: &[usize], lum: &[f32], w: usize, t: f32) -> Highlight {
    let (mut sw, mut sx, mut sy) = (0f64, 0f64, 0f64);
    for &i in blob {
        let wt = (sanitize(lum[i]) - t) as f64;
        sw += wt;
        sx += wt * (i % w) as f64;
        sy += wt * (i / w) as f64;
    }
    let (x, y) = (sx / sw, sy / sw);
    let var = blob
        .iter()
        .map(|&i| (sanitize(lum[i]) - t) as f64 * (((i % w) as f64 - x).powi(2) + ((i / w) as f64 - y).powi(2)))
        .sum::<f64>()
        / sw;
    Highlight { x, y, spread: var.sqrt() }
}

fn sanitize(v: f32) -> f32 {
    if v.is_finite() { v.max(0.0) } else { 0.0 }
}

fn median(values: &mut [f32]) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// `L = 2 (n . v) n - v` for the sphere normal at pixel `(x, y)`, `v = +z`.
fn reflect_light(circle: &Circle, x: f64, y: f64, photo: usize) -> Result<DVec3> {
    let nx = (x - circle.cx) / circle.radius;
    let ny = -(y - circle.cy) / circle.radius;
    let n = DVec3::new(nx, ny, (1.0 - nx * nx - ny * ny).max(0.0).sqrt()).normalize_or_zero();
    let l = 2.0 * n.z * n - DVec3::Z;
    if !(l.z > 0.0) {
        return Err(Error::Calibration(format!(
            "photo {}: the highlight at ({x:.1}, {y:.1}) is too close to the sphere's rim: it reflects a light at or below the mold plane",
            photo + 1
        )));
    }
    Ok(l.normalize())
}

struct LambertFit {
    b: DVec3,
    rms: f64,
    lit: usize,
}

/// Least squares `I = b . n` over lit pixels, dropping shadowed ones until the set is stable.
fn fit_lambert(lum: &[f32], pixels: &[(usize, DVec3)], photo: usize) -> Result<LambertFit> {
    let not_lit =
        || Error::Calibration(format!("photo {}: the matte sphere is not lit (or not found) in this photo", photo + 1));
    let peak = pixels.iter().map(|&(i, _)| sanitize(lum[i])).fold(0.0, f32::max);
    let mut lit: Vec<bool> = pixels.iter().map(|&(i, _)| sanitize(lum[i]) > 0.02 * peak).collect();
    let mut b = DVec3::ZERO;
    for _ in 0..20 {
        b = solve_lit(lum, pixels, &lit).ok_or_else(not_lit)?;
        let next: Vec<bool> = pixels.iter().map(|&(_, n)| b.dot(n) > SHADOW_COS * b.length()).collect();
        if next == lit {
            break;
        }
        lit = next;
    }
    let used: Vec<_> = pixels.iter().zip(&lit).filter(|(_, on)| **on).map(|(p, _)| *p).collect();
    if used.len() < 10 || !(b.length() > 0.0) {
        return Err(not_lit());
    }
    let mean = used.iter().map(|&(i, _)| sanitize(lum[i]) as f64).sum::<f64>() / used.len() as f64;
    let sq = used.iter().map(|&(i, n)| (sanitize(lum[i]) as f64 - b.dot(n)).powi(2)).sum::<f64>() / used.len() as f64;
    Ok(LambertFit { b, rms: sq.sqrt() / mean.max(f64::MIN_POSITIVE), lit: used.len() })
}

/// Normal equations `(sum n n^T) b = sum I n` over the lit pixels; `None` when singular.
fn solve_lit(lum: &[f32], pixels: &[(usize, DVec3)], lit: &[bool]) -> Option<DVec3> {
    let mut a = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = nalgebra::Vector3::<f64>::zeros();
    for (&(i, n), _) in pixels.iter().zip(lit).filter(|(_, on)| **on) {
        let v = nalgebra::Vector3::new(n.x, n.y, n.z);
        a += v * v.transpose();
        rhs += v * sanitize(lum[i]) as f64;
    }
    let b = a.cholesky()?.solve(&rhs);
    let b = DVec3::new(b.x, b.y, b.z);
    b.is_finite().then_some(b)
}

/// Per RGB channel the scale `s` of `I_c = s (d . n)` over pixels lit by direction `d`.
fn channel_scales(photo: &Photo, pixels: &[(usize, DVec3)], d: DVec3, index: usize) -> Result<Vec3> {
    let nc = photo.channels().count();
    let mut scales = [0f32; 3];
    for (c, s) in scales.iter_mut().enumerate() {
        let (mut num, mut den) = (0f64, 0f64);
        for &(i, n) in pixels {
            let cos = d.dot(n);
            if cos > SHADOW_COS {
                num += sanitize(photo.linear(i * nc + c.min(nc - 1))) as f64 * cos;
                den += cos * cos;
            }
        }
        *s = (num / den) as f32;
        if !(*s > 0.0 && s.is_finite()) {
            return Err(Error::Calibration(format!(
                "photo {}: the matte sphere shows no light in channel {c}",
                index + 1
            )));
        }
    }
    Ok(Vec3::from_array(scales))
}

/// Scales the intensities so each channel's mean over the lights is 1.
fn normalise_intensities(lights: &mut [(DVec3, Vec3)]) {
    let mean = lights.iter().map(|(_, e)| *e).sum::<Vec3>() / lights.len().max(1) as f32;
    for (_, e) in lights.iter_mut() {
        *e /= mean;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_of_inverts_normal_at() {
        let c = Circle { cx: 40.5, cy: 30.25, radius: 20.0 };
        let n = c.normal_at(50.0, 20.0).unwrap();
        let p = c.pixel_of(n);
        assert!((p[0] - 50.0).abs() < 1e-12 && (p[1] - 20.0).abs() < 1e-12);
        assert!(n.y > 0.0, "a pixel above the centre has a normal pointing up");
    }

    #[test]
    fn otsu_splits_two_levels() {
        let mut v = vec![0.0f32; 100];
        v.extend(vec![0.2f32; 50]);
        let t = otsu_threshold(&v).unwrap();
        assert!(t > 0.0 && t <= 0.2, "{t}");
    }
}
