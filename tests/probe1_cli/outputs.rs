//! Rows 7.x of the first probe: `--out` an existing folder, a read-only mount, a folder the user
//! may not write, or one of the command's own inputs. Each is found at start-up.

use std::path::PathBuf;

use super::layouts::layout;
use super::scenes::head_scene;
use super::{Scratch, mount_tmpfs, run_bin};
use crate::support::s;

/// A DiLiGenT folder `in/<name>` with three lights, both files present.
fn diligent(scratch: &Scratch, name: &str) -> PathBuf {
    let folder = scratch.folder(name);
    std::fs::write(folder.join("light_directions.txt"), "0 0 1\n0.5 0 0.8\n0 0.5 0.8\n").unwrap();
    std::fs::write(folder.join("light_intensities.txt"), "1 1 1\n1 1 1\n1 1 1\n").unwrap();
    folder
}

/// 7.2a, 7.2b, 7.2c, 7.2d, D14: `synth`, `stitch`, `render` and `rig import` with `--out` an
/// existing folder are usage errors naming it, found within 1.5 s, before the seconds of work
/// that precede a write.
#[test]
fn probe1_7_2_out_an_existing_folder_is_refused_at_start_up() {
    let scratch = Scratch::new();
    let truth = scratch.input("molds/cheek/truth.png");
    let scale3 = layout(&scratch, "scale3", "512, 256", "3.0", "");
    let scene = head_scene(&scratch, "head", &truth);
    let lights = diligent(&scratch, "diligent");
    let cases: [&[&str]; 4] = [
        &["synth", s(&truth), "--size", "384x384", "--out", "out/dir.png"],
        &["stitch", "--layout", s(&scale3), "--size", "256x128", "--out", "out/dir.png"],
        &["render", s(&scene), "--out", "out/dir.png"],
        &["rig", "import", "--diligent", s(&lights), "--out", "out/dir.toml"],
    ];
    for args in cases {
        std::fs::create_dir_all(scratch.out("dir.png")).unwrap();
        std::fs::create_dir_all(scratch.out("dir.toml")).unwrap();
        scratch.expect(&[2]).names("out/dir.").within_seconds(1.5).run(args);
    }
}

/// 7.3, D10: `synth --out` on a read-only mount fails naming the output once, after its role,
/// and saying `Read-only`. Needs a tmpfs mount (root).
#[test]
fn probe1_7_3_out_on_a_read_only_mount_is_refused() {
    let scratch = Scratch::new();
    let Some(ro) = mount_tmpfs(&scratch.root().join("ro"), "ro,size=64k") else {
        eprintln!("skipped: cannot mount a tmpfs here (needs root)");
        return;
    };
    let truth = scratch.input("molds/cheek/truth.png");
    let out = ro.0.join("s.png");
    let case = scratch.expect(&[1]).names(s(&out)).says(&["cannot write the normal map: ", s(&out), "Read-only"]);
    case.run(&["synth", s(&truth), "--size", "32x32", "--out", s(&out)]);
}

/// The user `nobody` (uid 65534), when this process may run the binary as that user.
fn nobody(scratch: &Scratch) -> Option<u32> {
    let r = run_bin(scratch.root(), &["--version"], 30, super::ADDRESS_SPACE_KIB, Some(65534));
    (r.code == 0).then_some(65534)
}

/// 7.4, D10: `synth --out` in a folder its user may not write fails naming the output once,
/// after its role, and saying `Permission denied`. Needs root, to run the binary as uid 65534.
#[test]
fn probe1_7_4_out_in_a_folder_without_write_permission_is_refused() {
    let scratch = Scratch::new();
    let Some(uid) = nobody(&scratch) else {
        eprintln!("skipped: cannot run the binary as uid 65534 here (needs root and a readable target folder)");
        return;
    };
    let locked = scratch.root().join("locked");
    std::fs::create_dir_all(&locked).unwrap();
    let truth = scratch.input("molds/cheek/truth.png");
    let out = locked.join("s.png");
    let case = scratch.expect(&[1]).names(s(&out)).run_as(uid);
    let case = case.says(&["cannot write the normal map: ", s(&out), "Permission denied"]);
    case.run(&["synth", s(&truth), "--size", "32x32", "--out", s(&out)]);
}

/// 7.5a, 7.5b, 7.5c, D5: `--out` the command's own input (synth's exemplar, render's normal
/// map, rig import's `light_directions.txt`) is a usage error naming it; the input survives.
#[test]
fn probe1_7_5_out_onto_its_own_input_is_refused() {
    let scratch = Scratch::new();
    let exemplar = scratch.folder("same").join("exemplar.png");
    std::fs::copy(scratch.input("molds/cheek/truth.png"), &exemplar).unwrap();
    let scene = head_scene(&scratch, "same-scene", &exemplar);
    let lights = diligent(&scratch, "same/diligent");
    let directions = lights.join("light_directions.txt");
    let cases: [(&str, &[&str]); 3] = [
        (s(&exemplar), &["synth", s(&exemplar), "--size", "64x64", "--out", s(&exemplar)]),
        (s(&exemplar), &["render", s(&scene), "--out", s(&exemplar)]),
        ("light_directions.txt", &["rig", "import", "--diligent", s(&lights), "--out", s(&directions)]),
    ];
    for (names, args) in cases {
        scratch.expect(&[2]).names(names).run(args);
    }
}

/// 7.6a, 7.6b, D5: `capture --out` its photo folder and `batch --out` its sessions folder are
/// usage errors naming the folder; no map is mixed in with the inputs.
#[test]
fn probe1_7_6_out_into_its_own_input_folder_is_refused() {
    let scratch = Scratch::new();
    let photos = scratch.input("same/photos");
    crate::support::sessions::copy_dir(&scratch.input("molds/cheek"), &photos);
    let sessions = scratch.input("same/sessions");
    crate::support::sessions::copy_dir(&scratch.input("molds/cheek"), &sessions.join("cheek"));
    let rig = photos.join("rig.toml");
    scratch.expect(&[2]).names(s(&photos)).run(&[
        "capture",
        "--rig",
        s(&rig),
        "--photos-from",
        s(&photos),
        "--out",
        s(&photos),
    ]);
    scratch.expect(&[2]).names(s(&sessions)).run(&["batch", s(&sessions), "--out", s(&sessions)]);
}
