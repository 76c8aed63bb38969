//! `skinkit stitch` and `skinkit face`: one synthesis per face region, joined by a multiresolution
//! spline along random curves (Haro et al. 2001, section 4.2; issue 4).
//!
//! `stitch` writes one map (and, if asked, the labels and a report); `face` writes a folder with
//! the map as 16-bit PNG and float EXR, the labels, every region's exemplar at the map's scale and
//! the report. Both capture the regions that name a photo session first (robust solver, detrend
//! block 50), in memory.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::Serialize;
use skinkit_maps::io::{self, Limits, PngLayout};
use skinkit_maps::{Grid, NormalEncoding, NormalMap, OutputSet};
use skinkit_stitch::compose::{ComposeSeconds, NO_REGION, RegionReport};
use skinkit_stitch::curve::CurveParams;
use skinkit_stitch::layout::{ExemplarSource, Layout};
use skinkit_stitch::seam::SeamReport;
use skinkit_stitch::{ComposeOptions, compose};
use skinkit_synth::SynthConfig;

use skinkit_capture::session::{self, Session};

use crate::flags;
use crate::output::Output;
use crate::solve_flags::{SolveArgs, SolverArg};
use crate::{guard, pipeline};

/// Options shared by `stitch` and `face`.
#[derive(clap::Args, Debug, Clone)]
pub struct StitchOptions {
    /// The face layout (TOML): size, scale, regions with exemplars and seed points.
    #[arg(long, value_name = "FILE")]
    pub layout: PathBuf,
    /// Output size (overrides the layout's; points keep their UV place, the scale follows; at
    /// most 2^30 texels).
    #[arg(long, value_parser = flags::map_size, value_name = "WxH")]
    pub size: Option<(usize, usize)>,
    /// Seed of the curves and of every region's synthesis.
    #[arg(long, default_value_t = 0, value_name = "S")]
    pub seed: u64,
    /// Spline levels (1 to 20; default: from the narrowest region, at most 6).
    #[arg(long, value_name = "L", value_parser = flags::usize_in(1, skinkit_stitch::spline::MAX_LEVELS))]
    pub levels: Option<usize>,
    /// Largest displacement of the random boundary curves, texels (default 64 at 4096 wide,
    /// scaled with the map).
    #[arg(long, value_name = "A", conflicts_with = "straight", value_parser = flags::number_in::<f64>(0.0, 32768.0, "an amplitude in texels"))]
    pub curve_amplitude: Option<f64>,
    /// Straight boundaries (the nearest-point partition as it is).
    #[arg(long)]
    pub straight: bool,
    /// No spline: every texel from its own region (hard boundaries).
    #[arg(long)]
    pub no_blend: bool,
    /// Band width of the seam metric, texels (1 to 256).
    #[arg(long, default_value_t = 4, value_name = "W", value_parser = flags::usize_in(1, 256))]
    pub seam_band: usize,
    /// Grow every region with the scanline start (`skinkit synth --scanline`: sequential, slower,
    /// higher in energy) instead of the default's upsampled coordinates.
    #[arg(long)]
    pub scanline: bool,
    /// The default since the upsampled start became it; accepted so older scripts still run.
    #[arg(long, hide = true, conflicts_with = "scanline")]
    pub upsampled: bool,
    /// The user's own head mesh (.obj, .gltf, .glb; overrides the layout's `mesh`): seed points
    /// may be 3-D `positions` on it, and each region's mm per texel is measured from its surface
    /// area against its UV area.
    #[arg(long, value_name = "FILE")]
    pub mesh: Option<PathBuf>,
    /// Millimetres per mesh unit (overrides the layout's `mm_per_unit`): 10 for centimetres,
    /// 1000 for metres.
    #[arg(long, value_name = "MM", value_parser = flags::positive_mm)]
    pub mm_per_unit: Option<f64>,
}

impl StitchOptions {
    /// The command's defaults for `layout` (its own size, seed 0, the default spline and curves),
    /// what `demo` and face batches stitch with.
    pub fn for_layout(layout: PathBuf) -> Self {
        StitchOptions {
            layout,
            size: None,
            seed: 0,
            levels: None,
            curve_amplitude: None,
            straight: false,
            no_blend: false,
            seam_band: 4,
            scanline: false,
            upsampled: false,
            mesh: None,
            mm_per_unit: None,
        }
    }
}

#[derive(clap::Args, Debug)]
pub struct StitchArgs {
    #[command(flatten)]
    pub options: StitchOptions,
    /// The face normal map (.png: 16-bit, .exr: float).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Also write the region labels (8-bit RGB PNG, one colour per region, black outside coverage).
    #[arg(long, value_name = "FILE")]
    pub labels: Option<PathBuf>,
    /// Also write the report (JSON).
    #[arg(long, value_name = "FILE")]
    pub report: Option<PathBuf>,
}

#[derive(clap::Args, Debug)]
pub struct FaceArgs {
    #[command(flatten)]
    pub options: StitchOptions,
    /// Output folder.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
}

/// Seconds per stage of a face.
#[derive(Clone, Debug, Default, Serialize)]
pub struct FaceSeconds {
    /// Reading exemplar maps and capturing sessions.
    pub exemplars: f64,
    #[serde(flatten)]
    pub compose: ComposeSeconds,
    pub write: f64,
    /// Integrating the face's height and writing its files (beside the normal maps' writing).
    pub height: f64,
    pub total: f64,
}

/// What `--report`, `--json` and `face`'s report.json hold.
#[derive(Clone, Debug, Serialize)]
pub struct FaceReport {
    pub layout: String,
    pub out: String,
    pub width: usize,
    pub height: usize,
    pub mm_per_texel: f64,
    pub levels: usize,
    pub curve_amplitude: f64,
    pub blend: bool,
    /// How the regions were grown: `upsampled` (the default) or `scanline`.
    pub start: String,
    pub seed: u64,
    pub regions: Vec<RegionReport>,
    /// On a mesh over several UDIM tiles: their numbers (one `normal.<tile>.png` each; `width x
    /// height` and the height files are then the tiles' atlas, side by side, higher v on top).
    pub udim_tiles: Option<Vec<u32>>,
    /// Regions grown at once: all, or 1 when their estimates do not fit `--memory-limit` together.
    pub regions_at_once: usize,
    pub seams: SeamReport,
    pub seconds: FaceSeconds,
    /// The face's height in mm (height.exr, height.png, cavity.png, bands.exr).
    pub height_map: Option<FaceHeight>,
    pub peak_memory_mib: Option<f64>,
}

/// A stitched face in memory, with what the report needs.
pub struct Face {
    pub layout: Layout,
    pub exemplars: Vec<NormalMap>,
    pub composed: skinkit_stitch::Composed,
    pub amplitude: f64,
    pub seconds_exemplars: f64,
}

/// Captured sessions by folder, so a mold used by several regions (or already captured by the
/// demo) is captured once.
pub type CaptureCache = BTreeMap<PathBuf, NormalMap>;

pub fn run_stitch(args: StitchArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    check_extension(&args.out, &["png", "exr"])?;
    if let Some(labels) = &args.labels {
        check_extension(labels, &["png"])?;
    }
    let given = [("--out", Some(&args.out)), ("--labels", args.labels.as_ref()), ("--report", args.report.as_ref())];
    let outputs = guard::given(&given);
    for (flag, path) in &outputs {
        guard::out_file(flag, path)?;
    }
    let check = |layout: &Layout| guard::not_an_input(&outputs, &layout_inputs(layout));
    let face = build(&args.options, &mut CaptureCache::new(), out, &check)?;
    let t = Instant::now();
    // One set: the map, the labels and the report appear together or not at all.
    let mut set = OutputSet::files();
    let written = |path: &Path| format!("cannot write {}", path.display());
    set.write_file(&args.out, |p| encode_map(p, &face.composed.normals)).with_context(|| written(&args.out))?;
    if let Some(path) = &args.labels {
        set.write_file(path, |p| encode_labels(p, &face.composed.labels)).with_context(|| written(path))?;
    }
    let report = report(&args.options, &face, &args.out, t.elapsed().as_secs_f64(), start);
    if let Some(path) = &args.report {
        pipeline::write_json_file(&mut set, path, &report)?;
    }
    out.swept(&set.commit().with_context(|| written(&args.out))?);
    out.result(&report, || human(&report));
    Ok(0)
}

pub fn run_face(args: FaceArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let report = face_to_dir(&args.options, &args.out, &mut CaptureCache::new(), out, start)?;
    out.result(&report, || human(&report));
    Ok(0)
}

/// The files a layout reads, named for messages.
fn layout_inputs(layout: &Layout) -> Vec<(String, PathBuf)> {
    let mut inputs = vec![("the layout".to_owned(), layout.origin.clone())];
    inputs.extend(layout.coverage.iter().map(|p| ("the coverage mask".to_owned(), p.clone())));
    for region in &layout.regions {
        if let ExemplarSource::NormalMap(path) = &region.exemplar {
            inputs.push((format!("region `{}`'s exemplar", region.name), path.clone()));
        }
    }
    inputs
}

/// `face --out`: refused when a file it writes is an input or it lies in a session folder.
fn check_face_out(dir: &Path, layout: &Layout) -> Result<()> {
    for region in &layout.regions {
        if let ExemplarSource::Session(session) = &region.exemplar {
            guard::not_in_input_folder("--out", dir, &format!("region `{}`'s session folder", region.name), session)?;
        }
    }
    let mut files: Vec<PathBuf> = ["normal.png", "normal.exr", "labels.png", "report.json"]
        .iter()
        .chain(&FACE_HEIGHT_FILES)
        .map(|f| dir.join(f))
        .collect();
    files.extend(layout.regions.iter().map(|r| dir.join("exemplars").join(format!("{}.png", r.name))));
    let outputs: Vec<(&str, &Path)> = files.iter().map(|f| ("--out", f.as_path())).collect();
    guard::not_an_input(&outputs, &layout_inputs(layout))
}

/// The height files of a face folder.
const FACE_HEIGHT_FILES: [&str; 4] = ["height.exr", "height.png", "cavity.png", "bands.exr"];

/// Builds a face and writes its folder: normal.png (16-bit), normal.exr, labels.png, the height
/// files (height.exr in mm, height.png at midlevel 0.5, cavity.png, bands.exr),
/// `exemplars/<region>.png` and report.json, as one output set (all or nothing, report last).
pub fn face_to_dir(
    options: &StitchOptions,
    dir: &Path,
    cache: &mut CaptureCache,
    out: &Output,
    start: Instant,
) -> Result<FaceReport> {
    guard::out_folder("--out", dir)?;
    // Staged before the work, so an interrupt during it removes the staging folder.
    let set = OutputSet::folder(dir, "report.json").with_context(|| format!("cannot write {}", dir.display()))?;
    let face = build(options, cache, out, &|layout: &Layout| check_face_out(dir, layout))?;
    let t = Instant::now();
    let map = &face.composed.normals;
    let (normals, height) = rayon::join(
        || write_normals(&set, dir, &face.layout, map),
        || write_height(&set, dir, map, face.layout.mm_per_texel, &face.composed.labels),
    );
    normals?;
    let (height, height_seconds) = height?;
    write_in(&set, dir, "labels.png", |p| encode_labels(p, &face.composed.labels))?;
    for (region, ex) in face.layout.regions.iter().zip(&face.exemplars) {
        write_in(&set, dir, &format!("exemplars/{}.png", region.name), |p| encode_map(p, ex))?;
    }
    let mut report = report(options, &face, &dir.join("normal.png"), t.elapsed().as_secs_f64(), start);
    report.height_map = Some(height);
    report.seconds.height = height_seconds;
    pipeline::write_json_in(&set, "report.json", &dir.join("report.json"), &report)?;
    out.swept(&set.commit().with_context(|| format!("cannot write {}", dir.display()))?);
    Ok(report)
}

/// The face's normal map as normal.png (16-bit) and normal.exr, or on a mesh over several UDIM
/// tiles one pair per tile, `normal.<tile>.png` and `.exr` ([`skinkit_stitch::udim`]).
fn write_normals(set: &OutputSet, dir: &Path, layout: &Layout, map: &NormalMap) -> Result<()> {
    let Some(atlas) = layout.atlas.as_ref().filter(|a| !a.is_single_1001()) else {
        write_in(set, dir, "normal.png", |p| encode_map(p, map))?;
        return write_in(set, dir, "normal.exr", |p| encode_map(p, map));
    };
    for (tile, grid) in atlas.split(map.grid())? {
        let tile_map = NormalMap::from_unit_grid(grid)?;
        for ext in ["png", "exr"] {
            write_in(set, dir, &format!("normal.{tile}.{ext}"), |p| encode_map(p, &tile_map))?;
        }
    }
    Ok(())
}

/// What a face's height files hold: the integration's report and how to load height.png.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FaceHeight {
    #[serde(flatten)]
    pub height: skinkit_height::HeightReport,
    pub png: skinkit_height::deliver::PngScale,
    /// The height's own normals against the face's normal map (through the same central
    /// differences), overall and on the regions' seams against off them.
    pub round_trip: skinkit_height::round_trip::Agreement,
}

/// Integrates the face's normals (Neumann: a face map does not wrap) into millimetres and writes
/// its height files ([`FACE_HEIGHT_FILES`]; the EXRs ZIP-compressed, since face maps are large).
/// Returns the files' report and the seconds they took (integrate, split, write).
fn write_height(
    set: &OutputSet,
    dir: &Path,
    map: &NormalMap,
    mm_per_texel: f64,
    labels: &Grid<u16>,
) -> Result<(FaceHeight, f64)> {
    use skinkit_height::deliver::{self, ExrStorage};
    let t = Instant::now();
    let scale = skinkit_height::Scale::from_mm(Some(mm_per_texel))?;
    let options = skinkit_height::HeightOptions { scale, ..Default::default() };
    let height = skinkit_height::integrate(map, &options).context("cannot integrate the face's normals")?;
    let storage = ExrStorage { zip: true, half: false };
    let h = pipeline::height_error;
    write_in(set, dir, "height.exr", |p| deliver::write_exr(p, &height, storage).map_err(h))?;
    let mut png = None;
    write_in(set, dir, "height.png", |p| deliver::write_png16(p, &height).map(|s| png = Some(s)).map_err(h))?;
    let bands = deliver::bands(&height);
    write_in(set, dir, "bands.exr", |p| deliver::write_bands_exr(p, &height, &bands, storage).map_err(h))?;
    let cavity = deliver::cavity(&bands);
    write_in(set, dir, "cavity.png", |p| deliver::write_cavity_png(p, &cavity).map_err(h))?;
    let png = png.expect("write_png16 returned its scale");
    let round_trip = skinkit_height::round_trip::height_agreement(map, &height, false, Some(labels));
    Ok((FaceHeight { height: height.report, png, round_trip }, t.elapsed().as_secs_f64()))
}

/// Writes `name` of the folder set `set` (destined for `dir`), naming the final path in errors.
fn write_in(
    set: &OutputSet,
    dir: &Path,
    name: &str,
    write: impl FnOnce(&Path) -> skinkit_maps::Result<()>,
) -> Result<()> {
    set.write(name, write).with_context(|| format!("cannot write {}", dir.join(name).display()))
}

/// Loads the layout, runs `check` on it (outputs against inputs, before any work), reads or
/// captures every exemplar and stitches.
pub fn build(
    options: &StitchOptions,
    cache: &mut CaptureCache,
    out: &Output,
    check: &dyn Fn(&Layout) -> Result<()>,
) -> Result<Face> {
    let mut layout = Layout::load(&options.layout)?;
    check(&layout)?;
    if let Some((w, h)) = options.size {
        layout = layout.with_size(w, h)?;
    }
    layout = on_mesh(layout, options, out)?;
    layout.check_placed()?;
    let amplitude = if options.straight {
        0.0
    } else {
        options.curve_amplitude.unwrap_or_else(|| ComposeOptions::default_amplitude(layout.width))
    };
    let synth = if options.scanline { SynthConfig::scanline(0, 0) } else { SynthConfig::default() };
    let compose_options = ComposeOptions {
        curve: CurveParams::new(amplitude, options.seed),
        levels: options.levels,
        blend: !options.no_blend,
        synth: SynthConfig { memory_limit: out.memory_limit(), ..synth },
        seed: options.seed,
        seam_band: options.seam_band,
    };
    // The map's own memory is checked before any exemplar is read or captured.
    skinkit_stitch::compose::check_memory(&layout, &compose_options)?;
    let t = Instant::now();
    let exemplars = exemplars(&layout, cache, out)?;
    let seconds_exemplars = t.elapsed().as_secs_f64();
    let bar = out.progress(layout.regions.len() as u64, "regions");
    let composed = compose(&layout, &exemplars, &compose_options, &|_| bar.inc(1))
        .with_context(|| format!("cannot stitch {}", options.layout.display()))?;
    bar.finish_and_clear();
    // Each region's synthesis takes as many pyramid levels as its exemplar allows (up to the
    // default); the layout does not ask for a number, so that is no news on stderr. The report
    // keeps what each region's synthesis adjusted (`regions[].warnings`).
    Ok(Face { layout, exemplars, composed, amplitude, seconds_exemplars })
}

/// The layout on its mesh (`--mesh`, else the layout's `mesh`), if it has one: loaded with the
/// renderer's loaders (OBJ's v flipped to the map's rows, split corners welded), scaled by
/// `--mm-per-unit` or the layout's `mm_per_unit`.
fn on_mesh(layout: Layout, options: &StitchOptions, out: &Output) -> Result<Layout> {
    let Some(path) = options.mesh.clone().or_else(|| layout.mesh.clone()) else { return Ok(layout) };
    let Some(mm_per_unit) = options.mm_per_unit.or(layout.mm_per_unit) else {
        bail!(
            "{}: mm_per_unit: missing: how long one unit of {} is, in millimetres (1 for mm, 10 for cm, \
             1000 for metres); give `mm_per_unit` in the layout or --mm-per-unit",
            layout.origin.display(),
            path.display()
        );
    };
    let loaded = skinkit_render::mesh::Mesh::load(&path)?;
    for w in &loaded.warnings {
        out.note(w.clone());
    }
    let m = &loaded.mesh;
    let positions: Vec<[f32; 3]> = m.positions.iter().map(|p| p.to_array()).collect();
    let uvs: Vec<[f32; 2]> = m.uvs.iter().map(|t| t.to_array()).collect();
    let name = path.display().to_string();
    let surface = skinkit_stitch::surface::Surface::new(&name, &positions, &uvs, &m.indices, mm_per_unit)?;
    Ok(layout.on_surface(surface)?)
}

/// Each region's exemplar: a normal map read from disk, or a session captured (once per folder).
fn exemplars(layout: &Layout, cache: &mut CaptureCache, out: &Output) -> Result<Vec<NormalMap>> {
    let options = SolveArgs::defaults(SolverArg::Robust).options(out)?;
    let mut maps = Vec::with_capacity(layout.regions.len());
    for region in &layout.regions {
        let map = match &region.exemplar {
            ExemplarSource::NormalMap(path) => io::read_normal_map(path, NormalEncoding::default(), &Limits::default())
                .with_context(|| {
                    format!("{}: region `{}`: cannot read its exemplar", layout.origin.display(), region.name)
                })?,
            ExemplarSource::Session(dir) => {
                let key = dir.canonicalize().unwrap_or_else(|_| dir.clone());
                if let Some(map) = cache.get(&key) {
                    map.clone()
                } else {
                    out.note(format!("capturing {} for region `{}`", dir.display(), region.name));
                    let context = || {
                        format!(
                            "{}: region `{}`: cannot capture {}",
                            layout.origin.display(),
                            region.name,
                            dir.display()
                        )
                    };
                    let files = Session::from_dir(dir).with_context(context)?;
                    let captured = session::capture(&files, &options, &|_| {}).with_context(context)?;
                    let map = captured.solution.normals;
                    cache.insert(key, map.clone());
                    map
                }
            }
        };
        maps.push(map);
    }
    Ok(maps)
}

fn report(options: &StitchOptions, face: &Face, out: &Path, write: f64, start: Instant) -> FaceReport {
    let c = &face.composed;
    FaceReport {
        layout: options.layout.display().to_string(),
        out: out.display().to_string(),
        width: face.layout.width,
        height: face.layout.height,
        mm_per_texel: face.layout.mm_per_texel,
        levels: c.levels,
        curve_amplitude: face.amplitude,
        blend: !options.no_blend,
        start: if options.scanline { "scanline" } else { "upsampled" }.to_owned(),
        seed: options.seed,
        regions: c.regions.clone(),
        udim_tiles: face.layout.atlas.as_ref().filter(|a| !a.is_single_1001()).map(|a| a.tiles.clone()),
        regions_at_once: c.regions_at_once,
        seams: c.seams.clone(),
        seconds: FaceSeconds {
            exemplars: face.seconds_exemplars,
            compose: c.seconds.clone(),
            write,
            height: 0.0,
            total: start.elapsed().as_secs_f64(),
        },
        height_map: None,
        peak_memory_mib: pipeline::peak_memory_mib(),
    }
}

fn human(r: &FaceReport) -> String {
    let s = &r.seams.summary;
    let ratio = |v: Option<f64>| v.map_or("-".to_owned(), |v| format!("{v:.2}"));
    let mut text = format!(
        "{}: {}x{} face map, {} regions, {} spline levels, curve amplitude {:.0}, {:.1} s\n",
        r.out,
        r.width,
        r.height,
        r.regions.len(),
        r.levels,
        r.curve_amplitude,
        r.seconds.total
    );
    text += &format!(
        "seams: {} boundaries, band/interior gradient {} (max {}), spread {}, jump mean {:.2} max {:.1} deg\n",
        s.boundaries,
        ratio(s.mean_gradient_ratio),
        ratio(s.max_gradient_ratio),
        ratio(s.mean_std_ratio),
        s.mean_jump_degrees,
        s.max_jump_degrees
    );
    let t = &r.seconds;
    text + &format!(
        "seconds: exemplars {:.2}, partition {:.2}, resample {:.2}, synthesis {:.2}, blend {:.2}, seams {:.2}, write {:.2}",
        t.exemplars,
        t.compose.partition,
        t.compose.resample,
        t.compose.synthesis,
        t.compose.blend,
        t.compose.seams,
        t.write
    )
}

fn check_extension(path: &Path, allowed: &[&str]) -> Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    if !allowed.contains(&ext.as_str()) {
        bail!("{}: unsupported output format (use {})", path.display(), allowed.join(" or "));
    }
    Ok(())
}

/// A normal map as 16-bit PNG or, for `.exr`, float EXR.
fn encode_map(path: &Path, map: &NormalMap) -> skinkit_maps::Result<()> {
    let bits = if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) { 32 } else { 16 };
    io::write_normal_map(path, map, NormalEncoding::default(), bits)
}

/// A distinct, stable colour per region index (golden-angle hues); black for no region.
fn label_colour(label: u16) -> [u16; 3] {
    if label == NO_REGION {
        return [0, 0, 0];
    }
    let hue = (label as f32 * 0.618_034).fract() * 6.0;
    let f = |n: f32| {
        let k = (n + hue) % 6.0;
        let v = 1.0 - (k.min(4.0 - k).clamp(0.0, 1.0)) * 0.75;
        (v * 255.0).round() as u16
    };
    [f(5.0), f(3.0), f(1.0)]
}

fn encode_labels(path: &Path, labels: &Grid<u16>) -> skinkit_maps::Result<()> {
    let (w, h) = labels.size();
    io::write_png_rows(path, w, h, PngLayout::Rgb8, io::PngColour::Srgb, |y, row| {
        for (px, &l) in row.chunks_exact_mut(3).zip(labels.row(y)) {
            px.copy_from_slice(&label_colour(l));
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn label_colours_differ_for_the_first_regions() {
        let colours: Vec<[u16; 3]> = (0..12).map(label_colour).collect();
        for (i, a) in colours.iter().enumerate() {
            assert!(a.iter().all(|&c| c <= 255));
            for b in &colours[..i] {
                assert_ne!(a, b);
            }
        }
        assert_eq!(label_colour(NO_REGION), [0, 0, 0]);
    }
}
