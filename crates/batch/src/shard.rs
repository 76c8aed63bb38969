//! Sharded batches (`skinkit batch --shard K/N`, `skinkit batch --merge`): a cluster runs N
//! copies of the batch, each on its own deterministic share of the sessions, with no scheduler of
//! ours; the shards' reports are then joined into the report one batch would have written.
//!
//! Shard `K` of `N` takes the sessions whose index in name order is `K - 1` modulo `N`, so the
//! shares differ by at most one session and a session's shard depends only on the sorted names.
//! Each shard writes `batch-report-K-of-N.json` beside the session folders (shards sharing one
//! output folder never write the same file) with the list of sessions it partitioned; `--merge`
//! checks that all N are there, that they partitioned one list (a session folder that appeared
//! between two shards would shift the shares) and that no session was reported twice, and writes
//! `batch-report.json`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::report::BatchReport;

/// Shard `index` (1-based) of `count`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// `K/N` with `1 <= K <= N`.
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("'{s}' is not a shard: expected K/N with 1 <= K <= N (e.g. 2/8)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) =
            (k.trim().parse::<usize>().map_err(|_| bad())?, n.trim().parse::<usize>().map_err(|_| bad())?);
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// This shard's share of `sessions` (sorted by name).
    pub fn select<T: Clone>(&self, sessions: &[T]) -> Vec<T> {
        sessions.iter().skip(self.index - 1).step_by(self.count).cloned().collect()
    }

    /// The file name of this shard's report.
    pub fn report_name(&self) -> String {
        format!("batch-report-{}-of-{}.json", self.index, self.count)
    }
}

/// The folder, in the output folder, of the reports of `--only` runs: `UNIT.json` per unit.
pub const PARTS: &str = "batch-parts";

/// The shard reports in `dir`: none, or `batch-report-K-of-N.json` for one N and every K; an
/// error names what is missing or mixed.
fn shard_reports(dir: &Path) -> Result<Vec<(Shard, PathBuf)>> {
    let mut found: Vec<(Shard, PathBuf)> = std::fs::read_dir(dir)
        .with_context(|| format!("cannot list {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let middle = name.strip_prefix("batch-report-")?.strip_suffix(".json")?;
            let (k, n) = middle.split_once("-of-")?;
            Some((format!("{k}/{n}").parse().ok()?, p))
        })
        .collect();
    found.sort_by_key(|(s, _)| s.index);
    let Some(count) = found.first().map(|(s, _)| s.count) else { return Ok(found) };
    if let Some((s, p)) = found.iter().find(|(s, _)| s.count != count) {
        bail!("{}: shard {s} does not belong to a batch of {count} shards", p.display());
    }
    let missing: Vec<String> =
        (1..=count).filter(|k| !found.iter().any(|(s, _)| s.index == *k)).map(|k| format!("{k}/{count}")).collect();
    if !missing.is_empty() {
        bail!("{}: shard reports missing for {} (run those shards first)", dir.display(), missing.join(", "));
    }
    Ok(found)
}

/// The reports of `--only` runs in `dir/batch-parts`, in name order.
fn part_reports(dir: &Path) -> Result<Vec<PathBuf>> {
    let parts = dir.join(PARTS);
    if !parts.is_dir() {
        return Ok(Vec::new());
    }
    let mut found: Vec<PathBuf> = std::fs::read_dir(&parts)
        .with_context(|| format!("cannot list {}", parts.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    found.sort();
    Ok(found)
}

fn read_report(path: &Path) -> Result<BatchReport> {
    let text = skinkit_maps::input::read_to_string(path, skinkit_maps::input::Kind::Report)?;
    serde_json::from_str(&text).with_context(|| format!("{}: not a batch report", path.display()))
}

/// Joins what ran into `dir` into one report: the shard reports (all N of them, when there are
/// any) and the reports of `--only` runs (`batch-parts/`), a session or face reported twice
/// taken from the later (a part after the shards). Counts are worked out again, outcomes in name
/// order, the memory figures the largest of any part, the time the longest, the rate the sum
/// of the shards', interrupted if any part was.
///
/// # Errors
/// When there is nothing to merge, a shard is missing, or a report does not read.
pub fn merge(dir: &Path) -> Result<BatchReport> {
    let mut reports = Vec::new();
    let mut paths = Vec::new();
    for (shard, path) in shard_reports(dir)? {
        let report = read_report(&path)?;
        if report.shard != Some(shard) {
            bail!("{}: its `shard` field says {:?}, not {shard}", path.display(), report.shard.map(|s| s.to_string()));
        }
        reports.push(report);
        paths.push(path);
    }
    check_coverage(&reports, &paths)?;
    for path in part_reports(dir)? {
        reports.push(read_report(&path)?);
    }
    if reports.is_empty() {
        bail!(
            "{}: nothing to merge: no shard reports (batch-report-K-of-N.json) and no reports of --only runs ({PARTS}/)",
            dir.display()
        );
    }
    Ok(join(reports))
}

/// Checks that the shard reports partitioned one list of sessions (a session folder that appeared
/// or vanished between two shards shifts every later session's shard: some would never be
/// captured and others twice) and that no session has an outcome in two of them.
fn check_coverage(shards: &[BatchReport], paths: &[PathBuf]) -> Result<()> {
    let Some(first) = shards.first() else { return Ok(()) };
    let rerun = "run every shard again (the sessions each finished are skipped as up to date), then --merge";
    for (report, path) in shards.iter().zip(paths) {
        if report.partition.is_empty() {
            bail!("{}: records no session list (written by an older skinkit); {rerun}", path.display());
        }
        if report.partition != first.partition {
            let differ = |a: &[String], b: &[String]| a.iter().filter(|n| !b.contains(n)).cloned().collect::<Vec<_>>();
            let (only_here, only_first) =
                (differ(&report.partition, &first.partition), differ(&first.partition, &report.partition));
            bail!(
                "{} and {}: the shards saw different sessions (only in the first: [{}]; only in the second: [{}]): a \
                 session folder appeared or vanished between them, so some sessions would be captured twice and \
                 others never; {rerun}",
                paths[0].display(),
                path.display(),
                only_first.join(", "),
                only_here.join(", ")
            );
        }
    }
    let mut seen = std::collections::BTreeMap::new();
    for (report, path) in shards.iter().zip(paths) {
        for o in &report.outcomes {
            if let Some(other) = seen.insert(o.session.as_str(), path) {
                bail!(
                    "session {}: reported by two shards ({} and {}); {rerun}",
                    o.session,
                    other.display(),
                    path.display()
                );
            }
        }
    }
    Ok(())
}

fn join(reports: Vec<BatchReport>) -> BatchReport {
    let mut outcomes = std::collections::BTreeMap::new();
    let mut faces = std::collections::BTreeMap::new();
    let mut unfinished = 0;
    let mut merged =
        BatchReport::new(0, Vec::new(), false, &skinkit_maps::limits::MemoryGate::new(0), None, Vec::new());
    for report in reports {
        unfinished += report.sessions.saturating_sub(report.outcomes.len());
        merged.interrupted |= report.interrupted;
        merged.memory_limit_mib = merged.memory_limit_mib.max(report.memory_limit_mib);
        merged.most_at_once = merged.most_at_once.max(report.most_at_once);
        merged.memory_peak_mib = merged.memory_peak_mib.max(report.memory_peak_mib);
        merged.seconds = merged.seconds.max(report.seconds);
        if report.shard.is_some() {
            merged.sessions_per_minute += report.sessions_per_minute;
        }
        outcomes.extend(report.outcomes.into_iter().map(|o| (o.session.clone(), o)));
        faces.extend(report.faces.into_iter().map(|f| (f.subject.clone(), f)));
    }
    merged.sessions = outcomes.len() + unfinished;
    merged.outcomes = outcomes.into_values().collect();
    merged.faces = faces.into_values().collect();
    merged.recount();
    merged
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition_in_name_order() {
        let s: Shard = "2/3".parse().unwrap();
        assert_eq!(s, Shard { index: 2, count: 3 });
        for bad in ["0/3", "4/3", "3", "a/b", "1/0", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let names: Vec<usize> = (0..7).collect();
        let shares: Vec<Vec<usize>> = (1..=3).map(|k| Shard { index: k, count: 3 }.select(&names)).collect();
        assert_eq!(shares, vec![vec![0, 3, 6], vec![1, 4], vec![2, 5]]);
        assert!(Shard { index: 5, count: 9 }.select(&names[..3]).is_empty());
    }
}
