//! `skinkit synth`: grow a normal or colour map from an exemplar by Wei-Levoy multiresolution
//! synthesis (Haro et al. 2001, section 4.1; issue 3), and `skinkit synth replay`: copy another map
//! of the exemplar's size (an albedo registered with the normals) through the coordinate map of a
//! run, so it stays in register with the synthesised output.
//!
//! The coordinate map is a 16-bit RGB PNG of the output's size: red holds the exemplar column
//! (x, 0 at the left) and green the exemplar row (y, 0 at the top) of the texel each output texel
//! copies; blue is 0. Exemplars wider or taller than 65535 texels cannot be described this way and
//! are refused when `--coords` is asked for.

use skinkit_maps::format::ImageFormat;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::Serialize;
use skinkit_maps::OutputSet;
use skinkit_maps::io::Limits;
use skinkit_maps::{NormalEncoding, Transfer};
use skinkit_synth::{Delivery, Grown, Map, OptionsReport, QualityReport, Search, SynthConfig, coords};

use crate::flags::{self, Green, MapKind, TransferArg};
use crate::output::Output;
use crate::pipeline;

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
    #[arg(long, value_name = "WxH", value_parser = flags::parse_size, required = true)]
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
    /// and Hoppe 2005). Slower, and higher in energy on every exemplar of the book's suite.
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

impl MapArgs {
    fn encoding(&self) -> Result<NormalEncoding> {
        Ok(self.green.encoding())
    }

    fn is_color(&self) -> bool {
        self.kind == MapKind::Color
    }

    /// What a map of this kind is, in errors: `the normal map` or `the colour image`.
    fn role(&self) -> &'static str {
        if self.is_color() { "the colour image" } else { "the normal map" }
    }

    /// Reads a normal map, or a colour image as linear RGB (grey replicated).
    fn read(&self, path: &Path) -> Result<Map> {
        let limits = Limits::default();
        let map = if self.is_color() {
            Map::read_color(path, Transfer::from(self.transfer), &limits)
        } else {
            Map::read_normals(path, self.encoding()?, &limits)
        };
        map.with_context(|| format!("cannot read {}", self.role()))
    }

    /// Adds `path` to the output set and writes `map` there; an error names the map's role.
    fn write(&self, set: &mut OutputSet, path: &Path, map: &Map) -> Result<()> {
        let encoding = self.encoding()?;
        set.write_file(path, |p| map.write(p, encoding)).with_context(|| format!("cannot write {}", self.role()))
    }
}

/// Refuses output names that are neither `.png` nor `.exr`, before any work is done.
fn check_map_extension(path: &Path) -> Result<()> {
    if !ImageFormat::is_one_of(path, &[ImageFormat::Png, ImageFormat::Exr]) {
        return Err(crate::output::usage(format!(
            "{}: output maps are written as .png (16-bit) or .exr",
            path.display()
        )));
    }
    Ok(())
}

/// Refuses, before any work, outputs of the wrong kind and outputs that are the exemplar.
fn check_outputs(args: &Args, exemplar_path: &Path, out_path: &Path) -> Result<()> {
    check_map_extension(out_path)?;
    if let Some(coords) = &args.coords
        && ImageFormat::of(coords) != Some(ImageFormat::Png)
    {
        let message = format!("{}: the coordinate map is written as a 16-bit PNG (.png)", coords.display());
        return Err(crate::output::usage(message));
    }
    let out_path = out_path.to_owned();
    if let Some(height) = &args.height {
        if args.map.is_color() {
            return Err(crate::output::usage(format!(
                "{}: --height needs a normal map (--kind normal)",
                height.display()
            )));
        }
        check_map_extension(height)?;
    }
    let outputs = [
        ("--out", Some(&out_path)),
        ("--coords", args.coords.as_ref()),
        ("--report", args.report.as_ref()),
        ("--height", args.height.as_ref()),
    ];
    Ok(skinkit_maps::gate::output_files(
        &skinkit_maps::gate::given(&outputs),
        &[("the exemplar".into(), exemplar_path.to_owned())],
    )?)
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
    /// What [`SynthConfig::memory_estimate`] gave for the run (the job is refused when it exceeds
    /// `--memory-limit`), and the process's peak resident memory where the platform tells it.
    pub memory_estimate_mib: u64,
    pub peak_memory_mib: Option<f64>,
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

fn run_synth(args: Args, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let (Some(exemplar_path), Some(out_path), Some(size)) = (&args.exemplar, &args.out, args.size) else {
        bail!("synth needs EXEMPLAR, --out and --size");
    };
    check_outputs(&args, exemplar_path, out_path)?;
    // The synthesis estimate from the exemplar's header, before the exemplar is decoded.
    let header = skinkit_maps::limits::image_header(exemplar_path, skinkit_maps::limits::MAX_IMAGE_PIXELS)?;
    // `--height` grows the map whole (its integration is global); otherwise it is streamed.
    let delivery = match args.height {
        Some(_) => Delivery::Whole,
        None => Delivery::Streamed { coords: args.coords.is_some() },
    };
    let requested = SynthConfig { memory_limit: out.memory_limit(), delivery, ..config(&args, size) };
    requested.validate(header.width as usize, header.height as usize).with_context(|| synthesis_context(&args))?;
    let exemplar = args.map.read(exemplar_path)?;
    let (ew, eh) = exemplar.size();
    if args.coords.is_some() && (ew > coords::MAX_COORD_SIDE || eh > coords::MAX_COORD_SIDE) {
        bail!(
            "{}: exemplar {ew}x{eh} is too large for a 16-bit coordinate map (sides up to {})",
            exemplar_path.display(),
            coords::MAX_COORD_SIDE
        );
    }
    let (validated, adjusted) = requested.validate(ew, eh).with_context(|| synthesis_context(&args))?;
    let bars = out.stage_bars();
    // One set: the map, the coordinates and the report appear together or not at all.
    let mut set = OutputSet::files();
    let grown = match &args.height {
        Some(height) => grow_whole(&args, &exemplar, &requested, (&mut set, height), &bars),
        None => grow_streamed(&args, &exemplar, &requested, &mut set, &bars),
    }?;
    let Outcome { warnings, level_seconds, quality, invalid_texels, height_map } = grown;
    // The default level count adapts to the exemplar without a word; a `--levels` the exemplar
    // cannot hold is worth a warning (the report gives the levels used either way).
    for w in warnings.iter().filter(|w| args.levels.is_some() || !adjusted.contains(w)) {
        out.warn(w);
    }
    let report = SynthReport {
        height_map,
        exemplar: exemplar_path.display().to_string(),
        out: out_path.display().to_string(),
        coords: args.coords.as_ref().map(|p| p.display().to_string()),
        exemplar_width: ew,
        exemplar_height: eh,
        width: size.0,
        height: size.1,
        options: OptionsReport::new(&validated, args.map.kind.name(), levels_requested(&args)),
        seconds: Seconds { levels: level_seconds, total: start.elapsed().as_secs_f64() },
        warnings,
        quality,
        invalid_texels,
        memory_estimate_mib: skinkit_maps::limits::mib(validated.memory_estimate(ew, eh)),
        peak_memory_mib: skinkit_maps::limits::peak_resident_mib(),
    };
    if let Some(path) = &args.report {
        pipeline::write_json_file(&mut set, path, "the synthesis report", &report)?;
    }
    out.swept(&set.commit().context("cannot finish writing the synthesis outputs")?);
    out.result(&report, || human(&report));
    Ok(invalid_exit(out, out_path, exemplar_path, invalid_texels, size))
}

/// What a failed growth's error says first.
fn synthesis_context(args: &Args) -> String {
    let exemplar = args.exemplar.as_deref().expect("checked by run_synth");
    format!("cannot synthesise from {}", exemplar.display())
}

/// What a growth gave, whichever way its outputs were written.
struct Outcome {
    warnings: Vec<String>,
    level_seconds: Vec<f64>,
    quality: QualityReport,
    invalid_texels: usize,
    height_map: Option<skinkit_height::HeightReport>,
}

/// Grows the map into its files as its bands finish (`skinkit_synth::deliver`): the whole output
/// is never held, so a 16K map fits where its pyramid would not.
fn grow_streamed(
    args: &Args,
    exemplar: &Map,
    config: &SynthConfig,
    set: &mut OutputSet,
    bars: &dyn skinkit_maps::progress::Progress,
) -> Result<Outcome> {
    let out_path = args.out.as_deref().expect("checked by run_synth");
    let coords_role = || "cannot write the coordinate map";
    let files = skinkit_synth::deliver::Files {
        map: set.file(out_path).with_context(|| format!("cannot write {}", args.map.role()))?,
        encoding: args.map.encoding()?,
        coords: args.coords.as_deref().map(|p| set.file(p)).transpose().with_context(coords_role)?,
    };
    // A write's error names the output's role and its final path; any other is the growth's.
    let d = skinkit_synth::deliver::grow_into_files(exemplar, config, bars, &files).map_err(|e| match e {
        skinkit_synth::Error::Write { output, source } => {
            anyhow::Error::new(skinkit_synth::Error::Write { output, source: set.unstage_error(source) })
        }
        other => anyhow::Error::new(other).context(synthesis_context(args)),
    })?;
    let skinkit_synth::deliver::Delivered { warnings, level_seconds, quality, invalid_texels, .. } = d;
    Ok(Outcome { warnings, level_seconds, quality, invalid_texels, height_map: None })
}

/// Grows the map whole, for `--height`: the integration of the grown normals into heights is
/// global, so it needs the whole map.
fn grow_whole(
    args: &Args,
    exemplar: &Map,
    config: &SynthConfig,
    (set, height): (&mut OutputSet, &Path),
    bars: &dyn skinkit_maps::progress::Progress,
) -> Result<Outcome> {
    let out_path = args.out.as_deref().expect("checked by run_synth");
    let Grown { map: output, coords, warnings, level_seconds, guards } =
        exemplar.grow(config, bars).with_context(|| synthesis_context(args))?;
    let wrap = config.exemplar_wrap;
    let quality =
        QualityReport::new(exemplar, &output, &coords, wrap, guards).expect("the output has the exemplar's kind");
    let invalid_texels = output.invalid_texels();
    args.map.write(set, out_path, &output)?;
    if let Some(path) = &args.coords {
        let context = || "cannot write the coordinate map";
        set.write_file(path, |p| coords::write(p, &coords)).with_context(context)?;
    }
    let height_map = match &output {
        Map::Normal(normals) => Some(pipeline::grown_height(set, height, normals, args.mm_per_texel)?),
        Map::Color(_) => None,
    };
    Ok(Outcome { warnings, level_seconds, quality, invalid_texels, height_map })
}

/// The exit code of a grown map with `invalid` invalid texels: 1 with an error naming both files
/// when more than [`MAX_INVALID_OUTPUT`] of it is invalid (the map is written, to be looked at).
fn invalid_exit(
    out: &Output,
    out_path: &Path,
    exemplar_path: &Path,
    invalid_texels: usize,
    size: (usize, usize),
) -> i32 {
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
        return 1;
    }
    0
}

/// The level count asked for: `--levels`, or the default of the start chosen.
fn levels_requested(args: &Args) -> usize {
    args.levels.unwrap_or(if args.scanline {
        SynthConfig::scanline(0, 0).levels
    } else {
        SynthConfig::default().levels
    })
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
    skinkit_maps::gate::output_files(&[("--out", args.out.as_path())], &inputs)?;
    let coords = coords::read(&args.coords)?;
    let source = args.map.read(&args.source)?;
    let (sw, sh) = source.size();
    let context = || {
        format!(
            "cannot replay {} on {} ({sw}x{sh}): the source must have the exemplar's size",
            args.coords.display(),
            args.source.display()
        )
    };
    let replayed = source.replay(&coords).with_context(context)?;
    let mut set = OutputSet::files();
    args.map.write(&mut set, &args.out, &replayed)?;
    out.swept(&set.commit().context("cannot finish writing the replayed map")?);
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
