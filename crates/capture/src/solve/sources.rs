//! Stored samples to intensity-divided linear readings, per light.

use glam::Vec3;
use skinkit_maps::{Photo, Samples, Transfer};

use super::{LUMA, SolveConfig};
use crate::readings;

/// A photo's samples as a typed slice.
#[derive(Clone, Copy)]
pub(super) enum Raw<'a> {
    U8(&'a [u8]),
    U16(&'a [u16]),
    F32(&'a [f32]),
}

impl<'a> Raw<'a> {
    pub(super) fn of(photo: &'a Photo) -> Self {
        match photo.samples() {
            Samples::U8(v) => Raw::U8(v),
            Samples::U16(v) => Raw::U16(v),
            Samples::F32(v) => Raw::F32(v),
        }
    }
}

/// A stored sample type.
pub(super) trait Sample: Copy + Sync {
    fn value(self) -> f32;
}
impl Sample for u8 {
    #[inline]
    fn value(self) -> f32 {
        self as f32
    }
}
impl Sample for u16 {
    #[inline]
    fn value(self) -> f32 {
        self as f32
    }
}
impl Sample for f32 {
    #[inline]
    fn value(self) -> f32 {
        self
    }
}

/// Stored value to linear value: identity (scale folded elsewhere), a table, or the sRGB curve.
#[derive(Clone, Copy)]
pub(super) enum Linearise<'a> {
    Identity,
    Table(&'a [f32]),
    SrgbCurve,
}

impl Linearise<'_> {
    #[inline]
    pub(super) fn apply(self, v: f32) -> f32 {
        match self {
            Linearise::Identity => v,
            Linearise::Table(t) => t[v as usize],
            Linearise::SrgbCurve => skinkit_maps::encoding::srgb_to_linear(v),
        }
    }
}

/// One light's photo and how its samples become intensity-divided linear readings.
pub(super) struct Source<'a> {
    pub(super) raw: Raw<'a>,
    pub(super) ambient: Option<Raw<'a>>,
    /// Per channel: linearised stored value times this = reading `r` (full scale 1, unit light).
    pub(super) scale: [f32; 3],
    /// The same for grey photos (divided by the luminance of the light's intensity).
    pub(super) gray_scale: f32,
    /// Raw stored values at or above this are saturated.
    pub(super) saturated_at: f32,
}

impl<'a> Source<'a> {
    pub(super) fn new(photo: &'a Photo, ambient: Option<&'a Photo>, intensity: Vec3, config: &SolveConfig) -> Self {
        let full = photo.samples().full_scale();
        // Linear photos keep stored units until this scale; tables and the sRGB curve give [0, 1].
        let unit = if photo.transfer() == Transfer::Linear { 1.0 / full } else { 1.0 };
        let luma = Vec3::from(LUMA).dot(intensity);
        Source {
            raw: Raw::of(photo),
            ambient: ambient.map(Raw::of),
            scale: (Vec3::splat(unit) / intensity).into(),
            gray_scale: unit / luma,
            saturated_at: readings::saturation_level(config.saturation, full),
        }
    }

    /// Grey readings `r` and saturation flags of the pixels starting at `p`.
    #[inline(always)]
    pub(super) fn load_gray(&self, p: usize, lin: Linearise, r: &mut [f32], sat: &mut [u8]) {
        let n = r.len();
        match (self.raw, self.ambient) {
            (Raw::U8(v), a) => gray::<u8>(&v[p..p + n], a.map(|a| &as_u8(a)[p..p + n]), lin, self, r, sat),
            (Raw::U16(v), a) => gray::<u16>(&v[p..p + n], a.map(|a| &as_u16(a)[p..p + n]), lin, self, r, sat),
            (Raw::F32(v), a) => gray::<f32>(&v[p..p + n], a.map(|a| &as_f32(a)[p..p + n]), lin, self, r, sat),
        }
    }

    /// RGB readings (per channel and luminance-combined) of the pixels starting at `p`.
    pub(super) fn load_rgb(&self, p: usize, lin: Linearise, r: &mut [f32], rgb: &mut [[f32; 3]], sat: &mut [u8]) {
        let range = 3 * p..3 * (p + r.len());
        match (self.raw, self.ambient) {
            (Raw::U8(v), a) => color::<u8>(&v[range.clone()], a.map(|a| &as_u8(a)[range]), lin, self, r, rgb, sat),
            (Raw::U16(v), a) => color::<u16>(&v[range.clone()], a.map(|a| &as_u16(a)[range]), lin, self, r, rgb, sat),
            (Raw::F32(v), a) => color::<f32>(&v[range.clone()], a.map(|a| &as_f32(a)[range]), lin, self, r, rgb, sat),
        }
    }
}

pub(super) fn as_u8(r: Raw<'_>) -> &[u8] {
    match r {
        Raw::U8(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}
pub(super) fn as_u16(r: Raw<'_>) -> &[u16] {
    match r {
        Raw::U16(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}
pub(super) fn as_f32(r: Raw<'_>) -> &[f32] {
    match r {
        Raw::F32(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}

/// Linear, ambient-subtracted, intensity-divided value of one stored sample.
#[inline]
pub(super) fn reading<T: Sample>(v: T, ambient: Option<T>, lin: Linearise) -> f32 {
    let x = lin.apply(v.value());
    match ambient {
        Some(a) => x - lin.apply(a.value()),
        None => x,
    }
}

#[inline(always)]
pub(super) fn gray<T: Sample>(v: &[T], amb: Option<&[T]>, lin: Linearise, src: &Source, r: &mut [f32], sat: &mut [u8]) {
    for (q, x) in sat.iter_mut().zip(v) {
        *q = (x.value() >= src.saturated_at) as u8;
    }
    match lin {
        // The common case stays a plain loop that vectorises.
        Linearise::Identity => {
            raw_values(v, amb, r);
            r.iter_mut().for_each(|x| *x *= src.gray_scale);
        }
        _ => {
            for j in 0..v.len() {
                r[j] = reading(v[j], amb.map(|a| a[j]), lin) * src.gray_scale;
            }
        }
    }
}

pub(super) fn color<T: Sample>(
    v: &[T],
    amb: Option<&[T]>,
    lin: Linearise,
    src: &Source,
    r: &mut [f32],
    rgb: &mut [[f32; 3]],
    sat: &mut [u8],
) {
    for j in 0..r.len() {
        let mut c = [0.0f32; 3];
        let mut s = false;
        for (ch, value) in c.iter_mut().enumerate() {
            let q = 3 * j + ch;
            s |= v[q].value() >= src.saturated_at;
            *value = reading(v[q], amb.map(|a| a[q]), lin) * src.scale[ch];
        }
        sat[j] = s as u8;
        rgb[j] = c;
        r[j] = LUMA[0] * c[0] + LUMA[1] * c[1] + LUMA[2] * c[2];
    }
}

/// Stored values minus the ambient frame's, as f32.
#[inline(always)]
pub(super) fn raw_values<T: Sample>(v: &[T], ambient: Option<&[T]>, out: &mut [f32]) {
    match ambient {
        None => out.iter_mut().zip(v).for_each(|(o, x)| *o = x.value()),
        Some(a) => out.iter_mut().zip(v.iter().zip(a)).for_each(|(o, (x, y))| *o = x.value() - y.value()),
    }
}
