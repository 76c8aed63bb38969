//! The hostile cases of issue 15's first reliability probe (every row it marked a defect or a
//! risk), one test each, numbered as the probe numbers its rows: images (1.x), rigs (2.x),
//! layouts (3.x), exemplars (4.x), meshes and scenes (5.x), batches, interrupts and full disks
//! (6.x), outputs pointed at folders, read-only places and inputs (7.x).
//!
//! Each case runs the binary from a scratch folder of inputs made here (`inputs`), under a
//! timeout and an address-space cap, and checks what the probe checked:
//! * exit: the expected code (0 success, 1 an input or job failed, 2 a usage error, 130
//!   interrupted; some cases accept either of two);
//! * line: a failure prints one `error:` line that names the file (or flag) once, never a
//!   temporary file, no OS error twice, with the case's words in order;
//! * out: nothing left at the output path of a failed run;
//! * temp: nothing hidden (a staging folder, a temporary file) anywhere in the scratch folder;
//! * inputs: every input file unchanged (a hash of its bytes before and after);
//! * memory: the peak resident memory under the case's bound, where it has one (the cheap
//!   refusals of huge requests), from the kernel's account of the child (`wait4`).
//!
//! The three cases that decode gigabytes of photos or run a 40-session batch of 1024-pixel molds
//! are `#[ignore]`d (minutes in a debug build): `cargo test -p skinkit-cli --test cli
//! probe1_cli:: -- --ignored` runs them. The cases that need root (a tmpfs to fill, a read-only
//! mount, another user) say they were skipped where they cannot run. The book's table of these
//! tests (`docs/book/src/scripts.md`, "Hostile inputs") is made from their doc comments by
//! `scripts/hostile-table.py`: each begins with its rows and defects, `/// 2.17a, 2.17b, D7, D11:`.

mod batches;
mod images;
mod inputs;
mod layouts;
mod outputs;
mod rigs;
mod scenes;

use std::collections::BTreeMap;
use std::io::Read;
use std::os::unix::fs::{MetadataExt, PermissionsExt};
use std::os::unix::process::CommandExt;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::support::{bin, mold, repo, s};

/// The address-space cap of every run (the probe's `ulimit -v 16000000`, in KiB): an allocation
/// gone wild fails in the child instead of taking the machine's memory from the other tests.
const ADDRESS_SPACE_KIB: u64 = 16_000_000;

/// What one run of the binary gave.
pub struct Run {
    /// The exit code, or 128 + the signal that ended it (a shell's `$?`).
    pub code: i32,
    pub stderr: String,
    pub seconds: f64,
    /// Peak resident memory in MiB (`ru_maxrss`).
    pub peak_mib: u64,
}

/// A scratch folder: `in/` holds the inputs (hashed before and after each case), `out/` is
/// where outputs go. Readable by everyone, so a case can run as another user.
pub struct Scratch {
    dir: tempfile::TempDir,
}

impl Scratch {
    /// A scratch folder whose `in/molds/cheek` and `in/molds/nose` are copies of those sample
    /// molds and `in/head/head.obj` the sample head.
    pub fn new() -> Scratch {
        // Not tempfile's default `.tmpXXXX`: an error line naming a `.tmp` path means a temporary file.
        let scratch = Scratch { dir: tempfile::Builder::new().prefix("skinkit-probe1-").tempdir().unwrap() };
        std::fs::set_permissions(scratch.dir.path(), std::fs::Permissions::from_mode(0o755)).unwrap();
        for region in ["cheek", "nose"] {
            crate::support::sessions::copy_dir(&mold(region), &scratch.input(&format!("molds/{region}")));
        }
        std::fs::create_dir_all(scratch.input("head")).unwrap();
        std::fs::copy(repo().join("samples/head/head.obj"), scratch.input("head/head.obj")).unwrap();
        std::fs::create_dir_all(scratch.out("")).unwrap();
        scratch
    }

    pub fn root(&self) -> &Path {
        self.dir.path()
    }

    pub fn input(&self, name: &str) -> PathBuf {
        self.dir.path().join("in").join(name)
    }

    pub fn out(&self, name: &str) -> PathBuf {
        self.dir.path().join("out").join(name)
    }

    /// `in/<name>` made as a folder (with its parents).
    pub fn folder(&self, name: &str) -> PathBuf {
        let path = self.input(name);
        std::fs::create_dir_all(&path).unwrap();
        path
    }

    /// The cheek mold's folder, rig and eight photos.
    pub fn cheek(&self) -> (PathBuf, PathBuf, Vec<String>) {
        let folder = self.input("molds/cheek");
        let photos = (1..=8).map(|i| s(&folder.join(format!("{i:02}.png"))).to_owned()).collect();
        (folder.clone(), folder.join("rig.toml"), photos)
    }

    /// A hash of every regular file under `in/` by path; a file of several hard links (the
    /// batch sessions share their photos) is read once.
    pub fn inputs(&self) -> BTreeMap<PathBuf, u64> {
        let (mut files, mut seen) = (BTreeMap::new(), BTreeMap::new());
        let mut folders = vec![self.input("")];
        while let Some(folder) = folders.pop() {
            for path in std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()) {
                let meta = std::fs::symlink_metadata(&path).unwrap();
                if meta.is_dir() {
                    folders.push(path);
                } else if meta.is_file() {
                    let hash = *seen.entry((meta.dev(), meta.ino())).or_insert_with(|| hash_file(&path));
                    files.insert(path, hash);
                }
            }
        }
        files
    }

    /// Hidden entries (staging folders, temporary files) anywhere in the scratch folder.
    pub fn hidden(&self) -> Vec<PathBuf> {
        hidden_under(self.dir.path())
    }

    /// A case expecting one of the exit codes `want`.
    pub fn expect(&self, want: &[i32]) -> Case<'_> {
        Case {
            scratch: self,
            want: want.to_vec(),
            names: Vec::new(),
            says: Vec::new(),
            absent: None,
            max_mib: None,
            max_seconds: None,
            timeout_s: 60,
            address_space_kib: ADDRESS_SPACE_KIB,
            uid: None,
            first_warning: false,
        }
    }
}

/// Hidden entries anywhere under `dir`.
pub fn hidden_under(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut folders = vec![dir.to_owned()];
    while let Some(folder) = folders.pop() {
        for path in std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()) {
            if path.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')) {
                found.push(path.clone());
            }
            if std::fs::symlink_metadata(&path).unwrap().is_dir() {
                folders.push(path);
            }
        }
    }
    found
}

fn hash_file(path: &Path) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut hasher = std::hash::DefaultHasher::new();
    std::fs::read(path).unwrap().hash(&mut hasher);
    hasher.finish()
}

/// One hostile case: what the run must give, checked by `run`.
pub struct Case<'s> {
    scratch: &'s Scratch,
    want: Vec<i32>,
    names: Vec<String>,
    says: Vec<String>,
    absent: Option<PathBuf>,
    max_mib: Option<u64>,
    max_seconds: Option<f64>,
    timeout_s: u64,
    address_space_kib: u64,
    uid: Option<u32>,
    first_warning: bool,
}

impl Case<'_> {
    /// The error line names `what` (a path, a flag, an OS error's words) exactly once; each
    /// call adds one more (a full disk's line names its file and `No space left` once each).
    pub fn names(mut self, what: impl AsRef<str>) -> Self {
        self.names.push(what.as_ref().to_owned());
        self
    }

    /// The error line (stderr, for a success) holds `words`, in this order.
    pub fn says(mut self, words: &[&str]) -> Self {
        self.says = words.iter().map(|w| (*w).to_owned()).collect();
        self
    }

    /// A failed run leaves nothing at `path`.
    pub fn leaves_nothing_at(mut self, path: impl AsRef<Path>) -> Self {
        self.absent = Some(path.as_ref().to_owned());
        self
    }

    /// The run's peak resident memory stays under `mib` MiB.
    pub fn within_mib(mut self, mib: u64) -> Self {
        self.max_mib = Some(mib);
        self
    }

    /// The run ends within `seconds` (the refusal comes before the work).
    pub fn within_seconds(mut self, seconds: f64) -> Self {
        self.max_seconds = Some(seconds);
        self
    }

    /// Kill the run (and fail the test) after `seconds` rather than 60.
    pub fn timeout(mut self, seconds: u64) -> Self {
        self.timeout_s = seconds;
        self
    }

    /// Cap the run's address space at `kib` KiB rather than [`ADDRESS_SPACE_KIB`].
    pub fn address_space(mut self, kib: u64) -> Self {
        self.address_space_kib = kib;
        self
    }

    /// Run as user and group `uid` (the caller checks it may).
    pub fn run_as(mut self, uid: u32) -> Self {
        self.uid = Some(uid);
        self
    }

    /// A batch reports a failed session as a `warning:` line: check the first of those when
    /// there is no `error:` line.
    pub fn first_warning(mut self) -> Self {
        self.first_warning = true;
        self
    }

    /// Runs `args` from the scratch folder and checks every property of the case.
    pub fn run(self, args: &[&str]) -> Run {
        let what = format!("skinkit {}", args.join(" "));
        let before = self.scratch.inputs();
        let r = run_bin(self.scratch.root(), args, self.timeout_s, self.address_space_kib, self.uid);
        assert!(self.want.contains(&r.code), "{what}: exit {} (want {:?}): {}", r.code, self.want, r.stderr);
        if r.code == 0 {
            assert!(in_order(&r.stderr, &self.says), "{what}: stderr lacks {:?}: {}", self.says, r.stderr);
        } else {
            self.check_line(&what, &r);
            if let Some(path) = &self.absent {
                assert!(!path.exists(), "{what}: left {}", path.display());
            }
        }
        assert_eq!(self.scratch.hidden(), Vec::<PathBuf>::new(), "{what}: hidden files left");
        assert!(before == self.scratch.inputs(), "{what}: an input changed");
        if let Some(mib) = self.max_mib {
            assert!(r.peak_mib <= mib, "{what}: peak {} MiB > {mib} MiB", r.peak_mib);
        }
        if let Some(seconds) = self.max_seconds {
            assert!(r.seconds <= seconds, "{what}: took {:.2} s > {seconds} s", r.seconds);
        }
        r
    }

    fn check_line(&self, what: &str, r: &Run) {
        let line = error_line(&r.stderr, r.code == 2, self.first_warning)
            .unwrap_or_else(|| panic!("{what}: not one error line: {}", r.stderr));
        for name in &self.names {
            assert_eq!(line.matches(name.as_str()).count(), 1, "{what}: does not name {name} once: {line}");
        }
        assert!(!line.contains(".tmp"), "{what}: a temporary file named: {line}");
        let os_errors: Vec<&str> = line.match_indices("(os error").map(|(i, _)| &line[i..]).collect();
        for (i, e) in os_errors.iter().enumerate() {
            let code = &e[..e.find(')').map_or(e.len(), |j| j + 1)];
            assert!(!os_errors[i + 1..].iter().any(|o| o.starts_with(code)), "{what}: OS error repeated: {line}");
        }
        assert!(in_order(&line, &self.says), "{what}: the error lacks {:?}: {line}", self.says);
    }
}

/// The one error line of a failed run's stderr (warnings, the Vulkan loader's notes and blank
/// lines aside), or `None` when there is not exactly one. A usage error is clap's: its first line
/// is the error, help follows. With `first_warning`, a batch's first failed session stands in
/// when there is no error line.
pub fn error_line(stderr: &str, usage: bool, first_warning: bool) -> Option<String> {
    let mut lines: Vec<&str> = stderr
        .lines()
        .filter(|l| !l.starts_with("warning: ") && !l.contains("XDG_RUNTIME_DIR") && !l.trim().is_empty())
        .collect();
    if usage {
        lines.truncate(1);
    }
    let warning = stderr.lines().find_map(|l| l.strip_prefix("warning: ")).map(|w| format!("error: {w}"));
    match (lines.as_slice(), warning) {
        ([line], _) if line.starts_with("error:") => Some((*line).to_owned()),
        ([], Some(warning)) if first_warning => Some(warning),
        _ => None,
    }
}

/// Whether `text` holds each of `words`, each after the one before.
pub fn in_order(text: &str, words: &[String]) -> bool {
    let mut rest = text;
    words.iter().all(|w| match rest.find(w.as_str()) {
        Some(i) => {
            rest = &rest[i + w.len()..];
            true
        }
        None => false,
    })
}

/// Runs the binary with `args` from `dir` (stdin closed, stdout dropped), capped at
/// `address_space_kib` of address space, as user `uid` when given; fails the test when it has
/// not ended after `timeout_s`. The child is reaped with `wait4`, for its peak memory.
pub fn run_bin(dir: &Path, args: &[&str], timeout_s: u64, address_space_kib: u64, uid: Option<u32>) -> Run {
    let mut command = bin();
    command.current_dir(dir).args(args).stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped());
    let bytes = address_space_kib * 1024;
    // SAFETY: setrlimit is async-signal-safe and touches no memory of the parent.
    unsafe {
        command.pre_exec(move || {
            let limit = libc::rlimit { rlim_cur: bytes, rlim_max: bytes };
            match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    if let Some(uid) = uid {
        // From root, std drops the supplementary groups too (setgroups(0) before setuid).
        command.uid(uid).gid(uid);
    }
    let start = Instant::now();
    let mut child = command.spawn().expect("skinkit runs");
    let mut pipe = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut bytes = Vec::new();
        pipe.read_to_end(&mut bytes).ok();
        String::from_utf8_lossy(&bytes).into_owned()
    });
    let (status, usage) = reap(&mut child, start, timeout_s, args);
    let seconds = start.elapsed().as_secs_f64();
    let code = if libc::WIFEXITED(status) { libc::WEXITSTATUS(status) } else { 128 + libc::WTERMSIG(status) };
    let peak_mib = usage.ru_maxrss as u64 / 1024;
    Run { code, stderr: reader.join().unwrap(), seconds, peak_mib }
}

/// Waits for `child` with `wait4` (polling, so a hang is caught) and returns its status and
/// resource usage; kills it and fails the test after `timeout_s`.
fn reap(child: &mut std::process::Child, start: Instant, timeout_s: u64, args: &[&str]) -> (i32, libc::rusage) {
    let pid = child.id() as libc::pid_t;
    loop {
        let mut status = 0;
        // SAFETY: an all-zero rusage is a valid value of this plain C struct.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        // SAFETY: both pointers are to live locals; `pid` is our own unreaped child.
        let got = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if got == pid {
            return (status, usage);
        }
        assert_eq!(got, 0, "wait4: {}", std::io::Error::last_os_error());
        if start.elapsed() > Duration::from_secs(timeout_s) {
            child.kill().ok();
            child.wait().ok();
            panic!("skinkit {} still running after {timeout_s} s", args.join(" "));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A tmpfs mounted at `at` with `options`, or `None` where this process may not mount (it needs
/// root); a case that needs one says it was skipped where it cannot.
pub fn mount_tmpfs(at: &Path, options: &str) -> Option<Mount> {
    std::fs::create_dir_all(at).unwrap();
    let mut mount = std::process::Command::new("mount");
    mount.args(["-t", "tmpfs", "-o", options, "tmpfs", s(at)]).stderr(Stdio::null());
    mount.status().is_ok_and(|st| st.success()).then(|| Mount(at.to_owned()))
}

/// A tmpfs mounted by [`mount_tmpfs`], unmounted when dropped.
pub struct Mount(pub PathBuf);

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = std::process::Command::new("umount").arg(&self.0).status();
    }
}

#[test]
fn error_lines_are_found_and_counted() {
    let one = "warning: exemplar: 3 texels invalid\nerror: a.png: bad\n";
    assert_eq!(error_line(one, false, false).as_deref(), Some("error: a.png: bad"));
    assert_eq!(error_line("error: a\nerror: b\n", false, false), None);
    assert_eq!(error_line("error: a\n\nUsage: skinkit\n", true, false).as_deref(), Some("error: a"));
    assert_eq!(error_line("warning: s1: full\n", false, true).as_deref(), Some("error: s1: full"));
    assert_eq!(error_line("warning: s1: full\n", false, false), None);
    let words = |w: &[&str]| w.iter().map(|s| (*s).to_owned()).collect::<Vec<_>>();
    assert!(in_order("line 5: index 99999", &words(&["line 5:", "99999"])));
    assert!(!in_order("99999 at line 5:", &words(&["line 5:", "99999"])));
}
