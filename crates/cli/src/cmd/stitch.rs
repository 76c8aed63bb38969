//! `skinkit stitch` and `skinkit face`: one synthesis per face region, joined by a multiresolution
//! spline along random curves (Haro et al. 2001, section 4.2; issue 4).
//!
//! `stitch` writes one map (and, if asked, the labels and a report); `face` writes a folder with
//! the map as 16-bit PNG and float EXR, the labels, every region's exemplar at the map's scale and
//! the report. Both capture the regions that name a photo session first (robust solver, detrend
//! block 50), in memory.

use skinkit_maps::format::ImageFormat;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use skinkit_maps::OutputSet;
use skinkit_stitch::FaceReport;
use skinkit_stitch::face::{ExemplarCache, files};
use skinkit_stitch::layout::Layout;

use crate::face::{self, StitchOptions};
use crate::output::Output;
use crate::pipeline;

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

pub fn run_stitch(args: StitchArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    check_extension(&args.out, &[ImageFormat::Png, ImageFormat::Exr])?;
    if let Some(labels) = &args.labels {
        check_extension(labels, &[ImageFormat::Png])?;
    }
    let given = [("--out", Some(&args.out)), ("--labels", args.labels.as_ref()), ("--report", args.report.as_ref())];
    let outputs = skinkit_maps::gate::given(&given);
    for (flag, path) in &outputs {
        skinkit_maps::gate::out_file(flag, path)?;
    }
    let check = |layout: &Layout| Ok(skinkit_maps::gate::not_an_input(&outputs, &face::layout_inputs(layout))?);
    let face = face::build(&args.options, &mut ExemplarCache::new(), out, &check)?;
    let t = Instant::now();
    // One set: the map, the labels and the report appear together or not at all.
    let mut set = OutputSet::files();
    set.write_file(&args.out, |p| files::write_normal_map(p, &face.composed.normals))
        .context("cannot write the normal map")?;
    if let Some(path) = &args.labels {
        set.write_file(path, |p| files::write_labels(p, &face.composed.labels))
            .context("cannot write the label map")?;
    }
    let mut report = face.report(&args.out, t.elapsed().as_secs_f64(), start.elapsed().as_secs_f64());
    report.peak_memory_mib = skinkit_maps::limits::peak_resident_mib();
    if let Some(path) = &args.report {
        pipeline::write_json_file(&mut set, path, "the stitch report", &report)?;
    }
    out.swept(&set.commit().context("cannot finish writing the stitch outputs")?);
    out.result(&report, || human(&report));
    Ok(0)
}

pub fn run_face(args: FaceArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let report = face::face_to_dir(&args.options, &args.out, &mut ExemplarCache::new(), out, start)?;
    out.result(&report, || human(&report));
    Ok(0)
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

fn check_extension(path: &Path, allowed: &[ImageFormat]) -> Result<()> {
    if !ImageFormat::is_one_of(path, allowed) {
        bail!("{}: unsupported output format (use {})", path.display(), ImageFormat::extensions(allowed));
    }
    Ok(())
}
