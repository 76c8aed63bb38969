//! `skinkit demo`: the pipeline that exists, run over the bundled samples. Today that is capture
//! of every sample mold with both solvers, each result's error against its ground truth, and what
//! the robust solver's accuracy costs in time.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Serialize;

use super::batch::session_in;
use super::capture::SolveArgs;
use crate::output::Output;
use crate::pipeline::{self, CaptureOptions};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Output folder.
    #[arg(long, default_value = "demo-out", value_name = "DIR")]
    pub out: PathBuf,
    /// Folder of sample molds (default: the repository's samples/molds).
    #[arg(long, value_name = "DIR")]
    pub samples: Option<PathBuf>,
}

#[derive(Serialize)]
struct MoldResult {
    region: String,
    solver: String,
    mean_error_deg: f32,
    rms_error_deg: f32,
    p95_error_deg: f32,
    invalid_pixels: usize,
    solve_seconds: f64,
    output: String,
}

#[derive(Serialize)]
struct DemoReport {
    molds: Vec<MoldResult>,
}

/// The repository's sample molds, found from the source tree this binary was built from, or in the
/// current folder.
fn default_samples() -> PathBuf {
    let here = PathBuf::from("samples/molds");
    if here.is_dir() { here } else { Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds") }
}

fn options(solver: &str) -> Result<CaptureOptions> {
    let args = SolveArgs {
        solver: solver.into(),
        detrend_block: 50,
        shadow_threshold: None,
        shadow_relative: None,
        saturation: None,
        transfer: "linear".into(),
        green: "up".into(),
    };
    args.options()
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let samples = args.samples.clone().unwrap_or_else(default_samples);
    let mut regions: Vec<PathBuf> = std::fs::read_dir(&samples)
        .with_context(|| {
            format!("cannot list sample molds in {} (run `skinkit samples` to make them)", samples.display())
        })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    regions.sort();
    let bar = out.progress(regions.len() as u64 * 2, "demo");
    let mut molds = Vec::new();
    for dir in &regions {
        let region = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let session = session_in(dir)?;
        for solver in ["robust", "ls"] {
            let options = options(solver)?;
            let mut captured = pipeline::capture(&session, &options, &|_| {})?;
            let target = args.out.join("capture").join(&region).join(solver);
            pipeline::write_outputs(&target, &mut captured, &options)?;
            let r = &captured.report;
            let e = r.error_vs_truth_degrees.context("sample mold without truth.png")?;
            molds.push(MoldResult {
                region: region.clone(),
                solver: solver.into(),
                mean_error_deg: e.mean,
                rms_error_deg: e.rms,
                p95_error_deg: e.p95,
                invalid_pixels: r.invalid_pixels,
                solve_seconds: r.timings_s.solve,
                output: target.display().to_string(),
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let report = DemoReport { molds };
    pipeline::write_json(&args.out.join("demo-report.json"), &report)?;
    out.result(&report, || {
        let mut s = format!(
            "{:<14} {:<7} {:>10} {:>9} {:>9} {:>8} {:>9}\n",
            "mold", "solver", "mean deg", "rms deg", "p95 deg", "invalid", "solve ms"
        );
        for m in &report.molds {
            s += &format!(
                "{:<14} {:<7} {:>10.3} {:>9.3} {:>9.3} {:>8} {:>9.2}\n",
                m.region,
                m.solver,
                m.mean_error_deg,
                m.rms_error_deg,
                m.p95_error_deg,
                m.invalid_pixels,
                m.solve_seconds * 1e3
            );
        }
        s + &format!("outputs and demo-report.json in {}", args.out.display())
    });
    Ok(0)
}
