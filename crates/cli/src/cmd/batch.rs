//! `skinkit batch`: every sub-folder of a folder is a capture session, processed in parallel; a
//! bad session is reported and skipped, the others go on.
//!
//! A session folder is read by `skinkit_capture::session::Session::from_dir`: `rig.toml`, the
//! photos (sorted by name), and optionally `mask.png`, `ambient.png` and `truth.png` (a
//! ground-truth normal map).
//!
//! Each session's folder is one output set (all its files or none, `report.json` last), so after
//! a failure or an interrupt every session folder is either complete or absent (issue 15, D3/D4);
//! an interrupt still writes `batch-report.json` of the sessions that finished.
//!
//! `--shard K/N` and `--merge` spread a batch over machines ([`shard`]); a re-run skips the
//! sessions whose outputs are complete and up to date ([`resume`]; `--force` redoes them). A
//! folder with a `layout.toml` is a subject: its face map is stitched after its sessions
//! ([`subject`]). With `--json`, stdout has one JSON line per session and per face as each ends,
//! then one line with the batch report.

mod resume;
mod shard;
mod subject;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use skinkit_capture::Rig;
use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_maps::OutputSet;
use skinkit_maps::limits::{self, MemoryGate};

use super::capture::SolveArgs;
use crate::interrupt::{self, HookGuard};
use crate::output::Output;
use crate::{guard, pipeline};
use shard::Shard;
use subject::{FaceOutcome, Job, Unit};

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder whose sub-folders are sessions (photos + rig.toml).
    #[arg(value_name = "SESSIONS_DIR", required_unless_present = "merge")]
    pub sessions: Option<PathBuf>,
    /// Output folder: one sub-folder per session, plus batch-report.json.
    #[arg(long, value_name = "OUT_DIR")]
    pub out: PathBuf,
    /// Process only shard K of N (1 <= K <= N): the sessions whose index in name order is K - 1
    /// modulo N. The report goes to batch-report-K-of-N.json; `--merge` joins the N of them.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Join the shard reports in OUT_DIR (all N of them) into OUT_DIR/batch-report.json.
    #[arg(long, conflicts_with_all = ["sessions", "shard", "force"])]
    pub merge: bool,
    /// Capture every session again, even those whose outputs are complete, newer than their
    /// inputs and made with the same options (by default those are skipped).
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub solve: SolveArgs,
}

/// One line of the batch summary.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SessionOutcome {
    pub session: String,
    pub ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub invalid_pixels: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
    /// Not captured again: its outputs were complete and up to date (`seconds` is the earlier run's).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub skipped: bool,
}

#[derive(Debug, Serialize, Deserialize)]
pub struct BatchReport {
    pub sessions: usize,
    pub succeeded: usize,
    pub failed: usize,
    /// Sessions among the succeeded that were up to date and not captured again.
    #[serde(default)]
    pub skipped: usize,
    /// True when a signal stopped the batch: `outcomes` lists the sessions that finished (their
    /// folders are complete); the others have no folder.
    pub interrupted: bool,
    /// The memory limit the sessions running at once had to fit together (`--memory-limit`).
    pub memory_limit_mib: u64,
    /// The most sessions that ran at once.
    pub most_at_once: usize,
    pub outcomes: Vec<SessionOutcome>,
    /// The shard this report covers (`--shard`); absent for a whole or merged batch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// The subjects' face maps (folders with a `layout.toml`), in subject name order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<FaceOutcome>,
}

/// What one session's run left: its figures, and what its commit cleaned up from killed runs.
struct SessionRun {
    invalid_pixels: usize,
    seconds: f64,
    skipped: bool,
    swept: Vec<PathBuf>,
}

/// Captures one session once its memory estimate fits beside the sessions running (`gate`); a
/// session that could never fit fails at once with its estimate and the limit. Without `force`,
/// a session whose outputs are up to date ([`resume::up_to_date`]) is skipped.
fn run_session(
    dir: &Path,
    out_dir: &Path,
    options: &CaptureOptions,
    gate: &MemoryGate,
    force: bool,
) -> Result<SessionRun> {
    let files = Session::from_dir(dir)?;
    // The rig's own ambient frame counts too; a rig that does not load is reported by `capture`.
    let rig_ambient = Rig::load(&files.rig).ok().and_then(|r| r.ambient().map(Path::to_path_buf));
    let ambient = files.ambient.clone().or(rig_ambient);
    if let Some(done) = resume::up_to_date(dir, &files, ambient.as_deref(), out_dir, options).filter(|_| !force) {
        let swept = skinkit_maps::output_set::sweep_folder(out_dir);
        return Ok(SessionRun { invalid_pixels: done.invalid_pixels, seconds: done.seconds, skipped: true, swept });
    }
    let estimate = session::memory_estimate(&files, ambient.as_deref(), options)?;
    limits::check_memory(&dir.display().to_string(), "capturing the session", estimate, gate.budget())?;
    let _admitted = gate.acquire(estimate);
    // Staged from the start, so an interrupt during the solve removes this session's folder too.
    let set = pipeline::capture_set(out_dir)?;
    let mut captured = session::capture(&files, options, &|_| {})?;
    let swept = pipeline::write_outputs(set, out_dir, &mut captured, options)?;
    let report = &captured.report;
    Ok(SessionRun { invalid_pixels: report.invalid_pixels, seconds: report.timings_s.total, skipped: false, swept })
}

/// One session's outcome; `swept` collects what its commit cleaned up from killed runs.
fn outcome(
    job: &Job,
    options: &CaptureOptions,
    gate: &MemoryGate,
    force: bool,
    swept: &Mutex<Vec<PathBuf>>,
) -> SessionOutcome {
    let name = job.name.clone();
    match run_session(&job.dir, &job.out, options, gate, force) {
        Ok(run) => {
            lock(swept).extend(run.swept);
            SessionOutcome {
                session: name,
                ok: true,
                error: None,
                invalid_pixels: Some(run.invalid_pixels),
                seconds: Some(run.seconds),
                skipped: run.skipped,
            }
        }
        Err(e) => SessionOutcome {
            session: name,
            ok: false,
            error: Some(crate::output::one_line(&e)),
            invalid_pixels: None,
            seconds: None,
            skipped: false,
        },
    }
}

fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl BatchReport {
    fn new(
        sessions: usize,
        mut outcomes: Vec<SessionOutcome>,
        interrupted: bool,
        gate: &MemoryGate,
        shard: Option<Shard>,
        faces: Vec<FaceOutcome>,
    ) -> Self {
        outcomes.sort_by(|a, b| a.session.cmp(&b.session));
        let failed = outcomes.iter().filter(|o| !o.ok).count();
        BatchReport {
            sessions,
            succeeded: outcomes.len() - failed,
            failed,
            skipped: outcomes.iter().filter(|o| o.skipped).count(),
            interrupted,
            memory_limit_mib: gate.budget() >> 20,
            most_at_once: gate.peaks().0,
            outcomes,
            shard,
            faces,
        }
    }

    /// Sessions and faces that failed.
    fn any_failed(&self) -> bool {
        self.failed > 0 || self.faces.iter().any(|f| !f.ok)
    }
}

/// On an interrupt: `batch-report.json` of the sessions that finished, marked interrupted.
fn report_on_interrupt(
    path: PathBuf,
    sessions: usize,
    finished: Arc<Mutex<Vec<SessionOutcome>>>,
    gate: Arc<MemoryGate>,
    shard: Option<Shard>,
) -> HookGuard {
    interrupt::on_interrupt(move || {
        let report = BatchReport::new(sessions, lock(&finished).clone(), true, &gate, shard, Vec::new());
        // Written by the signal thread itself, whole (atomically), before the exit.
        if let Err(e) = pipeline::write_json(&path, &report) {
            eprintln!("error: {e:#}");
        }
    })
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let Some(sessions) = args.sessions.as_deref().filter(|_| !args.merge) else {
        let report = shard::merge(&args.out)?;
        return finish(&report, &args.out.join("batch-report.json"), out);
    };
    let options = args.solve.options(out)?;
    guard::out_folder("--out", &args.out)?;
    guard::not_in_input_folder("--out", &args.out, "the sessions folder", sessions)?;
    let all = subject::units(sessions, &args.out)?;
    if all.iter().all(|u| u.jobs().is_empty()) {
        anyhow::bail!("{}: no session sub-folders", sessions.display());
    }
    let units = match args.shard {
        Some(shard) => shard.select(&all),
        None => all,
    };
    let jobs: Vec<Job> = units.iter().flat_map(|u| u.jobs().iter().cloned()).collect();
    // Made here, not by the sessions' output sets: one session's failure must not remove it.
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let report_path = args.out.join(args.shard.map_or_else(|| "batch-report.json".to_owned(), |s| s.report_name()));
    let finished = Arc::new(Mutex::new(Vec::new()));
    // As many sessions at once as there are workers, fewer when their estimates do not fit the
    // memory limit together.
    let gate = Arc::new(MemoryGate::new(options.memory_limit));
    let hook =
        report_on_interrupt(report_path.clone(), jobs.len(), Arc::clone(&finished), Arc::clone(&gate), args.shard);
    let swept = Mutex::new(Vec::new());
    let bar = out.progress(jobs.len() as u64, "batch");
    limits::run_queued(&jobs, rayon::current_num_threads(), |job| {
        let outcome = outcome(job, &options, &gate, args.force, &swept);
        if interrupt::requested() && !outcome.ok {
            // Failed because the interrupt removed its staging folder: unfinished, not failed.
            return;
        }
        if let Some(e) = &outcome.error {
            bar.suspend(|| out.warn(format!("{}: {e}", job.dir.display())));
        }
        bar.suspend(|| out.record("session", &outcome));
        lock(&finished).push(outcome);
        bar.inc(1);
    });
    bar.finish_and_clear();
    out.swept(&lock(&swept));
    let outcomes = lock(&finished).clone();
    let faces = faces(&units, &outcomes, args.force, out);
    let report = BatchReport::new(jobs.len(), outcomes, false, &gate, args.shard, faces);
    let code = finish(&report, &report_path, out);
    drop(hook);
    code
}

/// Each subject's face, one after the other (a face map takes the whole machine), once its
/// sessions are all captured; a subject with a failed session gets no face, and says which.
fn faces(units: &[Unit], outcomes: &[SessionOutcome], force: bool, out: &Output) -> Vec<FaceOutcome> {
    let mut faces = Vec::new();
    for unit in units {
        let Unit::Subject(subject) = unit else { continue };
        if interrupt::requested() {
            break;
        }
        let failed: Vec<&str> = subject
            .jobs
            .iter()
            .filter(|j| !outcomes.iter().any(|o| o.session == j.name && o.ok))
            .map(|j| j.name.as_str())
            .collect();
        let face = if failed.is_empty() {
            out.note(format!("stitching the face of {}", subject.layout.display()));
            subject::face(subject, force, out)
        } else {
            FaceOutcome {
                subject: subject.name.clone(),
                ok: false,
                error: Some(format!("not stitched: sessions {} failed", failed.join(", "))),
                seconds: None,
                skipped: false,
            }
        };
        if let Some(e) = &face.error {
            out.warn(format!("{}: {e}", subject.layout.display()));
        }
        out.record("face", &face);
        faces.push(face);
    }
    faces
}

/// Writes `report` to `path` and shows it; exit code 1 when a session failed.
fn finish(report: &BatchReport, path: &Path, out: &Output) -> Result<i32> {
    let mut set = OutputSet::files();
    pipeline::write_json_file(&mut set, path, report)?;
    set.commit().with_context(|| format!("cannot write {}", path.display()))?;
    out.result_record("batch", report, || {
        let shard = report.shard.map(|s| format!(" (shard {s})")).unwrap_or_default();
        let skipped =
            if report.skipped > 0 { format!(" ({} up to date, skipped)", report.skipped) } else { String::new() };
        let mut s = format!(
            "{} sessions{shard}: {} succeeded{skipped}, {} failed",
            report.sessions, report.succeeded, report.failed
        );
        for o in report.outcomes.iter().filter(|o| !o.ok) {
            s += &format!("\nfailed: {}: {}", o.session, o.error.as_deref().unwrap_or(""));
        }
        if !report.faces.is_empty() {
            let ok = report.faces.iter().filter(|f| f.ok).count();
            let skipped = report.faces.iter().filter(|f| f.skipped).count();
            s += &format!("\n{} faces: {ok} written or up to date ({skipped} skipped)", report.faces.len());
            for f in report.faces.iter().filter(|f| !f.ok) {
                s += &format!("\nface failed: {}: {}", f.subject, f.error.as_deref().unwrap_or(""));
            }
        }
        s
    });
    Ok(if report.any_failed() { 1 } else { 0 })
}
