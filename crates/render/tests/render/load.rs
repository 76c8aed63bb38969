//! Scenes into render inputs (`load`): maps read with their conventions, oversized maps halved
//! with a warning, albedo transfer by bit depth, turntable cameras, lights and lobes past the
//! pass's limits refused, and the plan of passes and resources.

use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use skinkit_maps::io::{PngLayout, write_normal_map, write_png};
use skinkit_maps::{GreenAxis, Grid, NormalEncoding, NormalMap};
use skinkit_render::gpu::OutputFormat;
use skinkit_render::head::write_obj;
use skinkit_render::load::{load, orbit};
use skinkit_render::mesh::Mesh;
use skinkit_render::pass::explain::plan;
use skinkit_render::pass::graph::PassGraph;
use skinkit_render::scene::{Camera, Scene};

fn quad(dir: &Path) -> PathBuf {
    let mesh = Mesh {
        positions: vec![
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(-1.0, -1.0, 0.0),
        ],
        normals: vec![Vec3::Z; 4],
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)],
        indices: vec![0, 3, 2, 0, 2, 1],
    };
    let path = dir.join("quad.obj");
    write_obj(&mesh, &path).unwrap();
    path
}

fn scene(dir: &Path, body: &str) -> Scene {
    let mesh = quad(dir);
    let text = format!(
        "mesh = \"{}\"\nmm_per_unit = 10.0\n{body}\n[[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, 1.0]\n\
         [[camera]]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n",
        mesh.display()
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, &text).unwrap();
    Scene::load(&path).unwrap()
}

/// A 256x128 map tilted toward +x on the left half and +y on the right half.
fn tilted(dir: &Path, green: GreenAxis) -> PathBuf {
    let map = NormalMap::from_grid(Grid::from_fn(256, 128, |x, _| {
        if x < 128 { Vec3::new(0.5, 0.0, 1.0).normalize() } else { Vec3::new(0.0, 0.5, 1.0).normalize() }
    }));
    let path = dir.join(format!("tilted-{green:?}.png"));
    write_normal_map(&path, &map, NormalEncoding { green }, 16).unwrap();
    path
}

#[test]
fn green_down_maps_are_read_green_up() {
    let tmp = tempfile::tempdir().unwrap();
    for green in [GreenAxis::Up, GreenAxis::Down] {
        let file = tilted(tmp.path(), green);
        let name = if green == GreenAxis::Up { "up" } else { "down" };
        let scene = scene(tmp.path(), &format!("[normal_map]\npath = \"{}\"\ngreen = \"{name}\"", file.display()));
        let loaded = load(&scene, 64, 64, 8192).unwrap();
        let t = loaded.inputs.normal_map.texels[200];
        assert!((t[1] - 0.5 / 1.25f32.sqrt()).abs() < 1e-4, "{green:?}: {t:?}");
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    }
}

#[test]
fn maps_above_the_device_limit_are_halved_with_a_warning() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tilted(tmp.path(), GreenAxis::Up);
    let scene = scene(tmp.path(), &format!("[normal_map]\npath = \"{}\"", file.display()));
    let loaded = load(&scene, 64, 64, 100).unwrap();
    let map = &loaded.inputs.normal_map;
    assert_eq!((map.width, map.height), (64, 32));
    assert!(
        loaded.warnings.iter().any(|w| w.contains("256x128") && w.contains("100") && w.contains("64x32")),
        "{:?}",
        loaded.warnings
    );
    // Box-filtered halves keep each side's tilt (the halves do not mix except at the middle).
    assert!((map.texels[0][0] - 0.5 / 1.25f32.sqrt()).abs() < 1e-4);
}

#[test]
fn eight_bit_albedo_is_srgb_and_sixteen_bit_is_linear() {
    let tmp = tempfile::tempdir().unwrap();
    let a8 = tmp.path().join("a8.png");
    write_png(&a8, 2, 1, PngLayout::Rgb8, &[128, 128, 128, 255, 0, 0]).unwrap();
    let a16 = tmp.path().join("a16.png");
    write_png(&a16, 1, 1, PngLayout::Gray16, &[32768]).unwrap();
    let s8 = scene(tmp.path(), &format!("albedo = \"{}\"", a8.display()));
    let t = load(&s8, 8, 8, 8192).unwrap().inputs.albedo;
    // sRGB 128/255 is 0.2158605 linear.
    assert!((t.texels[0][0] - 0.2158605).abs() < 1e-5, "{:?}", t.texels[0]);
    assert_eq!(t.texels[1], [1.0, 0.0, 0.0, 1.0]);
    let s16 = scene(tmp.path(), &format!("albedo = \"{}\"", a16.display()));
    let loaded = load(&s16, 8, 8, 8192).unwrap();
    assert!((loaded.inputs.albedo.texels[0][2] - 32768.0 / 65535.0).abs() < 1e-6);
    // A map is the whole rho_d: the BRDF's own diffuse is then 1.
    assert_eq!(loaded.inputs.brdf.diffuse, Vec3::ONE);
    // Without an albedo, rho_d is the BRDF's.
    let plain = scene(tmp.path(), "");
    let loaded = load(&plain, 8, 8, 8192).unwrap();
    assert_eq!(loaded.inputs.brdf.diffuse, plain.brdf.diffuse);
    assert_eq!(loaded.inputs.albedo.texels, vec![[1.0; 4]]);
}

#[test]
fn a_turntable_keeps_the_distance_and_starts_at_the_camera() {
    let camera =
        Camera { position: Vec3::new(3.0, 1.0, 4.0), target: Vec3::new(0.0, 1.0, 0.0), up: Vec3::Y, fov_deg: 30.0 };
    assert!((orbit(&camera, 0, 8).position - camera.position).length() < 1e-6);
    for f in 0..8 {
        let c = orbit(&camera, f, 8);
        assert!(((c.position - c.target).length() - 5.0).abs() < 1e-4);
        assert!((c.position.y - 1.0).abs() < 1e-5, "turns about the up axis");
    }
    let half = orbit(&camera, 4, 8);
    assert!((half.position - Vec3::new(-3.0, 1.0, -4.0)).length() < 1e-4, "{:?}", half.position);
}

#[test]
fn more_lights_than_the_pass_shades_are_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let light = "[[light]]\nkind = \"directional\"\ndirection = [0.0, 1.0, 1.0]\n";
    let mesh = quad(tmp.path());
    let text = format!(
        "mesh = \"{}\"\nmm_per_unit = 1.0\n{}[[camera]]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n",
        mesh.display(),
        light.repeat(5)
    );
    let path = tmp.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let e = Scene::load(&path).map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err();
    assert!(
        e.contains("scene.toml") && e.contains("light") && e.contains("5 lights") && e.contains("at most 4"),
        "{e}"
    );
}

/// The pass names and resource names of a scene's plan.
fn graph_of(body: &str) -> (Vec<String>, Vec<String>, Vec<String>) {
    let tmp = tempfile::tempdir().unwrap();
    let scene = scene(tmp.path(), body);
    let loaded = load(&scene, 8, 8, 8192).unwrap();
    let graph = PassGraph::build(&scene);
    let p = plan(&scene, &loaded, &graph, 8, 8, OutputFormat::Srgb8);
    assert_eq!(p.passes.iter().map(|p| p.name.clone()).collect::<Vec<_>>(), graph.pass_names());
    let passes = p.passes.iter().map(|p| p.name.clone()).collect();
    let resources = p.resources.iter().map(|r| r.name.clone()).collect();
    (passes, resources, p.notes)
}

const SHADOW_LIGHT: &str = "[[light]]\nkind = \"point\"\nposition = [0.0, 0.0, 3.0]\nshadows = true\n";

#[test]
fn a_scene_without_effects_is_the_base_pass_alone() {
    let (passes, resources, notes) = graph_of("");
    assert_eq!(passes, ["base"]);
    for absent in ["shadow map", "diffuse LUT", "shadow LUT", "zonal table", "per-vertex curvature", "light map A"] {
        assert!(!resources.iter().any(|r| r == absent), "{absent} in {resources:?}");
    }
    assert!(notes.is_empty(), "{notes:?}");
}

#[test]
fn shadows_need_a_shadow_casting_light_and_the_effect() {
    // The effect without a caster: no shadow map, and a note saying why.
    let (passes, resources, notes) = graph_of("effects = [\"shadows\"]");
    assert_eq!(passes, ["base"]);
    assert!(!resources.iter().any(|r| r == "shadow map"));
    assert!(notes.iter().any(|n| n.contains("shadows") && n.contains("no light")), "{notes:?}");
    // A caster without the effect: drawn unshadowed, with a note naming the light.
    let (passes, _, notes) = graph_of(SHADOW_LIGHT);
    assert_eq!(passes, ["base"]);
    assert!(notes.iter().any(|n| n.contains("light[0]") && n.contains("unshadowed")), "{notes:?}");
    // Both: one shadow map before the base pass, no LUT.
    let (passes, resources, _) = graph_of(&format!("effects = [\"shadows\"]\n{SHADOW_LIGHT}"));
    assert_eq!(passes, ["shadow map", "base"]);
    assert!(
        resources.iter().any(|r| r == "shadow map") && !resources.iter().any(|r| r.contains("LUT")),
        "{resources:?}"
    );
}

#[test]
fn the_lut_is_built_only_when_a_pass_reads_it() {
    let (passes, resources, _) = graph_of("effects = [\"preintegrated\"]");
    assert_eq!(passes, ["base"]);
    assert!(resources.iter().any(|r| r == "diffuse LUT") && resources.iter().any(|r| r == "per-vertex curvature"));
    assert!(!resources.iter().any(|r| r == "shadow map" || r == "shadow LUT"), "{resources:?}");
    // The derivative form reads no per-vertex curvature.
    let (_, resources, _) = graph_of("effects = [\"preintegrated\"]\n[preintegrated]\ncurvature = \"derivative\"");
    assert!(!resources.iter().any(|r| r == "per-vertex curvature"), "{resources:?}");
    // The closed forms need no table at all.
    let (_, resources, _) = graph_of("effects = [\"preintegrated-analytic\"]");
    assert!(!resources.iter().any(|r| r.contains("LUT")), "{resources:?}");
    // Shadow scattering adds its LUT to the shadow map.
    let body = format!("effects = [\"preintegrated\", \"shadows\", \"shadow-scattering\"]\n{SHADOW_LIGHT}");
    let (passes, resources, _) = graph_of(&body);
    assert_eq!(passes, ["shadow map", "base"]);
    for name in ["diffuse LUT", "shadow LUT", "shadow map"] {
        assert!(resources.iter().any(|r| r == name), "{name} missing: {resources:?}");
    }
}

#[test]
fn ambient_reads_the_zonal_table_only_over_a_preintegrated_diffuse() {
    let env = "\n[environment]\nsky = [0.3, 0.3, 0.4]\nground = [0.1, 0.1, 0.1]";
    let (passes, resources, _) = graph_of(&format!("effects = [\"sh-ambient\"]{env}"));
    assert_eq!(passes, ["base"]);
    assert!(!resources.iter().any(|r| r == "zonal table"), "{resources:?}");
    let (_, resources, _) = graph_of(&format!("effects = [\"sh-ambient\", \"preintegrated\"]{env}"));
    assert!(resources.iter().any(|r| r == "zonal table"), "{resources:?}");
}

#[test]
fn texture_space_diffusion_runs_its_pre_pass_light_map_and_blurs() {
    let (passes, resources, _) = graph_of("effects = [\"tsd\"]\n[tsd]\nkernel = \"single\"\npasses = 3\nsize = 256");
    assert_eq!(passes, ["tsd back-face pre-pass", "tsd light map", "tsd blur 1", "tsd blur 2", "tsd blur 3", "base"]);
    for name in ["tsd depth", "light map A", "light map B", "per-vertex curvature"] {
        assert!(resources.iter().any(|r| r == name), "{name} missing: {resources:?}");
    }
    assert!(!resources.iter().any(|r| r == "shadow map" || r.contains("LUT")), "{resources:?}");
    let (passes, _, _) = graph_of(&format!("effects = [\"tsd\", \"shadows\"]\n[tsd]\npasses = 0\n{SHADOW_LIGHT}"));
    assert_eq!(passes, ["shadow map", "tsd back-face pre-pass", "tsd light map", "base"]);
    // The profile's Gaussians: a dilating pass, then `passes` per Gaussian increment (four), and
    // a third light map that keeps the dilated irradiance.
    let (passes, resources, _) = graph_of("effects = [\"tsd\"]\n[tsd]\nkernel = \"gaussians\"\npasses = 2");
    assert_eq!(passes.iter().filter(|p| p.starts_with("tsd blur")).count(), 9, "{passes:?}");
    assert!(resources.iter().any(|r| r == "light map C"), "{resources:?}");
}

#[test]
fn contradicting_or_incomplete_effects_are_refused_by_name() {
    let tmp = tempfile::tempdir().unwrap();
    let refused = |body: &str| {
        let mesh = quad(tmp.path());
        let text = format!(
            "mesh = \"{}\"\nmm_per_unit = 1.0\n{body}\n[[light]]\nkind = \"directional\"\ndirection = [0.0, 0.0, 1.0]\n\
             [[camera]]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\n",
            mesh.display()
        );
        let path = tmp.path().join("bad.toml");
        std::fs::write(&path, &text).unwrap();
        Scene::load(&path).map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err()
    };
    let e = refused("effects = [\"preintegrated\", \"tsd\"]");
    assert!(e.contains("bad.toml") && e.contains("preintegrated") && e.contains("tsd"), "{e}");
    let e = refused("effects = [\"shadow-scattering\"]");
    assert!(e.contains("shadow-scattering") && e.contains("shadows"), "{e}");
    let e = refused("effects = [\"sh-ambient\"]");
    assert!(e.contains("environment"), "{e}");
    let e = refused("[shadow]\nfilter = 4");
    assert!(e.contains("shadow.filter") && e.contains("odd"), "{e}");
    let e = refused("[preintegrated]\nnormal_blur = [0.5, 2.0, 0.0]");
    assert!(e.contains("preintegrated.normal_blur[1]"), "{e}");
    let e = refused("[environment]\nconstant = [0.1, 0.1, 0.1]\nsky = [0.2, 0.2, 0.2]");
    assert!(e.contains("environment") && e.contains("exactly one"), "{e}");
    let e = refused("[tsd]\nsize = 8");
    assert!(e.contains("tsd.size"), "{e}");
    let e = refused("[tsd]\nblur = 3");
    assert!(e.contains("blur"), "{e}");
    let e = refused("[tsd]\nkernel = \"gaussians\"\nkernel_map = \"k.png\"");
    assert!(e.contains("tsd.kernel") && e.contains("single"), "{e}");
}

#[test]
fn translucent_casters_add_their_pass_only_to_a_shadow_map() {
    let lens = "[[translucent]]\nmesh = \"quad.obj\"\nopacity = [0.5, 0.2, 0.1]\n";
    let (passes, resources, _) = graph_of(&format!("effects = [\"shadows\"]\n{lens}{SHADOW_LIGHT}"));
    assert_eq!(passes, ["shadow map", "translucent shadows", "base"]);
    assert!(resources.iter().any(|r| r == "shadow opacity"), "{resources:?}");
    let (passes, _, notes) = graph_of(lens);
    assert_eq!(passes, ["base"]);
    assert!(notes.iter().any(|n| n.contains("translucent")), "{notes:?}");
}

/// Issue 15, D11 and D10: a mesh, normal map or albedo that cannot be read is reported as the
/// scene file, its field, then the file and the cause, each once.
#[test]
fn d11_render_errors_name_the_scene_file_and_field() {
    let tmp = tempfile::tempdir().unwrap();
    let scene_file = tmp.path().join("scene.toml").display().to_string();
    // A file that exists but is no image (so the existence check passes and the decoder refuses).
    let notes = tmp.path().join("notes.png");
    std::fs::write(&notes, "not an image\n").unwrap();
    for field in ["normal_map.path", "albedo"] {
        let body = match field {
            "albedo" => format!("albedo = \"{}\"", notes.display()),
            _ => format!("[normal_map]\npath = \"{}\"", notes.display()),
        };
        let e =
            load(&scene(tmp.path(), &body), 64, 64, 8192).map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err();
        assert!(e.starts_with(&format!("{scene_file}: {field}: {}: ", notes.display())), "{e}");
        assert_eq!(e.matches("notes.png").count(), 1, "{e}");
    }
    // The mesh is removed after the scene was read: the scene, `mesh`, the mesh file, the OS.
    let scene = scene(tmp.path(), "");
    std::fs::remove_file(tmp.path().join("quad.obj")).unwrap();
    let e = load(&scene, 64, 64, 8192).map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err();
    let want = format!("{scene_file}: mesh: {}: ", tmp.path().join("quad.obj").display());
    assert!(e.starts_with(&want), "{e}");
    assert_eq!(e.matches("(os error 2)").count(), 1, "{e}");
}
