//! Face batches: a folder that carries a `layout.toml` is a subject. `skinkit batch` captures the
//! sessions its layout names (each into its own output folder, as any session) and then stitches
//! the subject's face map from those captures into `face/`, as `skinkit face` would.
//!
//! - The sessions folder itself may be a subject: its outputs go straight into `--out`.
//! - Or its sub-folders may be subjects, one per folder (`SESSIONS/ann/layout.toml`): subject
//!   `ann` writes `OUT/ann/SESSION/` per session and `OUT/ann/face/`; its sessions are reported as
//!   `ann/SESSION`. Sub-folders without a layout are plain sessions, as before.
//!
//! A subject is one unit of a shard (`--shard`): its sessions and its face go to the same shard,
//! so a face never waits on another machine. The face is built from the sessions' own outputs
//! (`normal.exr`, float), so a re-run that skipped them still stitches the same map, and it is
//! itself skipped when its `report.json` is newer than the layout and every session's report.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use skinkit_maps::NormalEncoding;
use skinkit_maps::io::{self, Limits};
use skinkit_stitch::layout::{ExemplarSource, Layout};

use super::resume;
use crate::cmd::stitch::{CaptureCache, StitchOptions, face_to_dir};
use crate::output::Output;
use crate::pipeline;

/// The file that makes a folder a subject.
pub const LAYOUT: &str = "layout.toml";

/// One session to capture: its folder, its output folder and its name in the report.
#[derive(Clone, Debug)]
pub struct Job {
    pub dir: PathBuf,
    pub out: PathBuf,
    pub name: String,
}

/// A subject: its layout, its output folder and the sessions its layout names.
#[derive(Clone, Debug)]
pub struct Subject {
    pub name: String,
    pub layout: PathBuf,
    /// The files the layout reads besides its sessions (the layout itself, its coverage mask and
    /// normal-map exemplars).
    pub inputs: Vec<PathBuf>,
    pub out: PathBuf,
    pub jobs: Vec<Job>,
}

/// What a batch shares out: a session, or a subject with its sessions.
#[derive(Clone, Debug)]
pub enum Unit {
    Session(Job),
    Subject(Subject),
}

impl Unit {
    /// The unit's name: the session's, or the subject's (its folder's name).
    pub fn name(&self) -> &str {
        match self {
            Unit::Session(job) => &job.name,
            Unit::Subject(s) => &s.name,
        }
    }

    /// The sessions this unit captures.
    pub fn jobs(&self) -> &[Job] {
        match self {
            Unit::Session(job) => std::slice::from_ref(job),
            Unit::Subject(s) => &s.jobs,
        }
    }
}

/// A subject's face: written, skipped (up to date) or failed, and why.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct FaceOutcome {
    pub subject: String,
    pub ok: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
    /// Not stitched again: its outputs were newer than the layout and every session's.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub skipped: bool,
}

/// The units of the sessions folder `root`, in name order, with their output folders in `out`.
///
/// # Errors
/// When a folder cannot be listed or a subject's layout does not load.
pub fn units(root: &Path, out: &Path) -> Result<Vec<Unit>> {
    if root.join(LAYOUT).is_file() {
        let name = root.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        // The subject's own folder is the root: its name is only a label, not an output path.
        return Ok(vec![Unit::Subject(subject(root, name, out, "")?)]);
    }
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root)
        .with_context(|| format!("cannot list sessions in {}", root.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    dirs.into_iter()
        .map(|dir| {
            let name = output_name(&dir)?;
            let target = out.join(&name);
            if dir.join(LAYOUT).is_file() {
                Ok(Unit::Subject(subject(&dir, name.clone(), &target, &format!("{name}/"))?))
            } else {
                Ok(Unit::Session(Job { dir, out: target, name }))
            }
        })
        .collect()
}

/// The name of the output folder of the input folder `dir`: its own name, through the output gate
/// (a name that is not UTF-8, or not a plain file name, is refused before any work: written
/// lossily, two sessions could share one output folder).
fn output_name(dir: &Path) -> Result<String> {
    let name = dir.file_name().unwrap_or(dir.as_os_str());
    let name = skinkit_maps::names::file_component(name)
        .with_context(|| format!("{}: the folder's name cannot name an output folder", dir.display()))?;
    Ok(name.to_owned())
}

/// The subject of `dir/layout.toml`: the distinct sessions its regions name, in region order,
/// each captured into `out/FOLDER_NAME` and reported as `prefix` + folder name.
fn subject(dir: &Path, name: String, out: &Path, prefix: &str) -> Result<Subject> {
    let layout_path = dir.join(LAYOUT);
    let layout = Layout::load(&layout_path)?;
    let mut jobs: Vec<Job> = Vec::new();
    for region in &layout.regions {
        let ExemplarSource::Session(session) = &region.exemplar else { continue };
        if jobs.iter().any(|j| same_folder(&j.dir, session)) {
            continue;
        }
        let folder =
            output_name(session).with_context(|| format!("{}: region `{}`", layout_path.display(), region.name))?;
        if let Some(other) = jobs.iter().find(|j| j.out.ends_with(&folder)) {
            bail!(
                "{}: region `{}`: sessions {} and {} would share the output folder {}",
                layout_path.display(),
                region.name,
                other.dir.display(),
                session.display(),
                out.join(&folder).display()
            );
        }
        jobs.push(Job { dir: session.clone(), out: out.join(&folder), name: format!("{prefix}{folder}") });
    }
    Ok(Subject { name, layout: layout_path, inputs: layout.input_files(), out: out.to_owned(), jobs })
}

fn same_folder(a: &Path, b: &Path) -> bool {
    a == b || a.canonicalize().ok().is_some_and(|a| b.canonicalize().ok() == Some(a))
}

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
            pipeline::write_json(&dir.join(resume::MADE_FROM), &record)?;
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
    let mut cache = CaptureCache::new();
    for job in &subject.jobs {
        let path = job.out.join("normal.exr");
        let map = io::read_normal_map(&path, NormalEncoding::default(), &Limits::default())
            .with_context(|| format!("cannot read the captured map {}", path.display()))?;
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

fn previous_seconds(dir: &Path) -> Result<f64> {
    let path = dir.join("report.json");
    let text = skinkit_maps::input::read_to_string(&path, skinkit_maps::input::Kind::Report)?;
    let report: serde_json::Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    report["seconds"]["total"].as_f64().with_context(|| format!("{}: no seconds.total", path.display()))
}
