//! Re-running a batch (`skinkit batch` again on the same output folder): a session whose outputs
//! are complete and made from what it holds now is not captured again (`--force` redoes it).
//!
//! Complete: the session's `report.json` exists (its output set writes it last, so a folder with
//! it holds every output). Made from what it holds now: its `made-from.json` records the skinkit
//! version, every option that shapes the outputs (the whole resolved [`CaptureOptions`] but its
//! limits) and each input file's size and BLAKE3 hash (photos, rig, mask, ambient frame, flat
//! frames, truth, `filenames.txt`), and all of it equals what this run would record. Time stamps
//! decide nothing: a photo replaced by `cp -p`, `rsync -t` or `tar x` keeps an old one. A file's
//! hash is reused from the record only when its size, modification and status-change times and
//! inode all match (the status-change time no tool can set back), so an unchanged session costs a
//! `stat` per file, not a read. Anything else, including a record that does not parse, runs the
//! session again.

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use skinkit_capture::session::{CaptureOptions, Session};
use skinkit_maps::input::{self, Kind};

/// The file of a session's output folder that says what its outputs were made from.
pub const MADE_FROM: &str = "made-from.json";

/// What a skipped session's report says.
pub struct Done {
    pub invalid_pixels: usize,
    /// Pixels of the map (width x height).
    pub pixels: usize,
    pub condition_number: Option<f64>,
    pub seconds: f64,
}

/// What a session's outputs were made from.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MadeFrom {
    pub skinkit: String,
    /// The resolved options (Rust's `Debug` form of [`CaptureOptions`], limits reset): every
    /// field, including any added later, is in it.
    pub options: String,
    pub inputs: Vec<Stamp>,
}

/// One input file: its path, size and content hash, and the `stat` key that lets a later run
/// trust the hash without reading the file.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Stamp {
    pub file: String,
    pub size: u64,
    pub blake3: String,
    pub stat: StatKey,
}

impl PartialEq for Stamp {
    /// The same file with the same content; the `stat` key is only a shortcut.
    fn eq(&self, other: &Stamp) -> bool {
        (&self.file, self.size, &self.blake3) == (&other.file, other.size, &other.blake3)
    }
}

/// Size, times and identity of a file as `stat` gives them.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq, Eq)]
pub struct StatKey {
    pub size: u64,
    pub modified_ns: i128,
    pub changed_ns: i128,
    pub inode: u64,
    pub device: u64,
}

impl StatKey {
    fn of(path: &Path) -> Result<StatKey> {
        let m = std::fs::metadata(path).with_context(|| format!("cannot read {}", path.display()))?;
        Ok(stat_key(&m))
    }
}

#[cfg(unix)]
fn stat_key(m: &std::fs::Metadata) -> StatKey {
    use std::os::unix::fs::MetadataExt;
    let ns = |s: i64, n: i64| i128::from(s) * 1_000_000_000 + i128::from(n);
    StatKey {
        size: m.len(),
        modified_ns: ns(m.mtime(), m.mtime_nsec()),
        changed_ns: ns(m.ctime(), m.ctime_nsec()),
        inode: m.ino(),
        device: m.dev(),
    }
}

/// Elsewhere only the size and modification time are known: never trusted alone (the key is
/// used only when it also matches the inode, which is 0 here), so every file is hashed.
#[cfg(not(unix))]
fn stat_key(m: &std::fs::Metadata) -> StatKey {
    StatKey { size: m.len(), ..StatKey::default() }
}

/// The files a capture of `files` reads, the files of its `rig` (when it loads) included.
pub fn inputs(
    dir: &Path,
    files: &Session,
    ambient: Option<&Path>,
    rig: Option<&skinkit_capture::rig::Rig>,
) -> Vec<std::path::PathBuf> {
    let listing = dir.join("filenames.txt");
    let mut all: Vec<std::path::PathBuf> = files
        .photos
        .iter()
        .cloned()
        .chain([files.rig.clone()])
        .chain(files.mask.clone())
        .chain(ambient.map(Path::to_path_buf))
        .chain(rig.into_iter().flat_map(|r| r.input_files()).map(Path::to_path_buf))
        .chain(files.truth.clone())
        .chain(Some(listing).filter(|p| p.is_file()))
        .collect();
    all.dedup();
    all
}

/// What a capture of `inputs` with `options` is made from; hashes are taken from `previous`
/// where a file's `stat` key is unchanged.
///
/// # Errors
/// When an input cannot be read.
pub fn made_from(
    inputs: &[std::path::PathBuf],
    options: &CaptureOptions,
    previous: Option<&MadeFrom>,
) -> Result<MadeFrom> {
    let mut shaping = options.clone();
    // Limits refuse or admit a job; they never change its bytes.
    shaping.limits = Default::default();
    shaping.memory_limit = 0;
    stamped(inputs, format!("{shaping:?}"), previous)
}

/// What a job of `inputs` with the resolved `options` (their `Debug` form: every field) is made
/// from; hashes are taken from `previous` where a file's `stat` key is unchanged.
///
/// # Errors
/// When an input cannot be read.
pub fn stamped(inputs: &[std::path::PathBuf], options: String, previous: Option<&MadeFrom>) -> Result<MadeFrom> {
    let stamps = inputs
        .iter()
        .map(|path| {
            let file = path.display().to_string();
            let stat = StatKey::of(path)?;
            let known = previous
                .and_then(|p| p.inputs.iter().find(|s| s.file == file))
                .filter(|s| s.stat == stat && stat.inode != 0);
            let blake3 = match known {
                Some(s) => s.blake3.clone(),
                None => hash(path)?,
            };
            Ok(Stamp { file, size: stat.size, blake3, stat })
        })
        .collect::<Result<_>>()?;
    Ok(MadeFrom { skinkit: env!("CARGO_PKG_VERSION").to_owned(), options, inputs: stamps })
}

/// The blake3 hash of an input, read through the input gate as the kind of file it is.
fn hash(path: &Path) -> Result<String> {
    let file = input::open(path, input_kind(path))?;
    let mut hasher = blake3::Hasher::new();
    hasher.update_reader(file).with_context(|| format!("cannot read {}", path.display()))?;
    Ok(hasher.finalize().to_hex().to_string())
}

/// The kind of a session's input file for the input gate: the rig and the photo listing are
/// text, camera RAW photos have their own limit, everything else is an image.
fn input_kind(path: &Path) -> Kind {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("toml") => Kind::Toml,
        Some("txt") => Kind::Listing,
        _ if skinkit_maps::raw::is_raw(path) => Kind::RawPhoto,
        _ => Kind::Image,
    }
}

/// The record in `out_dir`, if it parses.
pub fn recorded(out_dir: &Path) -> Option<MadeFrom> {
    serde_json::from_str(&input::read_to_string(&out_dir.join(MADE_FROM), Kind::Report).ok()?).ok()
}

/// The session's previous result in `out_dir`, when it is complete and made from `now`.
pub fn up_to_date(out_dir: &Path, previous: Option<&MadeFrom>, now: &MadeFrom) -> Option<Done> {
    if previous? != now {
        return None;
    }
    let report: serde_json::Value =
        serde_json::from_str(&input::read_to_string(&out_dir.join("report.json"), Kind::Report).ok()?).ok()?;
    Some(Done {
        invalid_pixels: report["invalid_pixels"].as_u64()? as usize,
        pixels: (report["width"].as_u64()? * report["height"].as_u64()?) as usize,
        condition_number: report["condition_number"].as_f64(),
        seconds: report["timings_s"]["total"].as_f64()?,
    })
}
