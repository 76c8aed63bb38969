//! `skinkit synth`: grow a normal or colour map from an exemplar by Wei-Levoy multiresolution
//! synthesis (Haro et al. 2001, section 4.1; issue 3), and `skinkit synth replay`: copy another map
//! of the exemplar's size (an albedo registered with the normals) through the coordinate map of a
//! run, so it stays in register with the synthesised output.
//!
//! The coordinate map is a 16-bit RGB PNG of the output's size: red holds the exemplar column
//! (x, 0 at the left) and green the exemplar row (y, 0 at the top) of the texel each output texel
//! copies; blue is 0. Exemplars wider or taller than 65535 texels cannot be described this way and
//! are refused when `--coords` is asked for.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::ProgressBar;
use serde::Serialize;
use skinkit_maps::OutputSet;
use skinkit_maps::io::{self, Limits, PngLayout};
use skinkit_maps::{Channels, ColorMap, Grid, NormalEncoding, NormalMap, Samples, Transfer, Vec3};
use skinkit_synth::metrics::{self, DEFAULT_SPECTRUM_BINS};
use skinkit_synth::{Guards, Search, SynthConfig};

use crate::flags::{self, Green, MapKind, TransferArg};
use crate::output::Output;
use crate::{guard, pipeline};

/// The largest exemplar side a 16-bit coordinate map can address.
pub const MAX_COORD_SIDE: usize = u16::MAX as usize;

/// Steps of each level's progress bar (the library reports a fraction per output row).
const PROGRESS_STEPS: u64 = 1000;

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Exemplar: a normal map (PNG 8/16-bit or EXR), or with `--kind color` a colour image.
    #[arg(value_name = "EXEMPLAR", required = true)]
    pub exemplar: Option<PathBuf>,
    /// Output map (.png, 16-bit, or .exr, float).
    #[arg(long, value_name = "OUT", required = true)]
    pub out: Option<PathBuf>,
    /// Output size in texels, `WIDTHxHEIGHT` (e.g. 512x512).
    #[arg(long, value_name = "WxH", value_parser = parse_size, required = true)]
    pub size: Option<(usize, usize)>,
    /// Pyramid levels (1 = single resolution; default 5, 3 with `--scanline`); clamped, with a
    /// warning, to what the exemplar allows.
    #[arg(long, value_name = "L", value_parser = flags::usize_in(1, skinkit_synth::config::MAX_LEVELS))]
    pub levels: Option<usize>,
    /// Side of the causal neighbourhood at each level (odd, 3 to 99).
    #[arg(long, default_value_t = 5, value_name = "N", alias = "neighbourhood", value_parser = flags::odd_in(3, 99))]
    pub neighborhood: usize,
    /// Side of the full neighbourhood taken from the coarser level (odd, 1 to 99; default 1, 3
    /// with `--scanline`).
    #[arg(long, value_name = "M", value_parser = flags::odd_in(1, 99))]
    pub parent: Option<usize>,
    /// Correction passes at the finest level: every texel chosen again by its full window
    /// (default 1, as with `--scanline`; the coarser levels get 3, 1 with `--scanline`).
    #[arg(long, value_name = "P", value_parser = flags::usize_in(0, skinkit_synth::config::MAX_CORRECTIONS))]
    pub corrections: Option<usize>,
    /// Seam-polishing passes at the finest level, after its correction passes: every texel near a
    /// seam chosen again among its neighbours' blocks by all the windows it lies in (default 1, 0
    /// with `--scanline`).
    #[arg(long, value_name = "P", value_parser = flags::usize_in(0, skinkit_synth::config::MAX_CORRECTIONS))]
    pub polish: Option<usize>,
    /// Start every level with Wei and Levoy's causal scanline pass (sequential, 3 levels, k = 4,
    /// occurrence penalty 4, no copy cap) instead of the default's upsampled coordinates (Lefebvre
    /// and Hoppe 2005). Slower, and higher in energy on every exemplar of the README's suite.
    #[arg(long)]
    pub scanline: bool,
    /// The default since the upsampled start became it; accepted so older scripts still run.
    #[arg(long, hide = true, conflicts_with = "scanline")]
    pub upsampled: bool,
    /// Largest verbatim copy, as a share of the exemplar's area (0 < SHARE <= 1; default 0.09,
    /// none with `--scanline`): the last correction pass cuts bigger copied blocks apart.
    #[arg(long, value_name = "SHARE", value_parser = flags::share)]
    pub copy_cap: Option<f32>,
    /// Normal maps: weight of the detail channel the coarser levels match in place of z, so that
    /// pores, which averaging cancels, still steer where the output grows from (default 1.5, 0
    /// with `--scanline`; 0 = plain normals).
    #[arg(long, value_name = "W", value_parser = weight)]
    pub detail_weight: Option<f32>,
    /// Scale of the robust (Cauchy) distance the coarser levels' correction passes match with, in
    /// the level's typical squared distance per float (default 0.5, 0 with `--scanline`; 0 =
    /// squared L2, as the finest level always is).
    #[arg(long, value_name = "S", value_parser = weight)]
    pub robust_scale: Option<f32>,
    /// Occurrence penalty lambda (0 = off; default 0, 4 with `--scanline`).
    #[arg(long, value_name = "LAMBDA", value_parser = weight)]
    pub occurrence_penalty: Option<f32>,
    /// Occurrence penalty of the two coarsest levels, which lay out where in the exemplar the
    /// output grows from, so that it draws on all of it (default 0.05, 0 with `--scanline`; the
    /// larger of it and `--occurrence-penalty` applies there).
    #[arg(long, value_name = "LAMBDA", value_parser = weight)]
    pub layout_penalty: Option<f32>,
    /// k-coherence search (the default): candidates per source texel (Tong et al. 2002; default
    /// 2, 4 with `--scanline`).
    #[arg(long = "k", value_name = "K", conflicts_with_all = ["exact", "pca"], value_parser = flags::usize_in(1, 64))]
    pub k: Option<usize>,
    /// Search a PCA-projected kd-tree (plus Ashikhmin coherence) instead of k-coherence sets.
    #[arg(long, conflicts_with = "exact")]
    pub pca: bool,
    /// PCA dimensions of the kd-tree (1..=32), for `--pca` and for building k-coherence sets.
    #[arg(long, default_value_t = 8, value_name = "D", conflicts_with = "exact", value_parser = flags::usize_in(1, 32))]
    pub dims: usize,
    /// Approximate search: tree candidates re-scored in the full neighbourhood space.
    #[arg(long, default_value_t = 8, value_name = "K", conflicts_with = "exact", value_parser = flags::usize_in(1, skinkit_synth::config::MAX_RERANK))]
    pub rerank: usize,
    /// Exhaustive search over every exemplar neighbourhood (slow; the reference).
    #[arg(long)]
    pub exact: bool,
    /// Do not add Ashikhmin coherence candidates (approximate search).
    #[arg(long)]
    pub no_coherence: bool,
    /// Let exemplar neighbourhoods wrap around the exemplar (for tileable exemplars).
    #[arg(long)]
    pub exemplar_wrap: bool,
    /// Seed of the initial noise: the same seed gives the same output, bit for bit.
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub seed: u64,
    #[command(flatten)]
    pub map: MapArgs,
    /// Also write the coordinate map (16-bit RGB PNG: R = exemplar x, G = exemplar y, B = 0).
    #[arg(long, value_name = "FILE")]
    pub coords: Option<PathBuf>,
    /// Also write the report (sizes, options, timings, quality metrics) as JSON.
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
    /// Normal maps: also write the grown map's height (`.exr` float or `.png` 16-bit at midlevel
    /// 0.5), integrated periodically so that it tiles as the map does.
    #[arg(long, value_name = "FILE")]
    pub height: Option<PathBuf>,
    /// Size of an exemplar texel in millimetres, for `--height` (without it: texel widths).
    #[arg(long, value_name = "MM", value_parser = flags::positive_mm, requires = "height")]
    pub mm_per_texel: Option<f64>,
}

/// How maps are read and written: shared by `synth` and `synth replay`.
#[derive(clap::Args, Debug, Clone)]
pub struct MapArgs {
    /// What the maps hold: unit normals or linear colour.
    #[arg(long, value_enum, default_value_t = MapKind::Normal)]
    pub kind: MapKind,
    /// Green channel convention of normal maps read and written.
    #[arg(long, value_enum, default_value_t = Green::Up)]
    pub green: Green,
    /// How 8/16-bit colour values relate to light (colour maps only; outputs are linear).
    #[arg(long, value_enum, default_value_t = TransferArg::Linear)]
    pub transfer: TransferArg,
}

#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Copy a map of the exemplar's size through a coordinate map written by `synth --coords`.
    Replay(ReplayArgs),
}

#[derive(clap::Args, Debug)]
pub struct ReplayArgs {
    /// Coordinate map written by `skinkit synth --coords`.
    #[arg(long, value_name = "FILE")]
    pub coords: PathBuf,
    /// Map of the exemplar's size to copy (normal map, or colour with `--kind color`).
    #[arg(long, value_name = "MAP")]
    pub source: PathBuf,
    /// Output map (.png, 16-bit, or .exr).
    #[arg(long, value_name = "OUT")]
    pub out: PathBuf,
    #[command(flatten)]
    pub map: MapArgs,
}

/// Parses `WIDTHxHEIGHT` (`512x512`; `X` works too) into two positive sides.
/// A penalty, weight or scale of the matching: finite, from 0 to the library's
/// [`skinkit_synth::config::MAX_WEIGHT`].
fn weight(text: &str) -> Result<f32, String> {
    flags::number_in::<f32>(0.0, skinkit_synth::config::MAX_WEIGHT, "a weight")(text)
}

pub fn parse_size(text: &str) -> Result<(usize, usize), String> {
    let bad = || format!("`{text}` is not a size: expected WIDTHxHEIGHT with positive integers, e.g. 512x512");
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let side = |s: &str| s.trim().parse::<usize>().ok().filter(|&v| v > 0);
    match (side(w), side(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(bad()),
    }
}

/// An exemplar, a source or an output in memory.
pub(crate) enum Map {
    Normal(NormalMap),
    Color(ColorMap),
}

impl Map {
    fn size(&self) -> (usize, usize) {
        match self {
            Map::Normal(n) => n.size(),
            Map::Color(c) => c.size(),
        }
    }
}

impl MapArgs {
    fn encoding(&self) -> Result<NormalEncoding> {
        Ok(self.green.encoding())
    }

    fn is_color(&self) -> bool {
        self.kind == MapKind::Color
    }

    /// Reads a normal map, or a colour image as linear RGB (grey replicated).
    fn read(&self, path: &Path) -> Result<Map> {
        let limits = Limits::default();
        if !self.is_color() {
            let map = io::read_normal_map(path, self.encoding()?, &limits)
                .with_context(|| format!("cannot read normal map {}", path.display()))?;
            return Ok(Map::Normal(map));
        }
        let transfer = Transfer::from(self.transfer);
        let photo = io::read_photo(path, &limits)
            .with_context(|| format!("cannot read colour image {}", path.display()))?
            .with_transfer(transfer);
        let rgb = photo.channels() == Channels::Rgb;
        let color = Grid::from_fn(photo.width(), photo.height(), |x, y| {
            let i = y * photo.width() + x;
            if rgb {
                Vec3::new(photo.linear(3 * i), photo.linear(3 * i + 1), photo.linear(3 * i + 2))
            } else {
                Vec3::splat(photo.linear(i))
            }
        });
        Ok(Map::Color(color))
    }

    /// Adds `path` to the output set and writes `map` there.
    fn write(&self, set: &mut OutputSet, path: &Path, map: &Map) -> Result<()> {
        let encoding = self.encoding()?;
        set.write_file(path, |p| match map {
            Map::Normal(n) => io::write_normal_map(p, n, encoding, 16),
            Map::Color(c) => io::write_color_map(p, c, 16),
        })
        .with_context(|| format!("cannot write {}", path.display()))
    }
}

/// Refuses output names that are neither `.png` nor `.exr`, before any work is done.
fn check_map_extension(path: &Path) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if ext != "png" && ext != "exr" {
        return Err(guard::usage(format!("{}: output maps are written as .png (16-bit) or .exr", path.display())));
    }
    Ok(())
}

/// Refuses, before any work, outputs of the wrong kind and outputs that are the exemplar.
fn check_outputs(args: &Args, exemplar_path: &Path, out_path: &Path) -> Result<()> {
    check_map_extension(out_path)?;
    if let Some(coords) = &args.coords
        && coords.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() != Some("png")
    {
        let message = format!("{}: the coordinate map is written as a 16-bit PNG (.png)", coords.display());
        return Err(guard::usage(message));
    }
    let out_path = out_path.to_owned();
    if let Some(height) = &args.height {
        if args.map.is_color() {
            return Err(guard::usage(format!("{}: --height needs a normal map (--kind normal)", height.display())));
        }
        check_map_extension(height)?;
    }
    let outputs = [
        ("--out", Some(&out_path)),
        ("--coords", args.coords.as_ref()),
        ("--report", args.report.as_ref()),
        ("--height", args.height.as_ref()),
    ];
    guard::output_files(&guard::given(&outputs), &[("the exemplar".into(), exemplar_path.to_owned())])
}

/// What one synthesis gives: the map, its exemplar coordinates, warnings, seconds per level and
/// the guards' figures.
type Grown = (Map, Grid<[u32; 2]>, Vec<String>, Vec<f64>, Guards);

/// Grows `exemplar`, normals or colours, under `config`.
fn grow_map(exemplar: &Map, config: &SynthConfig, progress: &dyn Fn(usize, f32)) -> Result<Grown> {
    Ok(match exemplar {
        Map::Normal(n) => {
            let s = skinkit_synth::synthesize_normals(n, config, progress)?;
            (Map::Normal(s.normals), s.coords, s.warnings, s.level_seconds, s.guards)
        }
        Map::Color(c) => {
            let s = skinkit_synth::synthesize(c, config, progress)?;
            (Map::Color(s.texels), s.coords, s.warnings, s.level_seconds, s.guards)
        }
    })
}

/// The options as run, for the report.
#[derive(Clone, Debug, Serialize)]
pub struct OptionsReport {
    pub kind: String,
    pub levels_requested: usize,
    /// `scanline` (Wei-Levoy causal pass) or `upsampled` (Lefebvre-Hoppe coordinates).
    pub start: String,
    pub occurrence_penalty: f32,
    /// Occurrence penalty of the two coarsest levels (the larger of it and the general one).
    pub layout_penalty: f32,
    /// Largest verbatim copy allowed, share of the exemplar's area (`null`: no cap).
    pub copy_cap: Option<f32>,
    pub levels: usize,
    pub neighborhood: usize,
    pub parent: usize,
    pub corrections: usize,
    /// Correction passes at the coarser levels.
    pub coarse_corrections: usize,
    /// Seam-polishing passes at the finest level.
    pub polish: usize,
    /// Normal maps: weight of the coarser levels' detail channel (`null` for colour maps).
    pub detail_weight: Option<f32>,
    /// Scale of the coarser levels' robust distance (0: squared L2).
    pub robust_scale: f32,
    /// `exact`, `approximate` (PCA kd-tree) or `k-coherence (k = K)`.
    pub search: String,
    /// k-coherence: the tree fallback's ratio at the coarser levels and at the finest (`null`: no
    /// fallback).
    pub fallback: Option<f32>,
    pub finest_fallback: Option<f32>,
    /// k-coherence: the coherence bias at the coarser levels and at the finest.
    pub coherence_bias: f32,
    pub finest_coherence_bias: f32,
    pub dims: Option<usize>,
    pub rerank: Option<usize>,
    pub coherence: bool,
    pub exemplar_wrap: bool,
    pub seed: u64,
}

/// Quality of the output against its exemplar (see `skinkit_synth::metrics`).
#[derive(Clone, Debug, Serialize)]
pub struct QualityReport {
    /// Normal maps: mean Wasserstein-1 distance of the slope histograms (slope units).
    pub slope_distance: Option<f64>,
    /// Colour maps: mean Wasserstein-1 distance of the channel histograms.
    pub channel_distance: Option<f64>,
    /// Mean decades between the radial power spectra.
    pub spectrum_distance: f64,
    /// Squared differences across the output's wrap-around seam over interior ones (~1 tiles).
    pub seam_energy_ratio: f64,
    /// The same for the exemplar, for comparison.
    pub exemplar_seam_energy_ratio: f64,
    /// The collapse guard: the output's slope (normals) or channel (colour) standard deviation
    /// over the exemplar's, the smallest over axes or channels; under 0.5 a warning says the output
    /// may be nearly blank.
    pub variation: f64,
    /// The histogram guard: how far the output's slope or channel histograms are from the
    /// exemplar's, in the exemplar's deviations (Wasserstein-1 distance over deviation, mean over
    /// axes or channels); above 0.15, on outputs of at least 64x64 texels that have not collapsed,
    /// the output was grown again with an occurrence penalty.
    pub histogram_mismatch: f64,
    /// Whether the output is the histogram guard's second growth (kept because it came nearer).
    pub histogram_retry: bool,
    /// Texels of the largest verbatim copied block.
    pub largest_block: usize,
    /// Mean copied block size in texels.
    pub mean_block: f64,
    /// Distinct copy offsets.
    pub distinct_offsets: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct Seconds {
    /// Per pyramid level, `[0]` the finest.
    pub levels: Vec<f64>,
    /// Reading, synthesis, metrics and writing.
    pub total: f64,
}

/// What `--report` and `--json` hold.
#[derive(Clone, Debug, Serialize)]
pub struct SynthReport {
    pub exemplar: String,
    pub out: String,
    pub coords: Option<String>,
    pub exemplar_width: usize,
    pub exemplar_height: usize,
    pub width: usize,
    pub height: usize,
    pub options: OptionsReport,
    pub seconds: Seconds,
    pub warnings: Vec<String>,
    pub quality: QualityReport,
    /// Output texels that are the invalid marker (a normal map's zero normals, copied from the
    /// exemplar's invalid texels); above [`MAX_INVALID_OUTPUT`] of the map the run fails.
    pub invalid_texels: usize,
    /// The grown map's height (with `--height`): periodic, so it tiles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_map: Option<skinkit_height::HeightReport>,
}

/// The largest share of invalid texels a grown map may have and count as a result: beyond it
/// the map is written (to be looked at) but the run fails.
pub const MAX_INVALID_OUTPUT: f64 = 0.01;

pub fn run(args: Args, out: &Output) -> Result<i32> {
    match args.command {
        Some(Command::Replay(replay)) => run_replay(replay, out),
        None => run_synth(args, out),
    }
}

/// The library options the flags ask for.
fn config(args: &Args, (width, height): (usize, usize)) -> SynthConfig {
    let base = if args.scanline { SynthConfig::scanline(width, height) } else { SynthConfig::new(width, height) };
    SynthConfig {
        levels: args.levels.unwrap_or(base.levels),
        neighbourhood: args.neighborhood,
        parent: args.parent.unwrap_or(base.parent),
        corrections: args.corrections.unwrap_or(base.corrections),
        polish: args.polish.unwrap_or(base.polish),
        occurrence_penalty: args.occurrence_penalty.unwrap_or(base.occurrence_penalty),
        layout_penalty: args.layout_penalty.unwrap_or(base.layout_penalty),
        search: if args.exact {
            Search::Exact
        } else if args.pca {
            Search::Approximate { dims: args.dims, rerank: args.rerank }
        } else {
            let (k, fallback) = match base.search {
                Search::KCoherence { k, fallback, .. } => (args.k.unwrap_or(k), fallback),
                _ => (args.k.unwrap_or(Search::K_COHERENCE_K), None),
            };
            Search::KCoherence { k, fallback, dims: args.dims, rerank: args.rerank }
        },
        coherence: !args.no_coherence,
        exemplar_wrap: args.exemplar_wrap,
        copy_cap: args.copy_cap.or(base.copy_cap),
        detail_weight: args.detail_weight.unwrap_or(base.detail_weight),
        robust_scale: args.robust_scale.unwrap_or(base.robust_scale),
        seed: args.seed,
        ..base
    }
}

/// One progress bar per pyramid level, each created when its level starts.
struct LevelBars<'a> {
    out: &'a Output,
    current: RefCell<Option<(usize, ProgressBar)>>,
}

impl LevelBars<'_> {
    fn update(&self, level: usize, fraction: f32) {
        let mut current = self.current.borrow_mut();
        if current.as_ref().is_none_or(|(l, _)| *l != level) {
            if let Some((_, bar)) = current.take() {
                bar.finish();
            }
            *current = Some((level, self.out.progress(PROGRESS_STEPS, &format!("level {level}"))));
        }
        if let Some((_, bar)) = current.as_ref() {
            bar.set_position((fraction.clamp(0.0, 1.0) * PROGRESS_STEPS as f32).round() as u64);
        }
    }

    fn finish(&self) {
        if let Some((_, bar)) = self.current.borrow_mut().take() {
            bar.finish();
        }
    }
}

fn run_synth(args: Args, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let (Some(exemplar_path), Some(out_path), Some(size)) = (&args.exemplar, &args.out, args.size) else {
        bail!("synth needs EXEMPLAR, --out and --size");
    };
    check_outputs(&args, exemplar_path, out_path)?;
    // The synthesis estimate from the exemplar's header, before the exemplar is decoded.
    let header = skinkit_maps::limits::image_header(exemplar_path, skinkit_maps::limits::MAX_IMAGE_PIXELS)?;
    let requested = SynthConfig { memory_limit: out.memory_limit(), ..config(&args, size) };
    requested
        .validate(header.width as usize, header.height as usize)
        .with_context(|| format!("cannot synthesise from {}", exemplar_path.display()))?;
    let exemplar = args.map.read(exemplar_path)?;
    let (ew, eh) = exemplar.size();
    if args.coords.is_some() && (ew > MAX_COORD_SIDE || eh > MAX_COORD_SIDE) {
        bail!(
            "{}: exemplar {ew}x{eh} is too large for a 16-bit coordinate map (sides up to {MAX_COORD_SIDE})",
            exemplar_path.display()
        );
    }
    let context = || format!("cannot synthesise from {}", exemplar_path.display());
    let (validated, adjusted) = requested.validate(ew, eh).with_context(context)?;
    let bars = LevelBars { out, current: RefCell::new(None) };
    let progress = |level: usize, fraction: f32| bars.update(level, fraction);
    let (output, coords, warnings, level_seconds, guards) =
        grow_map(&exemplar, &requested, &progress).with_context(context)?;
    bars.finish();
    // The default level count adapts to the exemplar without a word; a `--levels` the exemplar
    // cannot hold is worth a warning (the report gives the levels used either way).
    for w in warnings.iter().filter(|w| args.levels.is_some() || !adjusted.contains(w)) {
        out.warn(w);
    }
    let quality = quality(&exemplar, &output, &coords, validated.exemplar_wrap, guards);
    let invalid_texels = match &output {
        Map::Normal(normals) => normals.as_slice().len() - normals.valid_count(),
        Map::Color(_) => 0,
    };
    // One set: the map, the coordinates and the report appear together or not at all.
    let mut set = OutputSet::files();
    args.map.write(&mut set, out_path, &output)?;
    if let Some(path) = &args.coords {
        let context = || format!("cannot write coordinate map {}", path.display());
        set.write_file(path, |p| encode_coords(p, &coords)).with_context(context)?;
    }
    let height_map = match (&args.height, &output) {
        (Some(path), Map::Normal(normals)) => Some(pipeline::grown_height(&mut set, path, normals, args.mm_per_texel)?),
        _ => None,
    };
    let report = SynthReport {
        height_map,
        exemplar: exemplar_path.display().to_string(),
        out: out_path.display().to_string(),
        coords: args.coords.as_ref().map(|p| p.display().to_string()),
        exemplar_width: ew,
        exemplar_height: eh,
        width: size.0,
        height: size.1,
        options: options_report(&args, &validated),
        seconds: Seconds { levels: level_seconds, total: start.elapsed().as_secs_f64() },
        warnings,
        quality,
        invalid_texels,
    };
    if let Some(path) = &args.report {
        pipeline::write_json_file(&mut set, path, &report)?;
    }
    out.swept(&set.commit().with_context(|| format!("cannot write {}", out_path.display()))?);
    out.result(&report, || human(&report));
    let share = invalid_texels as f64 / (size.0 * size.1).max(1) as f64;
    if share > MAX_INVALID_OUTPUT {
        out.error(&anyhow::anyhow!(
            "{}: {invalid_texels} of {} texels ({:.1}%) are invalid, more than the {}% a grown map may have: the \
             exemplar's invalid texels were copied; crop {} to its valid part",
            out_path.display(),
            size.0 * size.1,
            100.0 * share,
            100.0 * MAX_INVALID_OUTPUT,
            exemplar_path.display()
        ));
        return Ok(1);
    }
    Ok(0)
}

fn options_report(args: &Args, run: &SynthConfig) -> OptionsReport {
    let fallback = match run.search {
        Search::KCoherence { fallback, .. } => fallback,
        _ => None,
    };
    let (search, dims, rerank) = match run.search {
        Search::Exact => ("exact".to_owned(), None, None),
        Search::Approximate { dims, rerank } => ("approximate".to_owned(), Some(dims), Some(rerank)),
        Search::KCoherence { k, dims, rerank, .. } => (format!("k-coherence (k = {k})"), Some(dims), Some(rerank)),
        // Modes the flags cannot select yet (the library may grow more): named as the library does.
        #[allow(unreachable_patterns)]
        other => (format!("{other:?}"), None, None),
    };
    OptionsReport {
        kind: args.map.kind.name().to_owned(),
        levels_requested: args.levels.unwrap_or(if args.scanline {
            SynthConfig::scanline(0, 0).levels
        } else {
            SynthConfig::default().levels
        }),
        start: format!("{:?}", run.start).to_lowercase(),
        occurrence_penalty: run.occurrence_penalty,
        layout_penalty: run.layout_penalty,
        copy_cap: run.copy_cap,
        levels: run.levels,
        neighborhood: run.neighbourhood,
        parent: run.parent,
        corrections: run.corrections,
        coarse_corrections: run.coarse_corrections.unwrap_or(run.corrections),
        polish: run.polish,
        detail_weight: (!args.map.is_color()).then_some(run.detail_weight),
        robust_scale: run.robust_scale,
        search,
        fallback,
        finest_fallback: run.finest_fallback.or(fallback),
        coherence_bias: run.coherence_bias,
        finest_coherence_bias: run.finest_coherence_bias.unwrap_or(run.coherence_bias),
        dims,
        rerank,
        coherence: run.coherence,
        exemplar_wrap: run.exemplar_wrap,
        seed: run.seed,
    }
}

/// The quality metrics of an output against its exemplar (slopes or channels, spectrum, tiling,
/// copied blocks), with the synthesis's own guard figures.
pub(crate) fn quality(
    exemplar: &Map,
    output: &Map,
    coords: &Grid<[u32; 2]>,
    wrap: bool,
    guards: Guards,
) -> QualityReport {
    let bins = DEFAULT_SPECTRUM_BINS;
    let copies = metrics::copy_statistics(coords, exemplar.size(), wrap);
    let (slope, channel, spectrum, seam, exemplar_seam) = match (exemplar, output) {
        (Map::Normal(e), Map::Normal(o)) => (
            Some(metrics::slope_distance(o, e)),
            None,
            metrics::normal_spectrum_distance(o, e, bins),
            metrics::normal_seam_energy(o).ratio,
            metrics::normal_seam_energy(e).ratio,
        ),
        (Map::Color(e), Map::Color(o)) => (
            None,
            Some(metrics::channel_distance(o, e)),
            metrics::color_spectrum_distance(o, e, bins),
            metrics::seam_energy(o).ratio,
            metrics::seam_energy(e).ratio,
        ),
        _ => unreachable!("the output has the exemplar's kind"),
    };
    QualityReport {
        slope_distance: slope,
        channel_distance: channel,
        spectrum_distance: spectrum,
        seam_energy_ratio: seam,
        exemplar_seam_energy_ratio: exemplar_seam,
        variation: guards.variation,
        histogram_mismatch: guards.histogram,
        histogram_retry: guards.histogram_retry,
        largest_block: copies.largest_block,
        mean_block: copies.mean_block,
        distinct_offsets: copies.distinct_offsets,
    }
}

fn human(r: &SynthReport) -> String {
    let q = &r.quality;
    let histogram = match (q.slope_distance, q.channel_distance) {
        (Some(d), _) => format!("slope distance {d:.4}"),
        (_, Some(d)) => format!("channel distance {d:.4}"),
        _ => String::new(),
    };
    let retry = if q.histogram_retry { " (grown twice: the histogram guard)" } else { "" };
    format!(
        "{}: {}x{} from {}x{} in {} levels, {:.2} s\n{histogram}{retry}, spectrum distance {:.3}, variation {:.2} of \
         the exemplar's, seam ratio {:.2} (exemplar {:.2}), largest copied block {} texels, mean {:.1}",
        r.out,
        r.width,
        r.height,
        r.exemplar_width,
        r.exemplar_height,
        r.options.levels,
        r.seconds.total,
        q.spectrum_distance,
        q.variation,
        q.seam_energy_ratio,
        q.exemplar_seam_energy_ratio,
        q.largest_block,
        q.mean_block
    )
}

/// Writes a coordinate map: 16-bit RGB PNG, R = exemplar x, G = exemplar y, B = 0.
pub(crate) fn write_coords(path: &Path, coords: &Grid<[u32; 2]>) -> Result<()> {
    encode_coords(path, coords).with_context(|| format!("cannot write coordinate map {}", path.display()))
}

fn encode_coords(path: &Path, coords: &Grid<[u32; 2]>) -> skinkit_maps::Result<()> {
    let (w, h) = coords.size();
    io::write_png_rows(path, w, h, PngLayout::Rgb16, io::PngColour::Linear, |y, row| {
        for (px, c) in row.chunks_exact_mut(3).zip(coords.row(y)) {
            // Sides were checked against MAX_COORD_SIDE, so coordinates fit.
            px.copy_from_slice(&[c[0] as u16, c[1] as u16, 0]);
        }
    })
}

/// Reads a coordinate map written by [`write_coords`].
fn read_coords(path: &Path) -> Result<Grid<[u32; 2]>> {
    let photo = io::read_photo(path, &Limits::default())
        .with_context(|| format!("cannot read coordinate map {}", path.display()))?;
    let (Channels::Rgb, Samples::U16(samples)) = (photo.channels(), photo.samples()) else {
        bail!(
            "{}: not a coordinate map (expected a 16-bit RGB PNG from `skinkit synth --coords`, got {}-bit {:?})",
            path.display(),
            photo.bit_depth(),
            photo.channels()
        );
    };
    let texels = samples.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32]).collect();
    Ok(Grid::from_vec(photo.width(), photo.height(), texels)?)
}

/// What `synth replay --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct ReplayReport {
    pub coords: String,
    pub source: String,
    pub out: String,
    pub kind: String,
    pub width: usize,
    pub height: usize,
    pub seconds: f64,
}

fn run_replay(args: ReplayArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    check_map_extension(&args.out)?;
    let inputs = [("the coordinate map".into(), args.coords.clone()), ("the source map".into(), args.source.clone())];
    guard::output_files(&[("--out", args.out.as_path())], &inputs)?;
    let coords = read_coords(&args.coords)?;
    let source = args.map.read(&args.source)?;
    let (sw, sh) = source.size();
    let context = || {
        format!(
            "cannot replay {} on {} ({sw}x{sh}): the source must have the exemplar's size",
            args.coords.display(),
            args.source.display()
        )
    };
    let replayed = match &source {
        Map::Normal(n) => {
            let grid = skinkit_synth::replay(&coords, n.grid()).with_context(context)?;
            Map::Normal(NormalMap::from_unit_grid(grid)?)
        }
        Map::Color(c) => Map::Color(skinkit_synth::replay(&coords, c).with_context(context)?),
    };
    let mut set = OutputSet::files();
    args.map.write(&mut set, &args.out, &replayed)?;
    out.swept(&set.commit().with_context(|| format!("cannot write {}", args.out.display()))?);
    let (width, height) = coords.size();
    let report = ReplayReport {
        coords: args.coords.display().to_string(),
        source: args.source.display().to_string(),
        out: args.out.display().to_string(),
        kind: args.map.kind.name().to_owned(),
        width,
        height,
        seconds: start.elapsed().as_secs_f64(),
    };
    out.result(&report, || format!("{}: {width}x{height} replayed from {}", report.out, report.source));
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_and_bad_ones_explain_the_format() {
        assert_eq!(parse_size("512x256"), Ok((512, 256)));
        assert_eq!(parse_size("7X3"), Ok((7, 3)));
        for bad in ["512", "0x4", "ax4", "4x", "-1x3", "4x4x4"] {
            let e = parse_size(bad).unwrap_err();
            assert!(e.contains(bad) && e.contains("WIDTHxHEIGHT"), "{bad}: {e}");
        }
    }
}
