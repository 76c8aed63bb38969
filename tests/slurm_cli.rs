//! The README's Slurm array recipe under a real Slurm (issue 44): `scripts/slurm-local.sh`
//! starts a cluster of this one machine (installing Debian's `slurm-wlm` and `munge` when
//! missing), an array of 3 tasks runs `skinkit batch --shard auto` over 12 sessions (one of
//! blank photos), `--merge` joins them, and the result equals one batch bit for bit; the array
//! submitted again skips everything. Skips, saying why, only when Slurm cannot be installed or
//! started here.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::sessions::{self, Fault, assert_same_tree, molds, outcomes, report};
use crate::support::{repo, s, skinkit, stderr};

/// The single-node cluster, stopped (its daemons only) when dropped.
struct Cluster {
    dir: PathBuf,
    conf: String,
}

impl Cluster {
    /// Started by the script, or why it could not be.
    fn start(dir: &Path) -> Result<Cluster, String> {
        // Ports of this test's own, so a cluster already running here is left alone.
        let port = 20000 + (std::process::id() % 5000) * 2;
        let o = Command::new(repo().join("scripts/slurm-local.sh"))
            .args(["start", s(dir)])
            .env("SLURMCTLD_PORT", port.to_string())
            .env("SLURMD_PORT", (port + 1).to_string())
            .output()
            .expect("bash runs the script");
        match o.status.code() {
            Some(0) => {}
            Some(3) => return Err(stderr(&o)),
            _ => panic!("slurm-local.sh failed: {}", stderr(&o)),
        }
        let out = String::from_utf8_lossy(&o.stdout);
        let conf = out.lines().find_map(|l| l.strip_prefix("SLURM_CONF=")).expect("the script names the config");
        Ok(Cluster { dir: dir.to_owned(), conf: conf.to_owned() })
    }

    /// `sbatch --wait` of `script` from `dir`; its exit code (non-zero when a task failed).
    fn run_array(&self, script: &Path, dir: &Path) -> Option<i32> {
        let o = Command::new("sbatch")
            .env("SLURM_CONF", &self.conf)
            .args(["--wait", "--chdir", s(dir), "--output", "slurm-%A_%a.out", s(script)])
            .output()
            .expect("sbatch runs");
        eprintln!("sbatch: {}{}", String::from_utf8_lossy(&o.stdout), stderr(&o));
        o.status.code()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = Command::new(repo().join("scripts/slurm-local.sh")).args(["stop", s(&self.dir)]).output();
    }
}

/// The README's recipe, with this build's binary and the test's folders.
fn job_script(dir: &Path, sessions: &Path, maps: &Path) -> PathBuf {
    let script = dir.join("batch.sbatch");
    let text = format!(
        "#!/bin/sh\n#SBATCH --array=1-3\n#SBATCH --cpus-per-task=1\n'{}' batch --quiet '{}' --out '{}' --shard auto\n",
        env!("CARGO_BIN_EXE_skinkit"),
        s(sessions),
        s(maps)
    );
    std::fs::write(&script, text).unwrap();
    script
}

#[test]
fn a_slurm_array_of_three_tasks_merges_to_the_single_batch_and_resubmitted_skips_everything() {
    let tmp = tempfile::tempdir().unwrap();
    let cluster = match Cluster::start(&tmp.path().join("slurm")) {
        Ok(c) => c,
        Err(why) => {
            eprintln!("skipped: no Slurm here: {why}");
            return;
        }
    };
    let molds = molds(tmp.path(), 32);
    let names: Vec<String> = (0..12).map(|i| format!("mold-{i:02}")).collect();
    let dir = sessions::sessions(&tmp.path().join("sessions"), &molds, &names, &[(7, Fault::Blank)]);
    let (whole, maps) = (tmp.path().join("whole"), tmp.path().join("maps"));
    let o = skinkit(&["batch", "--quiet", s(&dir), "--out", s(&whole)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let script = job_script(tmp.path(), &dir, &maps);
    // A task whose shard holds the blank session exits 1, so sbatch --wait says a task failed.
    assert_ne!(cluster.run_array(&script, tmp.path()), Some(0));
    for k in 1..=3 {
        let shard = report(&maps.join(format!("batch-report-{k}-of-3.json")));
        assert_eq!(shard["sessions"], 4, "shard {k}");
    }
    let o = skinkit(&["batch", "--quiet", "--merge", "--out", s(&maps)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let (merged, single) = (report(&maps.join("batch-report.json")), report(&whole.join("batch-report.json")));
    assert_eq!(outcomes(&merged), outcomes(&single));
    assert_eq!((merged["sessions"].as_u64(), merged["failed"].as_u64()), (Some(12), Some(1)));
    let blank = merged["outcomes"].as_array().unwrap().iter().find(|o| o["session"] == "mold-07").unwrap();
    assert!(blank["ok"] == false && blank["error"].as_str().unwrap().contains("--min-valid"), "{blank}");
    assert_same_tree(&whole, &maps);
    assert!(maps.join("batch-review.html").is_file());
    // Submitted again: every session is up to date.
    cluster.run_array(&script, tmp.path());
    for k in 1..=3 {
        let shard = report(&maps.join(format!("batch-report-{k}-of-3.json")));
        assert_eq!(shard["skipped"], 4, "shard {k} ran again: {shard}");
    }
}
