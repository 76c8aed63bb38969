//! Wei-Levoy multiresolution synthesis (Wei and Levoy 2000; Haro et al. 2001, section 4.1).
//!
//! Coarse to fine over Gaussian pyramids of exemplar and output: each output level starts as
//! copies of seeded random exemplar texels ([`random_copies`]), then its texels are replaced in
//! scanline order by the exemplar texel whose neighbourhood ([`crate::neighbourhood`]) is nearest
//! in L2 (the causal pass, `causal`). The output is toroidal, so results tile. How a candidate is
//! scored, with the occurrence penalty of Kopf et al. 2007, is in `scoring`.
//!
//! With [`Search::KCoherence`](crate::Search::KCoherence) (Tong et al. 2002) a texel's candidates are, for each synthesised
//! causal neighbour, its source shifted back and that source's k-coherence set
//! ([`crate::search::KCoherenceSets`]), each scored once with an early-exit distance (exact at or
//! below the best so far, so the choice equals a full scoring of the same candidates).
//!
//! Correction passes ([`SynthConfig::corrections`]; Wei and Levoy 2000's multi-pass extension,
//! Ashikhmin 2001, Lefebvre and Hoppe 2005): after the causal pass, every texel of the level is
//! chosen again by its full `N x N` neighbourhood (centre included, toroidal) joined with the
//! coarser `M x M` window, against exemplar candidates with full-window features: exhaustively
//! ([`Search::Exact`](crate::Search::Exact)), through a PCA kd-tree built on the full features plus coherence candidates
//! ([`Search::Approximate`](crate::Search::Approximate)), or from the k-coherence sets of every neighbour's source shifted
//! back, the texel's own current source among them ([`Search::KCoherence`](crate::Search::KCoherence); its fallback tree is
//! also built on full features, thresholded by the full-window typical distance). A pass is split
//! into [`crate::config::CORRECTION_STRIDE`]`^2` interleaved sub-passes by `(x mod s, y mod s)`, in row-major
//! order of the residues; a sub-pass reads the state the previous sub-passes left (a snapshot for
//! its own texels), chooses its texels in parallel and then writes them, so the result is the
//! same on any thread count. With `s` = 3 most texels of a sub-pass see already corrected
//! neighbours on two sides (a Jacobi update, `s` = 1, and `s` = 2 or 5 measured slightly worse).
//!
//! Upsampled start ([`Start::Upsampled`], the default; Lefebvre and Hoppe 2005):
//! instead of the causal pass, the coarsest level starts as random exemplar copies and every finer
//! level as its coarser level's coordinates upsampled (texel `(x, y)` copies `2 p + (x mod 2,
//! y mod 2)`, clamped into the candidates, optionally jittered at the coarser levels); the
//! correction passes then do all the matching. Whole exemplar patches are carried down the
//! pyramid, so the output keeps the exemplar's slope histogram without an occurrence penalty, and
//! no step is sequential.
//!
//! Copy cap ([`SynthConfig::copy_cap`]): patches carried down the pyramid can be large (a quarter
//! of the exemplar). Before the finest level's last correction pass, the verbatim blocks of the
//! current coordinates are found ([`crate::metrics::copy_blocks`]); the texels of blocks over the cap that
//! lie on a grid of lines (spacing from the cap, phase from the seed) may not keep their source in
//! that pass, so each such block is cut into pieces along the best-matching seam the pass finds.
//! A cut texel may not continue a neighbour's block either, and the cut repeats on the cut texels
//! while any block still exceeds the cap (see `correction`).
//!
//! Seam polishing ([`SynthConfig::polish`], the finest level, after its correction passes and
//! before the cap's repeated cuts): each texel near a seam takes, among the sources that continue
//! its neighbours' blocks, the one that minimises the distances of all the windows it lies in,
//! without joining blocks beyond the cap (see `polish`).
//!
//! Patch size and seams (the default's choices, measured by `benches/suite.rs`): the suite's
//! energy counts every output window that is not verbatim in the exemplar, so it is mostly seams,
//! and the peer wins it with large copies. At the coarser levels a coherence bias
//! ([`SynthConfig::coherence_bias`]) keeps the patches the finest level inherits large, and a
//! texel whose best coherent candidate is far from its window searches the PCA kd-tree too (the
//! k-coherence fallback), which is where a good seam texel is found; the finest level places the
//! seams without a bias and with a looser fallback ratio (its tree queries cost the most).
//!
//! Per-level options: which penalty, bias, fallback ratio, distance, cap and passes a level runs
//! with is decided once per run by [`SynthConfig::schedule`], one [`LevelPlan`] per level; every
//! step of a level reads its plan (see [`LevelPlan`] for which value applies where).
//!
//! Guards ([`synthesize`], [`synthesize_normals`]; `guard`): an output that collapsed, or whose
//! histograms drifted from the exemplar's, is grown again with an occurrence penalty and the
//! better output kept.
//!
//! What runs in parallel: pyramids, exemplar features, PCA and kd-tree construction, the
//! exhaustive scan over candidates for one texel, and the texels of a correction sub-pass. The
//! causal texel loop stays sequential: each texel's causal neighbourhood holds the texels
//! synthesised just before it, including, through the toroidal wrap, the end of the previous row,
//! so a row cannot start before the previous one is finished (see `docs/synthesis-notes.md`).
//!
//! Normal maps are synthesised as unnormalised vectors, so pyramid averages stay meaningful; from
//! level [`crate::appearance::DETAIL_MIN_LEVEL`] up their `z` is replaced by a detail channel
//! ([`SynthConfig::detail_weight`], [`crate::appearance`]) so that sparse bumps such as pores,
//! which averaging cancels, still steer the coarse matching. The
//! finest level copies exemplar texels verbatim, so the output of a unit exemplar is unit (or
//! invalid zero) without renormalising, bit for bit the exemplar's texels.

use std::time::Instant;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use skinkit_maps::progress::Progress;
use skinkit_maps::pyramid::{Border, gaussian};
use skinkit_maps::{Grid, NormalMap};

use std::ops::Range;

use crate::band::{self, BAND_HALO, Collect, Window};
use crate::causal::causal_pass;
use crate::config::{Start, SynthConfig, half};
use crate::correction::CorrectionLevel;
use crate::exemplar::ExemplarLevel;
pub use crate::level::random_copies;
use crate::level::{LevelSearch, build_search, shape};

use crate::schedule::LevelPlan;
use crate::{Error, Result};

// The guards and the streamed runs are parts of synthesis: they run it (`grow_into`) and it
// returns their figures, so they are its children rather than siblings that would depend on it
// both ways.
mod guard;
mod stream;
pub use guard::Guards;
pub use stream::{BandSink, Streamed, synthesize_normals_streamed, synthesize_streamed};

/// The result of [`synthesize`].
#[derive(Clone, Debug)]
pub struct Synthesis {
    /// The finest output level.
    pub texels: Grid<Vec3>,
    /// For every output texel, the exemplar texel `[x, y]` it copies.
    pub coords: Grid<[u32; 2]>,
    /// What validation changed (clamped levels, sanitised texels).
    pub warnings: Vec<String>,
    /// Wall-clock seconds per level, `[0]` the finest.
    pub level_seconds: Vec<f64>,
    /// The guards' figures on channels ([`crate::metrics::variation_ratio`],
    /// [`crate::metrics::channel_histogram_mismatch`]).
    pub guards: Guards,
}

/// The result of [`synthesize_normals`].
#[derive(Clone, Debug)]
pub struct NormalSynthesis {
    /// Unit normals (or zero where the exemplar texel copied was invalid).
    pub normals: NormalMap,
    /// For every output texel, the exemplar texel `[x, y]` it copies.
    pub coords: Grid<[u32; 2]>,
    pub warnings: Vec<String>,
    pub level_seconds: Vec<f64>,
    /// The guards' figures on slopes ([`crate::metrics::slope_variation_ratio`],
    /// [`crate::metrics::slope_histogram_mismatch`]).
    pub guards: Guards,
}

/// Grows `exemplar` into a `config.width x config.height` map. `progress` is told a stage per
/// pyramid level (`level 2`, ..., `level 0`, the finest last), counted in output rows of each pass.
///
/// # Errors
/// When [`SynthConfig::validate`] fails.
pub fn synthesize(exemplar: &Grid<Vec3>, config: &SynthConfig, progress: &dyn Progress) -> Result<Synthesis> {
    let s = stream::collected(exemplar, config, progress, Texels::Colour)?;
    let (texels, coords) = s.sink.finish();
    Ok(Synthesis { texels, coords, warnings: s.warnings, level_seconds: s.level_seconds, guards: s.guards })
}

/// What a synthesis grows: it decides the pyramid the search matches in and how an output's
/// variation is measured ([`crate::metrics::GuardMeter`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Texels {
    Colour,
    /// Unnormalised normals, matched with a detail channel ([`crate::appearance`]).
    Normals,
}

impl Texels {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Texels::Colour => "colour",
            Texels::Normals => "slope",
        }
    }

    /// The exemplar pyramid the search matches in (level 0 is the exemplar itself).
    fn pyramid(self, exemplar: &Grid<Vec3>, config: &SynthConfig) -> Vec<Grid<Vec3>> {
        match self {
            Texels::Colour => gaussian(exemplar, config.levels, Border::Clamp),
            Texels::Normals => crate::appearance::normal_pyramid(exemplar, config.levels, config.detail_weight),
        }
    }
}

/// Receives a level's rows band by band, top to bottom ([`crate::band`]): the band's first level
/// row, its texels and their coordinates.
pub(crate) type Emit<'a> = dyn FnMut(usize, Grid<Vec3>, Grid<[u32; 2]>) -> Result<()> + 'a;

/// What a run tells besides its finest level's rows.
pub(crate) struct RunNotes {
    pub(crate) warnings: Vec<String>,
    pub(crate) level_seconds: Vec<f64>,
}

/// Grows `exemplar` level by level, coarse to fine, handing the finest level's bands to `finest`
/// as they finish; the coarser levels are held whole (each is read by the next finer one).
pub(crate) fn grow_into(
    exemplar: &Grid<Vec3>,
    config: &SynthConfig,
    progress: &dyn Progress,
    kind: Texels,
    finest: &mut Emit,
) -> Result<RunNotes> {
    let (ew, eh) = exemplar.size();
    let (config, mut warnings) = config.validate(ew, eh)?;
    let bad = exemplar.as_slice().iter().filter(|v| !v.is_finite()).count();
    let clean;
    let exemplar = if bad > 0 {
        warnings.push(format!("{bad} exemplar texels were not finite and were set to zero"));
        clean = exemplar.map(|v| if v.is_finite() { *v } else { Vec3::ZERO });
        &clean
    } else {
        exemplar
    };
    // Level 0 is the exemplar itself, so the output holds exemplar texels.
    let pyramid = kind.pyramid(exemplar, &config);
    let mut sizes = vec![(config.width, config.height)];
    while sizes.len() < config.levels {
        let (w, h) = sizes[sizes.len() - 1];
        sizes.push((half(w), half(h)));
    }
    let mut level_seconds = vec![0.0; config.levels];
    let mut coarser: Option<(Grid<Vec3>, Grid<[u32; 2]>)> = None;
    // The validated config's levels are clamped already, so the schedule has one plan per level.
    let schedule = config.schedule(ew, eh);
    for plan in schedule.iter().rev() {
        let (level, start) = (plan.level, Instant::now());
        let coarser_level = coarser.as_ref().map(|(t, c)| (t, c));
        if level == 0 {
            synthesize_level(&pyramid, plan, sizes[level], coarser_level, &config, progress, finest)?;
        } else {
            let (w, h) = sizes[level];
            let mut collect = Collect::new(w, h);
            synthesize_level(&pyramid, plan, (w, h), coarser_level, &config, progress, &mut |_, texels, coords| {
                collect.push(texels, coords);
                Ok(())
            })?;
            coarser = Some(collect.finish());
        }
        level_seconds[level] = start.elapsed().as_secs_f64();
    }
    Ok(RunNotes { warnings, level_seconds })
}

/// [`synthesize`] for a normal map: unnormalised vectors through the pyramid, unit on output.
///
/// # Errors
/// When [`SynthConfig::validate`] fails, or the exemplar has no valid texel
/// ([`crate::Error::NoValidNormals`], refused before any work).
pub fn synthesize_normals(
    exemplar: &NormalMap,
    config: &SynthConfig,
    progress: &dyn Progress,
) -> Result<NormalSynthesis> {
    let exemplar_warning = crate::exemplar::check_normal_exemplar(exemplar)?;
    let s = stream::collected(exemplar.grid(), config, progress, Texels::Normals)?;
    let ((texels, coords), mut warnings) = (s.sink.finish(), s.warnings);
    warnings.splice(0..0, exemplar_warning);
    // The finest level copies exemplar texels, which are unit (or invalid zero) already: wrapping
    // them keeps the bits, where renormalising would perturb the last one.
    let normals = NormalMap::from_unit_grid(texels)?;
    Ok(NormalSynthesis { normals, coords, warnings, level_seconds: s.level_seconds, guards: s.guards })
}

/// Copies `map` (a map of the exemplar's size, e.g. the albedo registered with the normals) through
/// a coordinate map, so the result stays in register with the synthesised output.
///
/// # Errors
/// When an entry of `coords` lies outside `map`.
pub fn replay<T: Clone + Send + Sync>(coords: &Grid<[u32; 2]>, map: &Grid<T>) -> Result<Grid<T>> {
    let (w, h) = map.size();
    for (i, &[x, y]) in coords.as_slice().iter().enumerate() {
        if x as usize >= w || y as usize >= h {
            let (col, row) = (i % coords.width(), i / coords.width());
            return Err(Error::CoordsOutside { x, y, col, row, width: w, height: h });
        }
    }
    Ok(Grid::from_fn(coords.width(), coords.height(), |x, y| {
        let [sx, sy] = *coords.get(x, y);
        map.get(sx as usize, sy as usize).clone()
    }))
}

/// Output noise whose per-channel histogram is the exemplar level's: each channel of each texel is
/// an independent draw from the exemplar's empirical distribution of that channel (inverse CDF of
/// a uniform), seeded by `seed` with one ChaCha stream per level. (The initial state of a level
/// before [`random_copies`] replaced it; kept as the noise baseline of the energy tests.)
pub fn histogram_noise(exemplar: &Grid<Vec3>, width: usize, height: usize, seed: u64, level: usize) -> Grid<Vec3> {
    let sorted: [Vec<f32>; 3] = std::array::from_fn(|c| {
        let mut v: Vec<f32> = exemplar.as_slice().iter().map(|t| t[c]).collect();
        v.sort_by(f32::total_cmp);
        v
    });
    let n = sorted[0].len();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(level as u64);
    let data = (0..width * height)
        .map(|_| {
            let mut draw = |c: usize| sorted[c][((rng.random::<f64>() * n as f64) as usize).min(n - 1)];
            let (x, y, z) = (draw(0), draw(1), draw(2));
            Vec3::new(x, y, z)
        })
        .collect();
    Grid::from_vec(width, height, data).expect("length is width * height")
}

/// Synthesises one output level given the finished coarser one: the causal scanline pass (or the
/// upsampled start), then `plan.corrections` correction passes; in bands ([`crate::band`]) when
/// the level is taller than one, handed to `emit` band by band.
fn synthesize_level(
    pyramid: &[Grid<Vec3>],
    plan: &LevelPlan,
    (w, h): (usize, usize),
    coarser_level: Option<(&Grid<Vec3>, &Grid<[u32; 2]>)>,
    config: &SynthConfig,
    progress: &dyn Progress,
    emit: &mut Emit,
) -> Result<()> {
    let level = plan.level;
    let coarser = coarser_level.map(|(t, _)| t);
    let nb = shape(config, false, coarser.is_some());
    let ex = ExemplarLevel::new(
        pyramid[level].clone(),
        pyramid.get(level + 1).filter(|_| coarser.is_some()),
        &nb,
        config.neighbourhood,
        config.exemplar_wrap,
    );
    let search = build_search(pyramid, plan, coarser.is_some(), &ex, config);
    // Progress counts rows: `h` for the causal pass and `h` for each correction pass.
    let total = (h * (usize::from(config.start == Start::Scanline) + plan.corrections)).max(1);
    progress.start(&format!("level {level}"), total as u64);
    let bands = band::bands(h);
    if let (Start::Upsampled, Some(parent), true) = (config.start, coarser_level, bands.len() > 1) {
        drop(ex);
        let level = BandedLevel { search: &search, plan, config, parent, width: w, bands: &bands };
        level.grow(progress, emit)?;
        progress.finish();
        return Ok(());
    }
    // The passes count rows done so far; the stage is told what each report adds.
    let done = std::cell::Cell::new(0);
    let report = |units: usize| progress.advance(units.saturating_sub(done.replace(units)) as u64);
    let rows: Vec<usize> = (0..h).collect();
    let (mut out, mut coords) = match (config.start, coarser_level) {
        (Start::Scanline, _) => causal_pass(plan, (w, h), coarser, &nb, &ex, &search, config, &report),
        (Start::Upsampled, None) => random_copies(ex.texels(), ex.margin(), w, h, config.seed, level),
        (Start::Upsampled, Some((_, parent))) => upsampled(&search.full, parent, w, &rows, plan, config.seed),
    };
    drop(ex);
    if plan.corrections > 0 {
        let full_nb = shape(config, true, coarser.is_some());
        let window = Window::whole(h);
        let level = CorrectionLevel { coarser, plan, nb: &full_nb, search: &search, config, window: &window };
        level.run(&mut out, &mut coords, &report);
    }
    progress.finish();
    emit(0, out, coords)
}

/// A level grown in bands ([`crate::band`]): what every band reads.
struct BandedLevel<'a> {
    search: &'a LevelSearch,
    plan: &'a LevelPlan,
    config: &'a SynthConfig,
    /// The finished coarser level's texels and coordinates.
    parent: (&'a Grid<Vec3>, &'a Grid<[u32; 2]>),
    width: usize,
    bands: &'a [Range<usize>],
}

impl BandedLevel<'_> {
    /// Grows the bands top to bottom, each in its window: upsampled, the frozen rows put back
    /// (the band above's last rows, and for the last band the first band's first rows), then
    /// corrected; its own rows go to `emit`.
    fn grow(&self, progress: &dyn Progress, emit: &mut Emit) -> Result<()> {
        let (plan, config, (coarser, parent)) = (self.plan, self.config, self.parent);
        let h = self.bands.last().map_or(0, |b| b.end);
        let full_nb = shape(config, true, true);
        let mut above: Option<(Grid<Vec3>, Grid<[u32; 2]>)> = None;
        let mut first: Option<(Grid<Vec3>, Grid<[u32; 2]>)> = None;
        for (k, band) in self.bands.iter().enumerate() {
            let bw = band::band_window(self.bands, k, h);
            let rows: Vec<usize> = (0..bw.len).map(|y| bw.window.level_row(y)).collect();
            let (mut out, mut coords) = upsampled(&self.search.full, parent, self.width, &rows, plan, config.seed);
            if let Some((t, c)) = above.as_ref().filter(|_| bw.frozen_top) {
                band::put_rows(&mut out, 0, t);
                band::put_rows(&mut coords, 0, c);
            }
            if let Some((t, c)) = first.as_ref().filter(|_| bw.frozen_bottom > 0) {
                band::put_rows(&mut out, bw.len - bw.frozen_bottom, t);
                band::put_rows(&mut coords, bw.len - bw.frozen_bottom, c);
            }
            if plan.corrections > 0 {
                let coarser = band::coarser_rows(coarser, &bw.window, bw.len);
                let window = &bw.window;
                let level = CorrectionLevel {
                    coarser: Some(&coarser),
                    plan,
                    nb: &full_nb,
                    search: self.search,
                    config,
                    window,
                };
                level.run(&mut out, &mut coords, &|_| {});
            }
            let own = bw.top..bw.top + band.len();
            let (texels, coords) = (band::rows_of(&out, own.clone()), band::rows_of(&coords, own));
            let last = band.len() - BAND_HALO..band.len();
            above = Some((band::rows_of(&texels, last.clone()), band::rows_of(&coords, last)));
            if k == 0 {
                first = Some((band::rows_of(&texels, 0..BAND_HALO), band::rows_of(&coords, 0..BAND_HALO)));
            }
            emit(band.start, texels, coords)?;
            progress.advance((band.len() * plan.corrections) as u64);
        }
        Ok(())
    }
}

/// A level's start from its coarser level's coordinates (Lefebvre and Hoppe 2005): texel `(x, y)`
/// copies exemplar position `2 p + (x mod 2, y mod 2)`, `p` the coarser texel's source, kept
/// inside the candidates (clamped, or wrapped when the exemplar wraps). `rows` are the level rows
/// of the grid's rows: the whole level, or a band's window. The jitter is drawn from one ChaCha
/// stream per level in row-major order for a whole level, from one stream per level row in a
/// band's window (so a row's jitter does not depend on the band it falls in).
fn upsampled(
    full: &ExemplarLevel,
    parent: &Grid<[u32; 2]>,
    w: usize,
    rows: &[usize],
    plan: &LevelPlan,
    seed: u64,
) -> (Grid<Vec3>, Grid<[u32; 2]>) {
    let (pw, ph, jitter, level) = (parent.width(), parent.height(), plan.jitter, plan.level);
    let whole = rows.iter().enumerate().all(|(i, &r)| i == r) && rows.len().div_ceil(2) == ph;
    let r = jitter as i64;
    let draw = |rng: &mut ChaCha8Rng| [rng.random_range(-r..=r) as isize, rng.random_range(-r..=r) as isize];
    // One ChaCha stream per level, offset from random_copies' streams; drawn in row-major order.
    let offsets: Vec<[isize; 2]> = if jitter == 0 {
        Vec::new()
    } else if whole {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1 << 32 | level as u64);
        (0..w * rows.len()).map(|_| draw(&mut rng)).collect()
    } else {
        let stream = |row: usize| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(1 << 48 | (level as u64) << 32 | row as u64);
            rng
        };
        rows.iter().flat_map(|&row| (0..w).scan(stream(row), |rng, _| Some(draw(rng)))).collect()
    };
    let coords = Grid::from_fn(w, rows.len(), |x, y| {
        let ly = rows[y];
        let [px, py] = *parent.get((x / 2).min(pw - 1), (ly / 2).min(ph - 1));
        let [jx, jy] = offsets.get(y * w + x).copied().unwrap_or([0, 0]);
        let (cx, cy) = (2 * px as isize + (x % 2) as isize + jx, 2 * py as isize + (ly % 2) as isize + jy);
        let i = full.index_of(cx, cy).unwrap_or_else(|| full.nearest_candidate(cx, cy));
        full.position(i)
    });
    let texels = coords.map(|&[x, y]| *full.texels().get(x as usize, y as usize));
    (texels, coords)
}
