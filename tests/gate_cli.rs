//! The input gate seen from the shell (issue 42): a file that is not a regular file, or is over
//! its kind's byte limit, is refused at once with a message naming the file, what it is and the
//! limit (D9, D10); folder entries that are skipped are named (D17).

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::{mkfifo, mold, run_within, s, stderr};

fn refused(o: &Output, wants: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for want in wants {
        assert!(e.contains(want), "`{want}` not in: {e}");
    }
}

/// A scene of one directional light and one camera around `mesh` (which need not exist yet).
fn scene(dir: &Path, mesh: &str) -> PathBuf {
    let path = dir.join("scene.toml");
    let text = format!(
        "mesh = \"{mesh}\"\nmm_per_unit = 1.0\n[[light]]\nkind = \"directional\"\ndirection = [0.75, 0.35, 0.55]\n\
         [[camera]]\nposition = [170.0, 25.0, 380.0]\ntarget = [0.0, 5.0, 0.0]\n[output]\nsize = [8, 8]\n"
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The cheek mold's eight photos in `dir` (as links), with its rig.
fn cheek_copy(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for entry in std::fs::read_dir(mold("cheek")).unwrap() {
        let path = entry.unwrap().path();
        std::os::unix::fs::symlink(&path, dir.join(path.file_name().unwrap())).unwrap();
    }
}

/// D9: a 3 GiB rig (sparse) is refused from its length, in well under a second of work.
#[test]
fn probe2_d9_a_huge_rig_is_refused_before_it_is_read() {
    let tmp = tempfile::tempdir().unwrap();
    let rig = tmp.path().join("d9.toml");
    std::fs::File::create(&rig).unwrap().set_len(3 << 30).unwrap();
    let o = run_within(20, None, &["rig", "check", s(&rig)]);
    refused(&o, &["d9.toml: 3221225472 bytes is over the limit for a TOML file of 16 MiB"]);
}

/// D9: `/dev/zero` as a rig, or as a scene's mesh, is a device: refused without reading it.
#[test]
fn probe2_d9_dev_zero_as_rig_or_mesh_is_refused() {
    let o = run_within(20, None, &["rig", "check", "/dev/zero"]);
    refused(&o, &["/dev/zero: a device, not a regular file (a TOML file is read only from a regular file)"]);
    let tmp = tempfile::tempdir().unwrap();
    std::os::unix::fs::symlink("/dev/zero", tmp.path().join("zero.obj")).unwrap();
    let scene = scene(tmp.path(), "zero.obj");
    let o = run_within(20, None, &["export", "gltf", "--scene", s(&scene), "--out", s(&tmp.path().join("o.glb"))]);
    refused(&o, &["zero.obj: a device, not a regular file (a mesh is read only from a regular file)"]);
}

/// D10: a FIFO nobody writes to, as a photo, an exemplar or a mesh, is refused at once.
#[test]
fn probe2_d10_a_fifo_as_photo_exemplar_or_mesh_is_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let fifo = tmp.path().join("d10.png");
    mkfifo(&fifo);
    let rig = mold("cheek").join("rig.toml");
    let mut photos: Vec<String> = (1..=8).map(|i| s(&mold("cheek").join(format!("{i:02}.png"))).to_owned()).collect();
    photos[2] = s(&fifo).to_owned();
    let out = tmp.path().join("out");
    let mut args = vec!["capture", "--rig", s(&rig), "--out", s(&out)];
    args.extend(photos.iter().map(String::as_str));
    let o = run_within(30, None, &args);
    refused(&o, &["photo 3: ", "d10.png: a FIFO (named pipe), not a regular file (an image is read only"]);
    assert!(!out.exists(), "a refused capture writes nothing");

    let o = run_within(30, None, &["synth", s(&fifo), "--size", "16x16", "--out", s(&tmp.path().join("s.png"))]);
    refused(&o, &["d10.png: a FIFO (named pipe), not a regular file"]);

    let mesh = tmp.path().join("m.obj");
    mkfifo(&mesh);
    let scene = scene(tmp.path(), "m.obj");
    let o = run_within(30, None, &["export", "gltf", "--scene", s(&scene), "--out", s(&tmp.path().join("o.glb"))]);
    refused(&o, &["m.obj: a FIFO (named pipe), not a regular file (a mesh is read only"]);
}

/// D17: a FIFO among a folder's photos is named: with the rig's count of photos beside it the
/// capture succeeds with a note and the report lists it; without, the count error names it.
#[test]
fn probe2_d17_skipped_photos_are_named_in_the_note_the_report_and_the_error() {
    let tmp = tempfile::tempdir().unwrap();
    let photos = tmp.path().join("photos");
    cheek_copy(&photos);
    mkfifo(&photos.join("09.png"));
    let rig = mold("cheek").join("rig.toml");
    let out = tmp.path().join("out");
    let o = run_within(60, None, &["capture", "--rig", s(&rig), "--photos-from", s(&photos), "--out", s(&out)]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("note: skipped ") && e.contains("09.png: a FIFO (named pipe), not a regular file"), "{e}");
    assert!(!e.contains("error"), "a skipped entry is a note, not an error: {e}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    let skipped = report["skipped"].as_array().expect("the report lists skipped entries");
    assert!(skipped.len() == 1 && skipped[0].as_str().unwrap().contains("09.png: a FIFO"), "{report}");

    std::fs::remove_file(photos.join("08.png")).unwrap();
    let o = run_within(60, None, &["capture", "--rig", s(&rig), "--photos-from", s(&photos), "--out", s(&out)]);
    refused(&o, &["7 photos", "skipped: ", "09.png: a FIFO (named pipe)"]);
}
