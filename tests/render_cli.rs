//! End-to-end tests of `skinkit render` and the head step of `skinkit samples`: the bundled head
//! scene drawn to PNG and EXR, the fine-scale map changing the picture, turntables, `--explain`,
//! and scenes that are wrong in the ways users get them wrong. Rendering needs an adapter (lavapipe
//! via scripts/test); these tests never pass by skipping it.

use std::path::{Path, PathBuf};
use std::process::Command;

use skinkit_maps::io::{Limits, read_photo};
use skinkit_maps::{NormalEncoding, NormalMap, Samples};

use crate::support::{repo, s, skinkit, stderr};

/// 8-bit RGB samples of a PNG render.
fn pixels(path: &Path) -> (usize, usize, Vec<u8>) {
    let photo = read_photo(path, &Limits::default()).unwrap();
    let Samples::U8(v) = photo.samples() else { panic!("{}: not 8-bit", path.display()) };
    (photo.width(), photo.height(), v.clone())
}

/// A scene for the committed sample head in `dir`, with `extra` TOML appended.
fn head_scene(dir: &Path, normal_map: Option<&Path>, extra: &str) -> PathBuf {
    let map = normal_map.map_or(String::new(), |p| format!("[normal_map]\npath = \"{}\"\n", s(p)));
    let text = format!(
        r#"mesh = "{}"
mm_per_unit = 1.0
{extra}
{map}
[[light]]
kind = "directional"
direction = [0.75, 0.35, 0.55]
intensity = 4.0
[[camera]]
position = [170.0, 25.0, 380.0]
target = [0.0, 5.0, 0.0]
[output]
size = [96, 80]
"#,
        s(&repo().join("samples/head/head.obj"))
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// A 256x128 normal map of strong ripples (16-bit PNG) in `dir`.
fn ripples(dir: &Path) -> PathBuf {
    let map = NormalMap::from_grid(skinkit_maps::Grid::from_fn(256, 128, |x, y| {
        let (a, b) = (x as f32 * 0.9, y as f32 * 0.7);
        glam::Vec3::new(0.6 * a.sin(), 0.6 * b.cos(), 1.0).normalize()
    }));
    let path = dir.join("ripples.png");
    skinkit_maps::io::write_normal_map(&path, &map, NormalEncoding::default(), 16).unwrap();
    path
}

#[test]
fn the_committed_sample_head_is_what_samples_writes() {
    let tmp = tempfile::tempdir().unwrap();
    let head = tmp.path().join("h/head.obj");
    let o = skinkit(&["samples", "--quiet", "--head", s(&head), "--head-only"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let made = std::fs::read(&head).unwrap();
    let committed = std::fs::read(repo().join("samples/head/head.obj")).unwrap();
    assert!(made == committed, "samples/head/head.obj differs from `skinkit samples --head`");
    // Only the head: no mold folders next to it.
    assert_eq!(std::fs::read_dir(tmp.path().join("h")).unwrap().count(), 1);
}

/// Issue 41: every sample scene renders on a fresh clone, without the demo's outputs (head.toml
/// wears the committed quarter-size face map, samples/face/normal.png).
#[test]
fn every_sample_scene_renders_as_committed() {
    let tmp = tempfile::tempdir().unwrap();
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(repo().join("samples/scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 6, "{scenes:?}");
    for scene in scenes {
        let out = tmp.path().join(scene.file_stem().unwrap()).with_extension("png");
        let o = skinkit(&["render", s(&scene), "--size", "48x40", "--out", s(&out), "--quiet"]);
        assert!(o.status.success(), "{}: {}", scene.display(), stderr(&o));
        let (w, h, pixels) = pixels(&out);
        assert_eq!((w, h), (48, 40), "{}", scene.display());
        assert!(pixels.iter().any(|&v| v > 0), "{}: a black frame", scene.display());
    }
}

#[test]
fn the_head_renders_and_the_normal_map_changes_it() {
    let tmp = tempfile::tempdir().unwrap();
    let smooth = head_scene(tmp.path(), None, "");
    let out_smooth = tmp.path().join("smooth.png");
    let o = skinkit(&["render", s(&smooth), "--out", s(&out_smooth), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["width"], 96);
    assert_eq!(report["images"].as_array().unwrap().len(), 1);
    assert!(report["vertices"].as_u64().unwrap() > 10_000);
    let (w, h, a) = pixels(&out_smooth);
    assert_eq!((w, h), (96, 80));
    // The head covers the middle of the frame and is lit; the corners are background.
    let at = |v: &[u8], x: usize, y: usize| v[3 * (y * w + x)] as u32 + v[3 * (y * w + x) + 1] as u32;
    assert!(at(&a, w / 2, h / 2) > 60, "centre is dark: {}", at(&a, w / 2, h / 2));
    assert_eq!(at(&a, 0, 0), 0);

    let map = ripples(tmp.path());
    let bumpy = head_scene(tmp.path(), Some(&map), "");
    let out_bumpy = tmp.path().join("bumpy.png");
    let o = skinkit(&["render", s(&bumpy), "--out", s(&out_bumpy), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, _, b) = pixels(&out_bumpy);
    let changed = a.chunks_exact(3).zip(b.chunks_exact(3)).filter(|(p, q)| p != q).count();
    assert!(changed > w * h / 10, "the normal map changed only {changed} pixels");
}

#[test]
fn exr_output_is_linear_and_orbit_writes_numbered_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path(), None, "");
    let exr = tmp.path().join("head.exr");
    let o = skinkit(&["render", s(&scene), "--out", s(&exr), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let photo = read_photo(&exr, &Limits::default()).unwrap();
    let Samples::F32(v) = photo.samples() else { panic!("EXR is not float") };
    assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0));
    assert!(v.iter().any(|&x| x > 0.05), "all dark");

    let o = skinkit(&[
        "render",
        s(&scene),
        "--out",
        s(&tmp.path().join("turn.png")),
        "--orbit",
        "--frames",
        "3",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frames: Vec<_> = (0..3).map(|f| pixels(&tmp.path().join(format!("turn-{f:04}.png"))).2).collect();
    assert_ne!(frames[0], frames[1]);
    assert_ne!(frames[1], frames[2]);
    // Frame 0 of a turntable is the camera itself.
    let still = tmp.path().join("still.png");
    assert!(skinkit(&["render", s(&scene), "--out", s(&still), "--quiet"]).status.success());
    assert_eq!(pixels(&still).2, frames[0]);
}

#[test]
fn explain_lists_the_base_pass_and_its_resources() {
    let tmp = tempfile::tempdir().unwrap();
    let map = ripples(tmp.path());
    let scene = head_scene(tmp.path(), Some(&map), "");
    let o = skinkit(&["render", s(&scene), "--out", "x.png", "--explain", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let passes = e["plan"]["passes"].as_array().unwrap();
    assert_eq!(passes.len(), 1);
    assert_eq!(passes[0]["name"], "base");
    let resources: Vec<&str> =
        e["plan"]["resources"].as_array().unwrap().iter().map(|r| r["name"].as_str().unwrap()).collect();
    assert!(resources.contains(&"normal map") && resources.contains(&"colour target"), "{resources:?}");
    let normal = e["plan"]["resources"].as_array().unwrap().iter().find(|r| r["name"] == "normal map").unwrap();
    // 256x128 Rgba16Float with its mip chain: 8 bytes a texel, about 4/3 of level 0.
    let bytes = normal["bytes"].as_u64().unwrap();
    assert!(bytes > 8 * 256 * 128 && bytes < 8 * 256 * 128 * 4 / 3 + 64, "{bytes}");
    assert!(!tmp.path().join("x.png").exists() && !Path::new("x.png").exists(), "explain rendered");
}

#[test]
fn bad_scenes_name_the_file_and_the_field() {
    let tmp = tempfile::tempdir().unwrap();
    let out = s(&tmp.path().join("o.png")).to_owned();
    let run = |extra: &str| {
        let scene = head_scene(tmp.path(), None, extra);
        let o = skinkit(&["render", s(&scene), "--out", &out]);
        assert_eq!(o.status.code(), Some(1), "{extra}: {}", stderr(&o));
        assert!(!Path::new(&out).exists());
        stderr(&o)
    };
    let e = run("intesity = 3.0");
    assert!(e.contains("scene.toml") && e.contains("intesity"), "{e}");
    let e = run("effects = [\"sh-ambient\"]");
    assert!(e.contains("scene.toml") && e.contains("environment"), "{e}");
    let e = run("effects = [\"preintegrated\", \"tsd\"]");
    assert!(e.contains("effects") && e.contains("tsd"), "{e}");
    let e = run("[normal_map]\npath = \"missing.png\"");
    assert!(e.contains("normal_map") && e.contains("missing.png"), "{e}");

    let scene = tmp.path().join("nomesh.toml");
    let text = std::fs::read_to_string(head_scene(tmp.path(), None, "")).unwrap().replace("head.obj", "nothere.obj");
    std::fs::write(&scene, text).unwrap();
    let o = skinkit(&["render", s(&scene), "--out", &out]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nothere.obj"), "{}", stderr(&o));

    let scene = head_scene(tmp.path(), None, "");
    let o = skinkit(&["render", s(&scene), "--out", s(&tmp.path().join("o.jpg"))]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains(".png or .exr"), "{}", stderr(&o));
}

#[test]
fn no_adapter_is_one_sentence_with_the_fix() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path(), None, "");
    // GL is not compiled in: asking for it alone leaves no backend with an adapter.
    let o = Command::new(env!("CARGO_BIN_EXE_skinkit"))
        .args(["render", s(&scene), "--out", s(&tmp.path().join("o.png"))])
        .env("WGPU_BACKEND", "gl")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("mesa-vulkan-drivers") && e.contains("WGPU_BACKEND=vulkan"), "{e}");
}

/// `head_scene` with its light casting shadows.
fn shadowed_head_scene(dir: &Path, extra: &str) -> PathBuf {
    let path = head_scene(dir, None, extra);
    let text = std::fs::read_to_string(&path).unwrap().replace("intensity = 4.0", "intensity = 4.0\nshadows = true");
    std::fs::write(&path, text).unwrap();
    path
}

fn explain_json(scene: &Path) -> serde_json::Value {
    let o = skinkit(&["render", s(scene), "--explain", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

fn names(v: &serde_json::Value, key: &str) -> Vec<String> {
    v["plan"][key].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
}

#[test]
fn explain_shows_the_graph_each_scene_asks_for() {
    let tmp = tempfile::tempdir().unwrap();
    let pre = explain_json(&shadowed_head_scene(
        tmp.path(),
        "effects = [\"preintegrated\", \"shadows\", \"shadow-scattering\"]",
    ));
    assert_eq!(names(&pre, "passes"), ["shadow map", "base"]);
    let resources = names(&pre, "resources");
    for name in ["diffuse LUT", "shadow LUT", "shadow map", "per-vertex curvature"] {
        assert!(resources.iter().any(|r| r == name), "{name}: {resources:?}");
    }
    let tsd = explain_json(&shadowed_head_scene(
        tmp.path(),
        "effects = [\"tsd\", \"shadows\"]\n[tsd]\nkernel = \"single\"\npasses = 2",
    ));
    assert_eq!(
        names(&tsd, "passes"),
        ["shadow map", "tsd back-face pre-pass", "tsd light map", "tsd blur 1", "tsd blur 2", "base"]
    );
    // The default kernel, the profile's Gaussians: a dilating blur and one per Gaussian increment.
    let gaussians = explain_json(&shadowed_head_scene(tmp.path(), "effects = [\"tsd\", \"shadows\"]"));
    let blurs = names(&gaussians, "passes").iter().filter(|p| p.starts_with("tsd blur")).count();
    assert_eq!(blurs, 5);
    assert!(!names(&tsd, "resources").iter().any(|r| r.contains("LUT")));
    // `shadows` with no shadow-casting light: no shadow map, and the warning says why.
    let none = explain_json(&head_scene(tmp.path(), None, "effects = [\"shadows\"]"));
    assert_eq!(names(&none, "passes"), ["base"]);
    let warnings = none["warnings"].as_array().unwrap();
    assert!(warnings.iter().any(|w| w.as_str().unwrap().contains("no light")), "{warnings:?}");
}

#[test]
fn skin_effects_and_the_reference_render_and_change_the_picture() {
    let tmp = tempfile::tempdir().unwrap();
    let render = |scene: &Path, name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let mut args = vec!["render", s(scene), "--out", s(&out), "--json"];
        args.extend_from_slice(extra);
        let o = skinkit(&args);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        pixels(&out).2
    };
    let lambert = render(&shadowed_head_scene(tmp.path(), "effects = [\"shadows\"]"), "lambert.png", &[]);
    let env = "\n[environment]\nsky = [0.3, 0.3, 0.35]\nground = [0.05, 0.04, 0.03]";
    let skin = render(
        &shadowed_head_scene(
            tmp.path(),
            &format!("effects = [\"preintegrated\", \"shadows\", \"shadow-scattering\", \"sh-ambient\"]{env}"),
        ),
        "skin.png",
        &[],
    );
    let reference =
        render(&shadowed_head_scene(tmp.path(), "effects = [\"shadows\"]"), "reference.png", &["--reference", "64"]);
    let differs = |a: &[u8], b: &[u8]| a.iter().zip(b).filter(|(x, y)| x.abs_diff(**y) > 8).count();
    assert!(differs(&lambert, &skin) > 100, "the skin effects changed {} samples", differs(&lambert, &skin));
    assert!(differs(&lambert, &reference) > 100, "the reference changed {} samples", differs(&lambert, &reference));
    let o = skinkit(&[
        "render",
        s(&head_scene(tmp.path(), None, "")),
        "--out",
        s(&tmp.path().join("x.png")),
        "--reference",
        "4",
    ]);
    // A flag value out of its range is a usage error (issue 15).
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--reference"), "{}", stderr(&o));
}

#[test]
fn a_render_over_the_memory_limit_is_refused_before_its_target_is_made() {
    let dir = tempfile::tempdir().unwrap();
    let scene = head_scene(dir.path(), None, "");
    let out = dir.path().join("big.png");
    // 16384x16384 as sRGB PNG needs about 9 GiB for one frame: over 1 GiB, refused at once.
    let args = ["--memory-limit", "1G", "render", s(&scene), "--size", "16384x16384", "--out", s(&out)];
    let o = skinkit(&args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("scene.toml") && e.contains("rendering 16384x16384") && e.contains("memory limit"), "{e}");
    assert!(!out.exists());
    // The same scene at its own size fits.
    let small = dir.path().join("small.png");
    let o = skinkit(&["--memory-limit", "1G", "render", "--quiet", s(&scene), "--out", s(&small)]);
    assert!(o.status.success(), "{}", stderr(&o));
}
