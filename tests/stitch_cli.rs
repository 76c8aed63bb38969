//! End-to-end tests of `skinkit stitch` and `skinkit face`: a small face from the sample molds'
//! maps, reports with seams and timings, reproducible by seed, `--straight` / `--no-blend`, and
//! layouts that are wrong in the ways users get them wrong.

use std::path::{Path, PathBuf};

use crate::support::{s, skinkit, stderr};

fn molds() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds").canonicalize().unwrap()
}

/// A 320x160 layout of three regions whose exemplars are the sample molds' truth maps (0.02 mm
/// per texel, the map 0.04: exemplars shrink to 128x128); `extra` is appended to the file.
fn small_layout(dir: &Path, extra: &str) -> PathBuf {
    let m = molds();
    let text = format!(
        r#"size = [320, 160]
mm_per_texel = 0.04
[[region]]
name = "forehead"
exemplar = "{}"
exemplar_mm_per_texel = 0.02
points = [[0.5, 0.2]]
[[region]]
name = "cheek"
exemplar = "{}"
exemplar_mm_per_texel = 0.02
pixels = [[60, 110]]
[[region]]
name = "nose"
exemplar = "{}"
exemplar_mm_per_texel = 0.02
points = [[0.75, 0.7]]
{extra}"#,
        m.join("forehead/truth.png").display(),
        m.join("cheek/truth.png").display(),
        m.join("nose/truth.png").display()
    );
    let path = dir.join("layout.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn stitch(layout: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["stitch", "--layout", s(layout), "--out", s(out), "--json", "--quiet"];
    args.extend_from_slice(extra);
    let o = skinkit(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn stitch_writes_the_map_labels_and_a_report_and_repeats_by_seed() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = small_layout(tmp.path(), "");
    let (a, b) = (tmp.path().join("a.png"), tmp.path().join("b.png"));
    let labels = tmp.path().join("labels.png");
    let report = tmp.path().join("report.json");
    let r = stitch(&layout, &a, &["--seed", "3", "--labels", s(&labels), "--report", s(&report)]);
    stitch(&layout, &b, &["--seed", "3"]);
    assert!(std::fs::read(&a).unwrap() == std::fs::read(&b).unwrap(), "same seed, different maps");
    assert!(labels.is_file() && report.is_file());
    assert_eq!((r["width"].as_u64(), r["height"].as_u64()), (Some(320), Some(160)));
    let regions = r["regions"].as_array().unwrap();
    assert_eq!(regions.len(), 3);
    for region in regions {
        assert!(region["texels"].as_u64().unwrap() > 1000, "{region}");
        assert_eq!(region["exemplar_size"], serde_json::json!([128, 128]));
    }
    assert!(r["levels"].as_u64().unwrap() >= 2);
    assert!(r["seams"]["summary"]["boundaries"].as_u64().unwrap() >= 2);
    for stage in ["exemplars", "partition", "resample", "synthesis", "blend", "seams", "write", "total"] {
        assert!(r["seconds"][stage].as_f64().unwrap() >= 0.0, "{stage}");
    }
    let map = skinkit_maps::io::read_normal_map(&a, Default::default(), &Default::default()).unwrap();
    assert_eq!(map.size(), (320, 160));
    assert!(map.grid().as_slice().iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
    let c = stitch(&layout, &tmp.path().join("c.png"), &["--seed", "4"]);
    assert_ne!(c["regions"][0]["seed"], r["regions"][0]["seed"]);
}

#[test]
fn straight_and_no_blend_are_what_they_say() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = small_layout(tmp.path(), "");
    let hard = stitch(&layout, &tmp.path().join("hard.exr"), &["--no-blend", "--straight"]);
    assert_eq!(hard["levels"], 1);
    assert_eq!(hard["curve_amplitude"].as_f64(), Some(0.0));
    assert_eq!(hard["blend"], false);
    let soft = stitch(&layout, &tmp.path().join("soft.exr"), &["--curve-amplitude", "6"]);
    assert_eq!(soft["curve_amplitude"].as_f64(), Some(6.0));
    let jump = |r: &serde_json::Value| r["seams"]["summary"]["mean_jump_degrees"].as_f64().unwrap();
    assert!(jump(&soft) < jump(&hard), "spline {} vs hard {}", jump(&soft), jump(&hard));
}

#[test]
fn face_captures_sessions_and_writes_its_folder() {
    let tmp = tempfile::tempdir().unwrap();
    let text = format!(
        r#"size = [200, 100]
mm_per_texel = 0.04
[[region]]
name = "left"
session = "{0}"
exemplar_mm_per_texel = 0.02
points = [[0.25, 0.5]]
[[region]]
name = "right"
session = "{0}"
exemplar_mm_per_texel = 0.02
points = [[0.75, 0.5]]
"#,
        molds().join("cheek").display()
    );
    let layout = tmp.path().join("layout.toml");
    std::fs::write(&layout, text).unwrap();
    let out = tmp.path().join("face");
    let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["normal.png", "normal.exr", "labels.png", "report.json", "exemplars/left.png", "exemplars/right.png"] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    // One session used twice is captured once.
    assert_eq!(stderr(&o).matches("capturing").count(), 1, "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_ne!(r["regions"][0]["seed"], r["regions"][1]["seed"]);
}

/// Runs `stitch` on a layout and returns its stderr, asserting failure and nothing written.
fn refused(layout_text: &str) -> String {
    let tmp = tempfile::tempdir().unwrap();
    let layout = tmp.path().join("face.toml");
    std::fs::write(&layout, layout_text).unwrap();
    let out = tmp.path().join("out.png");
    let o = skinkit(&["stitch", "--layout", s(&layout), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!out.exists());
    let e = stderr(&o);
    assert!(e.contains("face.toml"), "message does not name the layout: {e}");
    e
}

#[test]
fn bad_layouts_are_refused_with_the_field_named() {
    let m = molds();
    let region = |name: &str, exemplar: &str, point: &str| {
        format!(
            "[[region]]\nname = \"{name}\"\nexemplar = \"{exemplar}\"\nexemplar_mm_per_texel = 0.02\npoints = [{point}]\n"
        )
    };
    let truth = m.join("cheek/truth.png").display().to_string();
    let head = "size = [64, 32]\nmm_per_texel = 0.02\n";
    let e = refused(&format!("{head}{}", region("a", "missing.png", "[0.5, 0.5]")));
    assert!(e.contains("missing.png") && e.contains("`a`"), "{e}");
    let e = refused(&format!("{head}{}{}", region("a", &truth, "[0.5, 0.5]"), region("b", &truth, "[0.5, 0.5]")));
    assert!(e.contains("`a`") && e.contains("`b`") && e.contains("same texel"), "{e}");
    let e = refused(&format!("{head}{}", region("a", &truth, "[1.5, 0.5]")));
    assert!(e.contains("points") && e.contains("outside"), "{e}");
    let e = refused(&format!("{head}colour = 3\n{}", region("a", &truth, "[0.5, 0.5]")));
    assert!(e.contains("colour"), "{e}");
}

#[test]
fn scanline_regions_stitch_into_a_unit_map_unlike_the_default() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = small_layout(tmp.path(), "");
    let (up, default) = (tmp.path().join("up.png"), tmp.path().join("default.png"));
    let r = stitch(&layout, &up, &["--scanline", "--seed", "2"]);
    assert_eq!(r["start"], "scanline");
    assert_eq!(stitch(&layout, &default, &["--seed", "2"])["start"], "upsampled");
    let map = skinkit_maps::io::read_normal_map(&up, Default::default(), &Default::default()).unwrap();
    assert_eq!(map.size(), (320, 160));
    assert!(map.grid().as_slice().iter().all(|n| (n.length() - 1.0).abs() < 1e-3));
    assert!(std::fs::read(&up).unwrap() != std::fs::read(&default).unwrap(), "--scanline changed nothing");
}

/// Issue 42, D1: a region's name becomes the file name of its exemplar in the face folder, so a
/// name with a path in it (`../../../cheek`, `../normal`) used to overwrite the layout's own
/// exemplar or the face's normal map. It is refused when the layout loads, naming the field, and
/// nothing is written.
#[test]
fn d1_region_names_that_are_paths_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let exemplar = molds().join("cheek/truth.png");
    let before = std::fs::read(&exemplar).unwrap();
    for name in ["../../../cheek", "../normal", "sub/dir", ".hidden"] {
        let layout = small_layout(tmp.path(), "");
        let text =
            std::fs::read_to_string(&layout).unwrap().replacen("name = \"nose\"", &format!("name = \"{name}\""), 1);
        std::fs::write(&layout, text).unwrap();
        let out = tmp.path().join("face");
        let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out)]);
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        assert!(stderr(&o).contains("name"), "{name}: {}", stderr(&o));
        assert!(!out.exists(), "{name}: the face wrote before refusing");
    }
    assert_eq!(std::fs::read(&exemplar).unwrap(), before, "an input changed");
}
