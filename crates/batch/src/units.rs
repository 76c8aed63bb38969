//! What a batch shares out: sessions, and subjects (face batches). A folder that carries a `layout.toml` is a subject. `skinkit batch` captures the
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

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};
use skinkit_stitch::layout::{ExemplarSource, Layout};

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
