//! The hostile cases of issue 42's second reliability probe, one test each, run the way the probe
//! ran them: from a scratch folder of inputs, checking the exit code, the one `error:` line (its
//! words), that every input is unchanged (bytes before and after), and that nothing hidden (a
//! staging folder, a temporary file) is left anywhere in the scratch folder. The cases that need
//! several runs (resume, shards, the leftover sweep: D3-D5, D7, D8) are in `batch_cli.rs` and the
//! model-based test; those that need a mount (D12) in `outputs_cli.rs`.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::Output;
use std::time::{Duration, Instant};

use crate::support::{mkfifo, mold, run_within, s, stderr};

/// A scratch folder: `in/` holds the inputs, `out/` is where outputs go.
struct Scratch {
    dir: tempfile::TempDir,
}

impl Scratch {
    /// A scratch folder whose `in/cheek` and `in/nose` are copies of those sample molds.
    fn new() -> Scratch {
        let scratch = Scratch { dir: tempfile::tempdir().unwrap() };
        for region in ["cheek", "nose"] {
            let to = scratch.input(region);
            std::fs::create_dir_all(&to).unwrap();
            for entry in std::fs::read_dir(mold(region)).unwrap() {
                let path = entry.unwrap().path();
                std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
            }
        }
        std::fs::create_dir_all(scratch.out("")).unwrap();
        scratch
    }

    fn input(&self, name: &str) -> PathBuf {
        self.dir.path().join("in").join(name)
    }

    fn out(&self, name: &str) -> PathBuf {
        self.dir.path().join("out").join(name)
    }

    /// Every regular file under `in/` with its bytes (FIFOs and devices are not read).
    fn inputs(&self) -> BTreeMap<PathBuf, Vec<u8>> {
        let mut files = BTreeMap::new();
        let mut folders = vec![self.input("")];
        while let Some(folder) = folders.pop() {
            for path in std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()) {
                let kind = std::fs::symlink_metadata(&path).unwrap().file_type();
                if kind.is_dir() {
                    folders.push(path);
                } else if kind.is_file() {
                    files.insert(path.clone(), std::fs::read(&path).unwrap());
                }
            }
        }
        files
    }

    /// Hidden entries (staging folders, temporary files) anywhere in the scratch folder.
    fn hidden(&self) -> Vec<PathBuf> {
        let mut found = Vec::new();
        let mut folders = vec![self.dir.path().to_owned()];
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

    /// Runs `args` from the scratch folder (within 60 s: a hang fails the test) and checks what
    /// every case must hold: the exit code `want`, and for a failure one `error:` line holding
    /// each of `words`; inputs unchanged; nothing hidden left behind. Returns the run.
    fn case(&self, want: i32, words: &[&str], args: &[&str]) -> Output {
        let before = self.inputs();
        let o = run_within(60, Some(self.dir.path()), args);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(want), "skinkit {}: {e}", args.join(" "));
        if want != 0 {
            let errors: Vec<&str> = e.lines().filter(|l| l.starts_with("error:")).collect();
            assert_eq!(errors.len(), 1, "one error line: {e}");
            for word in words {
                assert!(errors[0].contains(word), "`{word}` not in: {}", errors[0]);
            }
        }
        assert!(before == self.inputs(), "skinkit {}: an input changed", args.join(" "));
        assert_eq!(self.hidden(), Vec::<PathBuf>::new(), "left behind by skinkit {}", args.join(" "));
        o
    }
}

/// The cheek's eight photos, in light order.
fn photos(scratch: &Scratch) -> Vec<String> {
    (1..=8).map(|i| s(&scratch.input(&format!("cheek/{i:02}.png"))).to_owned()).collect()
}

/// D1: a region named `../../../cheek` would have overwritten the layout's own exemplar.
#[test]
fn probe2_d1_a_region_name_that_is_a_path_is_refused() {
    let scratch = Scratch::new();
    let layout = scratch.input("layout.toml");
    let region = |name: &str, exemplar: &str, u: f32| {
        format!(
            "[[region]]\nname = \"{name}\"\nexemplar = \"{exemplar}\"\nexemplar_mm_per_texel = 0.05\npoints = [[{u}, 0.5]]\n"
        )
    };
    let text = format!(
        "size = [128, 64]\nmm_per_texel = 0.05\n{}{}",
        region("../../../cheek", "nose/truth.png", 0.3),
        region("b", "cheek/truth.png", 0.7)
    );
    std::fs::write(&layout, text).unwrap();
    scratch.case(1, &["../../../cheek"], &["face", "--quiet", "--layout", s(&layout), "--out", "out/face"]);
    assert!(!scratch.out("face").exists());
}

/// D2: `render --out` onto the scene's environment map would have replaced it.
#[test]
fn probe2_d2_render_onto_the_environment_map_is_refused() {
    let scratch = Scratch::new();
    let scene = scratch.input("scene.toml");
    let text = "mesh = \"head.obj\"\nmm_per_unit = 1.0\neffects = [\"sh-ambient\"]\n[environment]\n\
                latlong = \"cheek/truth.png\"\n[[light]]\nkind = \"directional\"\ndirection = [0.75, 0.35, 0.55]\n\
                [[camera]]\nposition = [170.0, 25.0, 380.0]\ntarget = [0.0, 5.0, 0.0]\n[output]\nsize = [32, 24]\n";
    std::fs::write(&scene, text).unwrap();
    std::fs::copy(crate::support::repo().join("samples/head/head.obj"), scratch.input("head.obj")).unwrap();
    let env = scratch.input("cheek/truth.png");
    scratch.case(2, &["--out", "truth.png"], &["render", s(&scene), "--out", s(&env)]);
}

/// D9: a 3 GiB rig (sparse) is refused from its length, not read.
#[test]
fn probe2_d9_a_huge_rig_is_refused_unread() {
    let scratch = Scratch::new();
    let rig = scratch.input("d9.toml");
    std::fs::File::create(&rig).unwrap().set_len(3 << 30).unwrap();
    let start = Instant::now();
    let o = run_within(60, Some(scratch.dir.path()), &["rig", "check", s(&rig)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("d9.toml"), "{}", stderr(&o));
    assert!(start.elapsed() < Duration::from_secs(30), "not read whole");
}

/// D10: a FIFO as photo 3 would have blocked forever.
#[test]
fn probe2_d10_a_fifo_photo_is_refused_at_once() {
    let scratch = Scratch::new();
    let fifo = scratch.input("d10.png");
    mkfifo(&fifo);
    let mut p = photos(&scratch);
    p[2] = s(&fifo).to_owned();
    let rig = scratch.input("cheek/rig.toml");
    let mut args = vec!["capture", "--quiet", "--rig", s(&rig), "--out", "out/c"];
    args.extend(p.iter().map(String::as_str));
    scratch.case(1, &["photo 3", "d10.png"], &args);
}

/// D13: a rig whose ambient frame is not an image fails `rig check` as it fails `capture`.
#[test]
fn probe2_d13_rig_check_refuses_what_capture_refuses() {
    let scratch = Scratch::new();
    let rig = scratch.input("d13b.toml");
    let original = std::fs::read_to_string(scratch.input("cheek/rig.toml")).unwrap();
    std::fs::write(&rig, format!("ambient = \"d13b.toml\"\n{original}")).unwrap();
    scratch.case(1, &["ambient"], &["rig", "check", "--quiet", s(&rig)]);
    let from = scratch.input("cheek");
    scratch.case(
        1,
        &["ambient"],
        &["capture", "--quiet", "--rig", s(&rig), "--photos-from", s(&from), "--out", "out/c"],
    );
}

/// D14: a shadow table wide past its limit, and a demo of a folder without samples, fail.
#[test]
fn probe2_d14_success_on_nothing_and_unranged_flags_are_refused() {
    let scratch = Scratch::new();
    scratch.case(2, &["--w-max-mm"], &["lut", "shadow", "--w-max-mm", "1e30", "--out", "out/d14.exr"]);
    std::fs::create_dir_all(scratch.input("empty")).unwrap();
    let empty = scratch.input("empty");
    let args = ["demo", "--quiet", "--samples", s(&empty), "--no-render", "--no-accuracy", "--out", "out/demo"];
    scratch.case(1, &["empty"], &args);
}

/// D15: a session folder named like the batch's report fails before any capture.
#[test]
fn probe2_d15_a_session_named_like_the_report_fails_first() {
    let scratch = Scratch::new();
    let sessions = scratch.input("sessions");
    std::fs::create_dir_all(&sessions).unwrap();
    std::fs::rename(scratch.input("cheek"), sessions.join("batch-report.json")).unwrap();
    std::fs::rename(scratch.input("nose"), sessions.join("nose")).unwrap();
    let o = run_within(60, Some(scratch.dir.path()), &["batch", "--quiet", s(&sessions), "--out", "out/maps"]);
    assert_ne!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("batch-report.json"), "{}", stderr(&o));
    assert!(!scratch.out("maps/nose/normal.png").exists(), "no session was captured first");
}

/// D17: a FIFO among a folder's photos is named, not silently skipped.
#[test]
fn probe2_d17_a_skipped_photo_is_named() {
    let scratch = Scratch::new();
    let folder = scratch.input("cheek");
    std::fs::remove_file(folder.join("05.png")).unwrap();
    mkfifo(&folder.join("05.png"));
    let rig = folder.join("rig.toml");
    scratch.case(
        1,
        &["05.png"],
        &["capture", "--quiet", "--rig", s(&rig), "--photos-from", s(&folder), "--out", "out/c"],
    );
}

/// The blank session: eight black photos (every pixel unsolvable) fail the session, and the
/// batch says so with a non-zero exit, not `ok` (its maps stay, for inspection, under a failed
/// outcome).
#[test]
fn probe2_a_blank_session_fails() {
    let scratch = Scratch::new();
    let sessions = scratch.input("sessions");
    let blank = sessions.join("blank");
    std::fs::create_dir_all(&blank).unwrap();
    std::fs::copy(scratch.input("cheek/rig.toml"), blank.join("rig.toml")).unwrap();
    let black = image::GrayImage::new(64, 64);
    for i in 1..=8 {
        black.save(blank.join(format!("{i:02}.png"))).unwrap();
    }
    std::fs::rename(scratch.input("nose"), sessions.join("nose")).unwrap();
    let o = run_within(60, Some(scratch.dir.path()), &["batch", s(&sessions), "--out", "out/maps"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("sessions/blank:") && e.contains("could be solved"), "the failed session is named: {e}");
    assert!(scratch.out("maps/nose/normal.png").exists(), "the batch goes on past it");
}
