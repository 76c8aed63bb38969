//! A subject's face in a batch (`skinkit_batch::units`): stitched from its sessions' captures
//! into `face/`, as `skinkit face` would, unless it is up to date.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Deserialize;
use skinkit_maps::NormalEncoding;
use skinkit_maps::io::{self, Limits};

use skinkit_batch::resume;
use skinkit_batch::{FaceOutcome, Subject};

use crate::face::{StitchOptions, face_to_dir};
use crate::output::Output;
use crate::pipeline;
use skinkit_stitch::face::ExemplarCache;

/// Stitches `subject`'s face into `out/face` from its sessions' outputs (all captured), unless
/// it is up to date and not `force`d.
pub fn face(subject: &Subject, force: bool, out: &Output) -> FaceOutcome {
    let dir = subject.out.join("face");
    let start = Instant::now();
    let previous = resume::recorded(&dir);
    let now = made_from(subject, previous.as_ref());
    let current = matches!((&previous, &now), (Some(p), Ok(n)) if p == n) && dir.join("report.json").is_file();
    let result = if !force && current {
        previous_seconds(&dir).map(|s| (s, true))
    } else {
        stitch(subject, &dir, out).and_then(|seconds| {
            // Recorded after the face is in place: a face without its record is made again.
            let record = now?;
            pipeline::write_json(&dir.join(resume::MADE_FROM), "the record of the inputs", &record)?;
            Ok((seconds, false))
        })
    };
    match result {
        Ok((seconds, skipped)) => {
            FaceOutcome { subject: subject.name.clone(), ok: true, error: None, seconds: Some(seconds), skipped }
        }
        Err(e) => FaceOutcome {
            subject: subject.name.clone(),
            ok: false,
            error: Some(crate::output::one_line(&e.context(format!(
                "{} after {:.1} s",
                dir.display(),
                start.elapsed().as_secs_f64()
            )))),
            seconds: None,
            skipped: false,
        },
    }
}

/// The face with the layout's own size, seed 0 and the default spline, as `skinkit face` makes
/// it, every exemplar taken from the batch's capture of its session.
fn stitch(subject: &Subject, dir: &Path, out: &Output) -> Result<f64> {
    let mut cache = ExemplarCache::new();
    for job in &subject.jobs {
        let path = job.out.join("normal.exr");
        let map = io::read_normal_map(&path, NormalEncoding::default(), &Limits::default())
            .context("cannot read the captured map")?;
        cache.insert(job.dir.canonicalize().unwrap_or_else(|_| job.dir.clone()), map);
    }
    let options = StitchOptions::for_layout(subject.layout.clone());
    let report = face_to_dir(&options, dir, &mut cache, out, Instant::now())?;
    Ok(report.seconds.total)
}

/// What the face is made from: the layout's files and every session's captured normal map (their
/// sizes and hashes), and the stitch's options.
fn made_from(subject: &Subject, previous: Option<&resume::MadeFrom>) -> Result<resume::MadeFrom> {
    let inputs: Vec<PathBuf> =
        subject.inputs.iter().cloned().chain(subject.jobs.iter().map(|j| j.out.join("normal.exr"))).collect();
    let options = StitchOptions::for_layout(subject.layout.clone());
    resume::stamped(&inputs, format!("{options:?}"), previous)
}

/// The part of a face's report.json a skipped face reports again: its seconds.
#[derive(Deserialize)]
struct PreviousFace {
    seconds: PreviousSeconds,
}

#[derive(Deserialize)]
struct PreviousSeconds {
    total: f64,
}

/// The seconds the face in `dir` took when it was made.
fn previous_seconds(dir: &Path) -> Result<f64> {
    let path = dir.join("report.json");
    let text = skinkit_maps::input::read_to_string(&path, skinkit_maps::input::Kind::Report)?;
    let report: PreviousFace = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a face report (no seconds.total)", path.display()))?;
    Ok(report.seconds.total)
}
