//! End-to-end test of `skinkit accuracy --quick`: every stage present and measured (rendering
//! too: the tests run where lavapipe gives an adapter, so it must not skip), every number
//! finite, every time positive, every plot a decodable PNG of a useful size, and accuracy.md
//! naming every stage.

use std::path::Path;
use std::process::Command;

use serde_json::Value;

const STAGES: [&str; 6] = ["capture", "detrend", "height", "synthesis", "stitching", "rendering"];

/// Every number in `value` (recursively), with its JSON path; `null`s are reported as NaN (a
/// non-finite float serialises as `null`), but for `skipped`, which is `null` when measured.
fn numbers(value: &Value, path: &str, out: &mut Vec<(String, f64)>) {
    match value {
        Value::Number(n) => out.push((path.to_owned(), n.as_f64().unwrap_or(f64::NAN))),
        Value::Null => out.push((path.to_owned(), f64::NAN)),
        Value::Array(items) => items.iter().enumerate().for_each(|(i, v)| numbers(v, &format!("{path}[{i}]"), out)),
        Value::Object(map) => map
            .iter()
            .filter(|(k, v)| !(k.as_str() == "skipped" && v.is_null()))
            .for_each(|(k, v)| numbers(v, &format!("{path}.{k}"), out)),
        _ => {}
    }
}

fn check_stage(dir: &Path, stage: &Value) {
    let name = stage["stage"].as_str().unwrap();
    assert!(stage["skipped"].is_null(), "{name} was skipped: {}", stage["skipped"]);
    let choices = stage["choices"].as_array().unwrap();
    assert!(choices.len() >= 2, "{name}: {} choices", choices.len());
    for c in choices {
        let what = format!("{name}: {} {}", c["series"], c["label"]);
        assert!(c["seconds"].as_f64().unwrap() > 0.0, "{what}: seconds");
        assert!(c["cost"].as_f64().unwrap() > 0.0, "{what}: cost");
        assert!(c["runs"].as_u64().unwrap() >= 1, "{what}: runs");
        assert!(!c["metrics"].as_array().unwrap().is_empty(), "{what}: no metrics");
    }
    let plot = dir.join(format!("accuracy-{name}.png"));
    let image = image::open(&plot).unwrap_or_else(|e| panic!("{}: {e}", plot.display())).to_rgb8();
    assert!(image.width() >= 600 && image.height() >= 400, "{name}: plot {:?}", image.dimensions());
    let ink = image.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(ink > 5000, "{name}: plot nearly blank ({ink} pixels drawn)");
}

#[test]
fn quick_accuracy_run_measures_every_stage() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("acc");
    let run = Command::new(env!("CARGO_BIN_EXE_skinkit"))
        .args(["accuracy", "--quick", "--json", "--out", out.to_str().unwrap()])
        .output()
        .expect("skinkit runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "skinkit accuracy failed: {stderr}");
    // --json: the report on stdout too, the same as the file.
    let printed: Value = serde_json::from_slice(&run.stdout).expect("stdout is the JSON report");
    let text = std::fs::read_to_string(out.join("accuracy.json")).unwrap();
    let report: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(printed["stages"], report["stages"]);
    assert_eq!(report["quick"], Value::Bool(true));

    let stages = report["stages"].as_array().unwrap();
    let names: Vec<&str> = stages.iter().map(|s| s["stage"].as_str().unwrap()).collect();
    assert_eq!(names, STAGES);
    let mut all = Vec::new();
    numbers(&report, "", &mut all);
    let bad: Vec<_> = all.iter().filter(|(_, v)| !v.is_finite()).collect();
    assert!(bad.is_empty(), "non-finite numbers: {bad:?}");
    for stage in stages {
        check_stage(&out, stage);
    }
    let md = std::fs::read_to_string(out.join("accuracy.md")).unwrap();
    for name in STAGES {
        assert!(md.contains(&format!("## {name}")), "accuracy.md has no {name} section");
        assert!(md.contains(&format!("accuracy-{name}.png")), "accuracy.md does not show the {name} plot");
    }
}

#[test]
fn an_unknown_stage_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_skinkit"))
        .args(["accuracy", "--quick", "--only", "capture,shading", "--out", dir.path().to_str().unwrap()])
        .output()
        .expect("skinkit runs");
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("`shading` is not a stage"));
}
