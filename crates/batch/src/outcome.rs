//! One session of a batch: captured (or skipped when up to date), judged against `--min-valid`,
//! its review previews drawn ([`crate::review`]), and its line of the batch report.
//!
//! A session whose solve leaves fewer valid pixels than `--min-valid` of the map (blank or dark
//! photos, a lens cap, a mold outside the frame) is a failed outcome with the reason, although
//! its maps are written for inspection: a batch of 300 must not say all succeeded when one
//! yielded nothing (issue 44).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use skinkit_capture::Rig;
use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_maps::limits::{self, MemoryGate};

use crate::resume;
use crate::review::{self, Signs};
use crate::units::Job;

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
    /// What flags a bad capture (for the review page); absent when the session wrote no maps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub signs: Option<Signs>,
    /// Entries of the session folder that looked like inputs but were not regular files, each
    /// with the reason (issue 42, D17); also printed as notes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub skipped_files: Vec<String>,
}

/// How a batch captures each session.
pub struct Settings<'a> {
    pub options: &'a CaptureOptions,
    pub gate: &'a MemoryGate,
    pub force: bool,
    /// Least share of the map's pixels that must be valid (`--min-valid`).
    pub min_valid: f64,
    /// Where the review previews go (`OUT/batch-review`).
    pub review_dir: &'a Path,
}

/// What one session's run left: its figures, and what its commit cleaned up from killed runs.
struct SessionRun {
    invalid_pixels: usize,
    pixels: usize,
    seconds: f64,
    skipped: bool,
    signs: Signs,
    swept: Vec<PathBuf>,
    skipped_files: Vec<String>,
}

/// Captures one session once its memory estimate fits beside the sessions running (`gate`); a
/// session that could never fit fails at once with its estimate and the limit. Without `force`,
/// a session whose outputs were made from what it holds now ([`resume::up_to_date`]) is skipped.
fn run_session(job: &Job, settings: &Settings) -> Result<SessionRun> {
    let (dir, out_dir, options) = (&job.dir, &job.out, settings.options);
    let files = Session::from_dir(dir)?;
    let skipped_files: Vec<String> = files.skipped.iter().map(ToString::to_string).collect();
    // The rig's own ambient frame counts too; a rig that does not load is reported by `capture`.
    let rig = Rig::load(&files.rig).ok();
    let ambient = files.ambient.clone().or_else(|| rig.as_ref().and_then(|r| r.ambient().map(Path::to_path_buf)));
    let previews = settings.review_dir.join(&job.name);
    // Hashed before the capture reads them: a file changed meanwhile is captured again next time.
    let previous = resume::recorded(out_dir);
    let made =
        resume::made_from(&resume::inputs(dir, &files, ambient.as_deref(), rig.as_ref()), options, previous.as_ref())?;
    if let Some(done) = resume::up_to_date(out_dir, previous.as_ref(), &made).filter(|_| !settings.force) {
        let swept = skinkit_maps::output_set::sweep_folder(out_dir);
        let signs = review::signs_of_skipped(out_dir, &previews, &done)?;
        let (invalid_pixels, pixels, seconds) = (done.invalid_pixels, done.pixels, done.seconds);
        return Ok(SessionRun { invalid_pixels, pixels, seconds, skipped: true, signs, swept, skipped_files });
    }
    let estimate = session::memory_estimate(&files, ambient.as_deref(), options)?;
    limits::check_memory(&dir.display().to_string(), "capturing the session", estimate, settings.gate.budget())?;
    let _admitted = settings.gate.acquire(estimate);
    // Staged from the start, so an interrupt during the solve removes this session's folder too.
    let set = skinkit_capture::outputs::output_set(out_dir)?;
    set.write(resume::MADE_FROM, |p| skinkit_maps::documents::write_json(p, &made))
        .context("cannot write the record of the inputs")?;
    let mut captured = session::capture(&files, options, &skinkit_maps::progress::NoProgress)?;
    let signs = review::signs(&captured);
    review::write_previews(&previews, &captured, &signs)?;
    let swept = skinkit_capture::outputs::write(set, &mut captured, options)?;
    let report = &captured.report;
    Ok(SessionRun {
        invalid_pixels: report.invalid_pixels,
        pixels: report.width * report.height,
        seconds: report.timings_s.total,
        skipped: false,
        signs,
        swept,
        skipped_files,
    })
}

/// The reason a session with `invalid` of `pixels` pixels unsolved fails `--min-valid`, if it does.
pub fn too_few_valid(invalid: usize, pixels: usize, min_valid: f64) -> Option<String> {
    let valid = pixels.saturating_sub(invalid);
    let share = if pixels == 0 { 0.0 } else { valid as f64 / pixels as f64 };
    (share < min_valid).then(|| {
        format!(
            "only {valid} of {pixels} pixels ({:.2}%) could be solved, below --min-valid {} \
             (blank, dark or saturated photos?); its maps are written for inspection",
            100.0 * share,
            min_valid
        )
    })
}

/// One session's outcome; `swept` collects what its commit cleaned up from killed runs.
pub fn outcome(job: &Job, settings: &Settings, swept: &Mutex<Vec<PathBuf>>) -> SessionOutcome {
    let name = job.name.clone();
    match run_session(job, settings) {
        Ok(run) => {
            lock(swept).extend(run.swept);
            let error = too_few_valid(run.invalid_pixels, run.pixels, settings.min_valid);
            SessionOutcome {
                session: name,
                ok: error.is_none(),
                error,
                invalid_pixels: Some(run.invalid_pixels),
                seconds: Some(run.seconds),
                skipped: run.skipped,
                signs: Some(run.signs),
                skipped_files: run.skipped_files,
            }
        }
        Err(e) => SessionOutcome {
            session: name,
            ok: false,
            error: Some(skinkit_maps::error::one_line(e.as_ref())),
            invalid_pixels: None,
            seconds: None,
            skipped: false,
            signs: None,
            skipped_files: Vec::new(),
        },
    }
}

/// The value behind `mutex`, also after a panicking holder (the outcomes stay readable).
pub fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_session_below_the_valid_share_fails_with_its_numbers() {
        assert_eq!(too_few_valid(0, 100, 0.01), None);
        assert_eq!(too_few_valid(99, 100, 0.01), None, "exactly 1% valid is enough");
        let why = too_few_valid(100, 100, 0.01).unwrap();
        assert!(why.contains("only 0 of 100 pixels (0.00%)") && why.contains("--min-valid 0.01"), "{why}");
        assert!(too_few_valid(0, 0, 0.01).is_some(), "an empty map yields nothing");
        assert_eq!(too_few_valid(100, 100, 0.0), None, "--min-valid 0 accepts anything");
    }
}
