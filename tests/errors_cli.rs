//! Issue 15, errors: every command exits 0 on success, 1 when an input or the job failed and 2 on
//! a usage error, and a failure prints one line that names the file (and field), each cause once,
//! never a temporary file's name.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::{mold, repo, s, skinkit, stderr};

/// A writer's temporary file (`.NAME.XXXXXX.tmp`) or an output set's staging folder
/// (`.NAME.staging.OWNER.PID.N`) in `line`. The tests' own scratch folders (`/tmp/.tmpXXXXXX/`) are not.
fn names_a_temporary(line: &str) -> bool {
    let temp_file = line
        .match_indices(".tmp")
        .any(|(i, _)| line[i + 4..].chars().next().is_none_or(|c| !c.is_ascii_alphanumeric()));
    temp_file || line.contains(".staging.")
}

/// Asserts the run failed with exit 1 and one error line that names `file` once, repeats no OS
/// error and shows no temporary file; returns the line.
fn one_clean_error(o: &Output, file: &str) -> String {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    let lines: Vec<&str> = e.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "not one line: {e}");
    let line = lines[0];
    assert!(line.starts_with("error: "), "{line}");
    assert_eq!(line.matches(file).count(), 1, "`{file}` not named exactly once: {line}");
    assert!(!names_a_temporary(line), "a temporary file leaks: {line}");
    for (i, _) in line.match_indices("(os error") {
        let code = &line[i..line[i..].find(')').map_or(line.len(), |j| i + j + 1)];
        assert_eq!(line.matches(code).count(), 1, "`{code}` repeated: {line}");
    }
    line.to_owned()
}

/// Issue 15, D10: the probe's repeated chains (a folder as a photo, random bytes as a rig, a
/// missing DiLiGenT file, a write into a missing folder) each say their cause once.
#[test]
fn d10_error_chains_name_each_cause_once_and_no_temp_file() {
    let tmp = tempfile::tempdir().unwrap();
    let folder = tmp.path().join("03.png");
    std::fs::create_dir(&folder).unwrap();
    let mut photos: Vec<String> = (1..=8).map(|i| s(&mold("cheek").join(format!("{i:02}.png"))).to_owned()).collect();
    photos[2] = s(&folder).to_owned();
    let rig = mold("cheek").join("rig.toml");
    let out = tmp.path().join("out");
    let mut args = vec!["capture", "--rig", s(&rig), "--out", s(&out)];
    args.extend(photos.iter().map(String::as_str));
    let line = one_clean_error(&skinkit(&args), s(&folder));
    assert!(line.starts_with(&format!("error: photo 3: {}: ", folder.display())), "{line}");

    let noise = tmp.path().join("noise.toml");
    std::fs::write(&noise, (0..2000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect::<Vec<_>>())
        .unwrap();
    one_clean_error(&skinkit(&["rig", "check", s(&noise)]), s(&noise));

    let diligent = tmp.path().join("diligent");
    std::fs::create_dir(&diligent).unwrap();
    std::fs::write(diligent.join("light_directions.txt"), "0 0 1\n0.5 0 0.8\n0 0.5 0.8\n").unwrap();
    let o = skinkit(&["rig", "import", "--diligent", s(&diligent), "--out", s(&tmp.path().join("r.toml"))]);
    one_clean_error(&o, "light_intensities.txt");

    // A folder that cannot be made (its parent is a file): output sets make missing folders.
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let target = file.join("grown.png");
    // 32x32: a 16x16 output keeps about a third of the cheek's slope variation (measured at the
    // output's scale), and the collapse guard's warnings would come before the error.
    let o = skinkit(&["synth", s(&mold("cheek").join("truth.png")), "--size", "32x32", "--out", s(&target)]);
    one_clean_error(&o, s(&target));
}

/// Issue 38: a failed write says which output it was, by its role (`cannot write the label
/// map`), and the path once, from the library error under it: every command's outputs into a
/// folder that cannot be made (its parent is a file).
#[test]
fn failed_writes_name_the_outputs_role_and_its_path_once() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str| tmp.path().join(name).display().to_string();
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"").unwrap();
    let bad = |name: &str| file.join(name).display().to_string();
    let (cheek, truth) = (s(&mold("cheek")).to_owned(), s(&mold("cheek").join("truth.png")).to_owned());
    let rig = s(&mold("cheek").join("rig.toml")).to_owned();
    let (scene, layout) = (s(&head_scene(tmp.path())).to_owned(), s(&small_layout(tmp.path())).to_owned());
    let synth =
        |out: &str, more: &[&str]| [owned(&["synth", &truth, "--size", "32x32", "--out", out]), owned(more)].concat();
    let g = t("g.png");
    let cases: Vec<(&str, String, Vec<String>)> = vec![
        ("the normal map", bad("g.png"), synth(&bad("g.png"), &[])),
        ("the coordinate map", bad("c.png"), synth(&g, &["--coords", &bad("c.png")])),
        ("the synthesis report", bad("r.json"), synth(&g, &["--report", &bad("r.json")])),
        ("the height map", bad("h.exr"), synth(&g, &["--height", &bad("h.exr")])),
        (
            "the cavity map",
            bad("cav.png"),
            owned(&["height", &truth, "--out", &t("h.exr"), "--cavity", &bad("cav.png")]),
        ),
        ("the LUT", bad("d.exr"), owned(&["lut", "diffuse", "--size", "16x8", "--out", &bad("d.exr")])),
        (
            "the capture folder",
            bad("cap"),
            owned(&["capture", "--rig", &rig, "--photos-from", &cheek, "--out", &bad("cap")]),
        ),
        (
            "the label map",
            bad("l.png"),
            owned(&["stitch", "--layout", &layout, "--out", &t("f.png"), "--labels", &bad("l.png")]),
        ),
        ("the face folder", bad("face"), owned(&["face", "--layout", &layout, "--out", &bad("face")])),
        ("the rendered image", bad("head.png"), owned(&["render", &scene, "--out", &bad("head.png")])),
        (
            "the exported model",
            bad("head.glb"),
            owned(&["export", "gltf", "--scene", &scene, "--out", &bad("head.glb")]),
        ),
    ];
    for (role, path, args) in &cases {
        let o = skinkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let line = one_clean_error(&o, path);
        let said = format!("error: cannot write {role}: {path}: ");
        assert!(line.starts_with(&said), "{}: not `{said}...`: {line}", args.join(" "));
    }
}

/// The arguments `words`, owned.
fn owned(words: &[&str]) -> Vec<String> {
    words.iter().map(|w| (*w).to_owned()).collect()
}

/// Issue 15, D13: JPEG data named `.png` is refused, saying why, and nothing is written.
#[test]
fn d13_a_jpeg_photo_named_png_is_refused_with_the_reason() {
    let tmp = tempfile::tempdir().unwrap();
    let jpeg = tmp.path().join("03.png");
    std::fs::write(&jpeg, b"\xff\xd8\xff\xe0\x00\x10JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00\xff\xd9").unwrap();
    let mut photos: Vec<String> = (1..=8).map(|i| s(&mold("nose").join(format!("{i:02}.png"))).to_owned()).collect();
    photos[2] = s(&jpeg).to_owned();
    let out = tmp.path().join("out");
    let rig = mold("nose").join("rig.toml");
    let mut args = vec!["capture", "--rig", s(&rig), "--out", s(&out)];
    args.extend(photos.iter().map(String::as_str));
    let line = one_clean_error(&skinkit(&args), s(&jpeg));
    assert!(line.contains("JPEG") && line.contains("linear"), "{line}");
    assert!(!out.exists());
}

/// Issue 15, D13: `synth --kind normal` on an exemplar without one valid normal is refused
/// before any work, with the reason.
#[test]
fn d13_synth_refuses_an_exemplar_without_valid_normals() {
    let tmp = tempfile::tempdir().unwrap();
    let exemplar = tmp.path().join("empty.exr");
    let zeros = skinkit_maps::NormalMap::from_grid(skinkit_maps::Grid::filled(64, 64, skinkit_maps::Vec3::ZERO));
    skinkit_maps::io::write_normal_map(&exemplar, &zeros, skinkit_maps::NormalEncoding::default(), 32).unwrap();
    let out = tmp.path().join("grown.png");
    let o = skinkit(&["synth", s(&exemplar), "--size", "128x128", "--out", s(&out)]);
    let line = one_clean_error(&o, s(&exemplar));
    assert!(line.contains("no valid normal"), "{line}");
    assert!(!out.exists());
}

/// A scene of the sample head with a small output.
fn head_scene(dir: &Path) -> PathBuf {
    let text = format!(
        "mesh = \"{}\"\nmm_per_unit = 1.0\n[[light]]\nkind = \"directional\"\ndirection = [0.75, 0.35, 0.55]\n\
         [[camera]]\nposition = [170.0, 25.0, 380.0]\ntarget = [0.0, 5.0, 0.0]\n[output]\nsize = [32, 24]\n",
        s(&repo().join("samples/head/head.obj"))
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A 64x32 layout of two regions grown from the sample molds' truth maps.
fn small_layout(dir: &Path) -> PathBuf {
    let text = format!(
        "size = [64, 32]\nmm_per_texel = 0.04\n\
         [[region]]\nname = \"cheek\"\nexemplar = \"{}\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.25, 0.5]]\n\
         [[region]]\nname = \"nose\"\nexemplar = \"{}\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.75, 0.5]]\n",
        s(&mold("cheek").join("truth.png")),
        s(&mold("nose").join("truth.png"))
    );
    let path = dir.join("layout.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The inputs of [`exit_codes_are_0_1_2_for_every_command`], made in `dir`.
struct ExitCodeInputs {
    missing: String,
    cheek: String,
    rig: String,
    truth: String,
    sessions: String,
    uw: String,
    scene: String,
    layout: String,
    coords: String,
    unwritable: String,
    a_file: String,
}

impl ExitCodeInputs {
    fn make(dir: &Path) -> ExitCodeInputs {
        let t = |name: &str| dir.join(name).display().to_string();
        std::fs::create_dir_all(dir.join("sessions/cheek")).unwrap();
        for entry in std::fs::read_dir(mold("cheek")).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, dir.join("sessions/cheek").join(path.file_name().unwrap())).unwrap();
        }
        let uw = t("lights.txt");
        std::fs::write(&uw, "3\n0 0 1\n0.6 0 0.8\n0 0.6 0.8\n").unwrap();
        let a_file = t("a-file");
        std::fs::write(&a_file, "not a folder\n").unwrap();
        ExitCodeInputs {
            missing: t("missing.toml"),
            cheek: s(&mold("cheek")).to_owned(),
            rig: s(&mold("cheek").join("rig.toml")).to_owned(),
            truth: s(&mold("cheek").join("truth.png")).to_owned(),
            sessions: t("sessions"),
            uw,
            scene: s(&head_scene(dir)).to_owned(),
            layout: s(&small_layout(dir)).to_owned(),
            coords: t("coords.png"),
            unwritable: t("no-such-folder/out.exr"),
            a_file,
        }
    }
}

/// The cases whose exit code is not the one wanted; a failure must also be one error line.
fn wrong_exit_codes(cases: &[(&str, i32, Vec<String>)]) -> Vec<String> {
    let mut wrong = Vec::new();
    for (command, want, args) in cases {
        let o = skinkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
        if o.status.code() != Some(*want) {
            wrong.push(format!("{command}: want {want}, got {:?}: {}", o.status.code(), stderr(&o).trim_end()));
        } else if *want == 1 {
            let e = stderr(&o);
            let lines = e.lines().filter(|l| l.starts_with("error: ")).count();
            assert_eq!(lines, 1, "{command}: {e}");
        }
    }
    wrong
}

/// The README's exit codes, for every command: 0 when it worked, 1 when an input or the job
/// failed (a missing or unreadable file, an unwritable output), 2 for a usage error (an unknown
/// flag, a missing argument, a value clap cannot parse). `demo`'s and `rig from-sphere`'s
/// successful runs are checked in `cli.rs` (they take long or need made-up sphere photos); 130
/// (interrupted) has its own tests.
#[test]
fn exit_codes_are_0_1_2_for_every_command() {
    let tmp = tempfile::tempdir().unwrap();
    let t = |name: &str| tmp.path().join(name).display().to_string();
    let ExitCodeInputs { missing, cheek, rig, truth, sessions, uw, scene, layout, coords, unwritable, a_file } =
        ExitCodeInputs::make(tmp.path());
    // Every argument as an owned string (the output paths are made in place).
    macro_rules! args {
        ($($arg:expr),* $(,)?) => { vec![$($arg.to_string()),*] };
    }
    let cases: Vec<(&str, i32, Vec<String>)> = vec![
        ("capture", 0, args!["capture", "-q", "--rig", &rig, "--photos-from", &cheek, "--out", &t("cap")]),
        ("capture", 1, args!["capture", "--rig", &missing, "--photos-from", &cheek, "--out", &t("cap1")]),
        ("capture", 2, args!["capture", "--rig", &rig, "--photos-from", &cheek, "--out", &t("cap2"), "--bogus"]),
        ("rig import", 0, args!["rig", "import", "--uw", &uw, "--out", &t("uw.toml")]),
        ("rig import", 1, args!["rig", "import", "--uw", &missing, "--out", &t("uw1.toml")]),
        ("rig import", 2, args!["rig", "import", "--out", &t("uw2.toml")]),
        ("rig from-sphere", 1, args!["rig", "from-sphere", &missing, "--out", &t("s1.toml")]),
        ("rig from-sphere", 2, args!["rig", "from-sphere", &truth]),
        ("rig check", 0, args!["rig", "check", "-q", &rig]),
        ("rig check", 1, args!["rig", "check", &missing]),
        ("rig check", 2, args!["rig", "check"]),
        ("batch", 0, args!["batch", "-q", &sessions, "--out", &t("batch")]),
        ("batch", 1, args!["batch", &missing, "--out", &t("batch1")]),
        ("batch", 2, args!["batch", &sessions]),
        ("samples", 0, args!["samples", "-q", "--size", "16", "--out", &t("samples")]),
        ("samples", 1, args!["samples", "--size", "16", "--out", &a_file]),
        ("samples", 2, args!["samples", "--size", "sixteen"]),
        ("demo", 1, args!["demo", "--samples", &missing, "--out", &t("demo1")]),
        ("demo", 2, args!["demo", "--bogus"]),
        ("synth", 0, args!["synth", "-q", &truth, "--size", "16x16", "--out", &t("g.png"), "--coords", &coords]),
        ("synth", 1, args!["synth", &missing, "--size", "16x16", "--out", &t("g1.png")]),
        ("synth", 2, args!["synth", &truth, "--out", &t("g2.png")]),
        (
            "synth replay",
            0,
            args!["synth", "replay", "-q", "--coords", &coords, "--source", &truth, "--out", &t("r.png")],
        ),
        ("synth replay", 1, args!["synth", "replay", "--coords", &missing, "--source", &truth, "--out", &t("r1.png")]),
        ("synth replay", 2, args!["synth", "replay", "--source", &truth, "--out", &t("r2.png")]),
        ("stitch", 0, args!["stitch", "-q", "--layout", &layout, "--out", &t("face.png")]),
        ("stitch", 1, args!["stitch", "--layout", &missing, "--out", &t("face1.png")]),
        ("stitch", 2, args!["stitch", "--out", &t("face2.png")]),
        ("face", 0, args!["face", "-q", "--layout", &layout, "--out", &t("face")]),
        ("face", 1, args!["face", "--layout", &missing, "--out", &t("face1")]),
        ("face", 2, args!["face", "--layout", &layout]),
        ("render", 0, args!["render", "-q", &scene, "--out", &t("head.png")]),
        ("render", 1, args!["render", &missing, "--out", &t("head1.png")]),
        ("render", 2, args!["render", &scene, "--frames", "many"]),
        ("export gltf", 0, args!["export", "gltf", "-q", "--scene", &scene, "--out", &t("head.glb")]),
        ("export gltf", 1, args!["export", "gltf", "--scene", &missing, "--out", &t("head1.glb")]),
        ("export gltf", 2, args!["export", "gltf", "--scene", &scene, "--out", &t("head2.obj")]),
        ("lut diffuse", 0, args!["lut", "diffuse", "-q", "--size", "16x8", "--out", &t("d.exr")]),
        ("lut diffuse", 1, args!["lut", "diffuse", "--size", "16x8", "--out", &unwritable]),
        ("lut diffuse", 2, args!["lut", "diffuse", "--out", &t("d2.exr"), "--bogus"]),
        ("lut shadow", 0, args!["lut", "shadow", "-q", "--size", "16x8", "--out", &t("sh.exr")]),
        ("lut shadow", 1, args!["lut", "shadow", "--size", "16x8", "--out", &unwritable]),
        ("lut shadow", 2, args!["lut", "shadow", "--bogus"]),
    ];
    let wrong = wrong_exit_codes(&cases);
    assert!(wrong.is_empty(), "{} of {} cases:\n{}", wrong.len(), cases.len(), wrong.join("\n"));
}

/// Issue 42, D13: `rig import` runs the check `capture` and `rig check` run before it writes: a
/// light file of 200 lights (capture takes at most 128) is refused and no rig is written.
#[test]
fn d13_rig_import_refuses_a_rig_that_capture_refuses() {
    let tmp = tempfile::tempdir().unwrap();
    let lights = tmp.path().join("lights.txt");
    let mut text = "200\n".to_owned();
    for i in 0..200 {
        let a = i as f64 * 0.1;
        text += &format!("{:.4} {:.4} 1\n", 0.4 * a.cos(), 0.4 * a.sin());
    }
    std::fs::write(&lights, text).unwrap();
    let out = tmp.path().join("rig.toml");
    let o = skinkit(&["rig", "import", "--uw", s(&lights), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("lights.txt") && e.contains("200 lights") && e.contains("at most 128"), "{e}");
    assert!(!out.exists(), "a rig that capture refuses was written");
}
