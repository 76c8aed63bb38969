//! Camera RAW photos end to end (issue 39): `skinkit capture` and `skinkit batch` read a session
//! of DNG files, say so in the report, and refuse a truncated or malformed DNG with exit 1 and
//! one line naming it, with no panic message.

use std::path::Path;

use crate::support::{s, skinkit, stderr};

use skinkit_heightfield::dng::dng_of_rgb;

const SIDE: usize = 24;

/// A flat grey target under a ring of 8 lights at 45 degrees, as 8 DNGs (RGGB, 12-bit) and the
/// rig.
fn session(dir: &Path) {
    let mut rig = String::new();
    for i in 0..8 {
        let a = std::f32::consts::TAU * i as f32 / 8.0;
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let d = [h * a.cos(), h * a.sin(), h];
        rig += &format!("[[light]]\ndirection = [{}, {}, {}]\n", d[0], d[1], d[2]);
        let rgb = vec![[0.35 * d[2], 0.5 * d[2], 0.3 * d[2]]; SIDE * SIDE];
        let dng = dng_of_rgb(&rgb, SIDE, SIDE, [0, 1, 1, 2], 128, 4095);
        std::fs::write(dir.join(format!("{:02}.dng", i + 1)), dng).unwrap();
    }
    std::fs::write(dir.join("rig.toml"), rig).unwrap();
}

#[test]
fn a_dng_session_captures_and_says_how_it_was_read() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("session");
    std::fs::create_dir(&dir).unwrap();
    session(&dir);
    let out = tmp.path().join("out");
    let o = skinkit(&["capture", "--rig", s(&dir.join("rig.toml")), "--photos-from", s(&dir), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["width"], SIDE);
    let first = report["corrections"][0].as_str().unwrap();
    assert!(first.starts_with("camera raw (half size"), "{first}");
    let o = skinkit(&[
        "capture",
        "--raw",
        "full",
        "--rig",
        s(&dir.join("rig.toml")),
        "--photos-from",
        s(&dir),
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["width"], 2 * SIDE);
}

/// Truncated and malformed DNGs: exit 1, one error line naming the file, no panic on stderr.
#[test]
fn malformed_dngs_exit_1_naming_the_file_without_a_panic() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("session");
    std::fs::create_dir(&dir).unwrap();
    session(&dir);
    let bad = dir.join("05.dng");
    let whole = std::fs::read(&bad).unwrap();
    let mut scrambled = whole.clone();
    scrambled[10..200].iter_mut().enumerate().for_each(|(i, b)| *b = (i as u8).wrapping_mul(151));
    for (what, bytes) in [("truncated", whole[..whole.len() / 3].to_vec()), ("scrambled", scrambled)] {
        std::fs::write(&bad, bytes).unwrap();
        let out = tmp.path().join(format!("out-{what}"));
        let o = skinkit(&["capture", "--rig", s(&dir.join("rig.toml")), "--photos-from", s(&dir), "--out", s(&out)]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{what}: {e}");
        assert!(!e.contains("panicked"), "{what}: {e}");
        let lines: Vec<&str> = e.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{what}: {e}");
        assert!(lines[0].contains("05.dng"), "{what}: {e}");
        assert!(!out.exists(), "{what}: nothing written");
    }
}
