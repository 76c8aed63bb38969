//! The exporter's numbers: tangent handedness on a quad with plain and mirrored UVs, read back
//! from the GLB; accessor counts; both containers; URIs.

use std::path::Path;

use glam::{Vec3, Vec4};

use super::*;

/// A unit quad in the xy plane facing +z as OBJ text. `mirrored`: u runs along -x instead of +x.
/// OBJ's `vt` v is bottom-origin, so image-up is +y either way.
fn quad_obj(mirrored: bool) -> String {
    let u = |x: f32| if mirrored { 1.0 - x } else { x };
    format!(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt {} 0\nvt {} 0\nvt {} 1\nvt {} 1\nvn 0 0 1\n\
         f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n",
        u(0.0),
        u(1.0),
        u(1.0),
        u(0.0)
    )
}

/// A scene in `dir` around `obj`, with a 4x2 albedo and normal map when `maps`.
fn scene(dir: &Path, obj: &str, maps: bool) -> Scene {
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    let mut text = "mesh = \"quad.obj\"\nmm_per_unit = 2.0\n".to_owned();
    if maps {
        let normals = skinkit_maps::NormalMap::from_grid(skinkit_maps::Grid::from_fn(4, 2, |x, _| {
            Vec3::new(x as f32 * 0.1, 0.3, 1.0).normalize()
        }));
        skinkit_maps::io::write_normal_map(&dir.join("n.png"), &normals, Default::default(), 16).unwrap();
        let albedo = skinkit_maps::Grid::from_fn(4, 2, |x, y| Vec3::new(x as f32 / 4.0, y as f32 / 2.0, 0.5));
        skinkit_maps::io::write_color_map(&dir.join("a.png"), &albedo, 16).unwrap();
        text.push_str("albedo = \"a.png\"\n[normal_map]\npath = \"n.png\"\nframes = \"mikktspace\"\n");
    }
    text.push_str("[[light]]\nkind = \"directional\"\ndirection = [0, 0, 1]\n[[camera]]\nposition = [0, 0, 5]\ntarget = [0, 0, 0]\n");
    Scene::parse(&text, &dir.join("scene.toml")).unwrap()
}

fn options(container: Container, bits: NormalBits) -> ExportOptions {
    ExportOptions { container, stem: "quad".into(), normal_bits: bits }
}

/// Tangents of the GLB's one primitive, read back through the `gltf` crate.
fn glb_tangents(bytes: &[u8]) -> Vec<Vec4> {
    let gltf = gltf::Gltf::from_slice(bytes).unwrap();
    let blob = gltf.blob.clone().unwrap();
    let mesh = gltf.document.meshes().next().unwrap();
    let primitive = mesh.primitives().next().unwrap();
    let reader = primitive.reader(|_| Some(blob.as_slice()));
    reader.read_tangents().unwrap().map(Vec4::from).collect()
}

#[test]
fn tangent_handedness_follows_the_uv_layout() {
    for (mirrored, w) in [(false, 1.0), (true, -1.0)] {
        let dir = tempfile::tempdir().unwrap();
        let scene = scene(dir.path(), &quad_obj(mirrored), false);
        let exported =
            export(&scene, &options(Container::Glb, NormalBits::Eight), &skinkit_maps::progress::NoProgress).unwrap();
        let tangents = glb_tangents(&exported.files[0].bytes);
        assert_eq!(tangents.len(), 4);
        for t in tangents {
            assert_eq!(t.w, w, "mirrored {mirrored}: {t}");
            assert!((t.truncate().length() - 1.0).abs() < 1e-6);
            // T along +u; B = cross(N, T) * w points up the image (+y) either way.
            let along_u = if mirrored { -Vec3::X } else { Vec3::X };
            assert!(t.truncate().dot(along_u) > 0.999, "{t}");
            let b = Vec3::Z.cross(t.truncate()) * t.w;
            assert!(b.dot(Vec3::Y) > 0.999, "mirrored {mirrored}: bitangent {b}");
        }
    }
}

#[test]
fn a_glb_holds_the_mesh_in_metres_and_both_textures() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), &quad_obj(false), true);
    let exported =
        export(&scene, &options(Container::Glb, NormalBits::Sixteen), &skinkit_maps::progress::NoProgress).unwrap();
    assert_eq!(exported.files.len(), 1);
    assert_eq!(exported.files[0].name, "quad.glb");
    let s = &exported.summary;
    assert_eq!((s.vertices, s.triangles, s.metres_per_unit), (4, 2, 0.002));
    assert_eq!(s.normal, Some(TextureInfo { width: 4, height: 2, bits: 16 }));
    assert_eq!(s.albedo.map(|a| a.bits), Some(8));
    let gltf = gltf::Gltf::from_slice(&exported.files[0].bytes).unwrap();
    let material = gltf.document.materials().next().unwrap();
    assert!(material.pbr_metallic_roughness().base_color_texture().is_some());
    assert!(material.normal_texture().is_some());
    assert_eq!(material.pbr_metallic_roughness().metallic_factor(), 0.0);
    let position = gltf.document.accessors().next().unwrap();
    // min/max hold the f32 values exactly (the validator compares them with the data).
    let max = position.max().unwrap();
    let max: Vec<f32> = max.as_array().unwrap().iter().map(|v| v.as_f64().unwrap() as f32).collect();
    assert_eq!(max, [0.002f32, 0.002, 0.0]);
}

#[test]
fn a_gltf_names_its_side_files_by_relative_uris() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), &quad_obj(false), true);
    let mut opts = options(Container::Gltf, NormalBits::Eight);
    opts.stem = "my head".into();
    let exported = export(&scene, &opts, &skinkit_maps::progress::NoProgress).unwrap();
    let names: Vec<&str> = exported.files.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["my head.gltf", "my head.bin", "my head-albedo.png", "my head-normal.png"]);
    let json = String::from_utf8(exported.files[0].bytes.clone()).unwrap();
    assert!(json.contains("\"my%20head.bin\"") && json.contains("\"my%20head-normal.png\""), "{json}");
}

#[test]
fn a_missing_map_names_the_scene_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), &quad_obj(false), true);
    std::fs::remove_file(dir.path().join("n.png")).unwrap();
    let error = export(&scene, &options(Container::Glb, NormalBits::Eight), &skinkit_maps::progress::NoProgress)
        .unwrap_err()
        .to_string();
    assert!(error.contains("scene.toml: normal_map.path:") && error.contains("n.png does not exist"), "{error}");
}

#[test]
fn uris_escape_all_but_unreserved_bytes() {
    assert_eq!(uri_encode("a-b_c.d~e"), "a-b_c.d~e");
    assert_eq!(uri_encode("head 2%.bin"), "head%202%25.bin");
    assert_eq!(uri_encode("tête"), "t%C3%AAte");
}

/// Writes an export's files into `dir` (as the CLI does, without the atomic set).
fn write_files(dir: &Path, exported: &Exported) -> std::path::PathBuf {
    for file in &exported.files {
        std::fs::write(dir.join(&file.name), &file.bytes).unwrap();
    }
    dir.join(&exported.files[0].name)
}

#[test]
fn a_scene_reads_its_maps_back_from_the_exported_material() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), &quad_obj(false), true);
    let limits = Limits::default();
    let normals = skinkit_maps::io::read_normal_map(&dir.path().join("n.png"), Default::default(), &limits).unwrap();
    let albedo = crate::load::read_albedo(&dir.path().join("a.png"), &limits).unwrap();
    for container in [Container::Glb, Container::Gltf] {
        let exported =
            export(&scene, &options(container, NormalBits::Eight), &skinkit_maps::progress::NoProgress).unwrap();
        let out = dir.path().join(format!("{container:?}"));
        std::fs::create_dir(&out).unwrap();
        let file = write_files(&out, &exported);
        let back = crate::gltf_maps::normal_map(&file, &limits).unwrap();
        assert_eq!(back.size(), normals.size());
        for (a, b) in back.as_slice().iter().zip(normals.as_slice()) {
            // Half an 8-bit step per component, then renormalised.
            assert!(a.angle_between(*b) < 0.006, "{container:?}: {a} against {b}");
        }
        let back = crate::gltf_maps::albedo(&file, &limits).unwrap();
        assert_eq!((back.width, back.height), (albedo.width, albedo.height));
        for (a, b) in back.texels.iter().zip(&albedo.texels) {
            (0..3).for_each(|c| assert!((a[c] - b[c]).abs() < 0.004, "{container:?}: {a:?} against {b:?}"));
        }
    }
}

#[test]
fn a_material_without_the_texture_is_named_in_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path(), &quad_obj(false), false);
    let exported =
        export(&scene, &options(Container::Glb, NormalBits::Eight), &skinkit_maps::progress::NoProgress).unwrap();
    let file = write_files(dir.path(), &exported);
    let error = crate::gltf_maps::normal_map(&file, &Limits::default()).unwrap_err().to_string();
    assert!(
        error.contains("quad.glb: normalTexture") && error.contains("material 0 (`skin`) has no normalTexture"),
        "{error}"
    );
    // A scene saying its glTF normal texture is green-down contradicts glTF: refused by name.
    let text = "mesh = \"quad.glb\"\nmm_per_unit = 1000.0\n[normal_map]\npath = \"quad.glb\"\ngreen = \"down\"\n\
         [[light]]\nkind = \"directional\"\ndirection = [0, 0, 1]\n[[camera]]\nposition = [0, 0, 5]\ntarget = [0, 0, 0]\n";
    let scene = Scene::parse(text, &dir.path().join("s.toml")).unwrap();
    let error = crate::load::load(&scene, 8, 8, 4096).unwrap_err().to_string();
    assert!(error.contains("s.toml: normal_map.green:") && error.contains("green-up"), "{error}");
}

#[test]
fn zero_area_uv_triangles_give_finite_unit_tangents() {
    let dir = tempfile::tempdir().unwrap();
    // Every vertex at one UV: no triangle has UV area.
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0.5 0.5\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf 1/1/1 3/1/1 4/1/1\n";
    let scene = scene(dir.path(), obj, false);
    let exported =
        export(&scene, &options(Container::Glb, NormalBits::Eight), &skinkit_maps::progress::NoProgress).unwrap();
    for t in glb_tangents(&exported.files[0].bytes) {
        assert!(t.is_finite() && (t.truncate().length() - 1.0).abs() < 1e-5 && t.w.abs() == 1.0, "{t}");
        assert!(t.truncate().dot(Vec3::Z).abs() < 1e-5, "the tangent is orthogonal to the normal: {t}");
    }
}
