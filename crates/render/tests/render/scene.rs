//! Scene files: a full scene, defaults, unknown keys and bad values.

use std::path::{Path, PathBuf};

use glam::Vec3;
use skinkit_maps::GreenAxis;
use skinkit_render::brdf::Lafortune;
use skinkit_render::effect::Effect;
use skinkit_render::frames::FrameMethod;
use skinkit_render::scene::{Albedo, OutputFormat, Scene, SceneError};
use skinkit_render::shading::{LightKind, SpecularMode};

const ORIGIN: &str = "/scenes/face/scene.toml";

fn parse(text: &str) -> Result<Scene, SceneError> {
    Scene::parse(text, Path::new(ORIGIN))
}

const MINIMAL: &str = r#"
mesh = "head.obj"
mm_per_unit = 1.0

[[light]]
kind = "directional"
direction = [0.0, 0.0, 2.0]

[[camera]]
position = [0.0, 0.0, 600.0]
target = [0.0, 0.0, 0.0]
"#;

const FULL: &str = r#"
mesh = "../meshes/head.glb"
mm_per_unit = 10.0
albedo = [0.5, 0.4, 0.3]
specular = "vertex"
effects = ["shadows", "preintegrated"]

[normal_map]
path = "maps/face.png"
green = "down"
frames = "mikktspace"

[brdf]
diffuse = [0.1, 0.2, 0.3]
lobes = [
  { cxy = [-1.0, -1.0, -1.0], cz = [0.5, 0.5, 0.5], n = [10.0, 20.0, 10000.0] },
  { cx = [-0.5, -0.6, -0.7], cy = [-0.4, -0.3, -0.2], cz = [1.0, 1.0, 1.0], n = [2.0, 2.0, 2.0] },
]

[[light]]
kind = "point"
position = [100.0, 200.0, 300.0]
colour = [1.0, 0.9, 0.8]
intensity = 5.0
shadows = true

[[light]]
kind = "directional"
direction = [3.0, 0.0, 4.0]

[[camera]]
position = [0.0, 0.0, 500.0]
target = [0.0, 10.0, 0.0]
up = [0.0, 2.0, 0.0]
fov_deg = 25.0

[[camera]]
position = [400.0, 0.0, 0.0]
target = [0.0, 0.0, 0.0]

[output]
size = [640, 480]
path = "out/render.EXR"
"#;

#[test]
fn full_scene_parses_with_paths_resolved_against_the_scene_folder() {
    let s = parse(FULL).unwrap();
    let base = Path::new("/scenes/face");
    assert_eq!(s.mesh, base.join("../meshes/head.glb"));
    assert_eq!(s.mm_per_unit, 10.0);
    assert_eq!(s.albedo, Some(Albedo::Constant(Vec3::new(0.5, 0.4, 0.3))));
    assert_eq!(s.specular, SpecularMode::Vertex);
    assert_eq!(s.effects, vec![Effect::Shadows, Effect::Preintegrated]);
    assert_eq!(s.file, Path::new(ORIGIN));
    let nm = s.normal_map.as_ref().unwrap();
    assert_eq!(nm.path, base.join("maps/face.png"));
    assert_eq!((nm.green, nm.frames), (GreenAxis::Down, FrameMethod::MikkTSpace));
    assert_eq!(s.brdf.diffuse, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(s.brdf.lobes.len(), 2);
    let l0 = s.brdf.lobes[0];
    assert_eq!((l0.cx, l0.cy), (Vec3::splat(-1.0), Vec3::splat(-1.0)));
    assert_eq!(l0.n, Vec3::new(10.0, 20.0, 10000.0));
    let l1 = s.brdf.lobes[1];
    assert_eq!((l1.cx, l1.cy), (Vec3::new(-0.5, -0.6, -0.7), Vec3::new(-0.4, -0.3, -0.2)));
    assert_eq!(s.lights.len(), 2);
    let l0 = s.lights[0];
    assert_eq!(l0.light.kind, LightKind::Point { position: Vec3::new(100.0, 200.0, 300.0) });
    assert_eq!((l0.light.color, l0.light.intensity, l0.shadows), (Vec3::new(1.0, 0.9, 0.8), 5.0, true));
    // Directions are normalised: (3, 0, 4) / 5.
    let LightKind::Directional { toward: direction } = s.lights[1].light.kind else { panic!("{:?}", s.lights[1]) };
    assert!((direction - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6);
    assert_eq!(s.cameras.len(), 2);
    assert_eq!((s.cameras[0].up, s.cameras[0].fov_deg), (Vec3::Y, 25.0));
    assert_eq!(s.cameras[0].target, Vec3::new(0.0, 10.0, 0.0));
    assert_eq!(s.output.size, [640, 480]);
    let out = s.output.path.as_ref().unwrap();
    assert_eq!(out, &base.join("out/render.EXR"));
    assert_eq!(OutputFormat::from_path(out), Some(OutputFormat::Exr));
}

#[test]
#[allow(clippy::excessive_precision)] // The table's digits, as published.
fn defaults_fill_everything_optional() {
    let s = parse(MINIMAL).unwrap();
    assert_eq!(s.mesh, PathBuf::from("/scenes/face/head.obj"));
    assert_eq!(s.albedo, None);
    assert_eq!(s.normal_map, None);
    assert_eq!(s.specular, SpecularMode::Pixel);
    assert!(s.effects.is_empty());
    assert_eq!(s.output.size, [1024, 1024]);
    assert_eq!(s.output.path, None);
    let light = s.lights[0];
    assert_eq!((light.light.color, light.light.intensity, light.shadows), (Vec3::ONE, 1.0, false));
    assert_eq!(light.light.kind, LightKind::Directional { toward: Vec3::Z });
    assert_eq!((s.cameras[0].up, s.cameras[0].fov_deg), (Vec3::Y, 30.0));
    // The skin set exactly as docs/references.md tabulates it.
    assert_eq!(s.brdf.diffuse, Vec3::new(0.428425, 0.301341, 0.331054));
    assert_eq!(s.brdf.lobes, Lafortune::skin().lobes);
    let l = &s.brdf.lobes;
    assert_eq!(l.len(), 3);
    assert_eq!(l[0].cx, Vec3::new(-1.131747, -1.016939, -0.966018));
    assert_eq!(l[0].cy, l[0].cx);
    assert_eq!(l[0].cz, Vec3::new(-1.209182, -1.462488, -1.222419));
    assert_eq!(l[0].n, Vec3::new(6.421658, 3.699932, 3.524889));
    assert_eq!(l[1].cx, Vec3::new(-0.546570, -0.643533, -0.638934));
    assert_eq!(l[1].cz, Vec3::new(0.380123, 0.410559, 0.437367));
    assert_eq!(l[1].n, Vec3::new(3.685044, 4.266495, 4.539742));
    assert_eq!(l[2].cy, Vec3::new(-0.998888, -1.020153, -1.027479));
    assert_eq!(l[2].cz, Vec3::new(0.857998, 0.703913, 0.573625));
    assert_eq!(l[2].n, Vec3::new(64.208486, 63.919687, 43.809866));
    // A [brdf] table with only lobes keeps the default diffuse, and the reverse.
    let only_diffuse = parse(&format!("{MINIMAL}\n[brdf]\ndiffuse = [0.2, 0.2, 0.2]\n")).unwrap();
    assert_eq!(only_diffuse.brdf.lobes, Lafortune::skin().lobes);
    let no_lobes = parse(&format!("{MINIMAL}\n[brdf]\nlobes = []\n")).unwrap();
    assert_eq!((no_lobes.brdf.diffuse, no_lobes.brdf.lobes.len()), (Lafortune::skin().diffuse, 0));
    // An albedo map path, resolved.
    let map = parse(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = 1.0\nalbedo = \"a.png\"")).unwrap();
    assert_eq!(map.albedo, Some(Albedo::Map(PathBuf::from("/scenes/face/a.png"))));
}

fn error(text: &str) -> String {
    let err = parse(text).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains(ORIGIN), "the message names the file: {msg}");
    msg
}

#[test]
fn unknown_keys_are_refused_by_name() {
    let top = error(&format!("colour_space = \"srgb\"\n{MINIMAL}"));
    assert!(top.contains("colour_space"), "{top}");
    let light = error(&MINIMAL.replace("kind = \"directional\"", "kind = \"directional\"\nintesity = 2.0"));
    assert!(light.contains("intesity"), "{light}");
    let normal = error(&format!("{MINIMAL}\n[normal_map]\npath = \"n.png\"\ngreen = \"up\"\nbasis = \"paper\"\n"));
    assert!(normal.contains("basis"), "{normal}");
    let lobe = error(&format!("{MINIMAL}\n[brdf]\nlobes = [{{ cxy = [1,1,1], cz = [1,1,1], n = [1,1,1], m = 2 }}]\n"));
    assert!(lobe.contains("`m`"), "{lobe}");
    let out = error(&format!("{MINIMAL}\n[output]\nsize = [8, 8]\nformat = \"png\"\n"));
    assert!(out.contains("format"), "{out}");
}

fn invalid(text: &str, field: &str) -> String {
    let err = parse(text).unwrap_err();
    match &err {
        SceneError::Invalid { field: f, .. } => assert_eq!(f, field, "{err}"),
        other => panic!("expected an invalid {field}, got {other}"),
    }
    let msg = err.to_string();
    assert!(msg.contains(ORIGIN) && msg.contains(field), "{msg}");
    msg
}

#[test]
fn bad_values_are_refused_with_file_and_field() {
    let lobe = |n: &str| format!("{MINIMAL}\n[brdf]\nlobes = [{{ cxy = [1,1,1], cz = [1,1,1], n = {n} }}]\n");
    invalid(&lobe("[10.0, -2.0, 10.0]"), "brdf.lobes[0].n");
    invalid(&lobe("[10.0, 0.0, 10.0]"), "brdf.lobes[0].n");
    invalid(&lobe("[10.0, nan, 10.0]"), "brdf.lobes[0].n");
    invalid(&MINIMAL.replace("[0.0, 0.0, 2.0]", "[0.0, 0.0, 0.0]"), "light[0].direction");
    invalid(
        &MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov_deg = 180.0"),
        "camera[0].fov_deg",
    );
    invalid(
        &MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov_deg = 0.0"),
        "camera[0].fov_deg",
    );
    invalid(&MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 600.0]"), "camera[0].target");
    invalid(
        &MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, 1.0]"),
        "camera[0].up",
    );
    invalid(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = -1.0"), "mm_per_unit");
    // Issue 41: named as missing, not "TOML parse error at line 1, column 1".
    let missing = invalid(&MINIMAL.replace("mm_per_unit = 1.0", ""), "mm_per_unit");
    assert!(missing.contains("missing") && missing.contains("millimetres") && !missing.contains("line 1"), "{missing}");
    invalid(&MINIMAL.replace("kind = \"directional\"", "kind = \"point\""), "light[0].position");
    invalid(
        &MINIMAL.replace("direction = [0.0, 0.0, 2.0]", "direction = [0.0, 0.0, 2.0]\nintensity = -1.0"),
        "light[0].intensity",
    );
    invalid(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = 1.0\nalbedo = [2.0, 0.5, 0.5]"), "albedo");
    let effect =
        invalid(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = 1.0\neffects = [\"bloom\"]"), "effects[0]");
    assert!(effect.contains("bloom") && effect.contains("preintegrated"), "{effect}");
    invalid(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = 1.0\neffects = [\"tsd\", \"tsd\"]"), "effects[1]");
    invalid(&format!("{MINIMAL}\n[output]\nsize = [0, 10]\n"), "output.size");
    invalid(&format!("{MINIMAL}\n[output]\npath = \"x.jpg\"\n"), "output.path");
    invalid(&lobe("[1,1,1], cx = [1,1,1]"), "brdf.lobes[0].cxy");
    let five_lobes = ["{ cxy = [1,1,1], cz = [1,1,1], n = [1,1,1] }"; 5].join(", ");
    let e = invalid(&format!("{MINIMAL}\n[brdf]\nlobes = [{five_lobes}]\n"), "brdf.lobes");
    assert!(e.contains("5 lobes") && e.contains("at most 4"), "{e}");
    let no_camera = MINIMAL.split("[[camera]]").next().unwrap();
    invalid(no_camera, "camera");
}

#[test]
fn wrong_types_and_variants_are_syntax_errors_naming_the_key() {
    let spec = error(&MINIMAL.replace("mm_per_unit = 1.0", "mm_per_unit = 1.0\nspecular = \"phong\""));
    assert!(spec.contains("phong") && spec.contains("specular"), "{spec}");
    let green = error(&format!("{MINIMAL}\n[normal_map]\npath = \"n.png\"\ngreen = \"sideways\"\n"));
    assert!(green.contains("sideways"), "{green}");
    let missing = error("mm_per_unit = 1.0\n");
    assert!(missing.contains("mesh"), "{missing}");
}

#[test]
fn load_reads_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, MINIMAL).unwrap();
    let s = Scene::load(&path).unwrap();
    assert_eq!(s.mesh, dir.path().join("head.obj"));
    let err = Scene::load(&dir.path().join("none.toml")).unwrap_err();
    // Read through the input gate (issue 42): its I/O error.
    let gate_io = matches!(err, SceneError::Input(skinkit_maps::input::InputError::Io { .. }));
    assert!(gate_io && err.to_string().contains("none.toml"), "{err}");
}
