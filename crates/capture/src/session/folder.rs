//! The files of a session: a session folder's layout ([`Session::from_dir`]) and its photos
//! ([`photos_in`]). An entry that looks like an input but is not a regular file (a FIFO, a
//! device, a looping or dangling symlink, a folder named `05.png`) is not taken, and not dropped
//! silently either: it is kept in [`Session::skipped`] with the input gate's reason
//! ([`skinkit_maps::input`]), so reports and messages name it (issue 42, D17).

use std::path::{Path, PathBuf};

use serde::Serialize;
use skinkit_maps::format::ImageFormat;
use skinkit_maps::input::{self, InputError, Kind};

use crate::{Error, Result};

/// File stems a session folder reserves for other inputs: never taken as photos.
pub const RESERVED_STEMS: &[&str] = &["mask", "ambient", "truth"];

/// The files of one capture session.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Session {
    pub rig: PathBuf,
    /// Photos in rig order.
    pub photos: Vec<PathBuf>,
    pub mask: Option<PathBuf>,
    /// Ambient frame; overrides the rig's own.
    pub ambient: Option<PathBuf>,
    /// Ground-truth normal map to compare against (samples and tests).
    pub truth: Option<PathBuf>,
    /// Entries of the session folder that look like inputs but were not taken, with the reason.
    pub skipped: Vec<Skipped>,
}

/// A folder entry that looks like an input (a photo's extension, `mask.png`) but is not a
/// regular file, so it was not taken.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Skipped {
    pub path: PathBuf,
    /// The input gate's message, which names the file: `s/05.png: a FIFO (named pipe), not a
    /// regular file (...)`.
    pub reason: String,
}

impl std::fmt::Display for Skipped {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.reason)
    }
}

/// The photos of a folder in light order, and the entries skipped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PhotoFolder {
    pub photos: Vec<PathBuf>,
    pub skipped: Vec<Skipped>,
}

impl Session {
    /// The session a folder holds (see the module docs of [`crate::session`] for the layout).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the folder has no `rig.toml` or no photo; [`Error::Io`] when
    /// it cannot be listed; [`Error::Maps`] when `filenames.txt` cannot be read.
    pub fn from_dir(dir: &Path) -> Result<Session> {
        let rig = dir.join("rig.toml");
        // A `rig.toml` that is there but not a file is named by the rig's reader, not called missing.
        if rig.symlink_metadata().is_err() {
            return Err(Error::InvalidInput(format!("{}: no rig.toml in the session folder", dir.display())));
        }
        let PhotoFolder { photos, mut skipped } = photos_in(dir)?;
        let mut optional = |name: &str| match entry(&dir.join(name)) {
            Some(Ok(path)) => Some(path),
            Some(Err(skip)) => {
                skipped.push(skip);
                None
            }
            None => None,
        };
        let (mask, ambient, truth) = (optional("mask.png"), optional("ambient.png"), optional("truth.png"));
        Ok(Session { rig, photos, mask, ambient, truth, skipped })
    }
}

/// Photo files of a folder in light order: the order `filenames.txt` gives when the folder has
/// one (the DiLiGenT layout), else sorted by name (only names whose [`ImageFormat`] is a photo format: PNG, TIFF, EXR, camera RAW; never
/// [`RESERVED_STEMS`]); entries with a photo's name that are not regular files are skipped and
/// named.
///
/// # Errors
/// [`Error::Io`] when the folder cannot be listed; [`Error::Maps`] when `filenames.txt` cannot
/// be read; [`Error::InvalidInput`] when `filenames.txt` names a missing file or there is no photo.
pub fn photos_in(dir: &Path) -> Result<PhotoFolder> {
    let listing = dir.join("filenames.txt");
    if listing.symlink_metadata().is_ok() {
        return Ok(PhotoFolder { photos: photos_listed(&listing)?, skipped: Vec::new() });
    }
    let entries = std::fs::read_dir(dir).map_err(|error| Error::Io { path: dir.to_owned(), error })?;
    let mut found = PhotoFolder::default();
    for path in entries.filter_map(|e| e.ok().map(|e| e.path())).filter(|p| is_photo(p)) {
        match entry(&path) {
            Some(Ok(photo)) => found.photos.push(photo),
            Some(Err(skip)) => found.skipped.push(skip),
            None => {}
        }
    }
    found.photos.sort();
    found.skipped.sort_by(|a, b| a.path.cmp(&b.path));
    if found.photos.is_empty() {
        let message = format!("{}: no photos (.png, .tif, .tiff, .exr, camera RAW) found", dir.display());
        return Err(Error::InvalidInput(with_skipped(message, &found.skipped)));
    }
    Ok(found)
}

/// `message`, followed by the skipped entries when there are any.
pub(crate) fn with_skipped(message: String, skipped: &[Skipped]) -> String {
    if skipped.is_empty() {
        return message;
    }
    let named: Vec<String> = skipped.iter().map(ToString::to_string).collect();
    format!("{message}; skipped: {}", named.join("; "))
}

/// A folder entry to take (`Ok`), to skip with the reason (`Err`), or absent (`None`). A file over
/// the image limit is taken, so that reading it names the limit.
fn entry(path: &Path) -> Option<std::result::Result<PathBuf, Skipped>> {
    match input::look(path, Kind::Image) {
        Ok(_) | Err(InputError::TooLarge { .. }) => Some(Ok(path.to_owned())),
        Err(_) if path.symlink_metadata().is_err() => None,
        Err(e) => Some(Err(Skipped { path: path.to_owned(), reason: skinkit_maps::error::one_line(&e) })),
    }
}

/// The photos a `filenames.txt` lists, one per line, relative to its folder.
fn photos_listed(listing: &Path) -> Result<Vec<PathBuf>> {
    let text = input::read_to_string(listing, Kind::Listing).map_err(skinkit_maps::Error::from)?;
    let dir = listing.parent().unwrap_or(Path::new("."));
    let mut photos = Vec::new();
    for (line, name) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let path = dir.join(name.trim());
        // A listed entry that is there but not a regular file is refused by name when it is read.
        if path.symlink_metadata().is_err() {
            return Err(Error::InvalidInput(format!(
                "{}: line {}: photo `{}` does not exist",
                listing.display(),
                line + 1,
                name.trim()
            )));
        }
        photos.push(path);
    }
    if photos.is_empty() {
        return Err(Error::InvalidInput(format!("{}: lists no photos", listing.display())));
    }
    Ok(photos)
}

fn is_photo(path: &Path) -> bool {
    let stem = path.file_stem().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let photo = ImageFormat::of(path).is_some_and(ImageFormat::is_photo);
    photo && !RESERVED_STEMS.contains(&stem.as_str())
}
