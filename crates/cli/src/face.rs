//! The face flags `stitch`, `face`, `demo` and face batches share, and the CLI's side of a face
//! build: the layout loaded and placed on the user's mesh, sessions captured with the default
//! solver, the folder staged and committed with its report. The build itself is
//! [`skinkit_stitch::Face`].

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use skinkit_maps::{NormalMap, OutputSet};
use skinkit_stitch::face::{ExemplarCache, files};
use skinkit_stitch::layout::Layout;
use skinkit_stitch::{Face, FaceOptions, FaceReport};

use skinkit_capture::session::{self, Session};

use crate::flags;
use crate::output::Output;
use crate::pipeline;
use crate::solve_flags::{SolveArgs, SolverArg};

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

    /// The library's options these flags ask for, under the run's memory limit.
    fn face_options(&self, memory_limit: u64) -> FaceOptions {
        FaceOptions {
            seed: self.seed,
            levels: self.levels,
            curve_amplitude: if self.straight { Some(0.0) } else { self.curve_amplitude },
            blend: !self.no_blend,
            seam_band: self.seam_band,
            scanline: self.scanline,
            memory_limit,
        }
    }
}

/// Builds a face and writes its folder ([`files`]: the maps, labels, height files and exemplars,
/// then report.json) as one output set: all or nothing, the report last.
pub fn face_to_dir(
    options: &StitchOptions,
    dir: &Path,
    cache: &mut ExemplarCache,
    out: &Output,
    start: Instant,
) -> Result<FaceReport> {
    skinkit_maps::gate::out_folder("--out", dir)?;
    // Staged before the work, so an interrupt during it removes the staging folder.
    let set = OutputSet::folder(dir, "report.json").context("cannot write the face folder")?;
    let face = build(options, cache, out, &|layout: &Layout| check_face_out(dir, layout))?;
    let t = Instant::now();
    let (height, height_seconds) = face.write_folder(&set)?;
    let mut report = face.report(&dir.join("normal.png"), t.elapsed().as_secs_f64(), start.elapsed().as_secs_f64());
    report.height_map = Some(height);
    report.seconds.height = height_seconds;
    report.peak_memory_mib = skinkit_maps::limits::peak_resident_mib();
    pipeline::write_json_in(&set, "report.json", "the face report", &report)?;
    out.swept(&set.commit().context("cannot finish writing the face folder")?);
    Ok(report)
}

/// Loads the layout, runs `check` on it (outputs against inputs, before any work), sizes it,
/// places it on its mesh, and builds the face (sessions captured with the default solver).
pub fn build(
    options: &StitchOptions,
    cache: &mut ExemplarCache,
    out: &Output,
    check: &dyn Fn(&Layout) -> Result<()>,
) -> Result<Face> {
    let mut layout = Layout::load(&options.layout)?;
    check(&layout)?;
    if let Some((w, h)) = options.size {
        layout = layout.with_size(w, h)?;
    }
    layout = on_mesh(layout, options, out)?;
    let solve = SolveArgs::defaults(SolverArg::Robust).options(out)?;
    let mut capture = |dir: &Path, region: &str| -> Result<NormalMap, skinkit_stitch::face::BoxError> {
        out.note(format!("capturing {} for region `{region}`", dir.display()));
        let files = Session::from_dir(dir)?;
        Ok(session::capture(&files, &solve, &skinkit_maps::progress::NoProgress)?.solution.normals)
    };
    let bar = out.progress(layout.regions.len() as u64, "regions");
    let face = Face::build(layout, &options.face_options(out.memory_limit()), cache, &mut capture, &bar)
        .context("cannot stitch the face")?;
    bar.clear();
    Ok(face)
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

/// The files a layout reads, named for messages.
pub fn layout_inputs(layout: &Layout) -> Vec<(String, PathBuf)> {
    use skinkit_stitch::layout::ExemplarSource;
    let mut inputs = vec![("the layout".to_owned(), layout.origin.clone())];
    inputs.extend(layout.coverage.iter().map(|p| ("the coverage mask".to_owned(), p.clone())));
    for region in &layout.regions {
        if let ExemplarSource::NormalMap(path) = &region.exemplar {
            inputs.push((format!("region `{}`'s exemplar", region.name), path.clone()));
        }
    }
    inputs
}

/// A face folder `--out`: refused when a file it writes is an input or it lies in a session folder.
fn check_face_out(dir: &Path, layout: &Layout) -> Result<()> {
    use skinkit_stitch::layout::ExemplarSource;
    for region in &layout.regions {
        if let ExemplarSource::Session(session) = &region.exemplar {
            skinkit_maps::gate::not_in_input_folder(
                "--out",
                dir,
                &format!("region `{}`'s session folder", region.name),
                session,
            )?;
        }
    }
    let mut files: Vec<PathBuf> = files::file_names(layout).iter().map(|f| dir.join(f)).collect();
    files.push(dir.join("report.json"));
    let outputs: Vec<(&str, &Path)> = files.iter().map(|f| ("--out", f.as_path())).collect();
    Ok(skinkit_maps::gate::not_an_input(&outputs, &layout_inputs(layout))?)
}
