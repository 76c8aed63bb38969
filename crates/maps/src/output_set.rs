//! Output sets written all or nothing (issue 15, defects D3 and D4).
//!
//! [`crate::io::write_atomic`] makes one file whole or absent; a command writes several (a capture
//! writes four maps and a report), and a reader must never find some of them new and some old or
//! missing. An [`OutputSet`] stages every file of one result in a hidden folder beside its
//! destination, on the same filesystem, and [`OutputSet::commit`] moves them into place with
//! renames only, after everything was written:
//!
//! * A folder set ([`OutputSet::folder`]) that did not exist becomes its staging folder in one
//!   rename. An existing folder holds its own staging folder, so the renames stay on its
//!   filesystem when it is a mount point; a rename that still crosses filesystems (`EXDEV`)
//!   falls back on a copy to a temporary file beside the destination and a rename of that. Into an existing folder (a re-capture), the set's marker file (the report, written
//!   last) is removed first, the other files are renamed over their old versions and the marker
//!   comes last, so a folder holding the marker holds one complete set. Files of the folder that the
//!   set does not write are left alone: `--out .` must not delete a user's files.
//! * A set of loose files ([`OutputSet::files`], e.g. `synth --out x.png --coords c.png`) stages
//!   each in a hidden folder in its destination's folder and renames them in the order they were
//!   added (the report last).
//!
//! Dropping a set that was not committed (an error, a panic unwinding) removes its staging folders
//! and the folders it created, so a failed run leaves the destination as it was.
//!
//! Interrupts: every live staging folder is listed in a process-wide registry, and a commit holds
//! the registry's lock while it renames. [`abandon_all`] (called by the binary's signal handler)
//! takes that lock and keeps it, so a commit in progress finishes first and none starts after;
//! then it removes every staging folder. A run that was killed outright (SIGKILL, power loss)
//! leaves its staging folder: staging folders carry the writer's process id, and the next set
//! written to the same destination removes those whose process is gone (`OutputSet::swept`).
//!
//! Test hook: with `SKINKIT_FAULT_WRITE_AFTER_BYTES=N` in the environment, an atomic write fails
//! with "No space left on device" once its file passes N bytes, as on a disk with N bytes free
//! (each failed write frees its space again). The end-to-end tests use it to fail chosen outputs
//! deterministically, besides a real small tmpfs where they can mount one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, OnceLock};

use crate::{Error, Result};

/// Middle part of a staging folder's name: `.<label>.staging.<owner>.<pid>.<n>`, where `owner`
/// says which machine and process namespace the writer runs in ([`owner`]).
const STAGING: &str = ".staging.";
/// Label of the staging folders of loose files.
const FILES_LABEL: &str = "skinkit";

/// Staging folders (and folders created for them) of every live set, by set id.
static LIVE: Mutex<BTreeMap<u64, Vec<PathBuf>>> = Mutex::new(BTreeMap::new());
/// Set ids and staging-name counters.
static NEXT: AtomicU64 = AtomicU64::new(0);

fn live() -> MutexGuard<'static, BTreeMap<u64, Vec<PathBuf>>> {
    LIVE.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Files written together, moved into place together (see the module documentation).
#[derive(Debug)]
pub struct OutputSet {
    id: u64,
    /// The destination folder and the marker file renamed last, for a folder set.
    folder: Option<(PathBuf, String)>,
    /// Staging folders, one per destination folder, with that destination.
    stagings: Vec<(PathBuf, PathBuf)>,
    /// Loose files: (staged path, final path), in commit order.
    files: Vec<(PathBuf, PathBuf)>,
    swept: Vec<PathBuf>,
    done: bool,
}

impl OutputSet {
    /// A set that becomes the folder `target`; `marker` (e.g. `report.json`) is written last by
    /// the caller and renamed in last.
    ///
    /// Removes what killed runs left: staging folders of `target` whose process is gone (and, at
    /// the commit, old temporary files of the files it replaces; see [`Self::commit`]).
    ///
    /// # Errors
    /// When `target` exists and is not a folder, or the staging folder cannot be created.
    pub fn folder(target: &Path, marker: &str) -> Result<OutputSet> {
        if target.exists() && !target.is_dir() {
            return Err(Error::InvalidParameter(format!(
                "{}: the output is a file, but a folder is written here",
                target.display()
            )));
        }
        let mut set = OutputSet::empty();
        set.folder = Some((target.to_owned(), marker.to_owned()));
        let (parent, name) = split(target)?;
        let name = label(&name);
        set.create_parent(&parent)?;
        set.swept.extend(sweep_staging(&parent, &name));
        // Into an existing folder the staging folder goes inside it (issue 42, D12): the commit's
        // renames then stay on the target's filesystem when it is a mount point (a container
        // volume, a scratch mount), which a staging folder beside it would not be on.
        let home = if target.is_dir() {
            set.swept.extend(sweep_staging(target, &name));
            target.to_owned()
        } else {
            parent
        };
        set.new_staging(&home, &name, target)?;
        Ok(set)
    }

    /// An empty set of loose files; add them with [`Self::file`].
    pub fn files() -> OutputSet {
        OutputSet::empty()
    }

    fn empty() -> OutputSet {
        let id = NEXT.fetch_add(1, Ordering::Relaxed);
        live().insert(id, Vec::new());
        OutputSet { id, folder: None, stagings: Vec::new(), files: Vec::new(), swept: Vec::new(), done: false }
    }

    /// Where to write `relative` (a file name, or `sub/name`) of a folder set: a path in the
    /// staging folder, whose parent folders exist.
    ///
    /// # Errors
    /// When this is not a folder set, or a sub-folder cannot be created.
    pub fn path(&self, relative: impl AsRef<Path>) -> Result<PathBuf> {
        let Some((staging, _)) = self.stagings.first().filter(|_| self.folder.is_some()) else {
            return Err(Error::InvalidParameter("OutputSet::path needs a folder set".into()));
        };
        let path = staging.join(relative);
        if let Some(parent) = path.parent() {
            // Under the registry's lock: after an interrupt removed the staging folder,
            // `create_dir_all` would make it again; this waits for the exit instead.
            let _live = live();
            std::fs::create_dir_all(parent).map_err(|e| Error::io(self.unstage(parent), e))?;
        }
        Ok(path)
    }

    /// Adds the loose file `target` and returns where to write it (in a staging folder beside it).
    ///
    /// # Errors
    /// When `target` is an existing folder, was already added, or its staging folder cannot be
    /// created.
    pub fn file(&mut self, target: &Path) -> Result<PathBuf> {
        if target.is_dir() {
            return Err(Error::InvalidParameter(format!(
                "{}: the output is a folder, but a file is written here",
                target.display()
            )));
        }
        if self.files.iter().any(|(_, t)| t == target) {
            return Err(Error::InvalidParameter(format!("{}: two outputs are written to this path", target.display())));
        }
        let (parent, name) = split(target)?;
        let staging = match self.stagings.iter().find(|(_, p)| *p == parent) {
            Some((staging, _)) => staging.clone(),
            None => {
                self.create_parent(&parent).map_err(|e| e.for_output(target))?;
                self.swept.extend(sweep_staging(&parent, FILES_LABEL));
                self.new_staging(&parent, FILES_LABEL, &parent).map_err(|e| e.for_output(target))?
            }
        };
        self.swept.extend(sweep_old_temps(target));
        let staged = staging.join(&name);
        self.files.push((staged.clone(), target.to_owned()));
        Ok(staged)
    }

    /// Runs `write` on the staged path of `relative` (folder set) and names the final path, not
    /// the staged one, in its error.
    ///
    /// # Errors
    /// Those of [`Self::path`] and of `write`.
    pub fn write(&self, relative: impl AsRef<Path>, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let path = self.path(relative)?;
        write(&path).map_err(|e| self.unstage_error(e))
    }

    /// [`Self::file`], then `write` on the staged path, naming `target` in its error.
    ///
    /// # Errors
    /// Those of [`Self::file`] and of `write`.
    pub fn write_file(&mut self, target: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
        let path = self.file(target)?;
        write(&path).map_err(|e| self.unstage_error(e))
    }

    /// The final path of a path inside one of this set's staging folders (others are returned
    /// as they are): for messages.
    pub fn unstage(&self, path: &Path) -> PathBuf {
        for (staging, dest) in &self.stagings {
            if let Ok(rest) = path.strip_prefix(staging) {
                return dest.join(rest);
            }
        }
        path.to_owned()
    }

    /// `error` with a staged path it names replaced by the final path: for errors of writes the
    /// caller ran on [`Self::file`]'s paths.
    pub fn unstage_error(&self, error: Error) -> Error {
        match error {
            Error::Io { path, error } => Error::Io { path: self.unstage(&path), error },
            Error::Encode { path, reason } => Error::Encode { path: self.unstage(&path), reason },
            other => other,
        }
    }

    /// Moves every file into place (renames only) and removes the staging folders. Returns what
    /// killed runs had left and was removed: their staging folders beside the destinations and
    /// the temporary files of [`crate::io::write_atomic`] (`.<name>.XXXXXX.tmp`) of the files
    /// this set writes, so that a re-run can say it cleaned up.
    ///
    /// # Errors
    /// When a destination is a folder or a rename fails; before the first rename nothing at the
    /// destination has changed, and dropping the set then removes what was staged.
    pub fn commit(mut self) -> Result<Vec<PathBuf>> {
        let guard = live();
        match self.folder.clone() {
            Some((target, marker)) => self.commit_folder(&target, &marker)?,
            None => self.commit_files()?,
        }
        for (staging, _) in &self.stagings {
            // Holds only empty sub-folders by now, or was renamed into place.
            let _ = std::fs::remove_dir_all(staging);
        }
        self.done = true;
        drop(guard);
        live().remove(&self.id);
        Ok(std::mem::take(&mut self.swept))
    }

    fn commit_folder(&mut self, target: &Path, marker: &str) -> Result<()> {
        let (staging, _) = &self.stagings[0];
        if !target.exists() {
            match std::fs::rename(staging, target) {
                // A mount point made meanwhile: moved file by file below, copying where needed.
                Err(e) if e.kind() == std::io::ErrorKind::CrossesDevices => {}
                done => return done.map_err(|e| Error::io(target, e)),
            }
        }
        let mut moves = Vec::new();
        staged_files(staging, target, &mut moves).map_err(|e| Error::io(target, e))?;
        // The marker last: remove the old one first, so no reader takes a mixed folder as done.
        moves.sort_by_key(|(_, to)| to == &target.join(marker));
        check_destinations(&moves)?;
        for (_, to) in &moves {
            self.swept.extend(sweep_old_temps(to));
        }
        let old_marker = target.join(marker);
        if old_marker.is_file() {
            std::fs::remove_file(&old_marker).map_err(|e| Error::io(&old_marker, e))?;
        }
        rename_all(&moves)
    }

    fn commit_files(&self) -> Result<()> {
        check_destinations(&self.files)?;
        rename_all(&self.files)
    }

    /// Creates `parent` and the missing folders above it, remembering them for the rollback.
    fn create_parent(&self, parent: &Path) -> Result<()> {
        let mut missing = Vec::new();
        let mut p = parent;
        while !p.as_os_str().is_empty() && !p.exists() {
            missing.push(p.to_owned());
            match p.parent() {
                Some(up) => p = up,
                None => break,
            }
        }
        // Created and listed under the registry's lock, so an interrupt sees both or neither.
        let mut live = live();
        for dir in missing.into_iter().rev() {
            match std::fs::create_dir(&dir) {
                Ok(()) => {}
                // Made by another writer meanwhile: theirs, not ours to remove.
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(Error::io(&dir, e)),
            }
            // Listed with the set's staging folders: removed, if empty, when the set is dropped.
            live.entry(self.id).or_default().push(dir);
        }
        Ok(())
    }

    /// Creates `.<label>.staging.<owner>.<pid>.<n>` in `parent` for the destination `dest`.
    fn new_staging(&mut self, parent: &Path, label: &str, dest: &Path) -> Result<PathBuf> {
        let pid = format!("{}.{}", owner(), std::process::id());
        // Created and registered under the registry's lock, so an interrupt (which takes the
        // lock for good) either removes it or comes before it exists.
        let mut live = live();
        loop {
            let n = NEXT.fetch_add(1, Ordering::Relaxed);
            let dir = parent.join(format!(".{label}{STAGING}{pid}.{n}"));
            match std::fs::create_dir(&dir) {
                Ok(()) => {
                    live.entry(self.id).or_default().push(dir.clone());
                    self.stagings.push((dir.clone(), dest.to_owned()));
                    return Ok(dir);
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                Err(e) => return Err(Error::io(dest, e)),
            }
        }
    }
}

impl Drop for OutputSet {
    /// Not committed: removes the staging folders and the folders created for them.
    fn drop(&mut self) {
        let mut live = live();
        if !self.done
            && let Some(paths) = live.get(&self.id)
        {
            remove_all(paths);
        }
        live.remove(&self.id);
    }
}

/// Removes every live set's staging folders and keeps the registry locked for good, so that no
/// set commits or starts after it: for a signal handler that ends the process next. Waits for a
/// commit in progress. Returns how many folders were removed.
pub fn abandon_all() -> usize {
    let live = live();
    let paths: Vec<PathBuf> = live.values().flatten().cloned().collect();
    let removed = remove_all(&paths);
    std::mem::forget(live);
    removed
}

/// Removes staging folders (retrying while a writer still adds files to them), then the created
/// folders that are empty, innermost first. Returns how many staging folders went.
fn remove_all(paths: &[PathBuf]) -> usize {
    let mut removed = 0;
    for path in paths.iter().filter(|p| is_staging(p)) {
        for _ in 0..50 {
            match std::fs::remove_dir_all(path) {
                Ok(()) => {
                    removed += 1;
                    break;
                }
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => break,
                Err(_) => std::thread::sleep(std::time::Duration::from_millis(2)),
            }
        }
    }
    for path in paths.iter().rev().filter(|p| !is_staging(p)) {
        let _ = std::fs::remove_dir(path);
    }
    removed
}

fn is_staging(path: &Path) -> bool {
    path.file_name().and_then(|n| n.to_str()).is_some_and(|n| n.starts_with('.') && n.contains(STAGING))
}

/// The parent folder (`.` for a bare name) and the file name of a destination. A name that is
/// not UTF-8 is a valid Linux name and is kept as it is (issue 42, D15: it was refused only at
/// the commit, after the work); staging folders are labelled with its lossy form ([`label`]).
fn split(target: &Path) -> Result<(PathBuf, std::ffi::OsString)> {
    if target.file_name().is_none() && target.exists() {
        // `.` or `dir/..`: the folder's own name, beside which its staging folder goes.
        let canonical = target.canonicalize().map_err(|e| Error::io(target, e))?;
        if canonical.file_name().is_some() {
            return split(&canonical);
        }
    }
    let name = target
        .file_name()
        .ok_or_else(|| Error::InvalidParameter(format!("{}: not a file or folder name", target.display())))?;
    let parent = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    };
    Ok((parent, name.to_owned()))
}

/// A destination's name as a staging folder's label: its lossy UTF-8 form.
fn label(name: &std::ffi::OsStr) -> String {
    name.to_string_lossy().into_owned()
}

/// Every file under `staging`, paired with its place under `target`.
fn staged_files(staging: &Path, target: &Path, out: &mut Vec<(PathBuf, PathBuf)>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(staging)? {
        let entry = entry?;
        let dest = target.join(entry.file_name());
        if entry.file_type()?.is_dir() {
            staged_files(&entry.path(), &dest, out)?;
        } else {
            out.push((entry.path(), dest));
        }
    }
    Ok(())
}

/// Refuses before any rename when a destination is a folder, or its folder is a file (a rename
/// would fail half-way).
fn check_destinations(moves: &[(PathBuf, PathBuf)]) -> Result<()> {
    for (_, to) in moves {
        if to.is_dir() {
            return Err(Error::InvalidParameter(format!(
                "{}: is a folder, so the output file cannot be written",
                to.display()
            )));
        }
        if let Some(dir) = to.parent().filter(|d| d.exists() && !d.is_dir()) {
            let refused = Error::InvalidParameter(format!("{}: is a file, but outputs go in it", dir.display()));
            return Err(refused.for_output(to));
        }
    }
    Ok(())
}

fn rename_all(moves: &[(PathBuf, PathBuf)]) -> Result<()> {
    for (from, to) in moves {
        if let Some(dir) = to.parent().filter(|d| !d.as_os_str().is_empty() && !d.exists()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e).for_output(to))?;
        }
        move_file(from, to).map_err(|e| Error::io(to, e))?;
    }
    Ok(())
}

/// Renames `from` to `to`; across filesystems (`EXDEV`, a destination that is or holds a mount
/// point), copies into a temporary file beside `to` and renames that instead, so `to` is still
/// replaced whole or not at all (issue 42, D12).
fn move_file(from: &Path, to: &Path) -> std::io::Result<()> {
    match std::fs::rename(from, to) {
        Err(e) if e.kind() == std::io::ErrorKind::CrossesDevices => copy_across(from, to),
        done => done,
    }
}

/// The copy of [`move_file`]: a temporary file named as [`crate::io::write_atomic`] names its
/// own (`.<name>.XXXXXX.tmp`, swept after a killed run), renamed over `to`, then `from` removed.
fn copy_across(from: &Path, to: &Path) -> std::io::Result<()> {
    let dir = match to.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = to.file_name().and_then(|n| n.to_str()).unwrap_or("output");
    let tmp = tempfile::Builder::new().prefix(&format!(".{name}.")).suffix(".tmp").tempfile_in(dir)?;
    std::fs::copy(from, tmp.path())?;
    tmp.as_file().sync_all()?;
    tmp.persist(to).map_err(|e| e.error)?;
    std::fs::remove_file(from)
}

/// Removes what killed runs left around the output folder `target` without writing it: the
/// staging folders of [`OutputSet::folder`] beside it whose process is gone, and the old temporary
/// files of the files in it (what a folder set's creation and commit sweep; for a caller that
/// keeps the folder as it is, such as a batch skipping an up-to-date session). Returns what it
/// removed.
pub fn sweep_folder(target: &Path) -> Vec<PathBuf> {
    let Ok((parent, name)) = split(target) else { return Vec::new() };
    let name = label(&name);
    let mut swept = sweep_staging(&parent, &name);
    swept.extend(sweep_staging(target, &name));
    for file in entries(target).into_iter().filter(|p| p.is_file()) {
        swept.extend(sweep_old_temps(&file));
    }
    swept
}

/// Removes the staging folders in `parent` of writers that are gone: ours
/// (`.<label>.staging.<owner>.<pid>.<n>` with this [`owner`]) whose process no longer runs, and
/// those of versions before owners (`.<label>.staging.<pid>.<n>`) likewise. A folder of another
/// owner (another host on a shared folder, another container) is never touched: its process is
/// not in this machine's `/proc` however alive it is.
fn sweep_staging(parent: &Path, label: &str) -> Vec<PathBuf> {
    let prefix = format!(".{label}{STAGING}");
    let mut swept = Vec::new();
    for path in entries(parent) {
        let Some(rest) = path.file_name().and_then(|n| n.to_str()).and_then(|n| n.strip_prefix(&prefix)) else {
            continue;
        };
        let parts: Vec<&str> = rest.split('.').collect();
        let pid = match parts[..] {
            [who, pid, _] if who == owner() => pid.parse::<u32>().ok(),
            [pid, _] => pid.parse::<u32>().ok(),
            _ => None,
        };
        if path.is_dir() && pid.is_some_and(|pid| !process_alive(pid)) && std::fs::remove_dir_all(&path).is_ok() {
            swept.push(path);
        }
    }
    swept
}

/// Who writes, for staging names: the kernel's boot id (different on every host and every boot)
/// and this process's PID namespace (different in every container), as `<8 hex digits>-<inode>`,
/// so that process ids are compared only where they mean the same process. `local` where the
/// system says neither.
fn owner() -> &'static str {
    static OWNER: OnceLock<String> = OnceLock::new();
    OWNER.get_or_init(|| {
        let boot: String = std::fs::read_to_string("/proc/sys/kernel/random/boot_id")
            .unwrap_or_default()
            .chars()
            .filter(char::is_ascii_hexdigit)
            .take(8)
            .collect();
        let namespace: String = std::fs::read_link("/proc/self/ns/pid")
            .map(|p| p.to_string_lossy().chars().filter(char::is_ascii_digit).collect())
            .unwrap_or_default();
        if boot.is_empty() && namespace.is_empty() { "local".to_owned() } else { format!("{boot}-{namespace}") }
    })
}

/// Removes the temporary files of [`crate::io::write_atomic`] (`.<name>.<6 characters>.tmp`)
/// beside `target` that belong to it. Outputs are staged, so no live writer puts them there; they
/// are left by runs killed before outputs were staged.
fn sweep_old_temps(target: &Path) -> Vec<PathBuf> {
    let (Some(dir), Some(name)) = (target.parent(), target.file_name().and_then(|n| n.to_str())) else {
        return Vec::new();
    };
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let mut swept = Vec::new();
    for path in entries(dir) {
        let Some(file) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let Some(inner) = file.strip_prefix('.').and_then(|f| f.strip_suffix(".tmp")) else { continue };
        let Some((stem, random)) = inner.rsplit_once('.') else { continue };
        let ours = random.len() == 6 && random.chars().all(|c| c.is_ascii_alphanumeric());
        if ours && stem == name && path.is_file() && std::fs::remove_file(&path).is_ok() {
            swept.push(path);
        }
    }
    swept
}

fn entries(dir: &Path) -> Vec<PathBuf> {
    match std::fs::read_dir(dir) {
        Ok(list) => list.filter_map(|e| e.ok().map(|e| e.path())).collect(),
        Err(_) => Vec::new(),
    }
}

/// Whether process `pid` runs (through /proc; without /proc only this process counts as alive).
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    Path::new("/proc/self").exists() && Path::new("/proc").join(pid.to_string()).exists()
}

/// The test hook's limit (see the module documentation); `None` when unset.
fn fault_limit() -> Option<u64> {
    static LIMIT: OnceLock<Option<u64>> = OnceLock::new();
    *LIMIT.get_or_init(|| std::env::var("SKINKIT_FAULT_WRITE_AFTER_BYTES").ok()?.trim().parse().ok())
}

/// The test hook: an error like a full disk's when the file written to `path` has more bytes than
/// `SKINKIT_FAULT_WRITE_AFTER_BYTES`. Does nothing without the environment variable.
pub(crate) fn charge_write(path: &Path, bytes: u64) -> Result<()> {
    match fault_limit() {
        // ENOSPC, the error a full disk gives (its text: "No space left on device").
        Some(limit) if bytes > limit => Err(Error::io(path, std::io::Error::from_raw_os_error(28))),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests;
