//! `skinkit face` on the user's own mesh (issue 41): an OBJ in centimetres whose `.mtl` is
//! missing, split per face corner, region points picked in 3-D; the report's per-region
//! `mm_per_texel` is the mesh's own area ratio, and a missing `mm_per_unit` is named.

use std::path::{Path, PathBuf};

use crate::support::{s, skinkit, stderr};

/// A 2 x 1 plane (cm) in two quads split at x = 1, every corner its own `v` line: the left quad
/// on u in [0, 0.25], the right on u in [0.25, 1]. OBJ's v runs up (`vt` v = y), so the map's
/// row 0 holds y = 1.
const PLANE_OBJ: &str = "mtllib missing.mtl\n\
v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\n\
vt 0 0\nvt 0.25 0\nvt 0.25 1\nvt 0 1\nvt 0.25 0\nvt 1 0\nvt 1 1\nvt 0.25 1\n\
f 1/1 2/2 3/3 4/4\nf 5/5 6/6 7/7 8/8\n";

fn layout(dir: &Path, head: &str) -> PathBuf {
    let molds = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds").canonicalize().unwrap();
    std::fs::write(dir.join("plane.obj"), PLANE_OBJ).unwrap();
    let text = format!(
        "size = [256, 128]\n{head}\n[[region]]\nname = \"left\"\nexemplar = \"{}\"\nexemplar_mm_per_texel = 0.02\n\
         positions = [[0.5, 0.25, 0.4]]\n[[region]]\nname = \"right\"\nexemplar = \"{}\"\n\
         exemplar_mm_per_texel = 0.02\npositions = [[1.5, 0.25, -0.3]]\n",
        molds.join("forehead/truth.png").display(),
        molds.join("nose/truth.png").display()
    );
    let path = dir.join("layout.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_face_on_a_user_mesh_is_grown_at_the_mesh_scale_per_region() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = layout(tmp.path(), "mesh = \"plane.obj\"\nmm_per_unit = 10.0");
    let out = tmp.path().join("face");
    let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out), "--straight"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    // Each quad is 10 x 10 mm; the left on 64 x 128 texels, the right on 192 x 128.
    for (i, texels) in [(0, 64.0 * 128.0), (1, 192.0 * 128.0)] {
        let region = &r["regions"][i];
        let want = (100.0f64 / texels).sqrt();
        let got = region["mm_per_texel"].as_f64().unwrap();
        assert!((got - want).abs() < 1e-6, "region {i}: {got} against {want}: {region}");
        assert!((region["mesh_scale"]["area_mm2"].as_f64().unwrap() - 100.0).abs() < 1e-3, "{region}");
    }
    // The 3-D points landed on their quads: (0.5, 0.25) at u = 0.125, v = 0.75 (OBJ v up).
    let labels = image::open(out.join("labels.png")).unwrap().to_rgb8();
    assert_ne!(labels.get_pixel(32, 96), labels.get_pixel(160, 96));
    assert_eq!(labels.get_pixel(32, 96), labels.get_pixel(10, 10));
}

#[test]
fn the_mesh_flag_and_a_missing_mm_per_unit() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = layout(tmp.path(), "");
    let mesh = tmp.path().join("plane.obj");
    let out = tmp.path().join("face");
    let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out), "--mesh", s(&mesh)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("mm_per_unit: missing") && e.contains("--mm-per-unit") && !e.contains("line 1"), "{e}");
    let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out), "--mesh", s(&mesh), "--mm-per-unit", "10"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn a_udim_mesh_gets_one_normal_map_per_tile() {
    let tmp = tempfile::tempdir().unwrap();
    let mut obj = String::new();
    for k in 0..4 {
        obj += &format!("v {k} 0 0\nv {} 0 0\nv {} 1 0\nv {k} 1 0\n", k + 1, k + 1);
        obj += &format!("vt {k} 0\nvt {} 0\nvt {} 1\nvt {k} 1\n", k + 1, k + 1);
        let b = 4 * k;
        obj += &format!("f {0}/{0} {1}/{1} {2}/{2} {3}/{3}\n", b + 1, b + 2, b + 3, b + 4);
    }
    let layout = layout(tmp.path(), "mesh = \"strip.obj\"\nmm_per_unit = 1.0");
    std::fs::write(tmp.path().join("strip.obj"), obj).unwrap();
    let text = std::fs::read_to_string(&layout).unwrap().replace("size = [256, 128]", "size = [32, 32]");
    let text = text.replace("[[1.5, 0.25, -0.3]]", "[[3.5, 0.5, 0.0]]");
    std::fs::write(&layout, text).unwrap();
    let out = tmp.path().join("face");
    let o = skinkit(&["face", "--layout", s(&layout), "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(r["udim_tiles"], serde_json::json!([1001, 1002, 1003, 1004]));
    for tile in 1001..=1004 {
        let png = image::open(out.join(format!("normal.{tile}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (32, 32));
        assert!(out.join(format!("normal.{tile}.exr")).is_file());
    }
    assert!(!out.join("normal.png").exists());
}
