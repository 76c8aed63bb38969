//! The whole stitching step: a layout and one exemplar per region in, one face normal map out
//! (Haro et al. 2001, section 4.2).
//!
//! 1. Partition the map by nearest seed point, boundaries warped into random curves
//!    ([`Partition::build`]); texels outside the layout's coverage mask get no region.
//! 2. Choose the spline's levels: `--levels`, or enblend's overlap rule on the narrowest region
//!    ([`spline::levels_for_overlap`] of its bounding box's short side), capped at
//!    [`MAX_AUTO_LEVELS`].
//! 3. Resample each exemplar to the map's scale ([`skinkit_maps::resample`]), so pores keep their
//!    physical size, and synthesise it over its region's bounding box grown by the spline's
//!    margin ([`spline::piece_rect`]), each region with its own seed, regions in parallel.
//! 4. Join the pieces with the N-way multiresolution spline ([`spline::blend`]) and measure the
//!    seams ([`seam::measure`]).
//!
//! Memory follows the pieces (each region's box plus margin), not regions x map. Before anything
//! of the map's size is allocated, the map's floor ([`check_memory`]) and, before any exemplar
//! is resampled, each resampled size and each region's synthesis estimate are checked against
//! the limits ([`skinkit_maps::limits`]).

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use skinkit_maps::progress::{NoProgress, Progress};
use skinkit_maps::resample::{resample_normals, scaled_size};
use skinkit_maps::{Grid, NormalMap, limits};
use skinkit_synth::SynthConfig;

use crate::curve::CurveParams;
use crate::layout::Layout;
use crate::partition::Partition;
use crate::seam::{self, SeamReport};
use crate::spline::{self, Blend, Piece, Rect, SplineConfig};
use crate::surface::RegionScale;
use crate::{Error, Result};

/// The most spline levels chosen automatically (a transition about 2^7 texels wide).
pub const MAX_AUTO_LEVELS: usize = 6;

/// Label of texels outside the coverage mask (no region: zero normal in the output).
pub const NO_REGION: u16 = u16::MAX;

/// Options of [`compose`].
#[derive(Clone, Debug)]
pub struct ComposeOptions {
    /// The boundary curves (amplitude 0: straight boundaries).
    pub curve: CurveParams,
    /// Spline levels; `None` chooses them from the narrowest region.
    pub levels: Option<usize>,
    /// `false`: hard labels, no spline (`--no-blend`).
    pub blend: bool,
    /// Synthesis options of every region (size and seed are set per region).
    pub synth: SynthConfig,
    /// Seed of the run: mixed with each region's own seed (or index).
    pub seed: u64,
    /// Band width of the seam metric, texels.
    pub seam_band: usize,
}

impl Default for ComposeOptions {
    fn default() -> Self {
        ComposeOptions {
            curve: CurveParams::new(0.0, 0),
            levels: None,
            blend: true,
            synth: SynthConfig::default(),
            seed: 0,
            seam_band: 4,
        }
    }
}

impl ComposeOptions {
    /// The default curve amplitude for a map `width` texels wide: 64 texels at 4096, scaled with
    /// the map.
    pub fn default_amplitude(width: usize) -> f64 {
        (64.0 * width as f64 / 4096.0).max(1.0)
    }
}

/// What [`compose`] did for one region.
#[derive(Clone, Debug, Serialize)]
pub struct RegionReport {
    pub name: String,
    /// Texels labelled with the region (covered texels only).
    pub texels: usize,
    /// The rectangle synthesised for it (`None`: the region has no texels).
    pub piece: Option<Rect>,
    /// Exemplar size after resampling to the region's scale.
    pub exemplar_size: (usize, usize),
    /// The scale the region was grown at: the layout's, or measured on its mesh.
    pub mm_per_texel: f64,
    /// On a mesh: the region's surface and UV areas the scale was measured from (`None` without
    /// a mesh, or when no triangle with UV area lies in the region: then the whole mesh's).
    pub mesh_scale: Option<RegionScale>,
    pub seed: u64,
    pub synthesis_seconds: f64,
    pub warnings: Vec<String>,
}

/// Wall-clock seconds per stage.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ComposeSeconds {
    pub partition: f64,
    pub resample: f64,
    pub synthesis: f64,
    pub blend: f64,
    pub seams: f64,
}

/// The result of [`compose`].
#[derive(Clone, Debug)]
pub struct Composed {
    pub normals: NormalMap,
    /// Region index per texel ([`NO_REGION`] outside the coverage mask).
    pub labels: Grid<u16>,
    /// Spline levels used (1 with `blend = false`).
    pub levels: usize,
    pub regions: Vec<RegionReport>,
    pub seams: SeamReport,
    pub seconds: ComposeSeconds,
    /// Regions grown at once: all of them when their memory estimates fit the limit together,
    /// else 1.
    pub regions_at_once: usize,
}

/// A region's synthesis seed: the run's seed mixed with the region's own (or its index), so
/// `--seed` changes every region and regions sharing a mold do not repeat each other.
pub fn region_seed(run: u64, region: usize, own: Option<u64>) -> u64 {
    let mut z = run ^ own.unwrap_or(region as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    // splitmix64 finaliser
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Stitches one synthesis per region of `layout` into a face map. `exemplars[i]` is region `i`'s
/// normal map at the region's `exemplar_mm_per_texel`; `progress` is told one stage, `regions`,
/// of a step per region, each as its synthesis ends.
///
/// # Errors
/// A count of exemplars that is not the count of regions, bad seed points or curve parameters, a
/// coverage mask that is unreadable or of another size, an exemplar too small to synthesise from
/// after resampling, a level count the regions cannot hold.
pub fn compose(
    layout: &Layout,
    exemplars: &[NormalMap],
    options: &ComposeOptions,
    progress: &dyn Progress,
) -> Result<Composed> {
    let regions = layout.regions.len();
    if exemplars.len() != regions {
        return Err(Error::InvalidParameter(format!(
            "{}: {regions} regions but {} exemplars were given",
            layout.origin.display(),
            exemplars.len()
        )));
    }
    let (w, h) = (layout.width, layout.height);
    let mut seconds = ComposeSeconds::default();
    check_memory(layout, options)?;
    layout.check_placed()?;

    let t = Instant::now();
    // The coverage mask first: its size is checked from its header before it is decoded, and
    // before the partition allocates the map.
    let coverage = layout.load_coverage()?;
    let mut partition = Partition::build(w, h, regions, &layout.seed_points(), &options.curve)?;
    let labels = match &coverage {
        Some(mask) => {
            partition.restrict_to(mask)?;
            let mut labels = partition.labels().clone();
            labels.as_mut_slice().par_iter_mut().zip(mask.as_slice().par_iter()).for_each(|(l, &covered)| {
                if !covered {
                    *l = NO_REGION;
                }
            });
            labels
        }
        None => partition.labels().clone(),
    };
    seconds.partition = t.elapsed().as_secs_f64();

    let bboxes: Vec<Option<Rect>> = partition
        .areas()
        .iter()
        .map(|a| a.bbox.map(|b| Rect { x0: b.x, y0: b.y, width: b.width, height: b.height }))
        .collect();
    let levels = spline_levels(&bboxes, options)?;
    let texels: Vec<usize> = partition.areas().iter().map(|a| a.texels).collect();
    let scales = region_scales(layout, &labels);
    let (grown, regions_at_once) =
        grow_regions(layout, exemplars, &bboxes, &texels, &scales, levels, options, progress, &mut seconds)?;
    let (pieces, reports): (Vec<Piece>, Vec<RegionReport>) = grown.into_iter().unzip();

    let t = Instant::now();
    let config = SplineConfig { levels, blend: Blend::NormalVectors };
    let blended = spline::blend(&labels, &pieces, &config)?;
    drop(pieces);
    let normals = NormalMap::from_unit_grid(blended)?;
    seconds.blend = t.elapsed().as_secs_f64();

    let t = Instant::now();
    let seams = seam::measure(&labels, normals.grid(), regions, options.seam_band.max(1))?;
    seconds.seams = t.elapsed().as_secs_f64();
    Ok(Composed { normals, labels, levels, regions: reports, seams, seconds, regions_at_once })
}

/// Each region's scale: measured over its triangles on the layout's mesh (issue 41), else the
/// layout's `mm_per_texel`.
fn region_scales(layout: &Layout, labels: &Grid<u16>) -> Vec<(f64, Option<RegionScale>)> {
    let n = layout.regions.len();
    match &layout.surface {
        Some(surface) => surface
            .region_scales(labels, n)
            .into_iter()
            .map(|s| (s.map_or(layout.mm_per_texel, |s| s.mm_per_texel), s))
            .collect(),
        None => vec![(layout.mm_per_texel, None); n],
    }
}

/// Bytes per face-map texel [`compose`] holds at least at once: the partition's cells and the
/// labels (2 + 2), the regions' pieces, which cover the map (12), and the blended map (12). A
/// floor, not the peak (the spline's pyramids and the syntheses come on top): a map whose floor
/// exceeds the memory limit is refused before anything is allocated.
pub const MAP_BYTES_PER_TEXEL: u64 = 28;

/// Refuses a layout whose map alone ([`MAP_BYTES_PER_TEXEL`]) exceeds the synthesis options'
/// memory limit, from its numbers alone: call it before reading or capturing any exemplar.
///
/// # Errors
/// [`skinkit_maps::Error::OverBudget`] naming the layout file and its `size`.
pub fn check_memory(layout: &Layout, options: &ComposeOptions) -> Result<()> {
    let texels = (layout.width as u64).saturating_mul(layout.height as u64);
    let what = format!("size: a {}x{} face map", layout.width, layout.height);
    let estimate = texels.saturating_mul(MAP_BYTES_PER_TEXEL);
    limits::check_memory(&layout.origin.display().to_string(), &what, estimate, options.synth.memory_limit)?;
    Ok(())
}

/// The spline's level count: the options' own, else as many as the narrowest region's overlap
/// allows (1 without blending).
fn spline_levels(bboxes: &[Option<Rect>], options: &ComposeOptions) -> Result<usize> {
    let levels = if !options.blend {
        1
    } else {
        match options.levels {
            Some(l) => l,
            None => {
                let narrowest = bboxes.iter().flatten().map(|b| b.width.min(b.height)).min().unwrap_or(1);
                spline::levels_for_overlap(narrowest).min(MAX_AUTO_LEVELS)
            }
        }
    };
    if levels == 0 || levels > spline::MAX_LEVELS {
        return Err(Error::InvalidParameter(format!("spline levels = {levels}: must be 1 to {}", spline::MAX_LEVELS)));
    }
    Ok(levels)
}

/// Resamples every region's exemplar to the map's scale and grows the region over its piece,
/// after checking every size and estimate first; the seconds of both steps go to `seconds`.
/// Gives the pieces and reports and how many regions grew at once.
#[allow(clippy::too_many_arguments)] // the steps of `compose` it stands for, by name
fn grow_regions(
    layout: &Layout,
    exemplars: &[NormalMap],
    bboxes: &[Option<Rect>],
    texels: &[usize],
    scales: &[(f64, Option<RegionScale>)],
    levels: usize,
    options: &ComposeOptions,
    progress: &dyn Progress,
    seconds: &mut ComposeSeconds,
) -> Result<(Vec<(Piece, RegionReport)>, usize)> {
    let regions = layout.regions.len();
    // Every resampled size and synthesis estimate is checked before any exemplar is resampled.
    let (sizes, estimates): (Vec<(usize, usize)>, Vec<u64>) = (0..regions)
        .map(|i| {
            let size = resampled_size(layout, i, scales[i].0, exemplars[i].size())?;
            Ok((size, check_region_synthesis(layout, i, scales[i].0, size, bboxes[i], levels, options)?))
        })
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .unzip();
    // Regions grow side by side when their estimates fit the limit together beside the map's
    // floor; else one at a time (each fits alone, and each synthesis is parallel within).
    let map_floor = (layout.width as u64 * layout.height as u64).saturating_mul(MAP_BYTES_PER_TEXEL);
    let together = estimates.iter().fold(map_floor, |sum, &e| sum.saturating_add(e));
    let side_by_side = together <= options.synth.memory_limit;
    let t = Instant::now();
    let resampled: Vec<NormalMap> = exemplars
        .par_iter()
        .zip(sizes.par_iter())
        .map(|(ex, &(rw, rh))| resample_normals(ex, rw, rh).map_err(Error::from))
        .collect::<Result<_>>()?;
    seconds.resample = t.elapsed().as_secs_f64();

    let t = Instant::now();
    progress.start("regions", regions as u64);
    let grow = |i: usize| {
        let grown = grow_region(layout, i, &resampled[i], bboxes[i], levels, texels[i], scales[i], options);
        if grown.is_ok() {
            progress.advance(1);
        }
        grown
    };
    let grown: Vec<(Piece, RegionReport)> = if side_by_side {
        (0..regions).into_par_iter().map(grow).collect::<Result<_>>()?
    } else {
        (0..regions).map(grow).collect::<Result<_>>()?
    };
    progress.finish();
    seconds.synthesis = t.elapsed().as_secs_f64();
    Ok((grown, if side_by_side { regions } else { 1 }))
}

/// Region `i`'s exemplar size at the map's scale, refused above
/// [`limits::MAX_EXEMPLAR_TEXELS`] (the arithmetic in f64, so no size overflows).
fn resampled_size(layout: &Layout, i: usize, mm: f64, (ew, eh): (usize, usize)) -> Result<(usize, usize)> {
    let region = &layout.regions[i];
    let scale = region.exemplar_mm_per_texel / mm;
    let side = |n: usize| (n as f64 * scale).round().max(1.0);
    let (rw, rh) = (side(ew), side(eh));
    // In f64 no product overflows: a huge scale gives a huge (or infinite) count, never a wrap.
    if rw * rh > limits::MAX_EXEMPLAR_TEXELS as f64 {
        return Err(Error::Layout {
            origin: layout.origin.clone(),
            field: format!("region `{}`: exemplar_mm_per_texel", region.name),
            message: format!(
                "{} mm against the map's {} mm per texel resamples the {ew}x{eh} exemplar to {rw:.0}x{rh:.0} texels, over the limit of {} texels",
                region.exemplar_mm_per_texel,
                mm,
                limits::MAX_EXEMPLAR_TEXELS
            ),
        });
    }
    let size = scaled_size(ew, eh, region.exemplar_mm_per_texel, mm);
    debug_assert_eq!(size, (rw as usize, rh as usize));
    Ok(size)
}

/// Checks region `i`'s synthesis options and memory estimate against its resampled exemplar
/// size, before the exemplar is resampled; gives the estimate (0 for a region without texels).
fn check_region_synthesis(
    layout: &Layout,
    i: usize,
    mm: f64,
    (rw, rh): (usize, usize),
    bbox: Option<Rect>,
    levels: usize,
    options: &ComposeOptions,
) -> Result<u64> {
    let Some(bbox) = bbox else { return Ok(0) };
    let rect = spline::piece_rect(bbox, levels, layout.width, layout.height);
    let config = SynthConfig { width: rect.width, height: rect.height, ..options.synth.clone() };
    let (validated, _) = config.validate(rw, rh).map_err(|e| synthesis_error(layout, i, mm, rect, (rw, rh), e))?;
    Ok(validated.memory_estimate(rw, rh))
}

/// Region `i`'s synthesis failure, naming the layout, the region and the sizes.
fn synthesis_error(
    layout: &Layout,
    i: usize,
    mm: f64,
    rect: Rect,
    (ew, eh): (usize, usize),
    e: skinkit_synth::Error,
) -> Error {
    let region = &layout.regions[i];
    Error::InvalidParameter(format!(
        "{}: region `{}`: cannot synthesise {}x{} from its {ew}x{eh} exemplar (after resampling to {} mm per texel; exemplar_mm_per_texel = {}): {}",
        layout.origin.display(),
        region.name,
        rect.width,
        rect.height,
        mm,
        region.exemplar_mm_per_texel,
        skinkit_maps::error::one_line(&e)
    ))
}

/// Synthesises region `i` over its piece rectangle (an empty piece for a region without texels).
#[allow(clippy::too_many_arguments)] // the region, its inputs and its scale, by name
fn grow_region(
    layout: &Layout,
    i: usize,
    exemplar: &NormalMap,
    bbox: Option<Rect>,
    levels: usize,
    texels: usize,
    (mm_per_texel, mesh_scale): (f64, Option<RegionScale>),
    options: &ComposeOptions,
) -> Result<(Piece, RegionReport)> {
    let region = &layout.regions[i];
    let seed = region_seed(options.seed, i, region.seed);
    let mut report = RegionReport {
        name: region.name.clone(),
        texels,
        piece: None,
        exemplar_size: exemplar.size(),
        mm_per_texel,
        mesh_scale,
        seed,
        synthesis_seconds: 0.0,
        warnings: Vec::new(),
    };
    let Some(bbox) = bbox else {
        return Ok((Piece::new(0, 0, Grid::filled(0, 0, glam::Vec3::ZERO)), report));
    };
    let rect = spline::piece_rect(bbox, levels, layout.width, layout.height);
    let t = Instant::now();
    let config = SynthConfig { width: rect.width, height: rect.height, seed, ..options.synth.clone() };
    let grown = skinkit_synth::synthesize_normals(exemplar, &config, &NoProgress)
        .map_err(|e| synthesis_error(layout, i, mm_per_texel, rect, exemplar.size(), e))?;
    report.synthesis_seconds = t.elapsed().as_secs_f64();
    report.warnings = grown.warnings;
    report.piece = Some(rect);
    Ok((Piece::new(rect.x0, rect.y0, grown.normals.grid().clone()), report))
}
