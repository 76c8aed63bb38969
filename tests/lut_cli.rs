//! End-to-end tests of `skinkit lut`: the binary writes a float EXR whose pixels and `skinkit.*`
//! attributes match `skin::lut` / `skin::shadow` built in process, prints its definitions, and
//! refuses bad flags naming them.

use skinkit_render::skin::lut::{DiffuseLut, DiffuseLutSpec};
use skinkit_render::skin::lut_file;
use skinkit_render::skin::profile::{Domain, Normalisation};
use skinkit_render::skin::shadow::{ShadowLut, ShadowLutSpec};

use crate::support::{s, skinkit};

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn lut_diffuse_writes_the_table_it_describes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lut.exr");
    let args = ["lut", "diffuse", "--out", s(&path), "--size", "64x32", "--integrate", "half", "--normalisation", "1d"];
    let o = skinkit(&[&args[..], &["--inv-r-max", "2"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    let stdout = text(&o.stdout);
    for needle in ["skinkit.normalisation: 1d", "skinkit.domain: half", "skinkit.inv_r_max: 2", "64x32"] {
        assert!(stdout.contains(needle), "stdout lacks `{needle}`:\n{stdout}");
    }

    let image = lut_file::read(&path).unwrap();
    assert_eq!((image.width, image.height), (64, 32));
    assert_eq!(image.text("skinkit.table"), Some("diffuse"));
    assert_eq!(image.text("skinkit.normalisation"), Some("1d"));
    assert_eq!(image.text("skinkit.domain"), Some("half"));
    assert_eq!(image.float("skinkit.inv_r_min"), Some(0.0));
    assert_eq!(image.float("skinkit.inv_r_max"), Some(2.0));
    // The top row is flat skin: the clamped N.L at column centres.
    for i in 0..64 {
        let n_dot_l = (i as f32 + 0.5) / 64.0 * 2.0 - 1.0;
        for c in image.texel(i, 0) {
            assert!((c - n_dot_l.max(0.0)).abs() < 1e-6, "column {i}: {c}");
        }
    }
    let spec = DiffuseLutSpec {
        width: 64,
        height: 32,
        normalisation: Normalisation::OneD,
        domain: Domain::Half,
        inv_r_min: 0.0,
        inv_r_max: 2.0,
    };
    assert_eq!(image.texels, DiffuseLut::build(&spec).unwrap().texels);
}

#[test]
fn lut_shadow_writes_json_and_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shadow.exr");
    let o = skinkit(&["--json", "lut", "shadow", "--out", s(&path), "--size", "32x8", "--w-max-mm", "16"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("one JSON document");
    assert_eq!(json["width"], 32);
    assert_eq!(json["definitions"]["skinkit.filter"], "disc");
    assert_eq!(json["definitions"]["skinkit.w_max_mm"], 16.0);

    let image = lut_file::read(&path).unwrap();
    assert_eq!((image.width, image.height), (32, 8));
    assert_eq!(image.text("skinkit.table"), Some("shadow"));
    assert_eq!(image.float("skinkit.new_penumbra"), Some(0.05));
    let spec = ShadowLutSpec { width: 32, height: 8, w_max_mm: 16.0, ..ShadowLutSpec::default() };
    assert_eq!(image.texels, ShadowLut::build(&spec).unwrap().texels);
}

#[test]
fn lut_refuses_bad_flags_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lut.exr");
    let cases: [(&[&str], &str); 5] = [
        (&["lut", "diffuse", "--size", "5000x16"], "'5000x16' for '--size"),
        (&["lut", "diffuse", "--size", "0x16"], "--size"),
        (&["lut", "diffuse", "--inv-r-max=-1"], "--inv-r-max"),
        (&["lut", "shadow", "--new-penumbra", "2"], "--new-penumbra"),
        (&["lut", "shadow", "--w-min-mm", "40"], "--w-min-mm / --w-max-mm"),
    ];
    for (args, needle) in cases {
        let o = skinkit(&[args, &["--out", s(&out)]].concat());
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(text(&o.stderr).contains(needle), "{args:?}: stderr lacks `{needle}`: {}", text(&o.stderr));
    }
    let o = skinkit(&["lut", "diffuse", "--out", s(&dir.path().join("lut.png"))]);
    assert!(!o.status.success() && text(&o.stderr).contains(".exr"), "{}", text(&o.stderr));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0, "nothing written");
}

/// Issue 42, D14: a penumbra width past the table's limit is a usage error (exit 2) naming the
/// flag, not a table that reads lit skin as shadow.
#[test]
fn d14_lut_shadow_refuses_a_penumbra_width_out_of_range() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d14.exr");
    for value in ["1e30", "1001", "-1", "inf"] {
        let o = skinkit(&["lut", "shadow", &format!("--w-max-mm={value}"), "--out", s(&out)]);
        assert_eq!(o.status.code(), Some(2), "{value}: {}", text(&o.stderr));
        assert!(text(&o.stderr).contains("--w-max-mm") && text(&o.stderr).contains("0 to 1000"), "{}", text(&o.stderr));
    }
    assert!(!out.exists(), "a table was written");
}
