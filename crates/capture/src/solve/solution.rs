//! What a solve returns: [`Solution`], [`AlbedoMap`], the [`NoiseFloor`] it measured, the albedo
//! texel types and the fresh zeroed maps they are written into.

use glam::Vec3;
use skinkit_maps::{ColorMap, NormalMap, ScalarMap};

use super::SolveStats;

/// The result of [`solve`](super::solve()).
#[derive(Clone, Debug)]
pub struct Solution {
    /// Unit normals, `(0, 0, 0)` where invalid.
    pub normals: NormalMap,
    /// Linear albedo as a fraction of full scale per unit light intensity; zero where invalid.
    /// One value per texel for grey photos, RGB for colour photos.
    pub albedo: AlbedoMap,
    /// Confidence in [0, 1] (see the module docs); 0 where invalid.
    pub confidence: ScalarMap,
    pub stats: SolveStats,
    /// [`Method::Robust`](super::Method::Robust): the noise floor measured before solving and the
    /// gate it set; `None` for other methods, 3 lights or too few usable pixels.
    pub noise: Option<NoiseFloor>,
}

/// The noise the sample of an image shows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoiseFloor {
    /// Noise of one reading (full scale 1, unit light), `sigma`.
    pub sigma: f32,
    /// The same relative to a pixel's `|r|` (median over the sample).
    pub relative: f32,
    /// Relative residual up to which least squares stands (at least `AGREEMENT`).
    pub gate: f32,
}

/// A solution's albedo: one value per texel for grey photos (a third of the memory of RGB), or
/// one linear RGB triple per texel for colour photos.
#[derive(Clone, Debug, PartialEq)]
pub enum AlbedoMap {
    Gray(ScalarMap),
    Rgb(ColorMap),
}

impl AlbedoMap {
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        match self {
            AlbedoMap::Gray(m) => m.size(),
            AlbedoMap::Rgb(m) => m.size(),
        }
    }
    pub fn width(&self) -> usize {
        self.size().0
    }
    pub fn height(&self) -> usize {
        self.size().1
    }
    /// The albedo at `(x, y)` as RGB (a grey value splatted to all three channels).
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        match self {
            AlbedoMap::Gray(m) => Vec3::splat(*m.get(x, y)),
            AlbedoMap::Rgb(m) => *m.get(x, y),
        }
    }
    /// The map as RGB (grey values splatted); a copy.
    pub fn to_color_map(&self) -> ColorMap {
        match self {
            AlbedoMap::Gray(m) => m.map(|&v| Vec3::splat(v)),
            AlbedoMap::Rgb(m) => m.clone(),
        }
    }
    /// The grey map, when the photos were grey.
    pub fn as_gray(&self) -> Option<&ScalarMap> {
        match self {
            AlbedoMap::Gray(m) => Some(m),
            AlbedoMap::Rgb(_) => None,
        }
    }
    /// The RGB map, when the photos were RGB.
    pub fn as_rgb(&self) -> Option<&ColorMap> {
        match self {
            AlbedoMap::Gray(_) => None,
            AlbedoMap::Rgb(m) => Some(m),
        }
    }
}

/// An albedo texel as stored in the output: `f32` for grey stacks, `Vec3` for RGB stacks.
pub(super) trait AlbedoTexel: Copy + Send + Sync {
    const ZERO: Self;
    /// A grey albedo.
    fn gray(v: f32) -> Self;
    /// An RGB albedo (grey stacks only ever pass splatted values; `f32` keeps `x`).
    fn rgb(c: Vec3) -> Self;
    /// A zero-filled vector of `n` texels, fresh from the allocator (see [`fresh_zeroed`]).
    fn fresh(n: usize) -> Vec<Self>;
    /// The texels as grey values, when they are grey (the fused kernel writes only those).
    fn gray_slice(texels: &mut [Self]) -> Option<&mut [f32]>;
}

impl AlbedoTexel for f32 {
    const ZERO: Self = 0.0;
    #[inline(always)]
    fn gray(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn rgb(c: Vec3) -> Self {
        c.x
    }
    fn fresh(n: usize) -> Vec<Self> {
        fresh_zeroed(n)
    }
    fn gray_slice(texels: &mut [Self]) -> Option<&mut [f32]> {
        Some(texels)
    }
}

impl AlbedoTexel for Vec3 {
    const ZERO: Self = Vec3::ZERO;
    #[inline(always)]
    fn gray(v: f32) -> Self {
        Vec3::splat(v)
    }
    #[inline(always)]
    fn rgb(c: Vec3) -> Self {
        c
    }
    fn fresh(n: usize) -> Vec<Self> {
        fresh_zeroed_vec3(n)
    }
    fn gray_slice(_: &mut [Self]) -> Option<&mut [f32]> {
        None
    }
}

/// `n` zeros from the allocator's zeroed allocation. Large sizes come straight from the OS as
/// untouched zero pages, so the only touch of each page is the solve's write to it, made by the
/// worker that owns the band (no separate fill pass).
///
/// Transparent huge pages were tried (`madvise(MADV_HUGEPAGE)`): they made the solve faster on
/// average but the whole 4096x4096 capture slower and erratic (0.13 to 0.44 s detrends, from
/// synchronous compaction), so the plain 4 KiB pages stay.
pub(crate) fn fresh_zeroed(n: usize) -> Vec<f32> {
    vec![0.0f32; n]
}

/// [`fresh_zeroed`] for `Vec3` texels.
pub(crate) fn fresh_zeroed_vec3(n: usize) -> Vec<Vec3> {
    const { assert!(size_of::<Vec3>() == 3 * size_of::<f32>() && align_of::<Vec3>() == align_of::<f32>()) };
    let mut floats = std::mem::ManuallyDrop::new(fresh_zeroed(3 * n));
    let (ptr, len, cap) = (floats.as_mut_ptr(), floats.len(), floats.capacity());
    // SAFETY: `Vec3` is `#[repr(C)] { x, y, z: f32 }` (size and alignment checked above), so the
    // allocation of `cap` zeroed floats, with `len == cap == 3 n` (`vec!` allocates exactly), has
    // the layout of `n` zero `Vec3`s, and the old vector is never dropped.
    debug_assert!(len == cap && len % 3 == 0);
    unsafe { Vec::from_raw_parts(ptr.cast::<Vec3>(), len / 3, cap / 3) }
}
