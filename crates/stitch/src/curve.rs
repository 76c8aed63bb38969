//! Random curves in place of the straight boundaries of the nearest-point partition (Haro et al.
//! 2001, section 4.2: "instead of performing the multi-resolution splining along a straight line
//! along the boundary, we compute a random curve through the boundary instead", figure 5b).
//!
//! # Construction: a warped Voronoi diagram
//! Let `p_i` be the seed points and `W` a smooth random warp of the map. A texel `x` goes to the
//! cell of the point nearest to it *after warping both*:
//!
//! ```text
//! cell(x) = argmin_i |W(x) - W(p_i)|        (ties: lowest region, then lowest point index)
//! ```
//!
//! so cell `i` is `W⁻¹(C_i ∩ R)`, where `C_i` is the Voronoi cell of the warped point `W(p_i)`
//! and `R` the map's rectangle. Why this is a valid partition:
//!
//! 1. `W = W_K ∘ ... ∘ W_1` is a composition of layers `W_k(x) = x + d_k(x)`, one per noise
//!    octave, each with a displacement `d_k` whose Lipschitz constant `L_k` is below 1 on `R`.
//!    Then `|W_k(x) - W_k(y)| >= (1 - L_k) |x - y|` (`R` is convex): each layer is injective
//!    on `R`.
//! 2. **Each layer maps `R` onto `R`**: the x-displacement fades to 0 on the left and right
//!    edges, the y-displacement on the top and bottom edges (smooth ramps). Each edge then maps
//!    into its own line with corners fixed, and by injectivity onto itself: `W_k(∂R) = ∂R`. By
//!    invariance of domain `W_k(int R)` is open, and its boundary lies in `W_k(∂R) = ∂R`, so it
//!    is open and closed in `R² \ ∂R`; being bounded and connected it is `int R`. So `W_k` is a
//!    homeomorphism of `R`, and so is the composition `W`.
//! 3. `C_i ∩ R` is convex: connected, without holes, and every component of its complement in `R`
//!    touches the edge of `R`. A homeomorphism keeps all three, so each cell is one piece without
//!    holes and no cell is an island inside another. It contains its own point: `W(p_i)` is at
//!    distance 0 from its own site. Boundaries are images of straight segments under a
//!    homeomorphism: simple curves that cannot cross themselves or each other.
//!
//! Composing layers rather than summing octaves into one displacement lets every octave use the
//! whole slope budget (a sum must share it), so the curves wiggle at every scale. The layers'
//! bound is computed from the noise's construction ([`CurveParams::slope_bound`]) and refused
//! unless below 1. Sampling at texel centres can still cut a thin sliver of a cell
//! (near an acute corner) from the rest diagonally; such stray pieces (a handful of texels, if
//! any) are given to the neighbour they share most edges with, so on the texel grid too every
//! cell is one 4-connected piece holding its point.
//!
//! Only the component of `d` normal to an edge fades near that edge: a boundary meeting the top
//! edge still wiggles sideways right up to it.
//!
//! # The noise
//! Layer `k` displaces by value noise: smoothly interpolated (cubic fade) random lattice values
//! in `[-1, 1]`, one noise per component, lattice spacing `wavelength / 2^k`, amplitude
//! `amplitude * w_k` with `w_k = roughness^k / sum_j roughness^j`, so the layers' displacements
//! add up to at most `amplitude` texels. Lattice values come from a hash of `(seed, octave,
//! component, lattice cell)`: no RNG state, the same bits on any thread count.
//!
//! # Cost
//! A texel whose two nearest warped sites differ in distance by more than `2 * amplitude` cannot
//! change cell under a total displacement of at most `amplitude`; a block of texels whose warped
//! centre is clear of every boundary by more than the warp's Lipschitz bound times the block's
//! radius cannot either. So whole blocks are filled at once and the noise is evaluated per texel
//! only in a thin band along the warped boundaries. The result is identical to evaluating the
//! warp at every texel (tested). 4096x2048 with 7 regions: 56 ms straight, 125-155 ms with
//! amplitudes 32-128 (release, 2 busy cores).
//!
//! The island repair works on runs of equal labels (a few per row), so it costs one scan.
//!
//! # Length
//! Over 600 lines (about 575 without its tests) on purpose: the warp and its noise, the warped
//! cells with their block and band shortcuts, and the full-warp reference those shortcuts are
//! tested against are one computation at two speeds, kept in one file so that each shortcut
//! reads beside the exact form it must reproduce; the island repair after them is short.

use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::partition::{self, SeedPoint};
use crate::{Error, Result};

/// The slope bound the automatic wavelength aims at: below 1 with room to spare, so every warp
/// layer is a homeomorphism (see the module docs).
pub const SLOPE_TARGET: f64 = 0.9;

/// Largest derivative of the cubic fade `3t^2 - 2t^3` (at `t = 1/2`), used both to interpolate
/// the noise and as the edge ramp. Its derivative vanishes at both ends, so the noise is C1.
const FADE_SLOPE: f64 = 1.5;

/// A layer's slope bound per unit of `amplitude_k / spacing_k`.
///
/// With `a = amplitude_k / sqrt(2)` per component and lattice values in `[-1, 1]`, each entry of
/// the noise Jacobian is at most `2 * 1.5 / spacing` (a lattice step of at most 2 times the fade
/// slope), so its norm is at most `6 a / spacing`; the edge ramps (width `spacing / 2`) multiply
/// a component of size at most `a` and add at most `1.5 a / (spacing / 2) = 3 a / spacing`.
const LAYER_SLOPE: f64 = (2.0 * 2.0 * FADE_SLOPE + 2.0 * FADE_SLOPE) / std::f64::consts::SQRT_2;

/// Parameters of the random boundary curves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveParams {
    /// Largest displacement of a boundary, in texels; 0 gives straight boundaries.
    pub amplitude: f64,
    /// Lattice spacing of the coarsest noise octave in texels; `None` picks the smallest that
    /// keeps [`CurveParams::slope_bound`] at [`SLOPE_TARGET`].
    pub wavelength: Option<f64>,
    /// Number of noise octaves (1 to 16); each halves the lattice spacing.
    pub octaves: u32,
    /// Amplitude ratio of successive octaves, in `(0, 1]`: higher is rougher (above 0.5 the
    /// finest octave sets the slope, so the automatic wavelength grows).
    pub roughness: f64,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for CurveParams {
    fn default() -> Self {
        CurveParams::new(0.0, 0)
    }
}

impl CurveParams {
    /// Curves of the given amplitude (texels) and seed: 3 octaves, roughness 0.5, automatic
    /// wavelength (about 4 x the amplitude).
    pub fn new(amplitude: f64, seed: u64) -> Self {
        CurveParams { amplitude, wavelength: None, octaves: 3, roughness: 0.5, seed }
    }

    /// Straight boundaries (`--straight`): amplitude 0.
    pub fn straight() -> Self {
        CurveParams::new(0.0, 0)
    }

    /// The octave weights `roughness^k`, normalised to sum to 1.
    fn weights(&self) -> Vec<f64> {
        let raw: Vec<f64> = (0..self.octaves).map(|k| self.roughness.powi(k as i32)).collect();
        let sum: f64 = raw.iter().sum();
        raw.iter().map(|w| w / sum).collect()
    }

    /// `max_k w_k 2^k`: the steepest layer relative to the coarsest lattice spacing.
    fn steepness(&self) -> f64 {
        self.weights().iter().enumerate().map(|(k, w)| w * f64::powi(2.0, k as i32)).fold(0.0, f64::max)
    }

    /// The lattice spacing of the coarsest octave, in texels.
    pub fn base_wavelength(&self) -> f64 {
        self.wavelength.unwrap_or_else(|| (LAYER_SLOPE * self.steepness() * self.amplitude / SLOPE_TARGET).max(1.0))
    }

    /// An upper bound of every warp layer's Lipschitz constant (its largest slope); below 1 each
    /// layer is a homeomorphism of the map and the curved partition is valid.
    pub fn slope_bound(&self) -> f64 {
        LAYER_SLOPE * self.steepness() * self.amplitude / self.base_wavelength()
    }

    /// Checks the parameters.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a negative or non-finite amplitude, a non-positive
    /// wavelength, octaves outside 1..=16, roughness outside `(0, 1]`, or a slope bound of 1 or
    /// more (the warp could fold the map: the message gives the smallest wavelength that works).
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(format!("curve: {m}")));
        if !(self.amplitude.is_finite() && self.amplitude >= 0.0) {
            return bad(format!("amplitude {} must be finite and >= 0 texels", self.amplitude));
        }
        if let Some(w) = self.wavelength
            && !(w.is_finite() && w > 0.0)
        {
            return bad(format!("wavelength {w} must be finite and > 0 texels"));
        }
        if !(1..=16).contains(&self.octaves) {
            return bad(format!("octaves {} must be between 1 and 16", self.octaves));
        }
        if !(self.roughness > 0.0 && self.roughness <= 1.0) {
            return bad(format!("roughness {} must be in (0, 1]", self.roughness));
        }
        let slope = self.slope_bound();
        if slope >= 1.0 {
            let needed = LAYER_SLOPE * self.steepness() * self.amplitude;
            return bad(format!(
                "amplitude {} texels with wavelength {} could fold the map (slope bound {slope:.3} >= 1): \
                 use a wavelength above {needed:.1} texels or a smaller amplitude",
                self.amplitude,
                self.base_wavelength()
            ));
        }
        Ok(())
    }
}

/// One noise octave of one displacement component.
#[derive(Clone, Copy, Debug)]
struct Octave {
    /// `1 / lattice spacing`.
    frequency: f64,
    key: u64,
    offset: [f64; 2],
}

/// One warp layer `x -> x + d_k(x)`: an octave per component.
#[derive(Clone, Copy, Debug)]
struct Layer {
    /// Per-component scale: `amplitude_k / sqrt(2)`, so `|d_k| <= amplitude_k`.
    scale: f64,
    /// `1 / width of the edge ramps in texels`.
    ramp_inverse: f64,
    noise: [Octave; 2],
}

/// The smooth random warp `W` of a `width x height` map: layers applied coarsest first (see the
/// module docs).
#[derive(Clone, Debug)]
pub struct Warp {
    layers: Vec<Layer>,
    amplitude: f64,
    /// Lipschitz bound of the whole warp: `prod_k (1 + L_k)`.
    lipschitz: f64,
    width: f64,
    height: f64,
}

impl Warp {
    /// The warp of a `width x height` map.
    ///
    /// # Errors
    /// As [`CurveParams::validate`].
    pub fn new(params: &CurveParams, width: usize, height: usize) -> Result<Warp> {
        params.validate()?;
        let wavelength = params.base_wavelength();
        let layers = if params.amplitude == 0.0 {
            Vec::new()
        } else {
            params.weights().iter().enumerate().map(|(k, &w)| layer(params, k, w, wavelength)).collect()
        };
        let lipschitz = layers
            .iter()
            .map(|l| 1.0 + LAYER_SLOPE * l.scale * std::f64::consts::SQRT_2 * l.ramp_inverse / 2.0)
            .product();
        Ok(Warp { layers, amplitude: params.amplitude, lipschitz, width: width as f64, height: height as f64 })
    }

    /// Number of layers (octaves; none for amplitude 0).
    pub fn layer_count(&self) -> usize {
        self.layers.len()
    }

    /// The displacement `d_k(x, y)` of layer `k` in texels at texel coordinates `(x, y)` (texel
    /// centres are integers, the map spans `[-0.5, width - 0.5] x [-0.5, height - 0.5]`).
    ///
    /// Panics when `k >= layer_count()`.
    pub fn layer_displacement(&self, k: usize, x: f64, y: f64) -> [f64; 2] {
        self.cached_layer_displacement(k, x, y, &mut [CellCache::EMPTY; 2])
    }

    fn cached_layer_displacement(&self, k: usize, x: f64, y: f64, cache: &mut [CellCache; 2]) -> [f64; 2] {
        let l = &self.layers[k];
        let ramp_x = smoothstep((x + 0.5).min(self.width - 0.5 - x) * l.ramp_inverse);
        let ramp_y = smoothstep((y + 0.5).min(self.height - 0.5 - y) * l.ramp_inverse);
        [
            l.scale * ramp_x * value_noise(&l.noise[0], x, y, &mut cache[0]),
            l.scale * ramp_y * value_noise(&l.noise[1], x, y, &mut cache[1]),
        ]
    }

    /// `W(x, y)`: every layer in turn.
    pub fn apply(&self, x: f64, y: f64) -> [f64; 2] {
        self.apply_cached(x, y, &mut self.cache())
    }

    /// An empty cache for [`Warp::apply_cached`].
    pub fn cache(&self) -> WarpCache {
        WarpCache(vec![[CellCache::EMPTY; 2]; self.layers.len()])
    }

    /// [`Warp::apply`] reusing lattice values between nearby calls (same result).
    pub fn apply_cached(&self, x: f64, y: f64, cache: &mut WarpCache) -> [f64; 2] {
        (0..self.layers.len()).fold([x, y], |[x, y], k| {
            let [dx, dy] = self.cached_layer_displacement(k, x, y, &mut cache.0[k]);
            [x + dx, y + dy]
        })
    }

    /// The largest total displacement `|W(x) - x|`, in texels.
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// A bound of the warp's Lipschitz constant: `|W(x) - W(y)| <= lipschitz * |x - y|`.
    pub fn lipschitz(&self) -> f64 {
        self.lipschitz
    }
}

/// Layer `k` of weight `w`.
fn layer(params: &CurveParams, k: usize, w: f64, wavelength: f64) -> Layer {
    let spacing = wavelength / f64::powi(2.0, k as i32);
    Layer {
        scale: params.amplitude * w / std::f64::consts::SQRT_2,
        ramp_inverse: 2.0 / spacing,
        noise: [0u64, 1].map(|component| octave(params.seed, component, k, spacing)),
    }
}

/// Octave `k` of a component: its spacing, hash key and a random lattice offset.
fn octave(seed: u64, component: u64, k: usize, spacing: f64) -> Octave {
    let key = mix(seed ^ mix(0x5EED_0000 + 2 * k as u64 + component));
    let offset = [unit(mix(key ^ 1)) * 1024.0, unit(mix(key ^ 2)) * 1024.0];
    Octave { frequency: 1.0 / spacing, key, offset }
}

/// Value noise of one octave: lattice values in `[-1, 1]` blended with the cubic fade. `cache`
/// holds the last lattice cell's corner values (neighbouring texels mostly share a cell), so
/// the result is the same bits with or without it.
fn value_noise(o: &Octave, x: f64, y: f64, cache: &mut CellCache) -> f64 {
    let (u, v) = (x * o.frequency + o.offset[0], y * o.frequency + o.offset[1]);
    let (i, j) = (u.floor(), v.floor());
    let (fx, fy) = (smoothstep(u - i), smoothstep(v - j));
    let (i, j) = (i as i64, j as i64);
    if cache.cell != (i, j) {
        let c =
            [lattice(o.key, i, j), lattice(o.key, i + 1, j), lattice(o.key, i, j + 1), lattice(o.key, i + 1, j + 1)];
        *cache = CellCache { cell: (i, j), corners: c };
    }
    let c = cache.corners;
    lerp(lerp(c[0], c[1], fx), lerp(c[2], c[3], fx), fy)
}

/// The corner values of the last lattice cell a noise was evaluated in.
#[derive(Clone, Copy, Debug)]
struct CellCache {
    cell: (i64, i64),
    corners: [f64; 4],
}

impl CellCache {
    const EMPTY: CellCache = CellCache { cell: (i64::MIN, i64::MIN), corners: [0.0; 4] };
}

/// Lattice caches for every layer and component of a [`Warp`] (one per thread or row).
#[derive(Clone, Debug)]
pub struct WarpCache(Vec<[CellCache; 2]>);

/// The random value in `[-1, 1]` at lattice point `(i, j)`.
fn lattice(key: u64, i: i64, j: i64) -> f64 {
    let h =
        mix(key ^ mix((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)));
    2.0 * unit(h) - 1.0
}

/// A 64-bit mixing function (the SplitMix64 finaliser): every input bit affects every output bit.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The top 53 bits of `h` as a float in `[0, 1)`.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

/// `3t^2 - 2t^3` of `t` clamped to `[0, 1]`.
fn smoothstep(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The curved cell map: index of the seed point whose cell each texel falls in (see the module
/// docs). Amplitude 0 gives exactly [`partition::nearest_cells`].
///
/// # Errors
/// As [`CurveParams::validate`] and [`partition::check_seeds`].
pub fn curved_cells(width: usize, height: usize, seeds: &[SeedPoint], params: &CurveParams) -> Result<Grid<u16>> {
    let regions = seeds.iter().map(|s| s.region + 1).max().unwrap_or(0);
    partition::check_seeds(width, height, regions, seeds)?;
    let mut cells = unrepaired_cells(width, height, seeds, params)?;
    repair_islands(&mut cells, seeds);
    Ok(cells)
}

/// The curved cells before the island repair, blocks decided at once where possible: a block
/// within `r` of its centre `c` is uniform when
/// * the two nearest warped sites of `c` differ in distance by more than `2 (amplitude + r)`:
///   every texel is then more than `2 * amplitude` closer to the same site (no noise needed), or
/// * the two nearest sites of `W(c)` differ by more than `2 Λ r`, with `Λ` the warp's Lipschitz
///   bound: every `W(x)` lies within `Λ r` of `W(c)`, so every texel has the same nearest site.
fn unrepaired_cells(width: usize, height: usize, seeds: &[SeedPoint], params: &CurveParams) -> Result<Grid<u16>> {
    let warp = Warp::new(params, width, height)?;
    let sites = Sites::new(seeds, &warp);
    let uniform = |cx: f64, cy: f64, r: f64, cache: &mut WarpCache| {
        let (best, d1, d2) = sites.two_nearest([cx, cy]);
        if d2.sqrt() - d1.sqrt() > 2.0 * (warp.amplitude() + r) + 1e-6 {
            return Some(best);
        }
        let (best, d1, d2) = sites.two_nearest(warp.apply_cached(cx, cy, cache));
        (d2.sqrt() - d1.sqrt() > 2.0 * warp.lipschitz() * r + 1e-6).then_some(best)
    };
    let texel = |x: usize, y: usize, cache: &mut WarpCache| sites.cell(x as f64, y as f64, &warp, true, cache);
    Ok(partition::fill_blocks(width, height, || warp.cache(), uniform, texel))
}

/// The warped seed points in tie-break order.
pub(crate) struct Sites {
    /// `(point index, W(p))` sorted by `(region, point index)`.
    warped: Vec<(u16, [f64; 2])>,
}

impl Sites {
    fn new(seeds: &[SeedPoint], warp: &Warp) -> Sites {
        let warped = partition::tie_order(seeds)
            .into_iter()
            .map(|i| (i as u16, warp.apply(f64::from(seeds[i].x), f64::from(seeds[i].y))))
            .collect();
        Sites { warped }
    }

    /// The cell of texel `(x, y)`. With `shortcut`, texels far from every boundary skip the noise
    /// (same result, see the module docs).
    fn cell(&self, x: f64, y: f64, warp: &Warp, shortcut: bool, cache: &mut WarpCache) -> u16 {
        if shortcut {
            let (best, d1, d2) = self.two_nearest([x, y]);
            if d2.sqrt() - d1.sqrt() > 2.0 * warp.amplitude() + 1e-6 {
                return best;
            }
        }
        self.two_nearest(warp.apply_cached(x, y, cache)).0
    }

    /// The nearest site to `p` and the squared distances to the nearest and second nearest.
    fn two_nearest(&self, p: [f64; 2]) -> (u16, f64, f64) {
        partition::two_nearest(&self.warped, p)
    }
}

/// The curved cell map before the island repair, either as [`curved_cells`] computes it
/// (`fast`: blocks and band shortcut) or with the full warp evaluated at every texel: the
/// reference the shortcuts are tested against.
#[doc(hidden)]
pub fn curved_cells_unrepaired_reference(
    width: usize,
    height: usize,
    seeds: &[SeedPoint],
    params: &CurveParams,
    fast: bool,
) -> Result<Grid<u16>> {
    if fast {
        return unrepaired_cells(width, height, seeds, params);
    }
    let warp = Warp::new(params, width, height)?;
    let sites = Sites::new(seeds, &warp);
    Ok(Grid::from_fn(width, height, |x, y| sites.cell(x as f64, y as f64, &warp, false, &mut warp.cache())))
}

/// A run of equal labels in one row: texels `x0..x1` of row `y`.
#[derive(Clone, Copy, Debug)]
struct Run {
    y: usize,
    x0: usize,
    x1: usize,
    label: u16,
}

/// The runs of every row, rows in order.
fn runs(labels: &Grid<u16>) -> Vec<Vec<Run>> {
    (0..labels.height()).into_par_iter().map(|y| row_runs(labels.row(y), y)).collect()
}

fn row_runs(row: &[u16], y: usize) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for (x, &label) in row.iter().enumerate() {
        match out.last_mut() {
            Some(r) if r.label == label => r.x1 = x + 1,
            _ => out.push(Run { y, x0: x, x1: x + 1, label }),
        }
    }
    out
}

/// Calls `f(upper, lower)` for every pair of runs in consecutive rows whose columns overlap
/// (so they share `overlap > 0` edges), with their indices in the flattened run list.
fn for_each_vertical_contact(rows: &[Vec<Run>], mut f: impl FnMut(usize, usize, usize)) {
    let mut start = 0;
    for pair in rows.windows(2) {
        let (up, down) = (&pair[0], &pair[1]);
        let (mut i, mut j) = (0, 0);
        while i < up.len() && j < down.len() {
            let overlap = up[i].x1.min(down[j].x1).saturating_sub(up[i].x0.max(down[j].x0));
            if overlap > 0 {
                f(start + i, start + up.len() + j, overlap);
            }
            if up[i].x1 < down[j].x1 { i += 1 } else { j += 1 }
        }
        start += up.len();
    }
}

/// Union-find root with path halving.
fn find(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}

/// 4-connected components of runs: the root run of each run's component.
fn run_components(rows: &[Vec<Run>]) -> Vec<usize> {
    let flat: Vec<Run> = rows.iter().flatten().copied().collect();
    let mut parent: Vec<usize> = (0..flat.len()).collect();
    for_each_vertical_contact(rows, |a, b, _| {
        if flat[a].label == flat[b].label {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            parent[ra.max(rb)] = ra.min(rb);
        }
    });
    (0..flat.len()).map(|a| find(&mut parent, a)).collect()
}

/// Gives every piece of a cell that does not hold the cell's point to the neighbouring cell it
/// shares most edges with (ties to the lowest cell index), until each cell is one piece.
/// Works on runs of equal labels, so its cost is a scan of the map plus a few runs per row.
fn repair_islands(cells: &mut Grid<u16>, seeds: &[SeedPoint]) {
    // Each pass merges every stray piece into a neighbour, so the piece count falls; the cap only
    // guards against a bug.
    for _ in 0..64 {
        let rows = runs(cells);
        let flat: Vec<Run> = rows.iter().flatten().copied().collect();
        let root = run_components(&rows);
        let mut keep = vec![false; flat.len()];
        for (i, s) in seeds.iter().enumerate() {
            let (x, y) = (s.x as usize, s.y as usize);
            if usize::from(*cells.get(x, y)) == i {
                let r =
                    rows[..y].iter().map(Vec::len).sum::<usize>() + rows[y].iter().position(|r| r.x1 > x).unwrap_or(0);
                keep[root[r]] = true;
            }
        }
        if (0..flat.len()).all(|a| keep[root[a]]) {
            return;
        }
        let target = island_targets(&rows, &flat, &root, &keep);
        let w = cells.width();
        for (a, run) in flat.iter().enumerate() {
            if let Some(&to) = target.get(&root[a]) {
                cells.as_mut_slice()[run.y * w + run.x0..run.y * w + run.x1].fill(to);
            }
        }
    }
}

/// For every stray piece (by root run), the label it shares most edges with (ties to the lowest).
fn island_targets(
    rows: &[Vec<Run>],
    flat: &[Run],
    root: &[usize],
    keep: &[bool],
) -> std::collections::HashMap<usize, u16> {
    let mut counts: std::collections::BTreeMap<(usize, u16), usize> = std::collections::BTreeMap::new();
    let mut add = |a: usize, b: usize, n: usize| {
        if root[a] != root[b] && !keep[root[a]] {
            *counts.entry((root[a], flat[b].label)).or_default() += n;
        }
    };
    let mut start = 0;
    for row in rows {
        for k in 1..row.len() {
            add(start + k - 1, start + k, 1);
            add(start + k, start + k - 1, 1);
        }
        start += row.len();
    }
    for_each_vertical_contact(rows, |a, b, n| {
        add(a, b, n);
        add(b, a, n);
    });
    let mut best: std::collections::HashMap<usize, (usize, u16)> = std::collections::HashMap::new();
    for (&(piece, label), &n) in &counts {
        let entry = best.entry(piece).or_insert((n, label));
        if n > entry.0 {
            *entry = (n, label);
        }
    }
    best.into_iter().map(|(piece, (_, label))| (piece, label)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(rows: &[&str]) -> Grid<u16> {
        let w = rows[0].len();
        let data = rows.iter().flat_map(|r| r.bytes().map(|b| u16::from(b - b'0'))).collect();
        Grid::from_vec(w, rows.len(), data).unwrap()
    }

    #[test]
    fn stray_pieces_go_to_the_neighbour_sharing_most_edges() {
        let mut cells = grid(&[
            "0000111", //
            "0102111", "0000111", "0022222", "2002222",
        ]);
        // Points: cell 0 at (0, 0), cell 1 at (6, 0), cell 2 at (4, 4).
        let seeds = [
            SeedPoint { region: 0, x: 0, y: 0 },
            SeedPoint { region: 1, x: 6, y: 0 },
            SeedPoint { region: 2, x: 4, y: 4 },
        ];
        repair_islands(&mut cells, &seeds);
        // The 1 inside the 0s joins 0; the lone 2 at (3, 1) borders 0 (3 edges) and 1 (1 edge):
        // it joins 0; the 2 at (0, 4) touches 0 only: it joins 0.
        assert_eq!(
            cells,
            grid(&[
                "0000111", //
                "0000111", "0000111", "0022222", "0002222",
            ])
        );
    }

    #[test]
    fn cached_and_uncached_warps_agree_bit_for_bit() {
        let params = CurveParams::new(20.0, 5);
        let warp = Warp::new(&params, 300, 200).unwrap();
        let mut cache = warp.cache();
        for y in (0..200).step_by(7) {
            for x in 0..300 {
                let (x, y) = (x as f64, y as f64);
                assert_eq!(warp.apply_cached(x, y, &mut cache), warp.apply(x, y));
            }
        }
    }
}
