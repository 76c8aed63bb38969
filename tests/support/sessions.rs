//! Sessions folders for the batch tests (`tests/batch_cli.rs`, `tests/slurm_cli.rs`): copies of
//! tiny sample molds made by `skinkit samples`, some made bad on purpose the ways a lab's
//! captures go bad, and what a batch's output tree holds, to compare two of them bit for bit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::support::{s, skinkit, stderr};

/// The sample regions, in the order sessions take them.
pub const REGIONS: [&str; 4] = ["cheek", "forehead", "forehead-edge", "nose"];

/// How a session is made bad.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// Every photo black: nothing can be solved.
    Blank,
    /// Two lamps saturate the whole frame.
    Saturated,
    /// The rig's lights listed in another order than the photos were taken.
    WrongRig,
}

/// The four sample molds at `side` pixels in `dir/molds-<side>`, without their truth maps.
pub fn molds(dir: &Path, side: usize) -> PathBuf {
    let out = dir.join(format!("molds-{side}"));
    let o = skinkit(&["samples", "--quiet", "--size", &side.to_string(), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for region in REGIONS {
        std::fs::remove_file(out.join(region).join("truth.png")).unwrap();
    }
    out
}

pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
    }
}

/// `dir/NAME` for each name: a copy of a mold (by turns), made bad where `faults` says.
pub fn sessions(dir: &Path, molds: &Path, names: &[String], faults: &[(usize, Fault)]) -> PathBuf {
    for (i, name) in names.iter().enumerate() {
        let session = dir.join(name);
        copy_dir(&molds.join(REGIONS[i % 4]), &session);
        if let Some((_, fault)) = faults.iter().find(|(at, _)| *at == i) {
            spoil(&session, *fault);
        }
    }
    dir.to_owned()
}

/// Makes the session in `dir` bad by `fault`.
pub fn spoil(dir: &Path, fault: Fault) {
    let side = image::image_dimensions(dir.join("01.png")).unwrap().0;
    let flat = |path: PathBuf, value: u16| {
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_pixel(side, side, image::Luma([value]))
            .save(path)
            .unwrap();
    };
    match fault {
        Fault::Blank => (1..=8).for_each(|i| flat(dir.join(format!("{i:02}.png")), 0)),
        Fault::Saturated => ["03.png", "04.png"].into_iter().for_each(|p| flat(dir.join(p), u16::MAX)),
        Fault::WrongRig => {
            let rig = std::fs::read_to_string(dir.join("rig.toml")).unwrap();
            let mut parts: Vec<&str> = rig.split("[[light]]").collect();
            parts.swap(1, 4);
            parts.swap(2, 7);
            std::fs::write(dir.join("rig.toml"), parts.join("[[light]]")).unwrap();
        }
    }
}

/// Every file of `dir` at any depth but the batch's own reports and page (relative path ->
/// bytes), session reports without what a rerun changes (timings, the process's peak memory).
pub fn tree(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut folders = vec![dir.to_owned()];
    while let Some(folder) = folders.pop() {
        for path in std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()) {
            let relative = path.strip_prefix(dir).unwrap().display().to_string();
            if path.is_dir() {
                folders.push(path);
            } else if folder != dir && !relative.starts_with("batch-parts") {
                files.insert(relative, contents(&path));
            }
        }
    }
    files
}

fn contents(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    if path.extension().is_none_or(|e| e != "json") {
        return bytes;
    }
    let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    for varies in ["timings_s", "peak_memory_mib"] {
        v.as_object_mut().unwrap().remove(varies);
    }
    serde_json::to_vec(&v).unwrap()
}

/// A batch report read from `path`.
pub fn report(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))).unwrap()
}

/// A batch report's outcomes without their times and skip marks (what differs between runs).
pub fn outcomes(report: &serde_json::Value) -> Vec<serde_json::Value> {
    let mut outcomes = report["outcomes"].as_array().unwrap().clone();
    for o in &mut outcomes {
        let o = o.as_object_mut().unwrap();
        o.remove("seconds");
        o.remove("skipped");
    }
    outcomes
}

/// Asserts two output trees hold the same files with the same bytes.
pub fn assert_same_tree(one: &Path, other: &Path) {
    let (a, b) = (tree(one), tree(other));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>(), "different files");
    for (name, bytes) in &a {
        assert!(b[name] == *bytes, "{name} differs between {} and {}", one.display(), other.display());
    }
}
