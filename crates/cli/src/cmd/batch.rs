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
//! sessions whose outputs are complete and up to date ([`skinkit_batch::resume`]; `--force` redoes them). A
//! folder with a `layout.toml` is a subject: its face map is stitched after its sessions
//! ([`subject`], [`skinkit_batch::units`]). With `--json`, stdout has one JSON line per session and per face as each ends,
//! then one line with the batch report.

mod report;
mod subject;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;

use skinkit_maps::limits::{self, MemoryGate};

use skinkit_capture::session::CaptureOptions;

use crate::solve_flags::SolveArgs;

/// The batch's report in its output folder (one per shard: [`shard::Shard::report_name`]).
const REPORT: &str = "batch-report.json";
use crate::interrupt::{self, HookGuard};
use crate::output::Output;
use skinkit_batch::outcome::{self, Settings, lock};
use skinkit_batch::scheduler::ShardSpec;
use skinkit_batch::shard::{self, Shard};
use skinkit_batch::{BatchReport, FaceOutcome, Job, SessionOutcome, Unit, page, review, units};
use skinkit_maps::progress::Progress;

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
    /// `auto`: K and N from the array job's environment (Slurm, Kubernetes Indexed Job, AWS
    /// Batch; see the book's Batches chapter), refused when they are missing or disagree.
    #[arg(long, value_name = "K/N|auto")]
    pub shard: Option<ShardSpec>,
    /// The number of tasks of the array, for `--shard auto` where the scheduler does not say
    /// (Kubernetes; AWS Batch without AWS_BATCH_JOB_ARRAY_SIZE); checked against it where it does.
    #[arg(long, value_name = "N", requires = "shard", value_parser = crate::flags::usize_in(1, 1_000_000))]
    pub shard_count: Option<usize>,
    /// Print the sessions and subjects (of the shard, with `--shard`) in shard order, one a line
    /// (a JSON array with `--json`), and stop: the items `--only` takes.
    #[arg(long, conflicts_with_all = ["merge", "only"])]
    pub list: bool,
    /// Process exactly these sessions or subjects (names as `--list` prints them) into the same
    /// output tree; each one's report goes to OUT_DIR/batch-parts/NAME.json for `--merge`.
    #[arg(long, value_name = "NAME", num_args = 1.., conflicts_with = "shard")]
    pub only: Vec<String>,
    /// Join what ran in OUT_DIR (the shard reports, all N of them, and the reports of `--only`
    /// runs) into OUT_DIR/batch-report.json and its review page.
    #[arg(long, conflicts_with_all = ["sessions", "shard", "force"])]
    pub merge: bool,
    /// Capture every session again, even those whose outputs are complete, newer than their
    /// inputs and made with the same options (by default those are skipped).
    #[arg(long)]
    pub force: bool,
    /// Least share of a session's pixels that must be solved (0 to 1): a session below it (blank
    /// or dark photos) is a failed outcome, its maps still written for inspection.
    #[arg(long, value_name = "SHARE", default_value_t = 0.01, value_parser = share)]
    pub min_valid: f64,
    #[command(flatten)]
    pub solve: SolveArgs,
}

/// A share between 0 and 1.
fn share(text: &str) -> std::result::Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("'{text}' is not a share: expected a number from 0 to 1 (e.g. 0.01 for 1%)")),
    }
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let Some(sessions) = args.sessions.as_deref().filter(|_| !args.merge) else {
        let report = shard::merge(&args.out)?;
        return report::finish(report, &args.out.join(REPORT), true, out);
    };
    let shard = match args.shard {
        None => None,
        Some(spec) => {
            Some(spec.resolve(&|name| std::env::var(name).ok(), args.shard_count).map_err(crate::output::usage)?)
        }
    };
    let all = units::units(sessions, &args.out)?;
    if all.iter().all(|u| u.jobs().is_empty()) {
        anyhow::bail!("{}: no session sub-folders", sessions.display());
    }
    refuse_reserved(&all, sessions)?;
    // What a shard partitioned, for `--merge` to check that every shard saw the same sessions.
    let partition: Vec<String> =
        if shard.is_some() { all.iter().map(|u| u.name().to_owned()).collect() } else { Vec::new() };
    let units = select(all, shard, &args.only, sessions)?;
    if args.list {
        list(&units, out);
        return Ok(0);
    }
    let options = args.solve.options(out)?;
    skinkit_maps::gate::out_folder("--out", &args.out)?;
    skinkit_maps::gate::not_in_input_folder("--out", &args.out, "the sessions folder", sessions)?;
    // Made here, not by the sessions' output sets: one session's failure must not remove it.
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    let (mut report, hook) = capture_units(&units, &args, &options, (shard, &partition), out);
    report.partition = partition;
    let code = if args.only.is_empty() {
        let path = args.out.join(shard.map_or_else(|| REPORT.to_owned(), |s| s.report_name()));
        report::finish(report, &path, shard.is_none(), out)
    } else {
        report::write_parts(report, &units, &args.out, out)
    };
    drop(hook);
    code
}

/// Refuses, before any work, a session or subject whose output folder would be one of the
/// batch's own outputs: its folders (`batch-review/`, `batch-parts/`) and its files (the report
/// and the shard reports, the review page; a session named `batch-report.json` failed the batch
/// only after every capture, issue 42, D15).
fn refuse_reserved(units: &[Unit], root: &Path) -> Result<()> {
    let top = |name: &str| name.split('/').next().unwrap_or_default().to_owned();
    let names = units.iter().flat_map(|u| std::iter::once(top(u.name())).chain(u.jobs().iter().map(|j| top(&j.name))));
    match names.into_iter().find(|name| batch_own(name)) {
        Some(name) => Err(crate::output::usage(format!(
            "{}: a session or subject named `{name}` would write over the batch's own `{name}`: rename it",
            root.display()
        ))),
        None => Ok(()),
    }
}

/// Whether the batch itself writes `name` in its output folder.
fn batch_own(name: &str) -> bool {
    let shard_report = name.strip_prefix("batch-report-").is_some_and(|n| n.ends_with(".json"));
    shard_report || [REPORT, page::PAGE, review::FOLDER, shard::PARTS].contains(&name)
}

/// The units of the shard, or those `only` names (each must be one).
fn select(all: Vec<Unit>, shard: Option<Shard>, only: &[String], root: &Path) -> Result<Vec<Unit>> {
    let units = match shard {
        Some(shard) => shard.select(&all),
        None => all,
    };
    if let Some(missing) = only.iter().find(|name| !units.iter().any(|u| u.name() == name.as_str())) {
        return Err(crate::output::usage(format!(
            "--only {missing}: no session or subject of that name in {} (`skinkit batch --list` names them)",
            root.display()
        )));
    }
    Ok(units.into_iter().filter(|u| only.is_empty() || only.iter().any(|n| n == u.name())).collect())
}

/// One item of `--list`.
#[derive(Serialize)]
struct Item<'a> {
    name: &'a str,
    kind: &'static str,
    sessions: Vec<&'a str>,
}

/// Prints the units' names, one a line, or as a JSON array with `--json` (nothing with `--quiet`).
fn list(units: &[Unit], out: &Output) {
    let items: Vec<Item> = units
        .iter()
        .map(|u| Item {
            name: u.name(),
            kind: if matches!(u, Unit::Subject(_)) { "subject" } else { "session" },
            sessions: u.jobs().iter().map(|j| j.name.as_str()).collect(),
        })
        .collect();
    out.result(&items, || items.iter().map(|i| i.name).collect::<Vec<_>>().join("\n"));
}

/// Captures the units' sessions, in parallel under the memory gate, then stitches their faces.
/// The interrupt hook is returned to be kept until the report is written.
fn capture_units(
    units: &[Unit],
    args: &Args,
    options: &CaptureOptions,
    (shard, partition): (Option<Shard>, &[String]),
    out: &Output,
) -> (BatchReport, Option<HookGuard>) {
    let start = Instant::now();
    let jobs: Vec<Job> = units.iter().flat_map(|u| u.jobs().iter().cloned()).collect();
    let finished = Arc::new(Mutex::new(Vec::new()));
    // As many sessions at once as there are workers, fewer when their estimates do not fit the
    // memory limit together.
    let gate = Arc::new(MemoryGate::new(options.memory_limit));
    // An interrupted `--only` run leaves no report: its finished sessions are complete folders,
    // which the next run skips.
    let hook = args.only.is_empty().then(|| {
        let name = shard.map_or_else(|| REPORT.to_owned(), |s| s.report_name());
        let partition = partition.to_vec();
        report::on_interrupt(
            args.out.join(name),
            jobs.len(),
            Arc::clone(&finished),
            Arc::clone(&gate),
            shard,
            partition,
        )
    });
    let swept = Mutex::new(Vec::new());
    let review_dir = args.out.join(review::FOLDER);
    let settings =
        Settings { options, gate: &gate, force: args.force, min_valid: args.min_valid, review_dir: &review_dir };
    let bar = out.progress(jobs.len() as u64, "batch");
    limits::run_queued(&jobs, rayon::current_num_threads(), |job| {
        let outcome = outcome::outcome(job, &settings, &swept);
        if interrupt::requested() && !outcome.ok {
            // Failed because the interrupt removed its staging folder: unfinished, not failed.
            return;
        }
        if let Some(e) = &outcome.error {
            bar.suspend(|| out.warn(format!("{}: {e}", job.dir.display())));
        }
        for skipped in &outcome.skipped_files {
            bar.suspend(|| out.note(format!("note: skipped {skipped}")));
        }
        bar.suspend(|| out.record("session", &outcome));
        lock(&finished).push(outcome);
        bar.advance(1);
    });
    bar.clear();
    out.swept(&lock(&swept));
    let outcomes = lock(&finished).clone();
    let faces = faces(units, &outcomes, args.force, out);
    (BatchReport::new(jobs.len(), outcomes, false, &gate, shard, faces).timed(start), hook)
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
