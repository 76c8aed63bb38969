//! End-to-end tests of the resource policy (issue 15, `skinkit_maps::limits`): every size from a
//! file or a flag is refused with a message naming the file or flag and the limit, before the
//! work starts; bad flag values are usage errors (exit 2); a batch runs fewer sessions at once
//! to stay within `--memory-limit`. Each test is named after the probe's defect it covers.

use std::path::{Path, PathBuf};
use std::process::Output;

use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_testkit::header_only_png;

use crate::support::{mold, s, skinkit, stderr};

/// Usage error: exit 2, and clap's message names the flag and the value.
fn assert_usage_error(args: &[&str], flag: &str, value: &str) {
    let o = skinkit(args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    assert!(e.contains(flag) && e.contains(value), "{args:?}: {e}");
}

/// A two-region layout on a 512x256 map; region `b`'s exemplar is `scale` mm per texel.
fn layout(dir: &Path, size: [usize; 2], scale: &str, extra: &str) -> PathBuf {
    let text = format!(
        r#"{extra}
size = [{}, {}]
mm_per_texel = 0.05
[[region]]
name = "a"
exemplar = "{truth}"
exemplar_mm_per_texel = 0.05
points = [[0.25, 0.5]]
[[region]]
name = "b"
exemplar = "{truth}"
exemplar_mm_per_texel = {scale}
points = [[0.75, 0.5]]
"#,
        size[0],
        size[1],
        truth = mold("cheek").join("truth.png").display()
    );
    let path = dir.join("layout.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn d1_huge_exemplar_scale_is_refused_before_allocating() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("face.png");
    for (scale, expect) in [("1e9", "over the limit of 268435456 texels"), ("3.0", "needs an estimated")] {
        let l = layout(tmp.path(), [512, 256], scale, "");
        let o = skinkit(&["stitch", "--quiet", "--memory-limit", "8G", "--layout", s(&l), "--out", s(&out)]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{scale}: {e}");
        assert!(e.contains("layout.toml") && e.contains("region `b`") && e.contains(expect), "{scale}: {e}");
        assert!(e.contains("exemplar_mm_per_texel"), "names the field: {e}");
        assert!(!out.exists());
    }
}

#[test]
fn d2_orbit_frames_are_bounded_by_the_flag_parser() {
    // Parsing fails before the scene is read, so no scene or GPU is needed.
    for frames in ["100000000000", "3601", "0"] {
        assert_usage_error(
            &["render", "scene.toml", "--out", "x.png", "--orbit", "--frames", frames],
            "--frames",
            frames,
        );
    }
    assert_usage_error(&["render", "scene.toml", "--size", "20000x20000"], "--size", "20000x20000");
    assert_usage_error(&["render", "scene.toml", "--reference", "0"], "--reference", "0");
}

#[test]
fn d6_coverage_mask_is_checked_from_its_header() {
    let tmp = tempfile::tempdir().unwrap();
    header_only_png(&tmp.path().join("bomb.png"), 32768, 32768);
    let l = layout(tmp.path(), [512, 256], "0.05", "coverage = \"bomb.png\"");
    let out = tmp.path().join("face.png");
    let o = skinkit(&["stitch", "--quiet", "--layout", s(&l), "--out", s(&out)]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("coverage") && e.contains("32768x32768 but the map is 512x256"), "{e}");
}

#[test]
fn d6_a_layout_at_the_size_limit_is_refused_before_reading_exemplars() {
    let tmp = tempfile::tempdir().unwrap();
    let l = tmp.path().join("big.toml");
    std::fs::rename(layout(tmp.path(), [32768, 32768], "0.05", ""), &l).unwrap();
    let face = tmp.path().join("face");
    let o = skinkit(&["face", "--quiet", "--memory-limit", "8G", "--layout", s(&l), "--out", s(&face)]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("big.toml") && e.contains("32768x32768 face map needs an estimated 28672 MiB"), "{e}");
    assert!(e.contains("memory limit of 8192 MiB"), "{e}");
    assert_usage_error(
        &["stitch", "--layout", "l.toml", "--out", "o.png", "--size", "32769x32768"],
        "--size",
        "32769x32768",
    );
}

/// An 8-light rig file near the plane y = 0: condition number about 70.
fn flat_rig(path: &Path, extra: &str) {
    let mut text = format!("name = \"flat\"\n{extra}\n");
    for i in 0..8 {
        let a = (25.0f64 + 130.0 * i as f64 / 7.0).to_radians();
        let y = if i % 2 == 0 { 0.01 } else { -0.01 };
        text += &format!("[[light]]\ndirection = [{}, {y}, {}]\nintensity = 1.0\n", a.cos(), a.sin());
    }
    std::fs::write(path, text).unwrap();
}

fn nose_photos() -> Vec<String> {
    (1..=8).map(|i| mold("nose").join(format!("{i:02}.png")).display().to_string()).collect()
}

fn capture(rig: &Path, out: &Path, photos: &[String], extra: &[&str]) -> Output {
    let mut args = vec!["capture", "--quiet", "--detrend-block", "0", "--rig", s(rig), "--out", s(out)];
    args.extend_from_slice(extra);
    args.extend(photos.iter().map(String::as_str));
    skinkit(&args)
}

#[test]
fn d7_rig_check_refuses_what_capture_refuses() {
    let tmp = tempfile::tempdir().unwrap();
    let rig = tmp.path().join("flat.toml");
    flat_rig(&rig, "");
    let o = skinkit(&["rig", "check", "--json", "--max-condition", "1000", s(&rig)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c = serde_json::from_slice::<serde_json::Value>(&o.stdout).unwrap()["condition_number"].as_f64().unwrap();
    assert!((50.0..1000.0).contains(&c), "condition {c}");
    let out = tmp.path().join("out");
    for (limit, ok) in [(None, false), (Some("1000"), true), (Some("50"), false)] {
        let flag: Vec<&str> = limit.map_or(vec![], |l| vec!["--max-condition", l]);
        let mut check = vec!["rig", "check", "--quiet"];
        check.extend_from_slice(&flag);
        check.push(s(&rig));
        let (checked, captured) = (skinkit(&check), capture(&rig, &out, &nose_photos(), &flag));
        assert_eq!(checked.status.success(), ok, "{limit:?}: {}", stderr(&checked));
        assert_eq!(captured.status.success(), ok, "{limit:?}: {}", stderr(&captured));
        if !ok {
            for e in [stderr(&checked), stderr(&captured)] {
                assert!(
                    e.contains("flat.toml") && e.contains("exceeds max_condition") && e.contains("--max-condition"),
                    "{e}"
                );
            }
        }
    }
    assert_usage_error(&["rig", "check", "--max-condition", "0.5", s(&rig)], "--max-condition", "0.5");
    assert_usage_error(
        &["capture", "--max-condition", "nan", "--rig", "r", "--out", "o", "p.png"],
        "--max-condition",
        "nan",
    );
}

#[test]
fn d7_too_many_lights_and_a_missing_ambient_fail_check_and_capture_alike() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let many = tmp.path().join("many.toml");
    let mut text = String::from("name = \"many\"\n");
    for i in 0..200 {
        let a = i as f64 * 2.4;
        text += &format!("[[light]]\ndirection = [{}, {}, 1.0]\nintensity = 1.0\n", 0.5 * a.cos(), 0.5 * a.sin());
    }
    std::fs::write(&many, text).unwrap();
    // 200 photos that are headers without pixels: refused for the rig before any is decoded.
    let photo = tmp.path().join("p.png");
    header_only_png(&photo, 64, 64);
    let photos = vec![photo.display().to_string(); 200];
    let no_ambient = tmp.path().join("ambient.toml");
    flat_rig(&no_ambient, "ambient = \"nope.png\"");
    let far = tmp.path().join("below.toml");
    let below = std::fs::read_to_string(mold("nose").join("rig.toml")).unwrap().replacen(
        "intensity = 1.0",
        "intensity = 1.0\nposition = [10.0, 0.0, 0.0]",
        1,
    );
    // The sample rig gives the pixel size (0.02 mm) that near lights need.
    assert!(below.contains("mm_per_pixel"));
    std::fs::write(&far, below).unwrap();
    for (rig, photos, expect) in [
        (&many, photos, "at most 128"),
        (&no_ambient, nose_photos(), "nope.png"),
        (&far, nose_photos(), "above the mold plane"),
    ] {
        let checked = skinkit(&["rig", "check", "--quiet", "--max-condition", "1000", s(rig)]);
        let captured = capture(rig, &out, &photos, &["--max-condition", "1000"]);
        for o in [&checked, &captured] {
            let e = stderr(o);
            assert_eq!(o.status.code(), Some(1), "{}: {e}", rig.display());
            assert!(e.contains(expect) && e.contains(rig.file_name().unwrap().to_str().unwrap()), "{e}");
        }
        assert!(!out.exists());
    }
}

#[test]
fn d8_threads_beyond_the_limit_are_a_usage_error() {
    for n in ["10000", "100000", "0", "x"] {
        assert_usage_error(&["--threads", n, "rig", "check", "r.toml"], "--threads", n);
    }
    let o = skinkit(&["--threads", "16", "rig", "check", "--quiet", s(&mold("nose").join("rig.toml"))]);
    assert!(o.status.success(), "16 threads are always allowed: {}", stderr(&o));
}

#[test]
fn d9_capture_over_the_memory_limit_is_refused_from_the_headers() {
    let tmp = tempfile::tempdir().unwrap();
    let photos: Vec<String> = (1..=8)
        .map(|i| {
            let p = tmp.path().join(format!("{i:02}.png"));
            header_only_png(&p, 16384, 16384);
            p.display().to_string()
        })
        .collect();
    let out = tmp.path().join("out");
    let o = capture(&mold("nose").join("rig.toml"), &out, &photos, &["--memory-limit", "4G"]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("capturing 8 photos needs an estimated 8192 MiB, over the memory limit of 4096 MiB"), "{e}");
    assert!(!out.exists());
    assert_usage_error(&["--memory-limit", "12X", "rig", "check", "r.toml"], "--memory-limit", "12X");
}

/// Copies sample molds into `dir/<name>` session folders.
fn sessions(dir: &Path, molds: &[&str]) -> Vec<PathBuf> {
    molds
        .iter()
        .map(|m| {
            let to = dir.join(m);
            std::fs::create_dir_all(&to).unwrap();
            for entry in std::fs::read_dir(mold(m)).unwrap() {
                let entry = entry.unwrap();
                std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
            }
            to
        })
        .collect()
}

fn batch(sessions: &Path, out: &Path, limit: &str) -> (Output, serde_json::Value) {
    let o = skinkit(&["--threads", "4", "--memory-limit", limit, "batch", "--json", s(sessions), "--out", s(out)]);
    // The last line of the --json stream is the batch report (one line per session before it).
    let last = String::from_utf8_lossy(&o.stdout).lines().last().map(str::to_owned);
    let report = last.and_then(|l| serde_json::from_str(&l).ok()).unwrap_or(serde_json::Value::Null);
    (o, report)
}

#[test]
fn d9_batch_runs_fewer_sessions_at_once_rather_than_failing() {
    let tmp = tempfile::tempdir().unwrap();
    let dirs = sessions(&tmp.path().join("s"), &["cheek", "nose", "forehead"]);
    let estimate =
        session::memory_estimate(&Session::from_dir(&dirs[0]).unwrap(), None, &CaptureOptions::default()).unwrap();
    // Room for one session at a time, not two.
    let one = format!("{}", estimate * 3 / 2);
    let (o, report) = batch(&tmp.path().join("s"), &tmp.path().join("out1"), &one);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!((report["succeeded"].as_u64(), report["most_at_once"].as_u64()), (Some(3), Some(1)), "{report}");
    assert_eq!(report["memory_limit_mib"].as_u64(), Some((estimate * 3 / 2) >> 20));
}

#[test]
fn d9_a_session_over_the_limit_alone_fails_and_the_batch_goes_on() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("s");
    sessions(&root, &["cheek", "nose"]);
    let big = root.join("big");
    std::fs::create_dir_all(&big).unwrap();
    std::fs::copy(mold("nose").join("rig.toml"), big.join("rig.toml")).unwrap();
    for i in 1..=8 {
        header_only_png(&big.join(format!("{i:02}.png")), 16384, 16384);
    }
    let (o, report) = batch(&root, &tmp.path().join("out"), "64M");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert_eq!((report["succeeded"].as_u64(), report["failed"].as_u64()), (Some(2), Some(1)), "{report}");
    let big_outcome = &report["outcomes"][0];
    assert_eq!(big_outcome["session"], "big");
    let e = big_outcome["error"].as_str().unwrap();
    assert!(
        e.contains("big") && e.contains("needs an estimated 8192 MiB") && e.contains("memory limit of 64 MiB"),
        "{e}"
    );
    assert!(tmp.path().join("out/cheek/report.json").is_file() && !tmp.path().join("out/big").exists());
}

#[test]
fn flag_values_refused_after_parsing_are_usage_errors() {
    let rig = mold("nose").join("rig.toml");
    for (flag, value) in [("--saturation", "0"), ("--shadow-threshold", "1"), ("--shadow-relative", "1.5")] {
        assert_usage_error(&["capture", flag, value, "--rig", s(&rig), "--out", "o", "p.png"], flag, value);
    }
    let ex = mold("nose").join("truth.png");
    for (flag, value) in [
        ("--k", "0"),
        ("--dims", "33"),
        ("--neighborhood", "4"),
        ("--parent", "2"),
        ("--levels", "0"),
        ("--corrections", "17"),
        ("--occurrence-penalty", "nan"),
        ("--rerank", "0"),
        ("--size", "0x0"),
    ] {
        let mut args = vec!["synth", s(&ex), "--out", "o.png", flag, value];
        if flag != "--size" {
            args.extend(["--size", "8x8"]);
        }
        assert_usage_error(&args, flag, value);
    }
    assert_usage_error(&["lut", "diffuse", "--out", "t.exr", "--size", "4097x16"], "--size", "4097x16");
    // Pairs and files a table spec refuses after parsing: still the user's flags, still exit 2.
    let pairs: [&[&str]; 3] = [
        &["lut", "diffuse", "--out", "t.exr", "--inv-r-min", "2", "--inv-r-max", "1"],
        &["lut", "shadow", "--out", "t.exr", "--w-min-mm", "3", "--w-max-mm", "1"],
        &["lut", "diffuse", "--out", "t.png"],
    ];
    for (args, flag) in pairs.iter().zip(["--inv-r-min / --inv-r-max", "--w-min-mm / --w-max-mm", "--out"]) {
        let o = skinkit(args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(flag), "{args:?}: {}", stderr(&o));
    }
    assert_usage_error(&["samples", "--size", "0", "--out", "o"], "--size", "0");
    assert_usage_error(&["samples", "--size", "20000", "--out", "o"], "--size", "20000");
    assert_usage_error(&["demo", "--synth-size", "0x0", "--out", "o"], "--synth-size", "0x0");
    assert_usage_error(&["demo", "--synth-size", "16385x16384", "--out", "o"], "--synth-size", "16385x16384");
    assert_usage_error(&["synth", s(&ex), "--size", "8x8", "--out", "o.jpg"], "o.jpg", "output maps");
    let coords = ["synth", s(&ex), "--size", "8x8", "--out", "o.png", "--coords", "c.exr"];
    assert_usage_error(&coords, "c.exr", "16-bit PNG");
    for (flag, value) in [("--levels", "0"), ("--levels", "21"), ("--curve-amplitude", "nan")] {
        assert_usage_error(&["stitch", "--layout", "l.toml", "--out", "o.png", flag, value], flag, value);
    }
}
