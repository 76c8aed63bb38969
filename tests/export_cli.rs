//! End-to-end tests of `skinkit export gltf`: the sample head with a ripple normal map and an
//! asymmetric albedo exported as GLB and as `.gltf`, checked by the Khronos glTF validator (the
//! npm package `gltf-validator`, run by `scripts/gltf-validate.mjs` under node), re-opened with the
//! `gltf` crate, and re-rendered by `skinkit render` from the GLB alone to the same image as the
//! scene it came from. Rendering needs an adapter (lavapipe via scripts/test). The validator step
//! installs its package when it is missing (`npm ci --prefix tools/gltf-validator`) and is skipped,
//! with a line on stderr, only when node or the package cannot be had.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use skinkit_maps::io::{Limits, read_photo};
use skinkit_maps::{NormalEncoding, NormalMap, Samples};

use skinkit_testkit::image_diff;

use crate::support::{repo, s, skinkit, stderr};

/// Render size: small, so the two renders stay quick on lavapipe.
const SIZE: u32 = 256;

/// The maps of the test scene in `dir`: a 256x128 ripple normal map (16-bit PNG) and a 64x32
/// albedo that differs left to right and top to bottom (16-bit linear PNG, what capture writes).
fn maps(dir: &Path) -> (PathBuf, PathBuf) {
    let normals = NormalMap::from_grid(skinkit_maps::Grid::from_fn(256, 128, |x, y| {
        let (a, b) = (x as f32 * 0.9, y as f32 * 0.7);
        glam::Vec3::new(0.6 * a.sin(), 0.6 * b.cos(), 1.0).normalize()
    }));
    let normal = dir.join("ripples.png");
    skinkit_maps::io::write_normal_map(&normal, &normals, NormalEncoding::default(), 16).unwrap();
    let colours = skinkit_maps::Grid::from_fn(64, 32, |x, y| {
        glam::Vec3::new(0.25 + 0.5 * x as f32 / 63.0, 0.2 + 0.3 * y as f32 / 31.0, 0.3)
    });
    let albedo = dir.join("albedo.png");
    skinkit_maps::io::write_color_map(&albedo, &colours, 16).unwrap();
    (normal, albedo)
}

/// A scene of `mesh` with `albedo` and `normal` (paths as written into the TOML), its camera
/// position and target times `scale` (1 for the head in millimetres, 0.001 for the export in
/// metres). Its lights are directional: a point light's `1/d^2` falloff is not scale-free, so it
/// would need its intensity rescaled with the units as well.
fn scene_file(dir: &Path, name: &str, mesh: &str, albedo: &str, normal: &str, mm_per_unit: f32, scale: f32) -> PathBuf {
    let text = format!(
        r#"mesh = "{mesh}"
mm_per_unit = {mm_per_unit}
albedo = "{albedo}"
[normal_map]
path = "{normal}"
frames = "mikktspace"
[[light]]
kind = "directional"
direction = [0.75, 0.35, 0.55]
intensity = 4.0
[[light]]
kind = "directional"
direction = [-0.5, 0.6, 0.6]
intensity = 1.5
[[camera]]
position = [{}, {}, {}]
target = [0.0, {}, 0.0]
fov_deg = 24.0
[output]
size = [{SIZE}, {SIZE}]
"#,
        170.0 * scale,
        25.0 * scale,
        380.0 * scale,
        5.0 * scale,
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// The head scene in `dir` with its maps.
fn head_scene(dir: &Path) -> PathBuf {
    let (normal, albedo) = maps(dir);
    let mesh = repo().join("samples/head/head.obj");
    scene_file(dir, "head.toml", s(&mesh), s(&albedo), s(&normal), 1.0, 1.0)
}

/// Runs the export and returns its `--json` report.
fn export(scene: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["export", "gltf", "--scene", s(scene), "--out", s(out), "--json"];
    args.extend_from_slice(extra);
    let o = skinkit(&args);
    assert!(o.status.success(), "export failed: {}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `node` and the installed validator package, installing the package once when it is missing;
/// `None` (after saying why on stderr) when neither can be had.
fn validator() -> Option<&'static Path> {
    static READY: OnceLock<Option<PathBuf>> = OnceLock::new();
    READY
        .get_or_init(|| {
            let tools = repo().join("tools/gltf-validator");
            if Command::new("node").arg("--version").output().is_err() {
                eprintln!("skipped: the glTF validator step: `node` is not installed");
                return None;
            }
            if !tools.join("node_modules/gltf-validator/package.json").exists() {
                let o = Command::new("npm")
                    .args(["ci", "--prefix", s(&tools), "--no-audit", "--no-fund", "--silent"])
                    .output();
                let installed = tools.join("node_modules/gltf-validator/package.json").exists();
                if !installed {
                    let why = o.map_or_else(|e| e.to_string(), |o| stderr(&o));
                    eprintln!("skipped: the glTF validator step: `npm ci --prefix {}` failed: {why}", tools.display());
                    return None;
                }
            }
            Some(repo().join("scripts/gltf-validate.mjs"))
        })
        .as_deref()
}

/// Validates `file` and asserts it has no errors; prints the counts.
fn validate(file: &Path) {
    let Some(script) = validator() else { return };
    let o = Command::new("node").arg(script).arg(file).output().expect("node runs");
    let report: serde_json::Value =
        serde_json::from_slice(&o.stdout).unwrap_or_else(|_| panic!("validator printed no report: {}", stderr(&o)));
    eprintln!(
        "{}: validator {}: {} errors, {} warnings, {} infos, {} hints",
        file.display(),
        report["validator"],
        report["numErrors"],
        report["numWarnings"],
        report["numInfos"],
        report["numHints"]
    );
    assert_eq!(report["numErrors"], 0, "the validator found errors: {report}");
    assert!(o.status.success(), "{}", stderr(&o));
}

/// Checks a GLB's contents against the mesh it came from: accessor counts, unit tangents with
/// `w = ±1`, both textures, the normal texture's bit depth.
fn check_contents(glb: &Path, normal_bits: u8) {
    let mesh = skinkit_render::mesh::Mesh::load(&repo().join("samples/head/head.obj")).unwrap().mesh;
    let gltf::Gltf { document, blob } = gltf::Gltf::open(glb).unwrap();
    let blob = blob.expect("a GLB has a binary chunk");
    let primitive = document.meshes().next().unwrap().primitives().next().unwrap();
    let n = mesh.positions.len();
    for (semantic, accessor) in primitive.attributes() {
        assert_eq!(accessor.count(), n, "{semantic:?}");
    }
    assert_eq!(primitive.indices().unwrap().count(), mesh.indices.len());
    let reader = primitive.reader(|_| Some(blob.as_slice()));
    for t in reader.read_tangents().expect("tangents") {
        let length = glam::Vec3::new(t[0], t[1], t[2]).length();
        assert!((length - 1.0).abs() < 1e-5 && (t[3] == 1.0 || t[3] == -1.0), "{t:?}");
    }
    let material = document.materials().next().unwrap();
    let base = material.pbr_metallic_roughness().base_color_texture().expect("baseColorTexture").texture();
    let normal = material.normal_texture().expect("normalTexture").texture();
    for (texture, bits) in [(base, 8), (normal, normal_bits)] {
        let gltf::image::Source::View { view, mime_type } = texture.source().source() else { panic!("not embedded") };
        assert_eq!(mime_type, "image/png");
        let png = &blob[view.offset()..view.offset() + view.length()];
        // The IHDR's bit depth: 8 signature bytes, 8 of chunk header, 8 of width and height.
        assert_eq!(png[24], bits, "texture {}", texture.index());
    }
}

#[test]
fn a_glb_export_passes_the_validator_and_holds_the_mesh_and_maps() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path());
    for (bits, name) in [(8u8, "head8.glb"), (16, "head16.glb")] {
        let glb = tmp.path().join(name);
        let report = export(&scene, &glb, &["--normal-bits", &bits.to_string()]);
        assert_eq!(report["normal"]["bits"], bits);
        assert_eq!(report["files"].as_array().unwrap().len(), 1);
        validate(&glb);
        check_contents(&glb, bits);
    }
}

#[test]
fn a_gltf_export_writes_its_side_files_and_passes_the_validator() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path());
    let out = tmp.path().join("out/head.gltf");
    std::fs::create_dir(tmp.path().join("out")).unwrap();
    export(&scene, &out, &[]);
    let mut names: Vec<String> = std::fs::read_dir(tmp.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, ["head-albedo.png", "head-normal.png", "head.bin", "head.gltf"], "no temporary files left");
    validate(&out);
    // The gltf crate resolves every relative URI.
    let (document, buffers, images) = gltf::import(&out).unwrap();
    assert_eq!((document.images().count(), buffers.len(), images.len()), (2, 1, 2));
    assert_eq!((images[1].width, images[1].height), (256, 128));
}

fn linear_pixels(path: &Path) -> Vec<f32> {
    let photo = read_photo(path, &Limits::default()).unwrap();
    let Samples::F32(v) = photo.samples() else { panic!("{}: not float", path.display()) };
    v.clone()
}

// The tolerances of the renderer's GPU tests (crates/render/tests/render/gpu.rs: mean 0.005 and 99th
// percentile 0.02 of the per-pixel largest channel error, relative to the brightest reference
// channel). The export adds quantisation on top of the renderer's own differences: the albedo goes
// from 16-bit linear to 8-bit sRGB and the normal map to 8 or 16 bits.
const MEAN_TOL: f32 = 0.005;
const P99_TOL: f32 = 0.02;

#[test]
fn skinkit_render_draws_the_exported_glb_like_its_scene() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path());
    let reference = tmp.path().join("reference.exr");
    let o = skinkit(&["render", s(&scene), "--out", s(&reference), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let expected = linear_pixels(&reference);
    for bits in ["8", "16"] {
        let glb = tmp.path().join(format!("head{bits}.glb"));
        export(&scene, &glb, &["--normal-bits", bits]);
        // The mesh and both maps come from the GLB; glTF positions are metres.
        let from_glb = scene_file(tmp.path(), "from-glb.toml", s(&glb), s(&glb), s(&glb), 1000.0, 0.001);
        let image = tmp.path().join(format!("from-glb{bits}.exr"));
        let o = skinkit(&["render", s(&from_glb), "--out", s(&image), "--quiet"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let c = image_diff(&linear_pixels(&image), &expected, 3);
        eprintln!("{bits}-bit normal texture: re-render against the scene's: {c:?}");
        assert!(
            c.mean < MEAN_TOL && c.p99 < P99_TOL,
            "{bits}-bit: {c:?} (tolerances mean {MEAN_TOL}, p99 {P99_TOL}); images in {}",
            tmp.keep().display()
        );
    }
}

#[test]
fn bad_requests_name_the_flag_file_or_field() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = head_scene(tmp.path());
    // Not a glTF name, or a bit depth glTF viewers do not take: usage errors.
    for args in [vec!["--out", "x.obj"], vec!["--out", "x.glb", "--normal-bits", "12"]] {
        let mut all = vec!["export", "gltf", "--scene", s(&scene)];
        all.extend(args);
        let o = skinkit(&all);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    }
    // Over one of the scene's inputs (here its mesh, a GLB that is not read before the refusal).
    let glb = tmp.path().join("x.glb");
    let over_mesh = scene_file(tmp.path(), "over.toml", s(&glb), "albedo.png", "ripples.png", 1000.0, 0.001);
    let o = skinkit(&["export", "gltf", "--scene", s(&over_mesh), "--out", s(&glb)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("the scene's mesh"), "{}", stderr(&o));
    let text = std::fs::read_to_string(&scene).unwrap();
    std::fs::write(&scene, text.replace("ripples.png", "missing.png")).unwrap();
    let out = tmp.path().join("m.glb");
    let o = skinkit(&["export", "gltf", "--scene", s(&scene), "--out", s(&out)]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("head.toml") && e.contains("normal_map.path") && e.contains("missing.png"), "{e}");
    assert!(!out.exists());
}
