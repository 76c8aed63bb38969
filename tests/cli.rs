//! End-to-end tests of the `skinkit` binary: what a user at a shell sees (exit codes, messages that
//! name the file and field, outputs written whole or not at all).
//!
//! This file is the root of skinkit-cli's one test binary, `cli` (issue 38): every other file in
//! `tests/` is one of its modules, so `cargo test -p skinkit-cli --test cli batch_cli::` runs one
//! former test file's tests. The shared helpers are `support` (with `support::sessions` and
//! `support::browser`), declared here once.

use std::path::Path;
use std::process::Output;

mod accuracy_cli;
mod architecture;
mod batch_cli;
mod demo_cli;
mod docs_links;
mod errors_cli;
mod export_cli;
mod fuzz_regressions;
#[cfg(unix)]
mod gate_cli;
mod height_cli;
mod limits_cli;
mod lut_cli;
mod mesh_face_cli;
mod outputs_cli;
#[cfg(unix)]
mod probe1_cli;
#[cfg(unix)]
mod probe2_cli;
mod raw_cli;
mod render_cli;
mod slurm_cli;
mod stitch_cli;
mod support;
mod synth_cli;

use support::{mold, skinkit, stderr};

/// The JSON lines of a `--json` stream (`skinkit batch`): one record per line.
fn records(o: &Output) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON record a line"))
        .collect()
}

/// The last record of a batch's `--json` stream: the batch report.
fn batch_report(o: &Output) -> serde_json::Value {
    let last = records(o).pop().expect("a batch report line");
    assert_eq!(last["record"], "batch", "{last}");
    last
}

fn photos(region: &str) -> Vec<String> {
    (1..=8).map(|i| mold(region).join(format!("{i:02}.png")).display().to_string()).collect()
}

fn capture_args<'a>(rig: &'a str, out: &'a str, photos: &'a [String]) -> Vec<&'a str> {
    let mut args = vec!["capture", "--quiet", "--rig", rig, "--out", out];
    args.extend(photos.iter().map(String::as_str));
    args
}

#[test]
fn capture_of_a_sample_mold_writes_every_output_and_matches_truth() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cheek");
    let truth = mold("cheek").join("truth.png");
    let o = skinkit(&[
        "capture",
        "--json",
        "--rig",
        mold("cheek").join("rig.toml").to_str().unwrap(),
        "--photos-from",
        mold("cheek").to_str().unwrap(),
        "--truth",
        truth.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["normal.exr", "normal.png", "albedo.png", "confidence.png", "report.json"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let printed: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(printed["light_count"], 8);
    assert_eq!(saved["width"], printed["width"]);
    for stage in ["decode", "solve", "detrend", "write", "total"] {
        assert!(saved["timings_s"][stage].as_f64().unwrap() >= 0.0, "timing {stage}");
    }
    // Shadows and 0.2% noise on the samples: the robust solve stays within a couple of degrees.
    let mean = saved["error_vs_truth_degrees"]["mean"].as_f64().unwrap();
    assert!(mean < 2.0, "mean error {mean} deg");
    let source_untouched = std::fs::read(mold("cheek").join("01.png")).unwrap();
    assert!(!source_untouched.is_empty());
}

#[test]
fn wrong_photo_count_is_refused_and_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let rig = mold("nose").join("rig.toml");
    let seven = &photos("nose")[..7];
    let o = skinkit(&capture_args(rig.to_str().unwrap(), out.to_str().unwrap(), seven));
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("8 lights") && e.contains("7 photos"), "{e}");
    assert!(!out.exists(), "output folder created for a refused capture");
}

#[test]
fn photos_of_different_sizes_name_both_files() {
    let tmp = tempfile::tempdir().unwrap();
    let mut p = photos("nose");
    let small = tmp.path().join("small.png");
    skinkit_write_gray16(&small, 10, 12);
    p[2] = small.display().to_string();
    let out = tmp.path().join("out");
    let o = skinkit(&capture_args(mold("nose").join("rig.toml").to_str().unwrap(), out.to_str().unwrap(), &p));
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("small.png") && e.contains("10x12"), "{e}");
    assert!(!out.exists());
}

/// A small valid 16-bit grey PNG.
fn skinkit_write_gray16(path: &Path, w: usize, h: usize) {
    skinkit_maps::io::write_png(path, w, h, skinkit_maps::io::PngLayout::Gray16, &vec![32768; w * h]).unwrap();
}

#[test]
fn truncated_and_fake_pngs_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let mut p = photos("forehead");
    let bytes = std::fs::read(&p[4]).unwrap();
    let cut = tmp.path().join("cut.png");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let fake = tmp.path().join("notes.png");
    std::fs::write(&fake, "these are my notes, not a photo\n").unwrap();
    for bad in [&cut, &fake] {
        p[4] = bad.display().to_string();
        let out = tmp.path().join("out");
        let o = skinkit(&capture_args(mold("forehead").join("rig.toml").to_str().unwrap(), out.to_str().unwrap(), &p));
        assert_eq!(o.status.code(), Some(1));
        let e = stderr(&o);
        assert!(e.contains(bad.file_name().unwrap().to_str().unwrap()), "{e}");
        assert!(!out.exists());
    }
}

#[test]
fn bad_rigs_name_the_file_and_field() {
    let tmp = tempfile::tempdir().unwrap();
    let good = std::fs::read_to_string(mold("cheek").join("rig.toml")).unwrap();
    let cases = [
        ("zero.toml", good.replacen("direction = [", "direction = [0.0, 0.0, 0.0] # was [", 1), "direction"),
        ("missing.toml", "name = \"x\"\n[[light]]\nintensity = 1.0\n".to_string(), "direction"),
    ];
    for (name, text, field) in cases {
        let rig = tmp.path().join(name);
        std::fs::write(&rig, text).unwrap();
        let out = tmp.path().join("out");
        let o = skinkit(&capture_args(rig.to_str().unwrap(), out.to_str().unwrap(), &photos("cheek")));
        assert_eq!(o.status.code(), Some(1), "{name}");
        let e = stderr(&o);
        assert!(e.contains(name) && e.contains(field), "{name}: {e}");
        assert!(!out.exists());
    }
}

#[test]
fn batch_goes_on_past_a_bad_session_and_says_which() {
    let tmp = tempfile::tempdir().unwrap();
    let sessions = tmp.path().join("sessions");
    let good = sessions.join("a-good");
    let bad = sessions.join("b-bad");
    for dir in [&good, &bad] {
        std::fs::create_dir_all(dir).unwrap();
        for entry in std::fs::read_dir(mold("forehead-edge")).unwrap() {
            let entry = entry.unwrap();
            std::fs::copy(entry.path(), dir.join(entry.file_name())).unwrap();
        }
    }
    std::fs::remove_file(bad.join("08.png")).unwrap();
    let out = tmp.path().join("out");
    let o = skinkit(&["batch", "--json", sessions.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // One line per session as it ends, then the report.
    let lines = records(&o);
    assert_eq!(lines.iter().filter(|r| r["record"] == "session").count(), 2);
    let report = batch_report(&o);
    assert_eq!(report["succeeded"], 1);
    assert_eq!(report["failed"], 1);
    assert_eq!(report["outcomes"][1]["session"], "b-bad");
    assert!(report["outcomes"][1]["error"].as_str().unwrap().contains("7 photos"));
    assert!(out.join("a-good/normal.png").is_file());
    assert!(!out.join("b-bad").exists());
    assert!(out.join("batch-report.json").is_file());
}

/// Every file in the sub-folders of `dir`, at any depth (relative path -> bytes), session
/// reports without what a rerun changes (timings, the process's peak memory).
fn tree_contents(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    let mut files = std::collections::BTreeMap::new();
    let mut folders: Vec<std::path::PathBuf> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_dir()).collect();
    while let Some(folder) = folders.pop() {
        for file in std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().path()) {
            if file.is_dir() {
                folders.push(file);
                continue;
            }
            let mut bytes = std::fs::read(&file).unwrap();
            if file.extension().is_some_and(|e| e == "json") {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                for varies in ["timings_s", "peak_memory_mib"] {
                    v.as_object_mut().unwrap().remove(varies);
                }
                bytes = serde_json::to_vec(&v).unwrap();
            }
            files.insert(file.strip_prefix(dir).unwrap().display().to_string(), bytes);
        }
    }
    files
}

/// A batch report's outcomes without their timings.
fn outcomes_without_seconds(report: &serde_json::Value) -> Vec<serde_json::Value> {
    let mut outcomes = report["outcomes"].as_array().unwrap().clone();
    outcomes.iter_mut().for_each(|o| drop(o.as_object_mut().unwrap().remove("seconds")));
    outcomes
}

#[test]
fn three_shards_merge_to_the_single_batch_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let sessions = tmp.path().join("sessions");
    for name in ["s1", "s2", "s3", "s4", "s5-bad"] {
        let dir = sessions.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        for entry in std::fs::read_dir(mold("forehead-edge")).unwrap() {
            let entry = entry.unwrap();
            std::fs::copy(entry.path(), dir.join(entry.file_name())).unwrap();
        }
    }
    std::fs::remove_file(sessions.join("s5-bad/08.png")).unwrap();
    let (whole, sharded) = (tmp.path().join("whole"), tmp.path().join("sharded"));
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let o = skinkit(&["batch", "--quiet", &s(&sessions), "--out", &s(&whole)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let mut shares = Vec::new();
    for k in 1..=3 {
        let shard = format!("{k}/3");
        // Merging before every shard has run names the missing ones.
        let early = skinkit(&["batch", "--merge", "--out", &s(&sharded)]);
        assert_eq!(early.status.code(), Some(1));
        assert!(k == 1 || stderr(&early).contains(&format!("{k}/3")), "{}", stderr(&early));
        let o = skinkit(&["batch", "--json", &s(&sessions), "--out", &s(&sharded), "--shard", &shard]);
        let report = batch_report(&o);
        assert_eq!(report["shard"]["index"], k);
        shares.push(report["sessions"].as_u64().unwrap());
        assert!(sharded.join(format!("batch-report-{k}-of-3.json")).is_file());
    }
    assert_eq!(shares, [2, 2, 1]);
    let (one, three) = (tree_contents(&whole), tree_contents(&sharded));
    assert_eq!(one.keys().collect::<Vec<_>>(), three.keys().collect::<Vec<_>>());
    for (name, bytes) in &one {
        assert!(three[name] == *bytes, "{name} differs between the single batch and the shards");
    }
    let o = skinkit(&["batch", "--merge", "--json", "--out", &s(&sharded)]);
    assert_eq!(o.status.code(), Some(1), "a session failed: {}", stderr(&o));
    let mut merged = batch_report(&o);
    merged.as_object_mut().unwrap().remove("record");
    let single: serde_json::Value =
        serde_json::from_slice(&std::fs::read(whole.join("batch-report.json")).unwrap()).unwrap();
    assert_eq!(outcomes_without_seconds(&merged), outcomes_without_seconds(&single));
    for field in ["sessions", "succeeded", "failed", "interrupted"] {
        assert_eq!(merged[field], single[field], "{field}");
    }
    assert!(merged.get("shard").is_none());
    assert!(sharded.join("batch-report.json").is_file());
    let bad = skinkit(&["batch", &s(&sessions), "--out", &s(&sharded), "--shard", "4/3"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("4/3"), "{}", stderr(&bad));
}

#[test]
fn a_rerun_skips_up_to_date_sessions_and_force_redoes_them() {
    let tmp = tempfile::tempdir().unwrap();
    let sessions = tmp.path().join("sessions");
    for name in ["a", "b"] {
        let dir = sessions.join(name);
        std::fs::create_dir_all(&dir).unwrap();
        for entry in std::fs::read_dir(mold("forehead-edge")).unwrap() {
            let entry = entry.unwrap();
            std::fs::copy(entry.path(), dir.join(entry.file_name())).unwrap();
        }
    }
    let out = tmp.path().join("out");
    let batch = |extra: &[&str]| {
        let mut args = vec!["batch", "--json", sessions.to_str().unwrap(), "--out", out.to_str().unwrap()];
        args.extend(extra);
        let o = skinkit(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let report = batch_report(&o);
        let skipped: Vec<bool> = report["outcomes"].as_array().unwrap().iter().map(|o| o["skipped"] == true).collect();
        (report["skipped"].as_u64().unwrap(), skipped)
    };
    let made = |name: &str| std::fs::metadata(out.join(name).join("normal.png")).unwrap().modified().unwrap();
    assert_eq!(batch(&[]), (0, vec![false, false]));
    let first = made("a");
    assert_eq!(batch(&[]), (2, vec![true, true]));
    assert_eq!(made("a"), first, "a skipped session's outputs are left as they were");
    // A photo touched but not changed: times decide nothing, both are still up to date.
    let photo = std::fs::File::options().write(true).open(sessions.join("b/03.png")).unwrap();
    let report = std::fs::metadata(out.join("b/report.json")).unwrap().modified().unwrap();
    photo.set_modified(report + std::time::Duration::from_millis(1)).unwrap();
    assert_eq!(batch(&[]), (2, vec![true, true]));
    // Issue 42, D8: a photo replaced by another with an older time stamp (`cp -p`, `rsync -t`):
    // that session alone runs again.
    let old = std::fs::metadata(sessions.join("b/03.png")).unwrap().modified().unwrap();
    std::fs::copy(sessions.join("b/05.png"), sessions.join("b/03.png")).unwrap();
    let photo = std::fs::File::options().write(true).open(sessions.join("b/03.png")).unwrap();
    photo.set_modified(old - std::time::Duration::from_secs(3600)).unwrap();
    assert_eq!(batch(&[]), (1, vec![true, false]));
    // Issue 42, D4: any option that changes the outputs runs both again (not only the solver).
    assert_eq!(batch(&["--green", "down"]), (0, vec![false, false]));
    assert_eq!(batch(&["--green", "down"]), (2, vec![true, true]));
    assert_eq!(batch(&["--green", "down", "--max-condition", "40"]), (0, vec![false, false]));
    // Other options: run again.
    assert_eq!(batch(&["--solver", "ls"]), (0, vec![false, false]));
    assert_eq!(batch(&["--solver", "ls"]), (2, vec![true, true]));
    assert_eq!(batch(&["--solver", "ls", "--force"]), (0, vec![false, false]));
    assert!(made("a") > first);
}

#[test]
fn rig_import_reads_diligent_and_uw_files() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("ball");
    std::fs::create_dir_all(&d).unwrap();
    std::fs::write(d.join("light_directions.txt"), "0.5 0.0 0.866\n-0.5 0.0 0.866\n0.0 0.5 0.866\n0.0 -0.5 0.866\n")
        .unwrap();
    std::fs::write(d.join("light_intensities.txt"), "1 1 1\n2 2 2\n1 1 1\n1 1.5 1\n").unwrap();
    let rig = tmp.path().join("diligent.toml");
    let o = skinkit(&["rig", "import", "--diligent", d.to_str().unwrap(), "--out", rig.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&rig).unwrap();
    assert_eq!(text.matches("[[light]]").count(), 4, "{text}");

    let uw = tmp.path().join("lights.txt");
    std::fs::write(&uw, "3\n0.3 0.2 0.93\n-0.4 0.1 0.91\n0.05 -0.5 0.86\n").unwrap();
    let rig = tmp.path().join("uw.toml");
    let o = skinkit(&["rig", "import", "--uw", uw.to_str().unwrap(), "--out", rig.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));

    let coplanar = tmp.path().join("flat");
    std::fs::create_dir_all(&coplanar).unwrap();
    std::fs::write(coplanar.join("light_directions.txt"), "1 0 1\n0 1 1\n1 1 2\n2 1 3\n").unwrap();
    std::fs::write(coplanar.join("light_intensities.txt"), "1 1 1\n1 1 1\n1 1 1\n1 1 1\n").unwrap();
    let rig = tmp.path().join("flat.toml");
    let o = skinkit(&["rig", "import", "--diligent", coplanar.to_str().unwrap(), "--out", rig.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("coplanar"), "{}", stderr(&o));
    assert!(!rig.exists());
}

#[test]
fn samples_regenerate_bit_for_bit() {
    let tmp = tempfile::tempdir().unwrap();
    let o = skinkit(&["samples", "--quiet", "--out", tmp.path().to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    for region in ["forehead", "forehead-edge", "nose", "cheek"] {
        for entry in std::fs::read_dir(mold(region)).unwrap() {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap();
            let fresh = std::fs::read(tmp.path().join(region).join(name)).unwrap();
            assert!(
                fresh == std::fs::read(&path).unwrap(),
                "{region}/{} differs from the committed sample",
                name.to_string_lossy()
            );
        }
    }
}

/// Writes `count` 16-bit photos of a flat RGB patch lit by the rig's lights, plus its rig.
fn write_flat_rgb_session(dir: &Path, w: usize, h: usize, directions: &[[f32; 3]]) {
    std::fs::create_dir_all(dir).unwrap();
    let mut rig = String::from("name = \"flat\"\n");
    let albedo = [0.6f32, 0.4, 0.3];
    for (i, d) in directions.iter().enumerate() {
        let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        rig += &format!("[[light]]\ndirection = [{}, {}, {}]\n", d[0], d[1], d[2]);
        let shade = d[2] / len;
        let px: Vec<u16> = (0..w * h).flat_map(|_| albedo.map(|a| (a * shade * 65535.0).round() as u16)).collect();
        let name = format!("img_{:03}.png", 100 - i);
        skinkit_maps::io::write_png(&dir.join(&name), w, h, skinkit_maps::io::PngLayout::Rgb16, &px).unwrap();
    }
    std::fs::write(dir.join("rig.toml"), rig).unwrap();
}

/// Captures the session folder `dir` (its rig.toml and photos) into `out`; returns the JSON report.
fn capture_session_json(dir: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let rig = dir.join("rig.toml");
    let mut args = vec!["capture", "--json", "--rig", rig.to_str().unwrap(), "--photos-from", dir.to_str().unwrap()];
    args.extend(["--out", out.to_str().unwrap()]);
    args.extend(extra);
    let o = skinkit(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("--json prints JSON")
}

#[test]
fn diligent_style_folder_uses_filenames_txt_order_and_gives_rgb_albedo() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("obj");
    let dirs = [[0.5, 0.0, 0.866], [-0.5, 0.0, 0.866], [0.0, 0.5, 0.866], [0.0, -0.5, 0.866], [0.3, 0.3, 0.9]];
    write_flat_rgb_session(&dir, 6, 5, &dirs);
    // Names sort in reverse light order; filenames.txt restores it, as in DiLiGenT.
    let listing: Vec<String> = (0..dirs.len()).map(|i| format!("img_{:03}.png", 100 - i)).collect();
    std::fs::write(dir.join("filenames.txt"), listing.join("\n") + "\n").unwrap();
    skinkit_maps::io::write_png(&dir.join("Normal_gt.png"), 6, 5, skinkit_maps::io::PngLayout::Rgb8, &[128; 90])
        .unwrap();
    let out = tmp.path().join("out");
    let report = capture_session_json(&dir, &out, &["--detrend-block", "0"]);
    assert_eq!(report["invalid_pixels"], 0);
    assert!(report["tilt_degrees"]["max"].as_f64().unwrap() < 0.05, "{}", report["tilt_degrees"]);
    let albedo = skinkit_maps::io::read_photo(&out.join("albedo.png"), &Default::default()).unwrap();
    assert_eq!(albedo.channels(), skinkit_maps::Channels::Rgb);
    for (c, want) in [0.6f32, 0.4, 0.3].into_iter().enumerate() {
        assert!((albedo.linear(c) - want).abs() < 2e-3, "channel {c}: {} vs {want}", albedo.linear(c));
    }
}

#[test]
fn a_one_pixel_capture_stays_finite() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("one");
    write_flat_rgb_session(&dir, 1, 1, &[[0.5, 0.0, 0.866], [-0.5, 0.0, 0.866], [0.0, 0.5, 0.866]]);
    let out = tmp.path().join("out");
    capture_session_json(&dir, &out, &[]);
    let normals =
        skinkit_maps::io::read_normal_map(&out.join("normal.exr"), Default::default(), &Default::default()).unwrap();
    assert!((normals.get(0, 0) - skinkit_maps::Vec3::Z).length() < 1e-4, "{}", normals.get(0, 0));
}

/// A 16-bit photo of a mirror sphere (dim disc, Gaussian highlight where it reflects `light`).
fn mirror_sphere_photo(path: &Path, light: [f32; 3], (w, h, cx, cy, r): (usize, usize, f32, f32, f32)) {
    let l = skinkit_maps::Vec3::from(light).normalize();
    let n = (l + skinkit_maps::Vec3::Z).normalize();
    let (hx, hy) = (cx + r * n.x, cy - r * n.y);
    let px: Vec<u16> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            if (x - cx).hypot(y - cy) > r {
                return 0;
            }
            let glint = (-((x - hx).powi(2) + (y - hy).powi(2)) / (2.0 * 1.2f32.powi(2))).exp();
            ((0.15 + 0.85 * glint) * 65535.0) as u16
        })
        .collect();
    skinkit_maps::io::write_png(path, w, h, skinkit_maps::io::PngLayout::Gray16, &px).unwrap();
}

#[test]
fn rig_from_mirror_sphere_recovers_the_light_directions() {
    let tmp = tempfile::tempdir().unwrap();
    let lights = [[0.6f32, 0.1, 0.8], [-0.5, 0.3, 0.81], [0.05, -0.6, 0.8], [0.2, 0.2, 0.96]];
    let mut args = vec!["rig".to_string(), "from-sphere".into(), "--quiet".into()];
    for (i, l) in lights.iter().enumerate() {
        let p = tmp.path().join(format!("chrome{i}.png"));
        mirror_sphere_photo(&p, *l, (120, 100, 58.0, 47.0, 40.0));
        args.push(p.display().to_string());
    }
    let rig = tmp.path().join("rig.toml");
    args.extend(["--out".into(), rig.display().to_string()]);
    let o = skinkit(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&rig).unwrap();
    let parsed: Vec<[f32; 3]> = text
        .lines()
        .filter_map(|l| l.trim().strip_prefix("direction = ["))
        .map(|l| {
            let v: Vec<f32> = l.trim_end_matches(']').split(',').map(|x| x.trim().parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(parsed.len(), lights.len(), "{text}");
    for (got, want) in parsed.iter().zip(lights) {
        let (g, w) = (skinkit_maps::Vec3::from(*got).normalize(), skinkit_maps::Vec3::from(want).normalize());
        let deg = skinkit_maps::normal::angle_degrees(g, w);
        // The sphere's circle is found automatically from 120x100 photos: about a degree at most.
        assert!(deg < 1.5, "{got:?} vs {want:?}: {deg} deg");
    }
}

#[test]
fn outputs_do_not_depend_on_the_thread_count() {
    let tmp = tempfile::tempdir().unwrap();
    let mut outputs = Vec::new();
    for threads in ["1", "2", "3"] {
        let out = tmp.path().join(threads);
        capture_session_json(&mold("nose"), &out, &["--threads", threads]);
        outputs.push(out);
    }
    for name in ["normal.exr", "normal.png", "albedo.png", "confidence.png"] {
        let first = std::fs::read(outputs[0].join(name)).unwrap();
        for other in &outputs[1..] {
            assert!(first == std::fs::read(other.join(name)).unwrap(), "{name} differs with {}", other.display());
        }
    }
}

/// Copies the sample mold `region` into `dir`.
fn copy_mold(region: &str, dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for entry in std::fs::read_dir(mold(region)).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), dir.join(entry.file_name())).unwrap();
    }
}

#[test]
fn a_subject_folder_gets_its_face_map_from_the_batch_captures() {
    let tmp = tempfile::tempdir().unwrap();
    let sessions = tmp.path().join("sessions");
    // Subject `ann`: two sessions its layout names and one it does not; `zed` is a plain session.
    copy_mold("forehead", &sessions.join("ann/brow"));
    copy_mold("nose", &sessions.join("ann/nose"));
    copy_mold("cheek", &sessions.join("ann/unused"));
    copy_mold("cheek", &sessions.join("zed"));
    let layout = "size = [256, 128]\nmm_per_texel = 0.05\n\
        [[region]]\nname = \"forehead\"\nsession = \"brow\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.25]]\nseed = 1\n\
        [[region]]\nname = \"nose\"\nsession = \"nose\"\nexemplar_mm_per_texel = 0.02\npoints = [[0.5, 0.75]]\nseed = 2\n";
    std::fs::write(sessions.join("ann/layout.toml"), layout).unwrap();
    let out = tmp.path().join("out");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let o = skinkit(&["batch", "--json", &s(&sessions), "--out", &s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines = records(&o);
    let mut names: Vec<&str> =
        lines.iter().filter(|r| r["record"] == "session").map(|r| r["session"].as_str().unwrap()).collect();
    names.sort();
    assert_eq!(names, ["ann/brow", "ann/nose", "zed"]);
    let report = batch_report(&o);
    assert_eq!(report["faces"][0]["subject"], "ann");
    assert_eq!(report["faces"][0]["ok"], true, "{report}");
    assert!(out.join("ann/brow/normal.exr").is_file() && !out.join("ann/unused").exists());
    // The same map `skinkit face` makes from the layout, bit for bit (same solver and seed).
    let alone = tmp.path().join("alone");
    let o = skinkit(&["face", "--quiet", "--layout", &s(&sessions.join("ann/layout.toml")), "--out", &s(&alone)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["normal.png", "labels.png"] {
        let (a, b) =
            (std::fs::read(out.join("ann/face").join(name)).unwrap(), std::fs::read(alone.join(name)).unwrap());
        assert!(a == b, "face/{name} differs from `skinkit face`'s");
    }
    // A re-run skips the sessions and the face; a failed session leaves its subject without one.
    let o = skinkit(&["batch", "--json", &s(&sessions), "--out", &s(&out)]);
    let report = batch_report(&o);
    assert_eq!((report["skipped"].as_u64(), report["faces"][0]["skipped"].as_bool()), (Some(3), Some(true)));
    // Issue 42: the face, too, goes by what it was made from, not by times: a layout changed (a
    // region's seed) but given back its old time stamp is stitched again.
    let layout_path = sessions.join("ann/layout.toml");
    let stamp = std::fs::metadata(&layout_path).unwrap().modified().unwrap();
    std::fs::write(&layout_path, layout.replace("seed = 2", "seed = 3")).unwrap();
    std::fs::File::options().write(true).open(&layout_path).unwrap().set_modified(stamp).unwrap();
    let o = skinkit(&["batch", "--json", &s(&sessions), "--out", &s(&out)]);
    let report = batch_report(&o);
    assert_eq!((report["skipped"].as_u64(), report["faces"][0]["skipped"].as_bool()), (Some(3), None));
    assert_eq!(report["faces"][0]["ok"], true, "{report}");
    assert!(out.join("ann/face/made-from.json").is_file());
    std::fs::remove_file(sessions.join("ann/nose/08.png")).unwrap();
    let o = skinkit(&["batch", "--json", &s(&sessions), "--out", &s(&tmp.path().join("out2"))]);
    assert_eq!(o.status.code(), Some(1));
    let report = batch_report(&o);
    let error = report["faces"][0]["error"].as_str().unwrap();
    assert!(error.contains("ann/nose"), "{error}");
}
