//! Mesh loading: OBJ and glTF/GLB, the UV flip, computed normals and the hard cases.

use std::path::Path;

use glam::{Vec2, Vec3};
use skinkit_render::mesh::{Mesh, MeshError};

fn obj(text: &str) -> Result<skinkit_render::mesh::LoadedMesh, MeshError> {
    Mesh::parse_obj(&mut text.as_bytes(), "test.obj")
}

const QUAD_OBJ: &str = "\
v 0 0 0
v 2 0 0
v 2 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 0.25
vt 0 0.25
vn 0 0 1
f 1/1/1 2/2/1 3/3/1 4/4/1
";

#[test]
fn obj_quad_is_triangulated_and_v_flipped() {
    let loaded = obj(QUAD_OBJ).unwrap();
    let m = &loaded.mesh;
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    assert_eq!(m.triangle_count(), 2);
    assert_eq!(m.positions.len(), 4);
    for (p, uv) in m.positions.iter().zip(&m.uvs) {
        // File: vt = (x / 2, y / 4) with v up; skinkit: v = 1 - y / 4 (top origin).
        assert!((uv.x - p.x / 2.0).abs() < 1e-6 && (uv.y - (1.0 - p.y / 4.0)).abs() < 1e-6, "{p} {uv}");
    }
    assert!(m.normals.iter().all(|n| *n == Vec3::Z));
    assert_eq!(m.bounds(), (Vec3::ZERO, Vec3::new(2.0, 1.0, 0.0)));
    m.validate().unwrap();
}

#[test]
fn obj_without_uvs_is_an_error_naming_the_file() {
    let err = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap_err();
    assert!(matches!(err, MeshError::NoUvs { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains("test.obj") && msg.contains("texture coordinates"), "{msg}");
}

#[test]
fn obj_without_normals_gets_area_weighted_normals_and_a_warning() {
    // Two triangles sharing the edge 1-2: one in the z = 0 plane facing +z with area 2, one in
    // the x = 0 plane facing +x with area 1. Area weighting gives the shared vertices
    // normalize(2 z + 1 x) (hand computed), the others their face normal.
    let text = "\
v 0 0 0
v 0 2 0
v -2 0 0
v 0 0 1
v 0 1 0
vt 0 0
vt 0 1
vt 1 0
vt 1 1
vt 0.5 0.5
f 1/1 2/2 3/3
f 1/1 2/2 4/4
f 2/2 5/5 2/2
";
    let loaded = obj(text).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("test.obj") && loaded.warnings[0].contains("normals"));
    let m = &loaded.mesh;
    // The third triangle has zero area: kept, but adds nothing.
    assert_eq!(m.triangle_count(), 3);
    let expected_shared = Vec3::new(1.0, 0.0, 2.0).normalize();
    let at = |p: Vec3| m.positions.iter().position(|&q| q == p).unwrap();
    for p in [Vec3::ZERO, Vec3::new(0.0, 2.0, 0.0)] {
        let n = m.normals[at(p)];
        assert!(n.angle_between(expected_shared) < 1e-5, "{p}: {n}");
    }
    assert!(m.normals[at(Vec3::new(-2.0, 0.0, 0.0))].angle_between(Vec3::Z) < 1e-6);
    assert!(m.normals[at(Vec3::new(0.0, 0.0, 1.0))].angle_between(Vec3::X) < 1e-6);
    // A vertex touched only by the zero-area triangle: finite, unit.
    let lonely = m.normals[at(Vec3::new(0.0, 1.0, 0.0))];
    assert!(lonely.is_finite() && (lonely.length() - 1.0).abs() < 1e-6);
}

#[test]
fn nan_position_is_an_error_naming_the_line() {
    let err = obj("v 0 0 0\nv nan 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, MeshError::ObjLine { line: 2, .. }), "{msg}");
    assert!(msg.starts_with("test.obj: line 2: `v` has a non-finite value"), "{msg}");
}

/// Issue 15, D12: OBJ errors give the line of the file, not a vertex number after re-indexing
/// (the probe's NaN on the 50th `v` line came out as "vertex 42"), and out-of-range face indices
/// name their line too.
#[test]
fn d12_obj_errors_name_the_source_line() {
    // A grid of 10 x 10 vertices in file order, faces after them, NaN on the 50th `v` line.
    let mut text = String::from("# a comment\nvt 0 0\nvt 1 0\nvt 0 1\n");
    for i in 0..100 {
        let x = if i == 49 { "nan".to_owned() } else { (i % 10).to_string() };
        text += &format!("v {x} {} 0\n", i / 10);
    }
    text += "f 1/1 2/2 11/3\nf 12/1 13/2 22/3\n";
    let err = obj(&text).unwrap_err();
    // Four lines before the first `v`: the 50th `v` line is line 54.
    assert!(err.to_string().starts_with("test.obj: line 54: `v`"), "{err}");
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 2/1 99999/1\n";
    let err = obj(text).unwrap_err().to_string();
    assert!(err.starts_with("test.obj: line 6: face vertex `99999/1`: `v` index 99999 is out of range"), "{err}");
    let err = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 -99999/1\n").unwrap_err().to_string();
    assert!(err.starts_with("test.obj: line 5: ") && err.contains("-99999"), "{err}");
    let err = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/99999\n").unwrap_err().to_string();
    assert!(err.starts_with("test.obj: line 5: ") && err.contains("`vt` index 99999"), "{err}");
}

#[test]
fn out_of_range_indices_are_errors() {
    let err = obj("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 9/1\n").unwrap_err();
    assert!(err.to_string().contains("test.obj"), "{err}");
    let mesh = Mesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: vec![Vec3::Z; 3],
        uvs: vec![Vec2::ZERO; 3],
        indices: vec![0, 1, 3],
    };
    let err = mesh.validate().unwrap_err();
    assert!(matches!(err, MeshError::IndexOutOfRange { triangle: 0, index: 3, count: 3, .. }), "{err}");
    let short = Mesh { indices: vec![0, 1], ..mesh.clone() };
    assert!(matches!(short.validate(), Err(MeshError::Layout { field: "indices", .. })));
    let bad_uv = Mesh { indices: vec![0, 1, 2], uvs: vec![Vec2::ZERO, Vec2::NAN, Vec2::ZERO], ..mesh };
    assert!(matches!(bad_uv.validate(), Err(MeshError::NonFinite { index: 1, field: "uv", .. })));
}

#[test]
fn load_dispatches_on_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("Quad.OBJ");
    std::fs::write(&path, QUAD_OBJ).unwrap();
    assert_eq!(Mesh::load(&path).unwrap().mesh, obj(QUAD_OBJ).unwrap().mesh);
    let ply = dir.path().join("quad.ply");
    std::fs::write(&ply, "ply").unwrap();
    assert!(matches!(Mesh::load(&ply), Err(MeshError::UnsupportedFormat { .. })));
    let missing = Mesh::load(&dir.path().join("missing.obj")).unwrap_err();
    assert!(missing.to_string().contains("missing.obj"));
}

/// A little-endian buffer: 3 positions, 3 uvs, 3 u16 indices (+2 bytes padding).
fn triangle_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for t in [[0f32, 1.0], [1.0, 1.0], [0.0, 0.0]] {
        t.iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for i in [0u16, 1, 2] {
        b.extend(i.to_le_bytes());
    }
    b.extend([0, 0]);
    b
}

/// glTF JSON for the triangle, drawn by two nodes: one translated and scaled, one mirrored in x.
fn triangle_json(buffer_uri: Option<&str>, len: usize) -> String {
    let uri = buffer_uri.map(|u| format!(r#""uri": "{u}", "#)).unwrap_or_default();
    format!(
        r#"{{
  "asset": {{ "version": "2.0" }},
  "scene": 0,
  "scenes": [{{ "nodes": [0, 1] }}],
  "nodes": [
    {{ "mesh": 0, "translation": [10, 0, 0], "scale": [2, 2, 2] }},
    {{ "children": [2], "scale": [-1, 1, 1] }},
    {{ "mesh": 0 }}
  ],
  "meshes": [{{ "primitives": [{{ "attributes": {{ "POSITION": 0, "TEXCOORD_0": 1 }}, "indices": 2 }}] }}],
  "buffers": [{{ {uri}"byteLength": {len} }}],
  "bufferViews": [
    {{ "buffer": 0, "byteOffset": 0, "byteLength": 36 }},
    {{ "buffer": 0, "byteOffset": 36, "byteLength": 24 }},
    {{ "buffer": 0, "byteOffset": 60, "byteLength": 6 }}
  ],
  "accessors": [
    {{ "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] }},
    {{ "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2" }},
    {{ "bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR" }}
  ]
}}"#
    )
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn check_transformed_triangles(loaded: &skinkit_render::mesh::LoadedMesh) {
    let m = &loaded.mesh;
    assert_eq!(m.triangle_count(), 2);
    // Node 0: scale 2 then translate by 10 in x.
    let first: Vec<Vec3> = m.triangle(0).iter().map(|&i| m.positions[i]).collect();
    assert_eq!(first, vec![Vec3::new(10.0, 0.0, 0.0), Vec3::new(12.0, 0.0, 0.0), Vec3::new(10.0, 2.0, 0.0)]);
    // Node 2 under the mirroring node 1: x negated, winding restored so the face still looks
    // along +z (computed normals follow the winding).
    let second: Vec<Vec3> = m.triangle(1).iter().map(|&i| m.positions[i]).collect();
    assert!(second.contains(&Vec3::new(-1.0, 0.0, 0.0)) && second.contains(&Vec3::new(0.0, 1.0, 0.0)));
    let face = (second[1] - second[0]).cross(second[2] - second[0]);
    assert!(face.z > 0.0, "{face}");
    assert!(m.normals.iter().all(|n| n.angle_between(Vec3::Z) < 1e-6), "{:?}", m.normals);
    // glTF UVs are top-origin already: not flipped.
    assert_eq!(&m.uvs[..3], &[Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 0.0)]);
    assert_eq!(loaded.warnings.len(), 2, "no normals in either primitive: {:?}", loaded.warnings);
}

#[test]
fn glb_applies_node_transforms() {
    let bin = triangle_buffer();
    let bytes = glb(&triangle_json(None, bin.len()), &bin);
    let loaded = Mesh::parse_gltf(&bytes, None, "t.glb").unwrap();
    check_transformed_triangles(&loaded);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.glb");
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(Mesh::load(&path).unwrap().mesh, loaded.mesh);
}

#[test]
fn gltf_with_external_buffer_resolves_against_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let bin = triangle_buffer();
    std::fs::write(dir.path().join("tri.bin"), &bin).unwrap();
    let path = dir.path().join("tri.gltf");
    std::fs::write(&path, triangle_json(Some("tri.bin"), bin.len())).unwrap();
    check_transformed_triangles(&Mesh::load(&path).unwrap());
}

/// Issue 15, D12: an accessor that overruns its buffer view, and a view that lies past its
/// buffer, are named as such (they read as "no positions" and "4 indices is not a multiple of 3").
#[test]
fn d12_gltf_range_errors_name_the_accessor_or_view() {
    let bin = triangle_buffer();
    let json =
        triangle_json(None, bin.len()).replace(r#""count": 3, "type": "VEC3""#, r#""count": 1000000, "type": "VEC3""#);
    let err = Mesh::parse_gltf(&glb(&json, &bin), None, "x.glb").unwrap_err().to_string();
    assert!(err.starts_with("x.glb: not a readable glTF file: mesh 0 primitive 0: POSITION: accessor 0"), "{err}");
    assert!(err.contains("1000000 elements of 12 bytes") && err.contains("bufferView 0 holds 36"), "{err}");
    let json = triangle_json(None, bin.len())
        .replace(r#""byteOffset": 60, "byteLength": 6"#, r#""byteOffset": 4096, "byteLength": 8"#);
    let err = Mesh::parse_gltf(&glb(&json, &bin), None, "x.glb").unwrap_err().to_string();
    assert!(err.contains("indices: bufferView 2 (bytes 4096..4104) lies past the end of buffer 0 (68 bytes)"), "{err}");
}

#[test]
fn gltf_without_uvs_is_an_error() {
    let bin = triangle_buffer();
    let json = triangle_json(None, bin.len()).replace(r#", "TEXCOORD_0": 1"#, "");
    let err = Mesh::parse_gltf(&glb(&json, &bin), None, Path::new("x.glb").to_str().unwrap()).unwrap_err();
    assert!(matches!(err, MeshError::NoUvs { .. }), "{err}");
    assert!(err.to_string().contains("x.glb"));
}

#[test]
fn zero_normals_are_replaced_with_a_warning_and_objects_merge() {
    let text = "\
o first
v 0 0 0
v 1 0 0
v 0 1 0
vt 0 0
vt 1 0
vt 0 1
vn 0 0 0
f 1/1/1 2/2/1 3/3/1
o second
v 5 0 0
v 6 0 0
v 5 0 1
vt 0 0
vt 1 0
vt 0 1
vn 0 -3 0
f 4/4/2 5/5/2 6/6/2
";
    let loaded = obj(text).unwrap();
    let m = &loaded.mesh;
    assert_eq!((m.triangle_count(), m.positions.len()), (2, 6));
    assert_eq!(m.triangle(1).map(|i| m.positions[i].x), [5.0, 6.0, 5.0]);
    // The zero normal becomes the face normal (+z); the long one is renormalised.
    assert!(m.normals[..3].iter().all(|n| n.angle_between(Vec3::Z) < 1e-6), "{:?}", m.normals);
    assert!(m.normals[3..].iter().all(|&n| n == -Vec3::Y), "{:?}", m.normals);
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("3 zero or non-finite normals"), "{:?}", loaded.warnings);
}

/// Issue 15 (found by reading the importer for its fuzz target): a node that is its own child
/// recursed until the stack overflowed, and a node with two parents multiplied its meshes.
#[test]
fn gltf_nodes_reached_twice_are_refused() {
    let bin = triangle_buffer();
    let cycle = triangle_json(None, bin.len()).replace(r#""children": [2]"#, r#""children": [1]"#);
    let err = Mesh::parse_gltf(&glb(&cycle, &bin), None, "c.glb").unwrap_err().to_string();
    assert!(err.starts_with("c.glb: ") && err.contains("node 1 is reached twice"), "{err}");
    let two_parents = triangle_json(None, bin.len()).replace(r#""children": [2]"#, r#""children": [2, 0]"#);
    let err = Mesh::parse_gltf(&glb(&two_parents, &bin), None, "d.glb").unwrap_err().to_string();
    assert!(err.contains("node 0 is reached twice"), "{err}");
}

/// A POSITION naming an accessor the file does not have: the `gltf` crate's validation indexed it
/// unchecked and panicked (the `gltf` fuzz target's crash input, kept in tests/fuzz-regressions).
#[test]
fn gltf_attributes_naming_missing_accessors_are_refused() {
    let bin = triangle_buffer();
    let json = triangle_json(None, bin.len()).replace(r#""POSITION": 0"#, r#""POSITION": 7"#);
    let err = Mesh::parse_gltf(&glb(&json, &bin), None, "p.glb").unwrap_err().to_string();
    assert!(
        err.starts_with("p.glb: ") && err.contains("mesh 0 primitive 0: POSITION names accessor 7 but the file has 3"),
        "{err}"
    );
}

/// A GLB whose header gives a total length below its own 12 bytes (a subtraction the `gltf`
/// crate makes unchecked; the second `gltf` fuzz crash).
#[test]
fn glb_lengths_shorter_than_the_header_are_refused() {
    let bin = triangle_buffer();
    let mut bytes = glb(&triangle_json(None, bin.len()), &bin);
    bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
    let err = Mesh::parse_gltf(&bytes, None, "s.glb").unwrap_err().to_string();
    assert!(err.contains("s.glb: ") && err.contains("total length 1 is shorter than the 12-byte header"), "{err}");
}

/// Accessors whose element layout is not what their semantic reads (the third `gltf` fuzz crash:
/// positions of 16-bit integers, which the crate's reader walked as f32 triples).
#[test]
fn gltf_accessor_layouts_must_match_their_semantics() {
    let bin = triangle_buffer();
    let base = triangle_json(None, bin.len());
    let position = base.replacen(r#""componentType": 5126"#, r#""componentType": 5123"#, 1);
    assert_ne!(position, base, "the first accessor is the positions' f32");
    let err = Mesh::parse_gltf(&glb(&position, &bin), None, "l.glb").unwrap_err().to_string();
    assert!(
        err.contains("l.glb: ") && err.contains("POSITION: accessor 0 holds Vec3 of U16, where Vec3 of F32 is read"),
        "{err}"
    );
}

/// A hierarchy deeper than the importer follows is refused, not recursed into.
#[test]
fn gltf_node_chains_deeper_than_the_limit_are_refused() {
    let bin = triangle_buffer();
    let base = triangle_json(None, bin.len());
    // The same mesh and buffers under a scene whose one root heads a chain of 300 nodes.
    let rest = &base[base.find(r#"  "meshes""#).unwrap()..];
    let mut nodes: Vec<String> = (0..300).map(|i| format!(r#"{{ "children": [{}] }}"#, i + 1)).collect();
    nodes.push(r#"{ "mesh": 0 }"#.to_owned());
    let json = format!(
        r#"{{ "asset": {{ "version": "2.0" }}, "scene": 0, "scenes": [{{ "nodes": [0] }}], "nodes": [{}],
{rest}"#,
        nodes.join(", ")
    );
    let err = Mesh::parse_gltf(&glb(&json, &bin), None, "deep.glb").unwrap_err().to_string();
    assert!(err.contains("nested deeper than 256 levels"), "{err}");
}

/// Buffer URIs the `gltf` crate would panic on (bad percent-encoding) or read without end (a
/// device) are refused with the buffer named; the input gate names what the file is (issue 42, D9).
#[test]
fn gltf_buffer_uris_that_are_not_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (uri, want) in [
        ("%FF", "percent-encoding is not UTF-8"),
        ("/dev/zero", "/dev/zero: a device, not a regular file (a glTF buffer is read only"),
        ("file:///dev/zero", "/dev/zero: a device, not a regular file"),
        (".", "a folder, not a regular file"),
    ] {
        let json = triangle_json(Some(uri), 68);
        let err = Mesh::parse_gltf(json.as_bytes(), Some(dir.path()), "u.gltf").unwrap_err().to_string();
        assert!(err.contains(&format!("buffer 0 (uri `{uri}`)")) && err.contains(want), "{uri}: {err}");
    }
}

/// A 4 x 4 cell patch of the paraboloid z = (x^2 + y^2) / 8 without normals, quads as two
/// triangles. Cells right of x = 2 take their UVs from a second island (u + 0.5), so the column
/// x = 2 is a UV seam. `split`: every face corner gets its own `v` and `vt` line, as exporters of
/// face meshes write them; else vertices are shared.
fn paraboloid_obj(split: bool) -> String {
    use std::collections::HashMap;
    let (mut text, mut faces) = (String::new(), String::new());
    let (mut vs, mut vts) = (HashMap::new(), HashMap::new());
    // The OBJ index of `key`'s line: a new line every time when `split`, else the first one.
    let index = |map: &mut HashMap<(i32, i32, bool), usize>, key, line: String, text: &mut String| {
        let count = text.lines().filter(|l| l.split(' ').next() == line.split(' ').next()).count();
        match map.get(&key) {
            Some(&i) if !split => i,
            _ => {
                *text += &line;
                map.insert(key, count + 1);
                count + 1
            }
        }
    };
    for y in 0..4 {
        for x in 0..4 {
            let right = x >= 2;
            let quad = [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)];
            let corners: Vec<(usize, usize)> = quad
                .iter()
                .map(|&(a, b)| {
                    let z = f64::from(a * a + b * b) / 8.0;
                    let v = index(&mut vs, (a, b, false), format!("v {a} {b} {z}\n"), &mut text);
                    let u = f64::from(a) / 8.0 + if right { 0.5 } else { 0.0 };
                    let t = index(&mut vts, (a, b, right), format!("vt {u} {}\n", f64::from(b) / 4.0), &mut text);
                    (v, t)
                })
                .collect();
            for tri in [[0, 1, 2], [0, 2, 3]] {
                let f: Vec<String> = tri.iter().map(|&k| format!("{}/{}", corners[k].0, corners[k].1)).collect();
                faces += &format!("f {}\n", f.join(" "));
            }
        }
    }
    text + &faces
}

#[test]
fn a_mesh_split_per_face_corner_is_welded_before_its_normals() {
    let split = obj(&paraboloid_obj(true)).unwrap().mesh;
    let shared = obj(&paraboloid_obj(false)).unwrap().mesh;
    // 25 grid positions plus 5 more on the seam column (its second UV): the same in both.
    assert_eq!(shared.positions.len(), 30);
    assert_eq!(split.positions.len(), shared.positions.len());
    assert_eq!(split.triangle_count(), 32);
    for (i, p) in split.positions.iter().enumerate() {
        let j = (0..shared.positions.len())
            .find(|&j| shared.positions[j] == *p && shared.uvs[j] == split.uvs[i])
            .unwrap_or_else(|| panic!("{p} {} is not in the shared mesh", split.uvs[i]));
        let (a, b) = (split.normals[i], shared.normals[j]);
        assert!(a.angle_between(b) < 1e-5, "{p}: split {a} against shared {b}");
        // Smooth: the analytic normal of the paraboloid, not a face normal (within the
        // discretisation of 1-unit cells).
        let analytic = Vec3::new(-p.x / 4.0, -p.y / 4.0, 1.0).normalize();
        let interior = (1.0..=3.0).contains(&p.x) && (1.0..=3.0).contains(&p.y);
        assert!(!interior || a.angle_between(analytic) < 0.05, "{p}: {a} against {analytic}");
    }
    // The seam's two copies of a position share one normal.
    let seam: Vec<usize> = (0..split.positions.len()).filter(|&i| split.positions[i].x == 2.0).collect();
    assert_eq!(seam.len(), 10);
    for &i in &seam {
        let twin = seam.iter().find(|&&j| j != i && split.positions[j] == split.positions[i]).unwrap();
        assert_ne!(split.uvs[i], split.uvs[*twin]);
        assert!(split.normals[i].angle_between(split.normals[*twin]) < 1e-6);
    }
}
