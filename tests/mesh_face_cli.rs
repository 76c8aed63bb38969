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

/// A strip of four 1 x 1 quads along x, quad `k` on UDIM tile `1001 + k`, with its UVs divided
/// by `u_scale` (4: the four tiles in the unit square).
fn strip_obj(u_scale: f64) -> String {
    let mut obj = String::new();
    for k in 0..4 {
        let (u0, u1) = (k as f64 / u_scale, (k + 1) as f64 / u_scale);
        obj += &format!("v {k} 0 0\nv {} 0 0\nv {} 1 0\nv {k} 1 0\n", k + 1, k + 1);
        obj += &format!("vt {u0} 0\nvt {u1} 0\nvt {u1} 1\nvt {u0} 1\n");
        let b = 4 * k;
        obj += &format!("f {0}/{0} {1}/{1} {2}/{2} {3}/{3}\n", b + 1, b + 2, b + 3, b + 4);
    }
    obj
}

/// A scene of `mesh` (in `dir`) wearing `map`, lit at grazing from +x, the camera square on the
/// boundary x = 1 between tiles 1001 and 1002 (x from 0.5 to 1.5 across 128 pixels).
fn strip_scene(dir: &Path, name: &str, mesh: &str, map: &str) -> PathBuf {
    let text = format!(
        "mesh = \"{mesh}\"\nmm_per_unit = 1.0\n[normal_map]\npath = \"{map}\"\n\
         [[light]]\nkind = \"directional\"\ndirection = [0.8, 0.2, 0.35]\nintensity = 3.0\n\
         [[camera]]\nposition = [1.0, 0.5, 3.0]\ntarget = [1.0, 0.5, 0.0]\nfov_deg = 18.92\n\
         [output]\nsize = [128, 128]\n"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Linear luminance of an EXR render, row-major, and its width.
fn luminance(path: &Path) -> (Vec<f32>, usize) {
    let photo = skinkit_maps::io::read_photo(path, &Default::default()).unwrap();
    let skinkit_maps::Samples::F32(v) = photo.samples() else { panic!("{}: not float", path.display()) };
    (v.chunks_exact(3).map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]).collect(), photo.width())
}

#[test]
fn a_udim_mesh_gets_one_normal_map_per_tile() {
    let tmp = tempfile::tempdir().unwrap();
    let layout = layout(tmp.path(), "mesh = \"strip.obj\"\nmm_per_unit = 1.0");
    std::fs::write(tmp.path().join("strip.obj"), strip_obj(1.0)).unwrap();
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
    // The height files and the labels are per tile too, one PNG scale for all.
    for name in ["height.{}.exr", "height.{}.png", "bands.{}.exr", "cavity.{}.png", "labels.{}.png"] {
        for tile in 1001..=1004 {
            assert!(out.join(name.replace("{}", &tile.to_string())).is_file(), "{name} of {tile}");
        }
        assert!(!out.join(name.replace(".{}", "")).exists(), "{name} whole");
    }
    render_across_the_tiles(tmp.path(), &out);
}

/// The tiles rendered through `normal.<UDIM>.png` are the joined atlas on UVs divided by four,
/// bit for bit, and the boundary between tiles 1001 and 1002 is no step in the picture: the
/// luminance jump between the two pixel columns astride it is no larger than the jumps between
/// other neighbouring columns (the 95th percentile of them).
fn render_across_the_tiles(dir: &Path, face: &Path) {
    let atlas = dir.join("atlas.exr");
    let maps: Vec<skinkit_maps::NormalMap> = (1001..=1004)
        .map(|t| {
            skinkit_maps::io::read_normal_map(
                &face.join(format!("normal.{t}.exr")),
                Default::default(),
                &Default::default(),
            )
            .unwrap()
        })
        .collect();
    let joined =
        skinkit_maps::NormalMap::from_grid(skinkit_maps::Grid::from_fn(128, 32, |x, y| maps[x / 32].get(x % 32, y)));
    skinkit_maps::io::write_normal_map(&atlas, &joined, Default::default(), 32).unwrap();
    std::fs::write(dir.join("strip-atlas.obj"), strip_obj(4.0)).unwrap();
    let udim = strip_scene(dir, "udim.toml", "strip.obj", &format!("{}/normal.<UDIM>.exr", s(face)));
    let single = strip_scene(dir, "single.toml", "strip-atlas.obj", s(&atlas));
    let (a, b) = (dir.join("udim.exr"), dir.join("single.exr"));
    for (scene, image) in [(&udim, &a), (&single, &b)] {
        let o = skinkit(&["render", s(scene), "--out", s(image)]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let ((la, w), (lb, _)) = (luminance(&a), luminance(&b));
    assert_eq!(la, lb, "the UDIM tiles render as their joined atlas");
    let jumps: Vec<f32> =
        (1..w).map(|x| (0..w).map(|y| (la[y * w + x] - la[y * w + x - 1]).abs()).sum::<f32>() / w as f32).collect();
    let boundary = jumps[w / 2 - 1];
    let mut others: Vec<f32> =
        jumps.iter().enumerate().filter(|(i, _)| i.abs_diff(w / 2 - 1) > 2).map(|p| *p.1).collect();
    others.sort_by(f32::total_cmp);
    let p95 = others[others.len() * 95 / 100];
    assert!(others[others.len() / 2] > 0.0, "the map shows in the render: {jumps:?}");
    assert!(boundary <= p95, "a step at the tile boundary: {boundary} against {p95} (95th percentile)");
    // The glTF export holds the atlas as one texture with the carried UVs.
    let glb = dir.join("strip.glb");
    let o = skinkit(&["export", "gltf", "--scene", s(&udim), "--out", s(&glb), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!((r["normal"]["width"].as_u64(), r["normal"]["height"].as_u64()), (Some(128), Some(32)), "{r}");
}
