//! Writing and showing the batch's report (`skinkit_batch::report`): on an interrupt, at the
//! end with its review page, and as one part per unit of an `--only` run.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use anyhow::{Context, Result};
use skinkit_batch::outcome::lock;
use skinkit_batch::shard::{self, Shard};
use skinkit_batch::{BatchReport, SessionOutcome, Unit, page, report};
use skinkit_maps::OutputSet;
use skinkit_maps::limits::MemoryGate;

use crate::interrupt::{self, HookGuard};
use crate::output::Output;
use crate::pipeline;

/// On an interrupt: the report of the sessions that finished, marked interrupted, at `path`.
pub fn on_interrupt(
    path: PathBuf,
    sessions: usize,
    finished: Arc<Mutex<Vec<SessionOutcome>>>,
    gate: Arc<MemoryGate>,
    shard: Option<Shard>,
    partition: Vec<String>,
) -> HookGuard {
    interrupt::on_interrupt(move || {
        let mut report = BatchReport::new(sessions, lock(&finished).clone(), true, &gate, shard, Vec::new());
        report.partition = partition.clone();
        // Written by the signal thread itself, whole (atomically), before the exit.
        if let Err(e) = pipeline::write_json(&path, "the batch report", &report) {
            eprintln!("error: {e:#}");
        }
    })
}

/// Writes the review page of `report` beside `path` (when `page` is set: a whole or merged
/// batch) and then `report` to `path`, and shows it; exit code 1 when a session failed.
pub fn finish(mut report: BatchReport, path: &Path, page: bool, out: &Output) -> Result<i32> {
    if page {
        let start = Instant::now();
        let page_path = path.with_file_name(page::PAGE);
        pipeline::write_text(&page_path, "the review page", &page::html(&report))?;
        report.page_seconds = start.elapsed().as_secs_f64();
    }
    let mut set = OutputSet::files();
    pipeline::write_json_file(&mut set, path, "the batch report", &report)?;
    set.commit().context("cannot finish writing the batch report")?;
    Ok(show(&report, out))
}

/// Shows `report` (the last record with `--json`); returns the exit code: 1 when a session or
/// face failed.
fn show(report: &BatchReport, out: &Output) -> i32 {
    out.result_record("batch", report, || report::summary(report));
    if report.any_failed() { 1 } else { 0 }
}

/// Writes the report of an `--only` run as one report per unit, `OUT/batch-parts/NAME.json`
/// (for `--merge`), and shows it whole.
///
/// # Errors
/// When a part cannot be written.
pub fn write_parts(report: BatchReport, units: &[Unit], out_dir: &Path, out: &Output) -> Result<i32> {
    let mut set = OutputSet::files();
    for unit in units {
        let path = out_dir.join(shard::PARTS).join(format!("{}.json", unit.name()));
        pipeline::write_json_file(&mut set, &path, "a part of the batch report", &report.part(unit))?;
    }
    set.commit().context("cannot finish writing the parts of the batch report")?;
    Ok(show(&report, out))
}
