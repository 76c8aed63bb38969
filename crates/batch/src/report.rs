//! The batch's summary, `batch-report.json` (or a shard's or an item's), with its throughput;
//! the review page beside it is [`crate::page`].

use std::time::Instant;

use serde::{Deserialize, Serialize};
use skinkit_maps::limits::MemoryGate;

use crate::outcome::SessionOutcome;
use crate::shard::Shard;
use crate::units::{FaceOutcome, Unit};

#[derive(Clone, Debug, Serialize, Deserialize)]
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
    /// The largest sum of the estimates of the sessions running at once: how much of the memory
    /// limit the batch used.
    #[serde(default)]
    pub memory_peak_mib: u64,
    /// Wall-clock time of the sessions (capture, previews, faces), seconds; for a merged report
    /// the longest of its parts' (they may have run at once).
    #[serde(default)]
    pub seconds: f64,
    /// Sessions captured (not skipped) per minute of `seconds`; for a merged report the sum of
    /// its shards' (shards run at once, on machines of their own).
    #[serde(default)]
    pub sessions_per_minute: f64,
    /// Time to write the review page, seconds.
    #[serde(default)]
    pub page_seconds: f64,
    pub outcomes: Vec<SessionOutcome>,
    /// The shard this report covers (`--shard`); absent for a whole or merged batch.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// For a shard: every session and subject it partitioned among the shards, in name order, as
    /// the sessions folder held them when it ran. `--merge` joins only shards that agree on it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub partition: Vec<String>,
    /// The units this report covers when it came from `--only` (one report per unit).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub only: Option<String>,
    /// The subjects' face maps (folders with a `layout.toml`), in subject name order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub faces: Vec<FaceOutcome>,
}

impl BatchReport {
    /// The report of `sessions` sessions of which `outcomes` finished, its counts worked out.
    pub fn new(
        sessions: usize,
        outcomes: Vec<SessionOutcome>,
        interrupted: bool,
        gate: &MemoryGate,
        shard: Option<Shard>,
        faces: Vec<FaceOutcome>,
    ) -> Self {
        let (most_at_once, peak) = gate.peaks();
        let mut report = BatchReport {
            sessions,
            succeeded: 0,
            failed: 0,
            skipped: 0,
            interrupted,
            memory_limit_mib: gate.budget() >> 20,
            most_at_once,
            memory_peak_mib: peak.div_ceil(1 << 20),
            seconds: 0.0,
            sessions_per_minute: 0.0,
            page_seconds: 0.0,
            outcomes,
            shard,
            partition: Vec::new(),
            only: None,
            faces,
        };
        report.recount();
        report
    }

    /// Sorts the outcomes and faces by name and counts them again.
    pub fn recount(&mut self) {
        self.outcomes.sort_by(|a, b| a.session.cmp(&b.session));
        self.faces.sort_by(|a, b| a.subject.cmp(&b.subject));
        self.failed = self.outcomes.iter().filter(|o| !o.ok).count();
        self.succeeded = self.outcomes.len() - self.failed;
        self.skipped = self.outcomes.iter().filter(|o| o.skipped).count();
    }

    /// Sets the wall-clock time the sessions took since `start`, and the rate.
    pub fn timed(mut self, start: Instant) -> Self {
        self.seconds = start.elapsed().as_secs_f64();
        let captured = self.outcomes.iter().filter(|o| !o.skipped && o.seconds.is_some()).count();
        self.sessions_per_minute = if self.seconds > 0.0 { 60.0 * captured as f64 / self.seconds } else { 0.0 };
        self
    }

    /// The part of this report (from `--only`) that covers `unit`: its sessions and face.
    pub fn part(&self, unit: &Unit) -> BatchReport {
        let names: Vec<&str> = unit.jobs().iter().map(|j| j.name.as_str()).collect();
        let outcomes: Vec<SessionOutcome> =
            self.outcomes.iter().filter(|o| names.contains(&o.session.as_str())).cloned().collect();
        let faces: Vec<FaceOutcome> = self.faces.iter().filter(|f| f.subject == unit.name()).cloned().collect();
        let mut part =
            BatchReport { sessions: names.len(), outcomes, faces, only: Some(unit.name().to_owned()), ..self.clone() };
        part.recount();
        part
    }

    /// Sessions and faces that failed.
    pub fn any_failed(&self) -> bool {
        self.failed > 0 || self.faces.iter().any(|f| !f.ok)
    }
}

/// The report in words.
pub fn summary(report: &BatchReport) -> String {
    let shard = report.shard.map(|s| format!(" (shard {s})")).unwrap_or_default();
    let skipped = if report.skipped > 0 { format!(" ({} up to date, skipped)", report.skipped) } else { String::new() };
    let mut s = format!(
        "{} sessions{shard}: {} succeeded{skipped}, {} failed; {:.1} sessions a minute, memory gate {} of {} MiB",
        report.sessions,
        report.succeeded,
        report.failed,
        report.sessions_per_minute,
        report.memory_peak_mib,
        report.memory_limit_mib
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
}
