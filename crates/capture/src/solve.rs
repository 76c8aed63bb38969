//! Per-pixel photometric-stereo solves (Haro et al. 2001, section 3, equation 1).
//!
//! Each pixel seen under k >= 3 lights gives `albedo * E_i * (n . L_i) = I_i`. Writing
//! `g = albedo * n` and `r_i = I_i / E_i` (the reading divided by the light's intensity, after
//! ambient subtraction, as a fraction of full scale), the readings are linear in `g`: `L g = r`.
//!
//! * [`Method::LeastSquares`] is the paper's solve: one 3 x k pseudo-inverse `P = (L^T L)^-1 L^T`
//!   serves every pixel. It is computed once in f64 and applied in f32, with the per-light
//!   intensity division and the integer-to-linear scale folded into it
//!   (`P'_ji = P_ji / (full_scale E_i)`), so the kernel is a 3 x k matrix-vector product on the
//!   raw samples. Pixels are processed in bands of rows in parallel and, within a row, in chunks
//!   of [`CHUNK`] pixels laid out structure-of-arrays so the loops vectorise (compiled twice:
//!   portable and, chosen at run time, AVX2 + FMA; both use `mul_add`, so both give the same
//!   bits). 8-bit and 16-bit sRGB photos go through a lookup table instead of the folded scale.
//!   With AVX2 + FMA, linear grey photos without an ambient frame (the common case) take a fused
//!   kernel instead (`fused::step`): 16 pixels at a time from the samples to the interleaved
//!   output in registers, the same operations in the same order as the chunk path, so the bits
//!   still match the portable build. When all lights have the same intensity, the per-light
//!   scale is taken out of `sum r^2` (one multiplication per reading fewer, in both builds).
//! * [`Method::Robust`] (the default) drops, per pixel, the readings that are shadowed or
//!   saturated and solves from the remaining lights with the pseudo-inverse of that subset.
//!   A reading is *shadowed* when `r_i < max(shadow_abs, shadow_rel * max_j r_j)`: below an
//!   absolute floor and also below a fraction of the pixel's own brightest reading (a cast shadow
//!   on a bright pixel is far above the noise floor but far below its neighbours in the stack). A
//!   reading is *saturated* when its raw stored value is at or above `saturation * full_scale`
//!   (any channel, before ambient subtraction). Subset pseudo-inverses are cached per bitmask:
//!   a dense lazily filled table for k <= [`DENSE_MAX_LIGHTS`], a per-worker map capped at
//!   [`SolveConfig::cache_capacity`] entries (cleared when full) above that. Entries are pure
//!   functions of the bitmask, so results never depend on the cache or the thread count.
//!   Pixels with all readings usable take the vectorised least-squares result unchanged; in the
//!   fused kernel a step of 16 pixels is solved in registers unless one of its readings is
//!   dropped (a reading is below the threshold iff the pixel's dimmest one is). Shadows are
//!   spatially coherent, so a step whose 16 pixels all drop the same readings is solved in
//!   registers too, with that subset's columns (`fused::subset_step`); other such steps go
//!   through the chunk path. There, with k <= [`DENSE_MAX_LIGHTS`], the pixels that drop
//!   readings are grouped by subset and each group is solved with its subset's columns
//!   (`Plan::finish_subsets`); with more lights, one pixel at a time. All three subset paths
//!   use the same operations in the same order (`g = g + c_i r_i` over the used lights, no
//!   fused multiply-add; `n = g / |g|`), so they give the same bits.
//!
//! RGB photos: the normal comes from the luminance-weighted (Rec. 709) sum of the
//! intensity-divided channels; then each channel's albedo is the least-squares fit
//! `sum_i r_ci (n . L_i) / sum_i (n . L_i)^2` over the lights used. Grey photos give `|g|` as the
//! albedo, one value per texel ([`AlbedoMap::Gray`]; a grey photo is divided by the luminance of
//! each light's intensity).
//!
//! Confidence, in [0, 1], is 0 for invalid pixels and otherwise the product of
//! * the fraction of the rig's lights used,
//! * `min(1, cond(L_all) / cond(L_used))`, how much worse the used subset is conditioned, and
//! * `1 / (1 + (rho / 0.1)^2)` with `rho` the relative residual `|r - L g| / |r|` over the lights
//!   used (a Lambertian, noise-free pixel has `rho = 0`; 10% residual halves the confidence).
//!
//! With least squares the first two factors are 1.
//!
//! Every pixel is computed by the same arithmetic whatever the thread count or cache state, so
//! results are bitwise deterministic. Non-finite or all-black readings give invalid pixels
//! (`(0, 0, 0)` normal, zero albedo and confidence), never NaN. [`solve_into`] reuses the maps of
//! an earlier solution (large fresh maps cost a page fault per 4 KiB, which dominates the solve).

use std::collections::HashMap;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use nalgebra::{Matrix3, Vector3};
use rayon::prelude::*;
use skinkit_maps::{Channels, ColorMap, Grid, NormalMap, Photo, Samples, ScalarMap, Transfer};

use crate::{Error, Result, Rig};

/// Pixels per structure-of-arrays chunk in the kernels.
pub const CHUNK: usize = 64;
/// Most lights a rig may have (subsets are `u128` bitmasks).
pub const MAX_LIGHTS: usize = 128;
/// Rigs with at most this many lights cache every subset in a dense `2^k` table.
pub const DENSE_MAX_LIGHTS: usize = 12;
/// Rows per parallel work item.
const BAND_ROWS: usize = 8;
/// Smallest `|g|` (albedo as a fraction of full scale) that still defines a normal.
const MIN_ALBEDO: f32 = 1e-6;
/// Relative residual at which the residual factor of the confidence is 1/2.
const RESIDUAL_SCALE: f32 = 0.1;
/// Rec. 709 luminance weights.
const LUMA: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Photos taken in rig order, validated to share one size and one sample format.
#[derive(Clone, Debug)]
pub struct PhotoStack {
    photos: Vec<Photo>,
    names: Vec<String>,
    ambient: Option<Photo>,
    mask: Option<Grid<bool>>,
}

impl PhotoStack {
    /// Wraps `photos` (in rig order) with display `names` (usually file names) used in messages.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are no photos, the name count differs, the photos are
    /// empty, or a photo differs from the first in size, channels, bit depth or transfer curve.
    pub fn new(photos: Vec<Photo>, names: Vec<String>) -> Result<Self> {
        if photos.is_empty() {
            return Err(Error::InvalidInput("no photos were given".into()));
        }
        if names.len() != photos.len() {
            return Err(Error::InvalidInput(format!("{} photos but {} names were given", photos.len(), names.len())));
        }
        if photos[0].pixel_count() == 0 {
            return Err(Error::InvalidInput(format!("photo 1 ({}) has no pixels", names[0])));
        }
        for (i, photo) in photos.iter().enumerate().skip(1) {
            check_same(photo, &format!("photo {} ({})", i + 1, names[i]), &photos[0], &names[0])?;
        }
        Ok(PhotoStack { photos, names, ambient: None, mask: None })
    }

    /// Adds an ambient frame (all rig lights off), subtracted from every photo.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when it differs from the photos in size or format.
    pub fn with_ambient(mut self, ambient: Photo, name: &str) -> Result<Self> {
        check_same(&ambient, &format!("ambient photo ({name})"), &self.photos[0], &self.names[0])?;
        self.ambient = Some(ambient);
        Ok(self)
    }

    /// Restricts the solve to texels where `mask` is true; the others come out invalid.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the mask's size differs from the photos'.
    pub fn with_mask(mut self, mask: Grid<bool>) -> Result<Self> {
        if mask.size() != self.size() {
            return Err(Error::InvalidInput(format!(
                "mask is {}x{} but photo 1 ({}) is {}x{}",
                mask.width(),
                mask.height(),
                self.names[0],
                self.width(),
                self.height()
            )));
        }
        self.mask = Some(mask);
        Ok(self)
    }

    pub fn len(&self) -> usize {
        self.photos.len()
    }
    pub fn is_empty(&self) -> bool {
        self.photos.is_empty()
    }
    pub fn width(&self) -> usize {
        self.photos[0].width()
    }
    pub fn height(&self) -> usize {
        self.photos[0].height()
    }
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width(), self.height())
    }
    pub fn channels(&self) -> Channels {
        self.photos[0].channels()
    }
    pub fn photos(&self) -> &[Photo] {
        &self.photos
    }
    pub fn names(&self) -> &[String] {
        &self.names
    }
    pub fn ambient(&self) -> Option<&Photo> {
        self.ambient.as_ref()
    }
    pub fn mask(&self) -> Option<&Grid<bool>> {
        self.mask.as_ref()
    }
}

/// `8-bit rgb srgb`-style description of a photo's format.
fn format_of(p: &Photo) -> String {
    let channels = match p.channels() {
        Channels::Gray => "grey",
        Channels::Rgb => "rgb",
    };
    let transfer = match p.transfer() {
        Transfer::Linear => "linear",
        Transfer::Srgb => "srgb",
    };
    format!("{}-bit {channels} {transfer}", p.bit_depth())
}

/// Checks that `photo` (described by `what`) matches the first photo in size and format.
fn check_same(photo: &Photo, what: &str, first: &Photo, first_name: &str) -> Result<()> {
    if (photo.width(), photo.height()) != (first.width(), first.height()) {
        return Err(Error::InvalidInput(format!(
            "{what} is {}x{} but photo 1 ({first_name}) is {}x{}",
            photo.width(),
            photo.height(),
            first.width(),
            first.height()
        )));
    }
    let (a, b) = (format_of(photo), format_of(first));
    if a != b {
        return Err(Error::InvalidInput(format!(
            "{what} is {a} but photo 1 ({first_name}) is {b}; convert the photos to one format"
        )));
    }
    Ok(())
}

/// Which per-pixel solve to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// One least-squares solve over all lights (the paper).
    LeastSquares,
    /// Drop shadowed and saturated readings per pixel, solve from the rest.
    #[default]
    Robust,
}

/// Parameters of [`solve`]; see the module docs for how the thresholds are applied.
#[derive(Clone, Debug, PartialEq)]
pub struct SolveConfig {
    pub method: Method,
    /// Absolute shadow floor, as a fraction of full scale after ambient subtraction and division
    /// by the light's intensity.
    pub shadow_abs: f32,
    /// Shadow threshold relative to the pixel's own brightest (intensity-divided) reading.
    pub shadow_rel: f32,
    /// Fraction of full scale at or above which a raw reading is saturated.
    pub saturation: f32,
    /// Fewest usable lights for a valid pixel (at least 3).
    pub min_lights: usize,
    /// Largest condition number `sigma_max / sigma_min` of the used lights' direction matrix.
    pub max_condition: f64,
    /// Subset pseudo-inverses kept per worker for rigs of more than [`DENSE_MAX_LIGHTS`] lights.
    pub cache_capacity: usize,
}

impl Default for SolveConfig {
    fn default() -> Self {
        SolveConfig {
            method: Method::Robust,
            shadow_abs: 0.005,
            shadow_rel: 0.05,
            saturation: 0.995,
            min_lights: 3,
            max_condition: 50.0,
            cache_capacity: 4096,
        }
    }
}

impl SolveConfig {
    /// Checks every field's range.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field and its value.
    pub fn validate(&self) -> Result<()> {
        let bad = |field: &str, value: String, want: &str| {
            Err(Error::InvalidInput(format!("solve config: {field} = {value} must be {want}")))
        };
        if !(0.0..1.0).contains(&self.shadow_abs) {
            return bad("shadow_abs", self.shadow_abs.to_string(), "in [0, 1)");
        }
        if !(0.0..1.0).contains(&self.shadow_rel) {
            return bad("shadow_rel", self.shadow_rel.to_string(), "in [0, 1)");
        }
        if !(self.saturation > 0.0 && self.saturation <= 1.0) {
            return bad("saturation", self.saturation.to_string(), "in (0, 1]");
        }
        if self.min_lights < 3 {
            return bad("min_lights", self.min_lights.to_string(), "at least 3");
        }
        if self.max_condition.is_nan() || self.max_condition < 1.0 {
            return bad("max_condition", self.max_condition.to_string(), "at least 1");
        }
        if self.cache_capacity == 0 {
            return bad("cache_capacity", "0".into(), "at least 1");
        }
        Ok(())
    }
}

/// Receives the fraction of the solve done, in [0, 1], from worker threads.
pub trait Progress: Sync {
    fn report(&self, done: f32);
}

impl<F: Fn(f32) + Sync> Progress for F {
    fn report(&self, done: f32) {
        self(done)
    }
}

/// A progress sink that ignores reports.
pub fn no_progress(_done: f32) {}

/// Counts gathered during a solve.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SolveStats {
    /// Texels in the map.
    pub pixels: usize,
    /// Texels with no normal (masked out, too few lights, ill-conditioned, black).
    pub invalid_count: usize,
    /// Texels outside the mask.
    pub masked_count: usize,
    /// `lights_used[m]`: unmasked texels with `m` usable readings (`len = k + 1`).
    pub lights_used: Vec<usize>,
}

impl SolveStats {
    fn empty(k: usize) -> Self {
        SolveStats { lights_used: vec![0; k + 1], ..SolveStats::default() }
    }
    fn merge(mut self, other: SolveStats) -> Self {
        self.pixels += other.pixels;
        self.invalid_count += other.invalid_count;
        self.masked_count += other.masked_count;
        for (a, b) in self.lights_used.iter_mut().zip(other.lights_used) {
            *a += b;
        }
        self
    }
}

/// The result of [`solve`].
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
trait AlbedoTexel: Copy + Send + Sync {
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

/// The pseudo-inverse of one subset of lights, with what the confidence needs.
#[derive(Clone, Debug)]
struct SubsetSolve {
    /// Column of `P` for each light in the subset, in light order.
    cols: Vec<[f32; 3]>,
    /// `L^T L` of the subset: xx, xy, xz, yy, yz, zz.
    gram: [f32; 6],
    /// `sigma_max / sigma_min` of the subset's direction matrix (infinite when singular).
    condition: f64,
    /// Whether the subset may be used (condition within bounds).
    usable: bool,
}

impl SubsetSolve {
    /// Solves for the subset `bits` of `lights` (f64, then stored as f32).
    fn new(lights: &[Vec3], bits: u128, max_condition: f64) -> Self {
        let used: Vec<Vector3<f64>> = lights
            .iter()
            .enumerate()
            .filter(|(i, _)| bits >> i & 1 == 1)
            .map(|(_, l)| Vector3::new(l.x as f64, l.y as f64, l.z as f64))
            .collect();
        let gram: Matrix3<f64> = used.iter().map(|l| l * l.transpose()).sum();
        let condition = condition_of(&gram);
        let usable = used.len() >= 3 && condition.is_finite() && condition <= max_condition;
        let inverse = gram.try_inverse().filter(|_| usable);
        let cols = match inverse {
            Some(inv) => used.iter().map(|l| (inv * l).map(|v| v as f32).into()).collect(),
            None => Vec::new(),
        };
        let g = gram.map(|v| v as f32);
        let gram = [g[(0, 0)], g[(0, 1)], g[(0, 2)], g[(1, 1)], g[(1, 2)], g[(2, 2)]];
        SubsetSolve { cols, gram, condition, usable: inverse.is_some() }
    }

    /// `g^T (L^T L) g`, the squared norm of the fitted readings.
    #[inline]
    fn fitted_sq(&self, g: [f32; 3]) -> f32 {
        gram_form(&self.gram, g)
    }
}

/// `g^T G g` for the symmetric 3x3 `G` stored as xx, xy, xz, yy, yz, zz.
#[inline(always)]
fn gram_form(m: &[f32; 6], g: [f32; 3]) -> f32 {
    let [x, y, z] = g;
    m[0] * x * x + m[3] * y * y + m[5] * z * z + 2.0 * (m[1] * x * y + m[2] * x * z + m[4] * y * z)
}

/// `sigma_max / sigma_min` of a direction matrix `L` from its Gram matrix `L^T L`.
fn condition_of(gram: &Matrix3<f64>) -> f64 {
    let eig = gram.symmetric_eigenvalues();
    let (lo, hi) = (eig.min(), eig.max());
    if lo > hi * 1e-15 && lo > 0.0 { (hi / lo).sqrt() } else { f64::INFINITY }
}

/// Subset pseudo-inverses shared by all workers (dense table) or kept per worker (bounded map).
struct Subsets<'a> {
    lights: &'a [Vec3],
    max_condition: f64,
    dense: Vec<OnceLock<SubsetSolve>>,
    capacity: usize,
}

impl<'a> Subsets<'a> {
    fn new(lights: &'a [Vec3], max_condition: f64, capacity: usize) -> Self {
        let dense = if lights.len() <= DENSE_MAX_LIGHTS {
            (0..1usize << lights.len()).map(|_| OnceLock::new()).collect()
        } else {
            Vec::new()
        };
        Subsets { lights, max_condition, dense, capacity }
    }

    /// The solve for subset `bits`, from the dense table or the worker's `local` map.
    fn get<'s>(&'s self, bits: u128, local: &'s mut HashMap<u128, SubsetSolve>) -> &'s SubsetSolve {
        if !self.dense.is_empty() {
            return self.dense[bits as usize].get_or_init(|| SubsetSolve::new(self.lights, bits, self.max_condition));
        }
        if local.len() >= self.capacity && !local.contains_key(&bits) {
            local.clear();
        }
        local.entry(bits).or_insert_with(|| SubsetSolve::new(self.lights, bits, self.max_condition))
    }
}

/// A photo's samples as a typed slice.
#[derive(Clone, Copy)]
enum Raw<'a> {
    U8(&'a [u8]),
    U16(&'a [u16]),
    F32(&'a [f32]),
}

impl<'a> Raw<'a> {
    fn of(photo: &'a Photo) -> Self {
        match photo.samples() {
            Samples::U8(v) => Raw::U8(v),
            Samples::U16(v) => Raw::U16(v),
            Samples::F32(v) => Raw::F32(v),
        }
    }
}

/// A stored sample type.
trait Sample: Copy + Sync {
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
enum Linearise<'a> {
    Identity,
    Table(&'a [f32]),
    SrgbCurve,
}

impl Linearise<'_> {
    #[inline]
    fn apply(self, v: f32) -> f32 {
        match self {
            Linearise::Identity => v,
            Linearise::Table(t) => t[v as usize],
            Linearise::SrgbCurve => skinkit_maps::encoding::srgb_to_linear(v),
        }
    }
}

/// One light's photo and how its samples become intensity-divided linear readings.
struct Source<'a> {
    raw: Raw<'a>,
    ambient: Option<Raw<'a>>,
    /// Per channel: linearised stored value times this = reading `r` (full scale 1, unit light).
    scale: [f32; 3],
    /// The same for grey photos (divided by the luminance of the light's intensity).
    gray_scale: f32,
    /// Raw stored values at or above this are saturated.
    saturated_at: f32,
}

/// Everything a worker needs, built once per solve.
struct Plan<'a> {
    width: usize,
    k: usize,
    rgb: bool,
    robust: bool,
    config: &'a SolveConfig,
    lights: Vec<Vec3>,
    sources: Vec<Source<'a>>,
    linearise: Linearise<'a>,
    full: SubsetSolve,
    /// `full.cols[i] * sources[i].gray_scale`: the folded pseudo-inverse of the fast path.
    folded: Vec<[f32; 3]>,
    /// Per light, the scale from raw values to readings (fast path), and ones.
    gray_scales: Vec<f32>,
    /// Fast path: `sum_i (raw_i * rr_scales_i)^2 * rr_post` is `sum r^2`. With one scale for all
    /// lights (equal intensities) the scale moves out of the sum (`rr_post = scale^2`, ones
    /// inside), a multiplication per reading fewer; else `rr_post = 1`.
    rr_scales: Vec<f32>,
    rr_post: f32,
    ones: Vec<f32>,
    fast_ls: bool,
    /// Whether the fused kernel applies: linear grey photos without an ambient frame.
    fused: bool,
    /// Robust with at most [`DENSE_MAX_LIGHTS`] lights: a chunk's pixels with dropped readings
    /// are grouped by subset and solved a group at a time ([`Self::finish_subsets`]); else one
    /// pixel at a time ([`Self::finish_subset`]). Both give the same bits.
    batch_subsets: bool,
    mask: Option<&'a [bool]>,
}

/// Per-worker scratch buffers, structure-of-arrays over one chunk.
struct Scratch {
    r: Vec<f32>,
    rgb: Vec<[f32; 3]>,
    sat: Vec<u8>,
    gx: [f32; CHUNK],
    gy: [f32; CHUNK],
    gz: [f32; CHUNK],
    rr: [f32; CHUNK],
    top: [f32; CHUNK],
    len: [f32; CHUNK],
    conf: [f32; CHUNK],
    dropped: [u32; CHUNK],
    /// Batched subsets: usable lights per pixel (bit `i` for light `i`).
    bits: [u32; CHUNK],
    /// Batched subsets: pixels still to solve, and those of the current group.
    pending: [u8; CHUNK],
    group: [u8; CHUNK],
    /// Batched subsets: `g` and `sum r^2` of the current group.
    bx: [f32; CHUNK],
    by: [f32; CHUNK],
    bz: [f32; CHUNK],
    brr: [f32; CHUNK],
    cache: HashMap<u128, SubsetSolve>,
}

impl Scratch {
    fn new(k: usize, rgb: bool) -> Self {
        Scratch {
            r: vec![0.0; k * CHUNK],
            rgb: if rgb { vec![[0.0; 3]; k * CHUNK] } else { Vec::new() },
            sat: vec![0; k * CHUNK],
            gx: [0.0; CHUNK],
            gy: [0.0; CHUNK],
            gz: [0.0; CHUNK],
            rr: [0.0; CHUNK],
            top: [0.0; CHUNK],
            len: [0.0; CHUNK],
            conf: [0.0; CHUNK],
            dropped: [0; CHUNK],
            bits: [0; CHUNK],
            pending: [0; CHUNK],
            group: [0; CHUNK],
            bx: [0.0; CHUNK],
            by: [0.0; CHUNK],
            bz: [0.0; CHUNK],
            brr: [0.0; CHUNK],
            cache: HashMap::new(),
        }
    }
}

/// Output slices of one chunk.
struct Out<'o, A> {
    normals: &'o mut [Vec3],
    albedo: &'o mut [A],
    confidence: &'o mut [f32],
}

/// Solves for normals, albedo and confidence from `stack` lit by `rig`.
///
/// # Errors
/// [`Error::InvalidInput`] when the photo count differs from the rig's light count, the rig has
/// more than [`MAX_LIGHTS`] lights, or `config` is out of range; [`Error::BadRig`] when a light has
/// a zero direction or a non-positive intensity, or the lights cannot determine a normal (fewer
/// than 3, coplanar, or a condition number above `config.max_condition`).
pub fn solve(stack: &PhotoStack, rig: &Rig, config: &SolveConfig, progress: &dyn Progress) -> Result<Solution> {
    // Empty maps: `solve_into` allocates fresh ones of the right size and kind, untouched until
    // the parallel bands write them.
    let mut solution = Solution {
        normals: NormalMap::flat(0, 0),
        albedo: AlbedoMap::Gray(Grid::filled(0, 0, 0.0)),
        confidence: Grid::filled(0, 0, 0.0),
        stats: SolveStats::default(),
    };
    solve_into(stack, rig, config, progress, &mut solution)?;
    Ok(solution)
}

/// [`solve`] into an existing solution, reusing its maps when they have the stack's size (for
/// repeated solves of large stacks: fresh maps cost a page fault per 4 KiB written).
///
/// # Errors
/// As [`solve`]; `out` is unchanged on error.
pub fn solve_into(
    stack: &PhotoStack,
    rig: &Rig,
    config: &SolveConfig,
    progress: &dyn Progress,
    out: &mut Solution,
) -> Result<()> {
    config.validate()?;
    let lights = check_rig(stack, rig)?;
    let table = srgb_table(stack);
    let plan = Plan::new(stack, rig, config, lights, table.as_deref())?;
    plan.run(stack, progress, out);
    Ok(())
}

/// Unit light directions of `rig`, after checking it against the stack and the config.
fn check_rig(stack: &PhotoStack, rig: &Rig) -> Result<Vec<Vec3>> {
    let k = rig.lights.len();
    if k != stack.len() {
        return Err(Error::InvalidInput(format!("rig has {k} lights but {} photos were given", stack.len())));
    }
    if k > MAX_LIGHTS {
        return Err(Error::InvalidInput(format!("rig has {k} lights; at most {MAX_LIGHTS} are supported")));
    }
    if k < 3 {
        return Err(Error::BadRig(format!("rig has {k} lights; a normal needs at least 3")));
    }
    rig.lights
        .iter()
        .enumerate()
        .map(|(i, light)| {
            let d = light.direction.normalize_or_zero();
            if d == Vec3::ZERO || !d.is_finite() {
                return Err(Error::BadRig(format!(
                    "rig light {}: direction {} has zero length",
                    i + 1,
                    light.direction
                )));
            }
            if !(light.intensity.min_element() > 0.0 && light.intensity.is_finite()) {
                return Err(Error::BadRig(format!(
                    "rig light {}: intensity {} must be positive",
                    i + 1,
                    light.intensity
                )));
            }
            Ok(d)
        })
        .collect()
}

/// A stored-value to linear table for 8- and 16-bit sRGB photos.
fn srgb_table(stack: &PhotoStack) -> Option<Vec<f32>> {
    let first = &stack.photos()[0];
    if first.transfer() != Transfer::Srgb || first.bit_depth() == 32 {
        return None;
    }
    let full = first.samples().full_scale();
    Some((0..=full as usize).map(|v| skinkit_maps::encoding::srgb_to_linear(v as f32 / full)).collect())
}

impl<'a> Plan<'a> {
    fn new(
        stack: &'a PhotoStack,
        rig: &Rig,
        config: &'a SolveConfig,
        lights: Vec<Vec3>,
        table: Option<&'a [f32]>,
    ) -> Result<Self> {
        let full_bits = if lights.len() == 128 { u128::MAX } else { (1u128 << lights.len()) - 1 };
        let full = SubsetSolve::new(&lights, full_bits, config.max_condition);
        if !full.usable {
            return Err(Error::BadRig(format!(
                "the rig's {} lights cannot determine a normal (coplanar or nearly so): condition number {:.4} exceeds max_condition {}",
                lights.len(),
                full.condition,
                config.max_condition
            )));
        }
        let first = &stack.photos()[0];
        let linearise = match (first.transfer(), table) {
            (Transfer::Linear, _) => Linearise::Identity,
            (Transfer::Srgb, Some(t)) => Linearise::Table(t),
            (Transfer::Srgb, None) => Linearise::SrgbCurve,
        };
        let sources: Vec<Source> = stack
            .photos()
            .iter()
            .zip(&rig.lights)
            .map(|(p, l)| Source::new(p, stack.ambient(), l.intensity, config))
            .collect();
        let k = lights.len();
        let sources_scales: Vec<f32> = sources.iter().map(|s| s.gray_scale).collect();
        let uniform = sources_scales.iter().all(|s| s.to_bits() == sources_scales[0].to_bits());
        let folded = full.cols.iter().zip(&sources).map(|(c, s)| c.map(|v| v * s.gray_scale)).collect();
        let rgb = first.channels() == Channels::Rgb;
        let robust = config.method == Method::Robust;
        Ok(Plan {
            width: stack.width(),
            k: lights.len(),
            rgb,
            robust,
            config,
            lights,
            sources,
            linearise,
            full,
            folded,
            rr_scales: if uniform { vec![1.0; k] } else { sources_scales.clone() },
            rr_post: if uniform { sources_scales[0] * sources_scales[0] } else { 1.0 },
            gray_scales: sources_scales,
            ones: vec![1.0; k],
            fast_ls: !robust && !rgb && first.transfer() == Transfer::Linear,
            fused: !rgb && first.transfer() == Transfer::Linear && stack.ambient().is_none(),
            batch_subsets: robust && k <= DENSE_MAX_LIGHTS,
            mask: stack.mask().map(|m| m.as_slice()),
        })
    }

    /// Solves every band of rows in parallel and assembles the maps.
    fn run(&self, stack: &PhotoStack, progress: &dyn Progress, out: &mut Solution) {
        let (w, h) = stack.size();
        let normals = std::mem::replace(&mut out.normals, NormalMap::flat(0, 0)).into_grid();
        let mut normals = if normals.size() == (w, h) { normals.into_vec() } else { fresh_zeroed_vec3(w * h) };
        let mut confidence = take_sized(std::mem::replace(&mut out.confidence, Grid::filled(0, 0, 0.0)), w, h);
        let albedo = std::mem::replace(&mut out.albedo, AlbedoMap::Gray(Grid::filled(0, 0, 0.0)));
        let stats = match (self.rgb, albedo) {
            (false, albedo) => {
                let mut a = match albedo {
                    AlbedoMap::Gray(g) => take_sized(g, w, h),
                    AlbedoMap::Rgb(_) => f32::fresh(w * h),
                };
                let stats = self.run_bands(progress, &mut normals, &mut a, &mut confidence);
                out.albedo = AlbedoMap::Gray(Grid::from_vec(w, h, a).expect("sized above"));
                stats
            }
            (true, albedo) => {
                let mut a = match albedo {
                    AlbedoMap::Rgb(g) => take_sized(g, w, h),
                    AlbedoMap::Gray(_) => Vec3::fresh(w * h),
                };
                let stats = self.run_bands(progress, &mut normals, &mut a, &mut confidence);
                out.albedo = AlbedoMap::Rgb(Grid::from_vec(w, h, a).expect("sized above"));
                stats
            }
        };
        out.normals = NormalMap::from_unit_grid(Grid::from_vec(w, h, normals).expect("sized above"))
            .expect("solver writes unit or zero normals");
        out.confidence = Grid::from_vec(w, h, confidence).expect("sized above");
        out.stats = stats;
    }

    /// Solves every band of rows in parallel into the output slices (each the image's size).
    fn run_bands<A: AlbedoTexel>(
        &self,
        progress: &dyn Progress,
        normals: &mut [Vec3],
        albedo: &mut [A],
        confidence: &mut [f32],
    ) -> SolveStats {
        let (w, h) = (self.width, normals.len() / self.width);
        let subsets = Subsets::new(&self.lights, self.config.max_condition, self.config.cache_capacity);
        let rows_done = AtomicUsize::new(0);
        progress.report(0.0);
        let band = BAND_ROWS * w;
        let stats = normals
            .par_chunks_mut(band)
            .zip(albedo.par_chunks_mut(band))
            .zip(confidence.par_chunks_mut(band))
            .enumerate()
            .map_init(
                || Scratch::new(self.k, self.rgb),
                |scratch, (b, ((n, a), c))| {
                    let stats =
                        self.solve_band(b * band, Out { normals: n, albedo: a, confidence: c }, scratch, &subsets);
                    let done = rows_done.fetch_add(stats.pixels / w, Ordering::Relaxed) + stats.pixels / w;
                    progress.report(done as f32 / h as f32);
                    stats
                },
            )
            .reduce(|| SolveStats::empty(self.k), SolveStats::merge);
        progress.report(1.0);
        stats
    }

    /// Solves the pixels starting at `p0` (a band of whole rows), row by row in chunks.
    fn solve_band<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU supports AVX2 and FMA, the features `solve_band_avx2` is compiled for.
            return unsafe { self.solve_band_avx2(p0, out, scratch, subsets) };
        }
        self.solve_band_portable(p0, out, scratch, subsets)
    }

    /// [`Self::solve_band`] compiled for AVX2 and FMA (8-wide loops). The kernels use explicit
    /// `mul_add` (exactly rounded everywhere), so this and the portable build give the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn solve_band_avx2<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        if !self.fused {
            return self.solve_band_portable(p0, out, scratch, subsets);
        }
        let Out { normals, albedo, confidence } = out;
        let Some(albedo) = A::gray_slice(albedo) else {
            return self.solve_band_portable(p0, Out { normals, albedo, confidence }, scratch, subsets);
        };
        let out = Out { normals, albedo, confidence };
        match (self.sources[0].raw, self.robust) {
            (Raw::U8(_), false) => self.solve_band_fused::<u8, false>(p0, out, scratch, subsets),
            (Raw::U8(_), true) => self.solve_band_fused::<u8, true>(p0, out, scratch, subsets),
            (Raw::U16(_), false) => self.solve_band_fused::<u16, false>(p0, out, scratch, subsets),
            (Raw::U16(_), true) => self.solve_band_fused::<u16, true>(p0, out, scratch, subsets),
            (Raw::F32(_), false) => self.solve_band_fused::<f32, false>(p0, out, scratch, subsets),
            (Raw::F32(_), true) => self.solve_band_fused::<f32, true>(p0, out, scratch, subsets),
        }
    }

    /// [`Self::solve_band`] for linear grey photos without an ambient frame: [`fused::step`]
    /// solves [`fused::STEP`] pixels at a time straight from the samples to the output. Steps it
    /// declines (a reading dropped by the robust tests, a masked texel) and the band's last few
    /// pixels go through [`Self::solve_chunk`], whose all-lights arithmetic is the same.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn solve_band_fused<T: fused::Lanes, const ROBUST: bool>(
        &self,
        p0: usize,
        out: Out<f32>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        const STEP: usize = fused::STEP;
        let rows: Vec<&[T]> = self.sources.iter().map(|s| T::of(s.raw)).collect();
        let kernel = fused::Kernel {
            coefs: if ROBUST { &self.full.cols } else { &self.folded },
            scales: if ROBUST { &self.ones } else { &self.rr_scales },
            unit_scales: ROBUST || self.rr_scales.iter().all(|&s| s == 1.0),
            rr_post: if ROBUST { 1.0 } else { self.rr_post },
            gains: &self.gray_scales,
            gram: self.full.gram,
            saturated_at: self.sources[0].saturated_at,
            shadow_abs: self.config.shadow_abs,
            shadow_rel: self.config.shadow_rel,
            group_subsets: self.batch_subsets,
        };
        let mut stats = SolveStats::empty(self.k);
        let n_px = out.normals.len();
        stats.pixels = n_px;
        let mut j = 0;
        while j < n_px {
            let n = STEP.min(n_px - j);
            let p = p0 + j;
            let chunk = Out {
                normals: &mut out.normals[j..j + n],
                albedo: &mut out.albedo[j..j + n],
                confidence: &mut out.confidence[j..j + n],
            };
            let inside = self.mask.is_none_or(|m| m[p..p + n].iter().all(|&v| v));
            let solved = if n == STEP && inside {
                fused::step::<T, ROBUST>(&kernel, &rows, p, chunk.normals, chunk.albedo, chunk.confidence)
            } else {
                fused::Step::Declined
            };
            match solved {
                fused::Step::Solved(invalid) => {
                    stats.lights_used[self.k] += STEP;
                    stats.invalid_count += invalid as usize;
                }
                fused::Step::Subset(bits) => {
                    let used = bits.count_ones() as usize;
                    stats.lights_used[used] += STEP;
                    let subset = if used < self.config.min_lights {
                        None
                    } else {
                        Some(subsets.get(bits as u128, &mut scratch.cache)).filter(|s| s.usable)
                    };
                    let Some(subset) = subset else {
                        chunk.normals.fill(Vec3::ZERO);
                        chunk.albedo.fill(0.0);
                        chunk.confidence.fill(0.0);
                        stats.invalid_count += STEP;
                        j += n;
                        continue;
                    };
                    let sk = fused::SubsetKernel {
                        bits,
                        cols: &subset.cols,
                        gains: &self.gray_scales,
                        gram: subset.gram,
                        weight: self.subset_weight(used, subset),
                    };
                    let invalid = fused::subset_step(&sk, &rows, p, chunk.normals, chunk.albedo, chunk.confidence);
                    stats.invalid_count += invalid as usize;
                }
                fused::Step::Declined => self.solve_chunk(p, chunk, scratch, subsets, &mut stats),
            }
            j += n;
        }
        stats
    }

    #[inline(always)]
    fn solve_band_portable<A: AlbedoTexel>(
        &self,
        p0: usize,
        out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
    ) -> SolveStats {
        let mut stats = SolveStats::empty(self.k);
        let n_px = out.normals.len();
        stats.pixels = n_px;
        let mut start = 0;
        while start < n_px {
            let row_end = (start / self.width + 1) * self.width;
            let n = CHUNK.min(row_end - start);
            let chunk = Out {
                normals: &mut out.normals[start..start + n],
                albedo: &mut out.albedo[start..start + n],
                confidence: &mut out.confidence[start..start + n],
            };
            self.solve_chunk(p0 + start, chunk, scratch, subsets, &mut stats);
            start += n;
        }
        stats
    }

    /// Solves the `n <= CHUNK` pixels starting at image pixel `p`.
    #[inline(always)]
    fn solve_chunk<A: AlbedoTexel>(
        &self,
        p: usize,
        mut out: Out<A>,
        scratch: &mut Scratch,
        subsets: &Subsets,
        stats: &mut SolveStats,
    ) {
        let n = out.normals.len();
        let inside = self.mask.map(|m| &m[p..p + n]);
        if let Some(inside) = inside {
            let masked = inside.iter().filter(|v| !**v).count();
            stats.masked_count += masked;
            if masked == n {
                out.normals.fill(Vec3::ZERO);
                out.albedo.fill(A::ZERO);
                out.confidence.fill(0.0);
                stats.invalid_count += n;
                return;
            }
        }
        if self.fast_ls {
            self.accumulate_folded(p, n, scratch);
        } else {
            self.load_readings(p, n, scratch);
            self.accumulate_readings(n, scratch);
            if self.robust {
                self.count_dropped(n, scratch);
            }
        }
        let invalid = self.normalise_all(n, scratch);
        let any_dropped = self.robust && scratch.dropped[..n].iter().any(|&d| d > 0);
        if !self.rgb && inside.is_none() && !any_dropped {
            write_all_lights(n, scratch, out);
            stats.lights_used[self.k] += n;
            stats.invalid_count += invalid;
            return;
        }
        let mut local = std::mem::take(&mut scratch.cache);
        let mut pending = 0;
        for j in 0..n {
            if inside.is_some_and(|m| !m[j]) {
                (out.normals[j], out.albedo[j], out.confidence[j]) = (Vec3::ZERO, A::ZERO, 0.0);
                continue;
            }
            if self.batch_subsets && scratch.dropped[j] > 0 {
                scratch.pending[pending] = j as u8;
                pending += 1;
                continue;
            }
            let (normal, albedo, confidence, used) = if self.robust && scratch.dropped[j] > 0 {
                self.finish_subset(j, scratch, subsets, &mut local)
            } else {
                let normal = Vec3::new(scratch.gx[j], scratch.gy[j], scratch.gz[j]);
                let albedo = if self.rgb {
                    self.rgb_albedo(j, self.full_bits(), normal, scratch)
                } else {
                    Vec3::splat(scratch.len[j])
                };
                (normal, albedo, scratch.conf[j], self.k)
            };
            stats.lights_used[used] += 1;
            out.normals[j] = normal;
            out.albedo[j] = A::rgb(albedo);
            out.confidence[j] = confidence;
        }
        if pending > 0 {
            self.finish_subsets(pending, scratch, subsets, &mut local, &mut out, stats);
        }
        scratch.cache = local;
        stats.invalid_count += out.normals.iter().filter(|v| **v == Vec3::ZERO).count();
    }

    /// Turns the all-lights solutions `g` of the chunk into normals (in place), albedo `|g|` and
    /// confidence, vectorised; `|g| <= MIN_ALBEDO` or non-finite gives zeros.
    #[inline(always)]
    fn normalise_all(&self, n: usize, s: &mut Scratch) -> usize {
        let m = self.full.gram;
        let mut invalid = 0u32;
        let it = s.gx[..n]
            .iter_mut()
            .zip(&mut s.gy[..n])
            .zip(&mut s.gz[..n])
            .zip(&s.rr[..n])
            .zip(&mut s.len[..n])
            .zip(&mut s.conf[..n]);
        for (((((x, y), z), &rr), len), conf) in it {
            let g = [*x, *y, *z];
            let l = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
            let ok = l > MIN_ALBEDO && l < f32::INFINITY;
            invalid += !ok as u32;
            // Selects, not products with zero: a NaN reading must not leak into the normal.
            let inv = if ok { 1.0 / l } else { 0.0 };
            *conf = if ok { residual_factor(rr, gram_form(&m, g)) } else { 0.0 };
            *len = if ok { l } else { 0.0 };
            (*x, *y, *z) = if ok { (g[0] * inv, g[1] * inv, g[2] * inv) } else { (0.0, 0.0, 0.0) };
        }
        invalid as usize
    }

    /// Fast least-squares path for linear grey photos: `g += P'_i * raw_i` with the folded
    /// pseudo-inverse and `rr += (raw_i * rr_scale_i)^2` (times `rr_post` at the end), straight
    /// from the stored samples (the conversion to f32 is exact), or from `s.r` holding raw values
    /// minus the ambient frame's.
    #[inline(always)]
    fn accumulate_folded(&self, p: usize, n: usize, s: &mut Scratch) {
        let (folded, scales) = (&self.folded[..], &self.rr_scales[..]);
        let sums = (&mut s.gx, &mut s.gy, &mut s.gz, &mut s.rr);
        let src = |i: usize| self.sources[i].raw;
        match (self.sources[0].raw, self.sources[0].ambient) {
            (Raw::U16(_), None) => accumulate_rows(n, |i| &as_u16(src(i))[p..p + n], sums, folded, scales),
            (Raw::U8(_), None) => accumulate_rows(n, |i| &as_u8(src(i))[p..p + n], sums, folded, scales),
            (Raw::F32(_), None) => accumulate_rows(n, |i| &as_f32(src(i))[p..p + n], sums, folded, scales),
            _ => {
                for (i, src) in self.sources.iter().enumerate() {
                    let out = &mut s.r[i * CHUNK..i * CHUNK + n];
                    match (src.raw, src.ambient) {
                        (Raw::U8(v), a) => raw_values::<u8>(&v[p..p + n], a.map(|a| &as_u8(a)[p..p + n]), out),
                        (Raw::U16(v), a) => raw_values::<u16>(&v[p..p + n], a.map(|a| &as_u16(a)[p..p + n]), out),
                        (Raw::F32(v), a) => raw_values::<f32>(&v[p..p + n], a.map(|a| &as_f32(a)[p..p + n]), out),
                    }
                }
                accumulate_all(n, s, folded, scales);
            }
        }
        let post = self.rr_post;
        s.rr[..n].iter_mut().for_each(|q| *q *= post);
    }

    /// Fills `s.r` (and `s.rgb`, `s.sat`) with every light's readings of the chunk.
    #[inline(always)]
    fn load_readings(&self, p: usize, n: usize, s: &mut Scratch) {
        for (i, src) in self.sources.iter().enumerate() {
            let r = &mut s.r[i * CHUNK..i * CHUNK + n];
            let sat = &mut s.sat[i * CHUNK..i * CHUNK + n];
            if self.rgb {
                let rgb = &mut s.rgb[i * CHUNK..i * CHUNK + n];
                src.load_rgb(p, self.linearise, r, rgb, sat);
            } else {
                src.load_gray(p, self.linearise, r, sat);
            }
        }
    }

    /// `g = P r` and `rr = sum r^2` over all lights, from the loaded readings.
    #[inline(always)]
    fn accumulate_readings(&self, n: usize, s: &mut Scratch) {
        accumulate_all(n, s, &self.full.cols, &self.ones);
    }

    /// Counts, per pixel, the readings that are shadowed or saturated (`s.dropped`).
    #[inline(always)]
    fn count_dropped(&self, n: usize, s: &mut Scratch) {
        s.top[..n].fill(f32::NEG_INFINITY);
        for i in 0..self.k {
            for (t, &v) in s.top[..n].iter_mut().zip(&s.r[i * CHUNK..i * CHUNK + n]) {
                *t = t.max(v);
            }
        }
        let (abs, rel) = (self.config.shadow_abs, self.config.shadow_rel);
        for t in &mut s.top[..n] {
            *t = abs.max(rel * *t);
        }
        s.dropped[..n].fill(0);
        for i in 0..self.k {
            let r = &s.r[i * CHUNK..i * CHUNK + n];
            let sat = &s.sat[i * CHUNK..i * CHUNK + n];
            for (((d, &t), &v), &q) in s.dropped[..n].iter_mut().zip(&s.top[..n]).zip(r).zip(sat) {
                *d += ((v < t) as u32) | q as u32;
            }
        }
        if self.batch_subsets {
            // The same test as `usable_bits` (a NaN reading is neither dropped nor usable).
            s.bits[..n].fill(0);
            for i in 0..self.k {
                let r = &s.r[i * CHUNK..i * CHUNK + n];
                let sat = &s.sat[i * CHUNK..i * CHUNK + n];
                for (((b, &t), &v), &q) in s.bits[..n].iter_mut().zip(&s.top[..n]).zip(r).zip(sat) {
                    *b |= (((v >= t) & (q == 0)) as u32) << i;
                }
            }
        }
    }

    /// The bitmask of usable lights of pixel `j` (robust mode, after [`Self::count_dropped`]).
    fn usable_bits(&self, j: usize, s: &Scratch) -> u128 {
        let threshold = s.top[j];
        (0..self.k).fold(0u128, |bits, i| {
            let ok = s.r[i * CHUNK + j] >= threshold && s.sat[i * CHUNK + j] == 0;
            bits | ((ok as u128) << i)
        })
    }

    /// Normal, albedo, confidence and lights used for pixel `j`, solved from its usable lights.
    fn finish_subset(
        &self,
        j: usize,
        s: &Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
    ) -> (Vec3, Vec3, f32, usize) {
        let invalid = |used| (Vec3::ZERO, Vec3::ZERO, 0.0, used);
        let bits = self.usable_bits(j, s);
        let used = bits.count_ones() as usize;
        if used < self.config.min_lights {
            return invalid(used);
        }
        let subset = subsets.get(bits, local);
        if !subset.usable {
            return invalid(used);
        }
        let (g, rr) = self.solve_subset(j, bits, subset, s);
        let len = Vec3::from(g).length();
        if !(len > MIN_ALBEDO && len < f32::INFINITY) {
            return invalid(used);
        }
        let normal = Vec3::from(g) / len;
        let confidence = self.subset_weight(used, subset) * residual_factor(rr, subset.fitted_sq(g));
        let albedo = if self.rgb { self.rgb_albedo(j, bits, normal, s) } else { Vec3::splat(len) };
        (normal, albedo, confidence, used)
    }

    /// [`Self::finish_subset`] for the `count` pixels listed in `s.pending` (robust, at most
    /// [`DENSE_MAX_LIGHTS`] lights, `s.bits` filled), written to `out`: the pixels are grouped by
    /// their subset (usually one or two per chunk, as shadows are coherent) and each group is
    /// solved with that subset's columns in registers, in the same operations and order as
    /// [`Self::solve_subset`], so the bits match the per-pixel path.
    fn finish_subsets<A: AlbedoTexel>(
        &self,
        mut count: usize,
        s: &mut Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
        out: &mut Out<A>,
        stats: &mut SolveStats,
    ) {
        while count > 0 {
            let bits = s.bits[s.pending[0] as usize];
            // Split the pending pixels into this subset's group and the rest (kept in place:
            // the rest's write index never passes the read index).
            let (mut grouped, mut rest) = (0, 0);
            for t in 0..count {
                let j = s.pending[t];
                if s.bits[j as usize] == bits {
                    s.group[grouped] = j;
                    grouped += 1;
                } else {
                    s.pending[rest] = j;
                    rest += 1;
                }
            }
            self.solve_group(bits, grouped, s, subsets, local, out);
            stats.lights_used[bits.count_ones() as usize] += grouped;
            count = rest;
        }
    }

    /// Solves the `m` pixels of `s.group`, whose usable lights are `bits`, into `out`.
    fn solve_group<A: AlbedoTexel>(
        &self,
        bits: u32,
        m: usize,
        s: &mut Scratch,
        subsets: &Subsets,
        local: &mut HashMap<u128, SubsetSolve>,
        out: &mut Out<A>,
    ) {
        let used = bits.count_ones() as usize;
        let subset = if used < self.config.min_lights { None } else { Some(subsets.get(bits as u128, local)) };
        let Some(subset) = subset.filter(|s| s.usable) else {
            for &j in &s.group[..m] {
                let j = j as usize;
                (out.normals[j], out.albedo[j], out.confidence[j]) = (Vec3::ZERO, A::ZERO, 0.0);
            }
            return;
        };
        {
            let Scratch { r, group, bx, by, bz, brr, .. } = &mut *s;
            let group = &group[..m];
            let (gx, gy, gz, rr) = (&mut bx[..m], &mut by[..m], &mut bz[..m], &mut brr[..m]);
            gx.fill(0.0);
            gy.fill(0.0);
            gz.fill(0.0);
            rr.fill(0.0);
            let lights = (0..self.k).filter(|i| bits >> i & 1 == 1);
            for (i, c) in lights.zip(&subset.cols) {
                let row: &[f32; CHUNK] = r[i * CHUNK..(i + 1) * CHUNK].try_into().expect("CHUNK readings per light");
                for t in 0..m {
                    // `& (CHUNK - 1)`: a no-op (pixels index a chunk) that drops the bounds check.
                    let v = row[group[t] as usize & (CHUNK - 1)];
                    gx[t] = gx[t] + c[0] * v;
                    gy[t] = gy[t] + c[1] * v;
                    gz[t] = gz[t] + c[2] * v;
                    rr[t] = rr[t] + v * v;
                }
            }
        }
        let s: &Scratch = s;
        let (group, gx, gy, gz, rr) = (&s.group[..m], &s.bx[..m], &s.by[..m], &s.bz[..m], &s.brr[..m]);
        let weight = self.subset_weight(used, subset);
        for t in 0..m {
            let j = group[t] as usize;
            let g = [gx[t], gy[t], gz[t]];
            let len = Vec3::from(g).length();
            let (normal, albedo, confidence) = if len > MIN_ALBEDO && len < f32::INFINITY {
                let normal = Vec3::from(g) / len;
                let confidence = weight * residual_factor(rr[t], subset.fitted_sq(g));
                let albedo = if self.rgb { self.rgb_albedo(j, bits as u128, normal, s) } else { Vec3::splat(len) };
                (normal, albedo, confidence)
            } else {
                (Vec3::ZERO, Vec3::ZERO, 0.0)
            };
            out.normals[j] = normal;
            out.albedo[j] = A::rgb(albedo);
            out.confidence[j] = confidence;
        }
    }

    /// The confidence factors of a pixel solved from `used` lights forming `subset`: the
    /// fraction of lights used times `min(1, cond(L_all) / cond(L_used))`.
    fn subset_weight(&self, used: usize, subset: &SubsetSolve) -> f32 {
        used as f32 / self.k as f32 * (self.full.condition / subset.condition).min(1.0) as f32
    }

    fn full_bits(&self) -> u128 {
        if self.k == 128 { u128::MAX } else { (1u128 << self.k) - 1 }
    }

    /// `g = P_S r_S` and `sum r_S^2` for pixel `j` over the lights in `bits`.
    fn solve_subset(&self, j: usize, bits: u128, subset: &SubsetSolve, s: &Scratch) -> ([f32; 3], f32) {
        let (mut g, mut rr) = ([0.0f32; 3], 0.0f32);
        let used = (0..self.k).filter(|i| bits >> i & 1 == 1);
        for (i, c) in used.zip(&subset.cols) {
            let v = s.r[i * CHUNK + j];
            g = [g[0] + c[0] * v, g[1] + c[1] * v, g[2] + c[2] * v];
            rr += v * v;
        }
        (g, rr)
    }

    /// Per-channel least-squares albedo `sum r_ci d_i / sum d_i^2`, `d_i = n . L_i`, over `bits`.
    fn rgb_albedo(&self, j: usize, bits: u128, normal: Vec3, s: &Scratch) -> Vec3 {
        let (mut num, mut den) = (Vec3::ZERO, 0.0f32);
        for (i, l) in self.lights.iter().enumerate().filter(|(i, _)| bits >> i & 1 == 1) {
            let d = normal.dot(*l);
            num += Vec3::from(s.rgb[i * CHUNK + j]) * d;
            den += d * d;
        }
        if den > 0.0 { (num / den).max(Vec3::ZERO) } else { Vec3::ZERO }
    }
}

/// The texels of `grid` when it is `w x h` (to be overwritten), else a fresh zeroed vector.
fn take_sized<T: AlbedoTexel>(grid: Grid<T>, w: usize, h: usize) -> Vec<T> {
    if grid.size() == (w, h) { grid.into_vec() } else { T::fresh(w * h) }
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

/// Copies the chunk's all-lights results (grey albedo) to the output.
#[inline(always)]
fn write_all_lights<A: AlbedoTexel>(n: usize, s: &Scratch, out: Out<A>) {
    let (normals, albedo) = (&mut out.normals[..n], &mut out.albedo[..n]);
    for j in 0..n {
        normals[j].x = s.gx[j];
        normals[j].y = s.gy[j];
        normals[j].z = s.gz[j];
        albedo[j] = A::gray(s.len[j]);
    }
    out.confidence.copy_from_slice(&s.conf[..n]);
}

/// `1 / (1 + (rho / RESIDUAL_SCALE)^2)` with `rho^2 = (|r|^2 - |L g|^2) / |r|^2`, the relative
/// residual of a least-squares fit (the fitted readings are orthogonal to the residual).
#[inline(always)]
fn residual_factor(rr: f32, fitted: f32) -> f32 {
    // 1 / (1 + rho^2 / s^2) = rr / (rr + (rr - fitted) / s^2): one division.
    let excess = (rr - fitted).max(0.0) * (1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
    if rr > 0.0 { rr / (rr + excess) } else { 1.0 }
}

/// Stored values minus the ambient frame's, as f32.
#[inline(always)]
fn raw_values<T: Sample>(v: &[T], ambient: Option<&[T]>, out: &mut [f32]) {
    match ambient {
        None => out.iter_mut().zip(v).for_each(|(o, x)| *o = x.value()),
        Some(a) => out.iter_mut().zip(v.iter().zip(a)).for_each(|(o, (x, y))| *o = x.value() - y.value()),
    }
}

/// `g += coefs_i * x_i` and `rr += (x_i * scales_i)^2` over all lights, `x_i` the rows of `s.r`.
#[inline(always)]
fn accumulate_all(n: usize, s: &mut Scratch, coefs: &[[f32; 3]], scales: &[f32]) {
    let Scratch { r, gx, gy, gz, rr, .. } = s;
    accumulate_rows(n, |i| &r[i * CHUNK..i * CHUNK + n], (gx, gy, gz, rr), coefs, scales);
}

/// `g += coefs_i * x_i` and `rr += (x_i * scales_i)^2` over all lights, `x_i = row(i)` (the `n`
/// values of light `i`, stored samples or readings), four lights per pass over the accumulators
/// (the sums are still formed light by light, so the grouping does not change a bit).
#[inline(always)]
fn accumulate_rows<'r, T: Sample + 'r>(
    n: usize,
    row: impl Fn(usize) -> &'r [T],
    sums: (&mut [f32; CHUNK], &mut [f32; CHUNK], &mut [f32; CHUNK], &mut [f32; CHUNK]),
    coefs: &[[f32; 3]],
    scales: &[f32],
) {
    let (gx, gy, gz, rr) = sums;
    for (g, (c, sc)) in coefs.chunks(4).zip(scales.chunks(4)).enumerate() {
        let sums = (&mut gx[..n], &mut gy[..n], &mut gz[..n], &mut rr[..n]);
        let rows = |t: usize| row(4 * g + t);
        match (c.len(), g == 0) {
            (4, true) => accumulate::<T, 4, true>(std::array::from_fn(rows), n, c, sc, sums),
            (4, false) => accumulate::<T, 4, false>(std::array::from_fn(rows), n, c, sc, sums),
            (3, true) => accumulate::<T, 3, true>(std::array::from_fn(rows), n, c, sc, sums),
            (3, false) => accumulate::<T, 3, false>(std::array::from_fn(rows), n, c, sc, sums),
            (2, _) => accumulate::<T, 2, false>(std::array::from_fn(rows), n, c, sc, sums),
            _ => accumulate::<T, 1, false>(std::array::from_fn(rows), n, c, sc, sums),
        }
    }
}

/// The kernel of [`accumulate_rows`] for `N` lights' values `xs`; `FIRST` starts the sums from
/// zero instead of reading them (no separate clearing pass).
#[inline(always)]
fn accumulate<T: Sample, const N: usize, const FIRST: bool>(
    xs: [&[T]; N],
    n: usize,
    coefs: &[[f32; 3]],
    scales: &[f32],
    sums: (&mut [f32], &mut [f32], &mut [f32], &mut [f32]),
) {
    let (gx, gy, gz, rr) = sums;
    let xs: [&[T]; N] = std::array::from_fn(|t| &xs[t][..n]);
    let c: [[f32; 3]; N] = std::array::from_fn(|t| coefs[t]);
    let sc: [f32; N] = std::array::from_fn(|t| scales[t]);
    let (gx, gy, gz, rr) = (&mut gx[..n], &mut gy[..n], &mut gz[..n], &mut rr[..n]);
    for j in 0..n {
        let (mut x, mut y, mut z, mut q) = if FIRST { (0.0, 0.0, 0.0, 0.0) } else { (gx[j], gy[j], gz[j], rr[j]) };
        for t in 0..N {
            let v = xs[t][j].value();
            // Fused multiply-adds: one rounding each, the same bits with or without FMA hardware.
            x = c[t][0].mul_add(v, x);
            y = c[t][1].mul_add(v, y);
            z = c[t][2].mul_add(v, z);
            let w = v * sc[t];
            q = w.mul_add(w, q);
        }
        (gx[j], gy[j], gz[j], rr[j]) = (x, y, z, q);
    }
}

impl<'a> Source<'a> {
    fn new(photo: &'a Photo, ambient: Option<&'a Photo>, intensity: Vec3, config: &SolveConfig) -> Self {
        let full = photo.samples().full_scale();
        // Linear photos keep stored units until this scale; tables and the sRGB curve give [0, 1].
        let unit = if photo.transfer() == Transfer::Linear { 1.0 / full } else { 1.0 };
        let luma = Vec3::from(LUMA).dot(intensity);
        Source {
            raw: Raw::of(photo),
            ambient: ambient.map(Raw::of),
            scale: (Vec3::splat(unit) / intensity).into(),
            gray_scale: unit / luma,
            saturated_at: config.saturation * full,
        }
    }

    /// Grey readings `r` and saturation flags of the pixels starting at `p`.
    #[inline(always)]
    fn load_gray(&self, p: usize, lin: Linearise, r: &mut [f32], sat: &mut [u8]) {
        let n = r.len();
        match (self.raw, self.ambient) {
            (Raw::U8(v), a) => gray::<u8>(&v[p..p + n], a.map(|a| &as_u8(a)[p..p + n]), lin, self, r, sat),
            (Raw::U16(v), a) => gray::<u16>(&v[p..p + n], a.map(|a| &as_u16(a)[p..p + n]), lin, self, r, sat),
            (Raw::F32(v), a) => gray::<f32>(&v[p..p + n], a.map(|a| &as_f32(a)[p..p + n]), lin, self, r, sat),
        }
    }

    /// RGB readings (per channel and luminance-combined) of the pixels starting at `p`.
    fn load_rgb(&self, p: usize, lin: Linearise, r: &mut [f32], rgb: &mut [[f32; 3]], sat: &mut [u8]) {
        let range = 3 * p..3 * (p + r.len());
        match (self.raw, self.ambient) {
            (Raw::U8(v), a) => color::<u8>(&v[range.clone()], a.map(|a| &as_u8(a)[range]), lin, self, r, rgb, sat),
            (Raw::U16(v), a) => color::<u16>(&v[range.clone()], a.map(|a| &as_u16(a)[range]), lin, self, r, rgb, sat),
            (Raw::F32(v), a) => color::<f32>(&v[range.clone()], a.map(|a| &as_f32(a)[range]), lin, self, r, rgb, sat),
        }
    }
}

fn as_u8(r: Raw<'_>) -> &[u8] {
    match r {
        Raw::U8(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}
fn as_u16(r: Raw<'_>) -> &[u16] {
    match r {
        Raw::U16(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}
fn as_f32(r: Raw<'_>) -> &[f32] {
    match r {
        Raw::F32(v) => v,
        _ => unreachable!("the stack checks that all photos and the ambient frame share one format"),
    }
}

/// Linear, ambient-subtracted, intensity-divided value of one stored sample.
#[inline]
fn reading<T: Sample>(v: T, ambient: Option<T>, lin: Linearise) -> f32 {
    let x = lin.apply(v.value());
    match ambient {
        Some(a) => x - lin.apply(a.value()),
        None => x,
    }
}

#[inline(always)]
fn gray<T: Sample>(v: &[T], amb: Option<&[T]>, lin: Linearise, src: &Source, r: &mut [f32], sat: &mut [u8]) {
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

fn color<T: Sample>(
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

/// The fused all-lights kernel (AVX2 + FMA) for linear grey photos without an ambient frame.
///
/// Per step of [`STEP`] pixels (two 8-lane vectors, so each light's broadcast coefficients serve
/// 16 pixels) it loads every light's samples, converts them (exactly) to f32, accumulates `g` and
/// `sum w^2` in registers, normalises, and writes interleaved normals, albedo and confidence: one
/// pass over the samples and one over the outputs, no scratch round trips. The arithmetic is the
/// scalar path's operation for operation (`mul_add` is `vfmadd`, `sqrt` and `/` are exactly
/// rounded, `max` keeps the non-NaN operand as `f32::max` does), so both give the same bits; the
/// unit tests compare them bitwise.
#[cfg(target_arch = "x86_64")]
mod fused {
    use std::arch::x86_64::*;

    use glam::Vec3;

    use super::{MIN_ALBEDO, RESIDUAL_SCALE, Raw, as_f32, as_u8, as_u16};

    /// Pixels per step.
    pub(super) const STEP: usize = 16;

    /// A stored sample type the kernel loads eight at a time.
    pub(super) trait Lanes: Copy + Sync {
        /// The samples of a photo of this type.
        fn of(raw: Raw<'_>) -> &[Self];
        /// The 8 samples at `p`, as f32 (exact for all three types).
        ///
        /// # Safety
        /// `p` must be valid for reading 8 samples, and the CPU must support AVX2.
        unsafe fn load8(p: *const Self) -> __m256;
    }

    impl Lanes for u8 {
        fn of(raw: Raw<'_>) -> &[Self] {
            as_u8(raw)
        }
        #[inline(always)]
        unsafe fn load8(p: *const Self) -> __m256 {
            // SAFETY: 8 readable bytes at `p` (unaligned load), AVX2 present (caller).
            unsafe { _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(p.cast()))) }
        }
    }

    impl Lanes for u16 {
        fn of(raw: Raw<'_>) -> &[Self] {
            as_u16(raw)
        }
        #[inline(always)]
        unsafe fn load8(p: *const Self) -> __m256 {
            // SAFETY: 16 readable bytes at `p` (unaligned load), AVX2 present (caller).
            unsafe { _mm256_cvtepi32_ps(_mm256_cvtepu16_epi32(_mm_loadu_si128(p.cast()))) }
        }
    }

    impl Lanes for f32 {
        fn of(raw: Raw<'_>) -> &[Self] {
            as_f32(raw)
        }
        #[inline(always)]
        unsafe fn load8(p: *const Self) -> __m256 {
            // SAFETY: 32 readable bytes at `p` (unaligned load), AVX (caller).
            unsafe { _mm256_loadu_ps(p) }
        }
    }

    /// What the kernel applies, per light and per pixel.
    pub(super) struct Kernel<'a> {
        /// Column of the pseudo-inverse per light (folded with the sample scale for least squares).
        pub coefs: &'a [[f32; 3]],
        /// `w_i = x_i * scales[i]` enters `sum w^2` (the readings, for least squares; ones, and
        /// not applied, for robust, whose `x_i` are the readings).
        pub scales: &'a [f32],
        /// Whether `scales` are all ones.
        pub unit_scales: bool,
        /// Least squares: `sum w^2` is multiplied by this at the end.
        pub rr_post: f32,
        /// Robust only: sample to reading scale per light (the readings are solved directly).
        pub gains: &'a [f32],
        /// `L^T L`: xx, xy, xz, yy, yz, zz.
        pub gram: [f32; 6],
        /// Robust only: stored values at or above this are saturated.
        pub saturated_at: f32,
        pub shadow_abs: f32,
        pub shadow_rel: f32,
        /// Robust only: whether a step whose pixels all drop readings, the same ones, is
        /// reported as [`Step::Subset`] (at most 12 lights, so the usable set fits in the lanes).
        pub group_subsets: bool,
    }

    /// What [`step`] did with its pixels.
    pub(super) enum Step {
        /// Solved from all lights and written; this many are invalid.
        Solved(u32),
        /// Not written: every pixel drops a reading and all have these usable lights.
        Subset(u32),
        /// Not written: some pixels drop readings, not all or not the same ones.
        Declined,
    }

    /// Solves the [`STEP`] pixels from `p` into the three output slices (each `STEP` long) and
    /// returns how many are invalid; with `ROBUST`, writes nothing when any pixel has a shadowed
    /// or saturated reading, and returns the pixels' usable lights when they all share them
    /// (`usable_bits`: `r_i >= threshold` and not saturated) and all drop some reading.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn step<T: Lanes, const ROBUST: bool>(
        kernel: &Kernel,
        rows: &[&[T]],
        p: usize,
        normals: &mut [Vec3],
        albedo: &mut [f32],
        confidence: &mut [f32],
    ) -> Step {
        assert!(normals.len() == STEP && albedo.len() == STEP && confidence.len() == STEP);
        let zero = _mm256_setzero_ps();
        let (mut gx, mut gy, mut gz, mut rr) = ([zero; 2], [zero; 2], [zero; 2], [zero; 2]);
        let (mut lo, mut hi) = ([_mm256_set1_ps(f32::INFINITY); 2], [_mm256_set1_ps(f32::NEG_INFINITY); 2]);
        let mut saturated = [zero; 2];
        let saturated_at = _mm256_set1_ps(kernel.saturated_at);
        let lights = rows.iter().zip(kernel.coefs).zip(kernel.scales).enumerate();
        for (i, ((row, c), &scale)) in lights {
            let row = &row[p..p + STEP];
            let (cx, cy, cz) = (_mm256_set1_ps(c[0]), _mm256_set1_ps(c[1]), _mm256_set1_ps(c[2]));
            let scale = _mm256_set1_ps(scale);
            for h in 0..2 {
                // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
                let mut v = unsafe { T::load8(row.as_ptr().add(8 * h)) };
                if ROBUST {
                    saturated[h] = _mm256_or_ps(saturated[h], _mm256_cmp_ps::<_CMP_GE_OQ>(v, saturated_at));
                    v = _mm256_mul_ps(v, _mm256_set1_ps(kernel.gains[i]));
                    // `min`/`max` return the second operand when one is NaN: NaN readings are
                    // skipped, as `f32::max` skips them in the scalar path.
                    lo[h] = _mm256_min_ps(v, lo[h]);
                    hi[h] = _mm256_max_ps(v, hi[h]);
                }
                gx[h] = _mm256_fmadd_ps(cx, v, gx[h]);
                gy[h] = _mm256_fmadd_ps(cy, v, gy[h]);
                gz[h] = _mm256_fmadd_ps(cz, v, gz[h]);
                // Unit scales: `v * 1 == v` bit for bit, so the product is skipped.
                let w = if kernel.unit_scales { v } else { _mm256_mul_ps(v, scale) };
                rr[h] = _mm256_fmadd_ps(w, w, rr[h]);
            }
        }
        if !ROBUST {
            let post = _mm256_set1_ps(kernel.rr_post);
            rr = rr.map(|q| _mm256_mul_ps(q, post));
        }
        if ROBUST {
            // Some reading is below `max(abs, rel * brightest)` iff the dimmest one is.
            let (abs, rel) = (_mm256_set1_ps(kernel.shadow_abs), _mm256_set1_ps(kernel.shadow_rel));
            let mut dropped = 0;
            let mut threshold = [zero; 2];
            for h in 0..2 {
                threshold[h] = _mm256_max_ps(_mm256_mul_ps(rel, hi[h]), abs);
                let shadowed = _mm256_cmp_ps::<_CMP_LT_OQ>(lo[h], threshold[h]);
                dropped |= _mm256_movemask_ps(_mm256_or_ps(shadowed, saturated[h])) << (8 * h);
            }
            if dropped == 0xffff && kernel.group_subsets {
                return common_usable(kernel, rows, p, threshold).map_or(Step::Declined, Step::Subset);
            }
            if dropped != 0 {
                return Step::Declined;
            }
        }
        let m = kernel.gram.map(|v| _mm256_set1_ps(v));
        let one = _mm256_set1_ps(1.0);
        let excess_scale = _mm256_set1_ps(1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
        let mut invalid = 0;
        for h in 0..2 {
            let (x, y, z, rr) = (gx[h], gy[h], gz[h], rr[h]);
            let mul = |a, b| _mm256_mul_ps(a, b);
            let add = |a, b| _mm256_add_ps(a, b);
            let len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
            let ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(len, _mm256_set1_ps(MIN_ALBEDO)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(len, _mm256_set1_ps(f32::INFINITY)),
            );
            invalid += 8 - _mm256_movemask_ps(ok).count_ones();
            let inv = _mm256_div_ps(one, len);
            // `gram_form` and `residual_factor`, in the same order.
            let diagonal = add(add(mul(mul(m[0], x), x), mul(mul(m[3], y), y)), mul(mul(m[5], z), z));
            let cross = add(add(mul(mul(m[1], x), y), mul(mul(m[2], x), z)), mul(mul(m[4], y), z));
            let fitted = add(diagonal, mul(_mm256_set1_ps(2.0), cross));
            let excess = mul(_mm256_max_ps(_mm256_sub_ps(rr, fitted), zero), excess_scale);
            let factor =
                _mm256_blendv_ps(one, _mm256_div_ps(rr, add(rr, excess)), _mm256_cmp_ps::<_CMP_GT_OQ>(rr, zero));
            // Masks, not products with zero: a NaN must not leak into the outputs.
            let keep = |v| _mm256_and_ps(ok, v);
            let (nx, ny, nz) = (keep(mul(x, inv)), keep(mul(y, inv)), keep(mul(z, inv)));
            let [a, b, c] = interleave3(nx, ny, nz);
            // SAFETY: each output slice holds STEP = 16 texels (asserted); half `h` writes
            // texels 8h..8h+8 (24 floats of `Vec3 { x, y, z }`, `repr(C)`) and floats 8h..8h+8.
            unsafe {
                let n = normals.as_mut_ptr().cast::<f32>().add(24 * h);
                _mm256_storeu_ps(n, a);
                _mm256_storeu_ps(n.add(8), b);
                _mm256_storeu_ps(n.add(16), c);
                _mm256_storeu_ps(albedo.as_mut_ptr().add(8 * h), keep(len));
                _mm256_storeu_ps(confidence.as_mut_ptr().add(8 * h), keep(factor));
            }
        }
        Step::Solved(invalid)
    }

    /// The usable lights (bit `i` for light `i`) of the [`STEP`] pixels at `p` given their shadow
    /// thresholds, when all pixels have the same ones.
    // Kept out of line: inlined into `step`, its constants would crowd the main loop's registers.
    #[inline(never)]
    #[target_feature(enable = "avx2,fma")]
    fn common_usable<T: Lanes>(kernel: &Kernel, rows: &[&[T]], p: usize, threshold: [__m256; 2]) -> Option<u32> {
        let saturated_at = _mm256_set1_ps(kernel.saturated_at);
        let mut bits = [_mm256_setzero_si256(); 2];
        for (i, row) in rows.iter().enumerate() {
            let row = &row[p..p + STEP];
            let bit = _mm256_set1_epi32(1 << i);
            for h in 0..2 {
                // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
                let raw = unsafe { T::load8(row.as_ptr().add(8 * h)) };
                let saturated = _mm256_cmp_ps::<_CMP_GE_OQ>(raw, saturated_at);
                let v = _mm256_mul_ps(raw, _mm256_set1_ps(kernel.gains[i]));
                let ok = _mm256_andnot_ps(saturated, _mm256_cmp_ps::<_CMP_GE_OQ>(v, threshold[h]));
                bits[h] = _mm256_or_si256(bits[h], _mm256_and_si256(_mm256_castps_si256(ok), bit));
            }
        }
        let first = _mm256_cvtsi256_si32(bits[0]);
        let all = _mm256_set1_epi32(first);
        let same = _mm256_and_si256(_mm256_cmpeq_epi32(bits[0], all), _mm256_cmpeq_epi32(bits[1], all));
        (_mm256_movemask_epi8(same) == -1).then_some(first as u32)
    }

    /// What [`subset_step`] applies: one subset's pseudo-inverse and confidence terms.
    pub(super) struct SubsetKernel<'a> {
        /// The subset's usable lights, bit `i` for light `i`.
        pub bits: u32,
        /// Column of the subset's pseudo-inverse per usable light, in light order.
        pub cols: &'a [[f32; 3]],
        /// Sample to reading scale per light.
        pub gains: &'a [f32],
        /// The subset's `L^T L`: xx, xy, xz, yy, yz, zz.
        pub gram: [f32; 6],
        /// Lights-used and conditioning factors of the confidence.
        pub weight: f32,
    }

    /// Solves the [`STEP`] pixels from `p` with one subset of lights (what `finish_subset` does
    /// per pixel, in the same operations: `g = g + c * r` light by light without fusing,
    /// `n = g / |g|`, confidence `weight * residual_factor`), writes them and returns how many
    /// are invalid.
    #[inline(never)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn subset_step<T: Lanes>(
        kernel: &SubsetKernel,
        rows: &[&[T]],
        p: usize,
        normals: &mut [Vec3],
        albedo: &mut [f32],
        confidence: &mut [f32],
    ) -> u32 {
        assert!(normals.len() == STEP && albedo.len() == STEP && confidence.len() == STEP);
        let zero = _mm256_setzero_ps();
        let (mut gx, mut gy, mut gz, mut rr) = ([zero; 2], [zero; 2], [zero; 2], [zero; 2]);
        let used = rows.iter().enumerate().filter(|(i, _)| kernel.bits >> i & 1 == 1);
        for ((i, row), c) in used.zip(kernel.cols) {
            let row = &row[p..p + STEP];
            let (cx, cy, cz) = (_mm256_set1_ps(c[0]), _mm256_set1_ps(c[1]), _mm256_set1_ps(c[2]));
            let gain = _mm256_set1_ps(kernel.gains[i]);
            for h in 0..2 {
                // SAFETY: `row` holds STEP = 16 samples; AVX2 is enabled here.
                let v = _mm256_mul_ps(unsafe { T::load8(row.as_ptr().add(8 * h)) }, gain);
                gx[h] = _mm256_add_ps(gx[h], _mm256_mul_ps(cx, v));
                gy[h] = _mm256_add_ps(gy[h], _mm256_mul_ps(cy, v));
                gz[h] = _mm256_add_ps(gz[h], _mm256_mul_ps(cz, v));
                rr[h] = _mm256_add_ps(rr[h], _mm256_mul_ps(v, v));
            }
        }
        let m = kernel.gram.map(|v| _mm256_set1_ps(v));
        let one = _mm256_set1_ps(1.0);
        let excess_scale = _mm256_set1_ps(1.0 / (RESIDUAL_SCALE * RESIDUAL_SCALE));
        let weight = _mm256_set1_ps(kernel.weight);
        let mut invalid = 0;
        for h in 0..2 {
            let (x, y, z, rr) = (gx[h], gy[h], gz[h], rr[h]);
            let mul = |a, b| _mm256_mul_ps(a, b);
            let add = |a, b| _mm256_add_ps(a, b);
            // `Vec3::length`: `sqrt((x x + y y) + z z)`.
            let len = _mm256_sqrt_ps(add(add(mul(x, x), mul(y, y)), mul(z, z)));
            let ok = _mm256_and_ps(
                _mm256_cmp_ps::<_CMP_GT_OQ>(len, _mm256_set1_ps(MIN_ALBEDO)),
                _mm256_cmp_ps::<_CMP_LT_OQ>(len, _mm256_set1_ps(f32::INFINITY)),
            );
            invalid += 8 - _mm256_movemask_ps(ok).count_ones();
            // `gram_form` and `residual_factor`, in the same order.
            let diagonal = add(add(mul(mul(m[0], x), x), mul(mul(m[3], y), y)), mul(mul(m[5], z), z));
            let cross = add(add(mul(mul(m[1], x), y), mul(mul(m[2], x), z)), mul(mul(m[4], y), z));
            let fitted = add(diagonal, mul(_mm256_set1_ps(2.0), cross));
            let excess = mul(_mm256_max_ps(_mm256_sub_ps(rr, fitted), zero), excess_scale);
            let factor =
                _mm256_blendv_ps(one, _mm256_div_ps(rr, add(rr, excess)), _mm256_cmp_ps::<_CMP_GT_OQ>(rr, zero));
            let keep = |v| _mm256_and_ps(ok, v);
            let div = |a| _mm256_div_ps(a, len);
            let (nx, ny, nz) = (keep(div(x)), keep(div(y)), keep(div(z)));
            let [a, b, c] = interleave3(nx, ny, nz);
            // SAFETY: as in `step`: half `h` writes texels 8h..8h+8 of slices of STEP texels.
            unsafe {
                let n = normals.as_mut_ptr().cast::<f32>().add(24 * h);
                _mm256_storeu_ps(n, a);
                _mm256_storeu_ps(n.add(8), b);
                _mm256_storeu_ps(n.add(16), c);
                _mm256_storeu_ps(albedo.as_mut_ptr().add(8 * h), keep(len));
                _mm256_storeu_ps(confidence.as_mut_ptr().add(8 * h), keep(mul(weight, factor)));
            }
        }
        invalid
    }

    /// `x0 y0 z0 x1 y1 z1 ... x7 y7 z7` from the three vectors, as three vectors.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn interleave3(x: __m256, y: __m256, z: __m256) -> [__m256; 3] {
        // Per 128-bit lane (lane 1 likewise with 4..7):
        let xy = _mm256_shuffle_ps::<0b10_00_10_00>(x, y); // x0 x2 y0 y2
        let yz = _mm256_shuffle_ps::<0b11_01_11_01>(y, z); // y1 y3 z1 z3
        let zx = _mm256_shuffle_ps::<0b11_01_10_00>(z, x); // z0 z2 x1 x3
        let a = _mm256_shuffle_ps::<0b10_00_10_00>(xy, zx); // x0 y0 z0 x1
        let b = _mm256_shuffle_ps::<0b11_01_10_00>(yz, xy); // y1 z1 x2 y2
        let c = _mm256_shuffle_ps::<0b11_01_11_01>(zx, yz); // z2 x3 y3 z3
        [
            _mm256_permute2f128_ps::<0x20>(a, b), // x0 y0 z0 x1 y1 z1 x2 y2
            _mm256_permute2f128_ps::<0x30>(c, a), // z2 x3 y3 z3 x4 y4 z4 x5
            _mm256_permute2f128_ps::<0x31>(b, c), // y5 z5 x6 y6 z6 x7 y7 z7
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small grey stack with a few shadowed readings, and its rig (equal light intensities).
    fn inputs(samples: impl Fn(usize, usize) -> Samples) -> (PhotoStack, Rig) {
        inputs_with(samples, |_| 0.9)
    }

    fn inputs_with(samples: impl Fn(usize, usize) -> Samples, intensity: impl Fn(usize) -> f32) -> (PhotoStack, Rig) {
        let lights: Vec<crate::Light> = (0..8)
            .map(|i| {
                let a = i as f32 * 0.785 + 0.2;
                crate::Light {
                    direction: Vec3::new(0.7 * a.cos(), 0.7 * a.sin(), 0.714),
                    intensity: Vec3::splat(intensity(i)),
                    position: None,
                }
            })
            .collect();
        let photos = (0..8).map(|i| Photo::new(37, 11, Channels::Gray, samples(i, 37 * 11)).unwrap()).collect();
        let stack = PhotoStack::new(photos, (0..8).map(|i| i.to_string()).collect()).unwrap();
        (stack, Rig { lights, ..Rig::default() })
    }

    fn pseudo_random(i: usize, p: usize) -> u32 {
        let mut x = (i * 7919 + p * 104729) as u32 ^ 0x9e37_79b9;
        x ^= x << 13;
        x ^= x >> 17;
        x ^ (x << 5)
    }

    /// Samples of photo `i`: mostly mid-range, with zeros (dropped by the robust tests),
    /// saturated values and, for floats, NaN, infinities, negative and huge values.
    fn mixed_samples(kind: usize, i: usize, n: usize) -> Samples {
        let r = |p: usize| pseudo_random(i, p);
        match kind {
            0 => Samples::U16((0..n).map(|p| if r(p).is_multiple_of(9) { 0 } else { (r(p) % 60000) as u16 }).collect()),
            // Rarely dropped readings, so that most steps take the fused path in robust mode too.
            1 => Samples::U16(
                (0..n).map(|p| if r(p).is_multiple_of(97) { 65535 } else { 30000 + (r(p) % 20000) as u16 }).collect(),
            ),
            2 => Samples::U8(
                (0..n).map(|p| if r(p).is_multiple_of(53) { 0 } else { 100 + (r(p) % 150) as u8 }).collect(),
            ),
            // Readings dropped in runs of 16 pixels (one or two lights, some saturated, some
            // runs with too few lights left), so that whole fused steps share a subset.
            4 => Samples::U16((0..n).map(|p| block_shadowed(i, p, 30000 + (r(p) % 20000) as u16, 65535)).collect()),
            // The same in floats, with a rare NaN breaking a run's common subset.
            5 => Samples::F32(
                (0..n)
                    .map(|p| {
                        if r(p).is_multiple_of(89) {
                            f32::NAN
                        } else {
                            block_shadowed(i, p, 0.3 + (r(p) % 50) as f32 * 0.01, 1.5)
                        }
                    })
                    .collect(),
            ),
            _ => Samples::F32(
                (0..n)
                    .map(|p| match r(p) % 61 {
                        0 => f32::NAN,
                        1 => f32::INFINITY,
                        2 => -0.3,
                        3 => 3e38,
                        4 => 0.0,
                        v => 0.3 + v as f32 * 0.01,
                    })
                    .collect(),
            ),
        }
    }

    /// Light `i`'s sample at pixel `p` for sample kinds 4 and 5: `lit`, or zero or `saturated`
    /// depending on the run of 16 pixels.
    fn block_shadowed<T: From<u8>>(i: usize, p: usize, lit: T, saturated: T) -> T {
        let run = p / 16;
        match run % 6 {
            0 => lit,
            1 | 2 if (run + i) % 5 == 0 => T::from(0),
            3 if i == 2 => saturated,
            4 if i < 6 => T::from(0),
            _ => lit,
        }
    }

    /// Solves every band with the portable and (when the CPU has it) the AVX2 build, whose
    /// linear grey path is the fused kernel: same bits and the same counts.
    #[test]
    fn portable_and_vectorised_builds_agree_bitwise() {
        for kind in 0..6 {
            for (method, masked) in [(Method::LeastSquares, false), (Method::Robust, false), (Method::Robust, true)] {
                // Unequal intensities for the even kinds: per-light scales inside `sum r^2`.
                let intensity = |i: usize| if kind % 2 == 0 { 0.8 + 0.03 * i as f32 } else { 0.9 };
                let (mut stack, rig) = inputs_with(|i, n| mixed_samples(kind, i, n), intensity);
                if masked {
                    let mask = Grid::from_fn(37, 11, |x, y| (x * 7 + y * 3) % 29 != 0);
                    stack = stack.with_mask(mask).unwrap();
                }
                let config = SolveConfig { method, ..SolveConfig::default() };
                let lights = check_rig(&stack, &rig).unwrap();
                let plan = Plan::new(&stack, &rig, &config, lights, None).unwrap();
                let subsets = Subsets::new(&plan.lights, config.max_condition, config.cache_capacity);
                let n = stack.width() * stack.height();
                let band = BAND_ROWS * stack.width();
                let run = |vectorised: bool| {
                    let (mut normals, mut albedo, mut conf) = (vec![Vec3::ZERO; n], vec![0.0f32; n], vec![0.0f32; n]);
                    let mut scratch = Scratch::new(8, false);
                    let mut stats = SolveStats::empty(8);
                    for p0 in (0..n).step_by(band) {
                        let end = (p0 + band).min(n);
                        let out = Out {
                            normals: &mut normals[p0..end],
                            albedo: &mut albedo[p0..end],
                            confidence: &mut conf[p0..end],
                        };
                        stats = stats.merge(if vectorised {
                            plan.solve_band(p0, out, &mut scratch, &subsets)
                        } else {
                            plan.solve_band_portable(p0, out, &mut scratch, &subsets)
                        });
                    }
                    let bits: Vec<u32> =
                        normals.iter().flat_map(|v| v.to_array()).chain(albedo).chain(conf).map(f32::to_bits).collect();
                    (bits, stats)
                };
                let (a, b) = (run(false), run(true));
                let what = format!("samples {kind}, {method:?}, masked {masked}");
                assert_eq!(a, b, "{what}");
                assert!(a.1.invalid_count < n / 2, "{what}");
                assert!(a.1.lights_used[8] > n / 4, "{what}");
                assert!(a.0.iter().all(|v| f32::from_bits(*v).is_finite()), "{what}");
            }
        }
    }

    /// Pixels with dropped readings solved in groups by subset ([`Plan::finish_subsets`]) get the
    /// same bits as solved one at a time ([`Plan::finish_subset`]), in both builds, grey and RGB.
    #[test]
    fn grouped_subset_solves_match_per_pixel_ones_bitwise() {
        for (kind, rgb, masked) in [
            (0, false, false),
            (0, false, true),
            (1, true, false),
            (2, false, false),
            (3, false, false),
            (3, true, true),
        ] {
            let channels = if rgb { Channels::Rgb } else { Channels::Gray };
            let (w, h) = (37, 11);
            let per = if rgb { 3 } else { 1 };
            let photos =
                (0..8).map(|i| Photo::new(w, h, channels, mixed_samples(kind, i, per * w * h)).unwrap()).collect();
            let mut stack = PhotoStack::new(photos, (0..8).map(|i| i.to_string()).collect()).unwrap();
            let (_, rig) = inputs_with(|i, n| mixed_samples(kind, i, n), |i| 0.8 + 0.03 * i as f32);
            if masked {
                stack = stack.with_mask(Grid::from_fn(w, h, |x, y| (x * 7 + y * 3) % 29 != 0)).unwrap();
            }
            let config = SolveConfig::default();
            let lights = check_rig(&stack, &rig).unwrap();
            let mut plan = Plan::new(&stack, &rig, &config, lights, None).unwrap();
            assert!(plan.batch_subsets);
            let directions = plan.lights.clone();
            let subsets = Subsets::new(&directions, config.max_condition, config.cache_capacity);
            let n = w * h;
            let band = BAND_ROWS * w;
            let mut run = |grouped: bool, vectorised: bool| {
                plan.batch_subsets = grouped;
                let (mut normals, mut albedo, mut conf) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![0.0f32; n]);
                let mut scratch = Scratch::new(8, rgb);
                let mut stats = SolveStats::empty(8);
                for p0 in (0..n).step_by(band) {
                    let end = (p0 + band).min(n);
                    let out = Out {
                        normals: &mut normals[p0..end],
                        albedo: &mut albedo[p0..end],
                        confidence: &mut conf[p0..end],
                    };
                    stats = stats.merge(if vectorised {
                        plan.solve_band(p0, out, &mut scratch, &subsets)
                    } else {
                        plan.solve_band_portable(p0, out, &mut scratch, &subsets)
                    });
                }
                let bits: Vec<u32> =
                    normals.iter().chain(&albedo).flat_map(|v| v.to_array()).chain(conf).map(f32::to_bits).collect();
                (bits, stats)
            };
            for vectorised in [false, true] {
                let (a, b) = (run(false, vectorised), run(true, vectorised));
                let what = format!("samples {kind}, rgb {rgb}, masked {masked}, vectorised {vectorised}");
                assert_eq!(a, b, "{what}");
                let subset_pixels: usize = a.1.lights_used[..8].iter().sum();
                assert!(subset_pixels > n / 20 && a.1.lights_used[7] > 0, "{what}: {:?}", a.1);
            }
        }
    }

    #[test]
    fn non_finite_float_readings_give_invalid_pixels() {
        let floats = |i: usize, n: usize| {
            Samples::F32(
                (0..n)
                    .map(|p| match (p, i) {
                        (0, 3) => f32::NAN,
                        (1, _) => f32::INFINITY,
                        _ => 0.4,
                    })
                    .collect(),
            )
        };
        for method in [Method::LeastSquares, Method::Robust] {
            let (stack, rig) = inputs(floats);
            let sol = solve(&stack, &rig, &SolveConfig { method, ..SolveConfig::default() }, &no_progress).unwrap();
            let finite = sol.normals.as_slice().iter().all(|v| v.is_finite())
                && sol.albedo.as_gray().unwrap().as_slice().iter().all(|v| v.is_finite());
            assert!(finite && sol.confidence.as_slice().iter().all(|c| c.is_finite()), "{method:?}");
            assert_eq!(sol.normals.get(1, 0), Vec3::ZERO);
            assert!(sol.normals.get(2, 0) != Vec3::ZERO);
        }
    }

    #[test]
    fn subset_solve_is_the_pseudo_inverse() {
        let lights = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.6, 0.0, 0.8)];
        let s = SubsetSolve::new(&lights, 0b0111, 100.0);
        assert!(s.usable && (s.condition - 1.0).abs() < 1e-12);
        assert_eq!(s.cols, vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        // Two lights cannot determine a normal; nor can three coplanar ones.
        assert!(!SubsetSolve::new(&lights, 0b0011, 100.0).usable);
        assert!(!SubsetSolve::new(&lights, 0b1101, 100.0).usable);
    }
}
