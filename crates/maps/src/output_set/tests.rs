//! Tests of [`OutputSet`]: staging, commit, rollback and the clean-up of killed runs.

use super::*;

fn write(path: &Path, text: &str) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|e| Error::io(path, e))
    })
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap()
}

/// Names in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = entries(dir).iter().map(|p| p.file_name().unwrap().to_string_lossy().into()).collect();
    names.sort();
    names
}

fn folder_set(target: &Path, a: &str, report: &str) -> OutputSet {
    let set = OutputSet::folder(target, "report.json").unwrap();
    set.write("a.txt", |p| write(p, a)).unwrap();
    set.write("sub/b.txt", |p| write(p, a)).unwrap();
    set.write("report.json", |p| write(p, report)).unwrap();
    set
}

#[test]
fn d3_a_folder_set_appears_only_at_the_commit() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("deep/out");
    let set = folder_set(&target, "1", "r1");
    assert!(!target.exists(), "visible before the commit");
    assert!(set.commit().unwrap().is_empty());
    assert_eq!((read(&target.join("a.txt")), read(&target.join("sub/b.txt"))), ("1".into(), "1".into()));
    assert_eq!(names(&tmp.path().join("deep")), ["out"], "staging folder left");
}

#[test]
fn d3_a_dropped_set_leaves_nothing_not_even_the_folders_it_made() {
    let tmp = tempfile::tempdir().unwrap();
    let set = folder_set(&tmp.path().join("deep/er/out"), "1", "r1");
    drop(set);
    assert!(names(tmp.path()).is_empty(), "{:?}", names(tmp.path()));
    let mut files = OutputSet::files();
    files.write_file(&tmp.path().join("new/x.png"), |p| write(p, "x")).unwrap();
    drop(files);
    assert!(names(tmp.path()).is_empty(), "{:?}", names(tmp.path()));
}

#[test]
fn d3_failed_rewrite_keeps_the_previous_set() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("out");
    folder_set(&target, "1", "r1").commit().unwrap();
    std::fs::write(target.join("user.txt"), "mine").unwrap();
    // A second run writes its first file, then fails before its report.
    let set = OutputSet::folder(&target, "report.json").unwrap();
    set.write("a.txt", |p| write(p, "2")).unwrap();
    let failed = set.write("report.json", |_| Err(Error::InvalidParameter("disk full".into())));
    assert!(failed.is_err());
    drop(set);
    assert_eq!((read(&target.join("a.txt")), read(&target.join("report.json"))), ("1".into(), "r1".into()));
    assert_eq!(names(tmp.path()), ["out"]);
    // A complete re-run replaces the set and keeps the user's own file.
    folder_set(&target, "3", "r3").commit().unwrap();
    assert_eq!(read(&target.join("a.txt")), "3");
    assert_eq!(read(&target.join("sub/b.txt")), "3");
    assert_eq!(read(&target.join("report.json")), "r3");
    assert_eq!(names(&target), ["a.txt", "report.json", "sub", "user.txt"]);
    assert_eq!(names(tmp.path()), ["out"], "staging folder left after a merge");
}

#[test]
fn d3_a_folder_in_the_way_fails_the_commit_before_any_rename() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("out");
    std::fs::create_dir_all(target.join("report.json")).unwrap();
    std::fs::write(target.join("a.txt"), "old").unwrap();
    let e = folder_set(&target, "new", "r").commit().unwrap_err().to_string();
    assert!(e.contains("report.json") && e.contains("is a folder"), "{e}");
    assert_eq!(read(&target.join("a.txt")), "old");
    assert_eq!(names(tmp.path()), ["out"], "staging folder left");
}

#[test]
fn a_folder_named_dot_dot_is_staged_beside_itself() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("out");
    std::fs::create_dir_all(target.join("sub")).unwrap();
    folder_set(&target.join("sub/.."), "1", "r1").commit().unwrap();
    assert_eq!(read(&target.join("report.json")), "r1");
    assert_eq!(names(tmp.path()), ["out"]);
}

#[test]
fn d14_a_file_where_a_folder_goes_and_the_reverse_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("f");
    std::fs::write(&file, "x").unwrap();
    let e = OutputSet::folder(&file, "report.json").unwrap_err().to_string();
    assert!(e.contains("is a file"), "{e}");
    let e = OutputSet::files().file(tmp.path()).unwrap_err().to_string();
    assert!(e.contains("is a folder"), "{e}");
}

#[test]
fn loose_files_are_renamed_in_together_and_errors_name_the_final_path() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a.png"), tmp.path().join("other/b.json"));
    let mut set = OutputSet::files();
    set.write_file(&a, |p| write(p, "a")).unwrap();
    let e = set.write_file(&a, |p| write(p, "again")).unwrap_err().to_string();
    assert!(e.contains("two outputs"), "{e}");
    let staged = set.file(&b).unwrap();
    let e = set.unstage_error(Error::io(&staged, std::io::Error::from_raw_os_error(28)));
    assert!(e.to_string().starts_with(&b.display().to_string()), "{e}");
    write(&staged, "b").unwrap();
    assert!(!a.exists() && !b.exists());
    set.commit().unwrap();
    assert_eq!((read(&a), read(&b)), ("a".into(), "b".into()));
    assert_eq!(names(tmp.path()), ["a.png", "other"]);
}

#[test]
fn d4_a_rerun_removes_what_killed_runs_left_and_says_so() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("out");
    folder_set(&target, "1", "r1").commit().unwrap();
    // No process has id u32::MAX (Linux caps ids at 2^22); this process's own is alive.
    let dead = tmp.path().join(format!(".out{STAGING}{}.7", u32::MAX));
    let alive = tmp.path().join(format!(".out{STAGING}{}.99999", std::process::id()));
    let temp = target.join(".a.txt.Ab12Cd.tmp");
    let foreign = target.join(".notes.Ab12Cd.tmp");
    std::fs::create_dir_all(dead.join("sub")).unwrap();
    std::fs::create_dir(&alive).unwrap();
    std::fs::write(&temp, "half").unwrap();
    std::fs::write(&foreign, "not ours").unwrap();
    let mut swept = folder_set(&target, "2", "r2").commit().unwrap();
    swept.sort();
    assert_eq!(swept, [dead, temp]);
    assert!(alive.is_dir() && foreign.is_file());
}

/// Issue 42, D12: an existing output folder (a mount point, say) holds its own staging folder,
/// so the commit renames within its filesystem; nothing is left inside it or beside it.
#[test]
fn d12_an_existing_folder_is_staged_inside_itself() {
    let tmp = tempfile::tempdir().unwrap();
    let target = tmp.path().join("mnt");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("mine.txt"), "kept").unwrap();
    let set = folder_set(&target, "1", "r1");
    let staged = set.path("a.txt").unwrap();
    assert!(staged.starts_with(&target) && staged.parent().unwrap() != target, "{}", staged.display());
    assert_eq!(names(tmp.path()), ["mnt"], "a staging folder beside the target");
    set.commit().unwrap();
    assert_eq!(names(&target), ["a.txt", "mine.txt", "report.json", "sub"]);
    assert_eq!(read(&target.join("report.json")), "r1");
}

/// Issue 42, D12: a move across filesystems copies to a temporary file beside the destination
/// and renames it (the fallback of a rename that fails with `EXDEV`).
#[test]
fn d12_a_copy_across_filesystems_replaces_the_destination_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let (from, to) = (tmp.path().join("staged.txt"), tmp.path().join("out.txt"));
    std::fs::write(&from, "new").unwrap();
    std::fs::write(&to, "old").unwrap();
    copy_across(&from, &to).unwrap();
    assert_eq!(read(&to), "new");
    assert_eq!(names(tmp.path()), ["out.txt"], "the source or a temporary file left");
}

/// Issue 42, D15: names that are not UTF-8 are valid file and folder names: written, not refused
/// at the commit after the work.
#[cfg(unix)]
#[test]
fn d15_names_that_are_not_utf8_are_written() {
    use std::os::unix::ffi::OsStrExt;
    let tmp = tempfile::tempdir().unwrap();
    let name = std::ffi::OsStr::from_bytes(b"o\xff");
    let mut files = OutputSet::files();
    files.write_file(&tmp.path().join(name), |p| write(p, "file")).unwrap();
    files.commit().unwrap();
    assert_eq!(read(&tmp.path().join(name)), "file");
    let target = tmp.path().join("d").join(name);
    folder_set(&target, "1", "r1").commit().unwrap();
    assert_eq!(read(&target.join("report.json")), "r1");
}

/// Issue 42, D7: the sweep removed the live staging folder of a writer it could not see (another
/// host on the shared folder, another container), since that writer's process id was not in this
/// machine's `/proc`. Staging names now carry the writer's owner (boot id and PID namespace), and
/// the sweep removes only its own owner's dead writers' folders (and those of versions before
/// owners): another owner's folder stays, whatever its process id.
#[test]
fn probe2_d7_the_sweep_leaves_other_hosts_staging_folders_alone() {
    let tmp = tempfile::tempdir().unwrap();
    let dead = u32::MAX;
    let ours = tmp.path().join(format!(".x{STAGING}{}.{dead}.1", owner()));
    let legacy = tmp.path().join(format!(".x{STAGING}{dead}.2"));
    let elsewhere = tmp.path().join(format!(".x{STAGING}0badc0de-4026531836.{dead}.3"));
    let live_here = tmp.path().join(format!(".x{STAGING}{}.{}.4", owner(), std::process::id()));
    for dir in [&ours, &legacy, &elsewhere, &live_here] {
        std::fs::create_dir(dir).unwrap();
    }
    let mut swept = sweep_staging(tmp.path(), "x");
    swept.sort();
    let mut expected = vec![ours, legacy];
    expected.sort();
    assert_eq!(swept, expected);
    assert!(elsewhere.is_dir() && live_here.is_dir(), "{:?}", names(tmp.path()));
    assert!(owner().contains('-') || owner() == "local", "{}", owner());
}
