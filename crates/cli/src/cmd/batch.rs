//! `skinkit batch`: every sub-folder of a folder is a capture session, processed in parallel; a
//! bad session is reported and skipped, the others go on.
//!
//! A session folder is read by `skinkit_capture::session::Session::from_dir`: `rig.toml`, the
//! photos (sorted by name), and optionally `mask.png`, `ambient.png` and `truth.png` (a
//! ground-truth normal map).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use rayon::prelude::*;
use serde::Serialize;

use skinkit_capture::session::{self, CaptureOptions, CaptureReport, Session};

use super::capture::SolveArgs;
use crate::output::Output;
use crate::pipeline;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder whose sub-folders are sessions (photos + rig.toml).
    #[arg(value_name = "SESSIONS_DIR")]
    pub sessions: PathBuf,
    /// Output folder: one sub-folder per session, plus batch-report.json.
    #[arg(long, value_name = "OUT_DIR")]
    pub out: PathBuf,
    #[command(flatten)]
    pub solve: SolveArgs,
}

/// One line of the batch summary.
#[derive(Debug, Serialize)]
pub struct SessionOutcome {
    pub session: String,
    pub ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub invalid_pixels: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
}

#[derive(Debug, Serialize)]
pub struct BatchReport {
    pub sessions: usize,
    pub succeeded: usize,
    pub failed: usize,
    pub outcomes: Vec<SessionOutcome>,
}

/// The session sub-folders of `dir`, sorted by name.
fn session_dirs(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot list sessions in {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    Ok(dirs)
}

fn run_session(dir: &Path, out_dir: &Path, options: &CaptureOptions) -> Result<CaptureReport> {
    let files = Session::from_dir(dir)?;
    let mut captured = session::capture(&files, options, &|_| {})?;
    pipeline::write_outputs(out_dir, &mut captured, options)?;
    Ok(captured.report)
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let options = args.solve.options()?;
    let dirs = session_dirs(&args.sessions)?;
    if dirs.is_empty() {
        anyhow::bail!("{}: no session sub-folders", args.sessions.display());
    }
    let bar = out.progress(dirs.len() as u64, "batch");
    let outcomes: Vec<SessionOutcome> = dirs
        .par_iter()
        .map(|dir| {
            let name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
            let result = run_session(dir, &args.out.join(&name), &options);
            bar.inc(1);
            match result {
                Ok(report) => SessionOutcome {
                    session: name,
                    ok: true,
                    error: None,
                    invalid_pixels: Some(report.invalid_pixels),
                    seconds: Some(report.timings_s.total),
                },
                Err(e) => {
                    let line = crate::output::one_line(&e);
                    bar.suspend(|| out.warn(format!("{}: {line}", dir.display())));
                    SessionOutcome { session: name, ok: false, error: Some(line), invalid_pixels: None, seconds: None }
                }
            }
        })
        .collect();
    bar.finish_and_clear();
    let failed = outcomes.iter().filter(|o| !o.ok).count();
    let report = BatchReport { sessions: outcomes.len(), succeeded: outcomes.len() - failed, failed, outcomes };
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    pipeline::write_json(&args.out.join("batch-report.json"), &report)?;
    out.result(&report, || {
        let mut s = format!("{} sessions: {} succeeded, {} failed", report.sessions, report.succeeded, report.failed);
        for o in report.outcomes.iter().filter(|o| !o.ok) {
            s += &format!("\nfailed: {}: {}", o.session, o.error.as_deref().unwrap_or(""));
        }
        s
    });
    Ok(if failed > 0 { 1 } else { 0 })
}
