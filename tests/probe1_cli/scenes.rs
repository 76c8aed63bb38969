//! Rows 5.x of the first probe: scenes whose mesh or maps are missing, lie or are not images,
//! and orbit frame counts out of range. Each is refused before anything is drawn.

use std::path::{Path, PathBuf};

use super::Scratch;
use super::inputs::{GltfLie, gltf, grey_png, png_header_only};
use crate::support::s;

/// `in/scenes/<name>.toml`: the sample head's lights and camera, a 32 x 24 output, `mesh`, and
/// `body` (maps) added.
pub fn scene(scratch: &Scratch, name: &str, mesh: &Path, body: &str) -> PathBuf {
    let path = scratch.folder("scenes").join(format!("{name}.toml"));
    let text = format!(
        "mesh = \"{}\"\nmm_per_unit = 1.0\n{body}\n[[light]]\nkind = \"directional\"\ndirection = [0.75, 0.35, 0.55]\n\
         [[camera]]\nposition = [170.0, 25.0, 380.0]\ntarget = [0.0, 5.0, 0.0]\n[output]\nsize = [32, 24]\n",
        s(mesh)
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The sample head with `[normal_map]` the cheek's truth map: a scene that renders.
pub fn head_scene(scratch: &Scratch, name: &str, map: &Path) -> PathBuf {
    scene(scratch, name, &scratch.input("head/head.obj"), &format!("[normal_map]\npath = \"{}\"", s(map)))
}

/// `render SCENE` fails naming `names` once and saying `words`, and writes no image.
fn render_refuses(scratch: &Scratch, scene: &Path, names: &str, words: &[&str]) {
    let case = scratch.expect(&[1]).names(names).says(words).leaves_nothing_at(scratch.out("r.png"));
    case.run(&["render", s(scene), "--out", "out/r.png"]);
}

/// The sample head's text with `edit` applied to its lines; the file line (1-based) of the first
/// line `edit` changed.
fn edited_head(scratch: &Scratch, name: &str, edit: impl Fn(usize, &str) -> Option<String>) -> (PathBuf, usize) {
    let head = std::fs::read_to_string(scratch.input("head/head.obj")).unwrap();
    let (mut text, mut first, mut vertices) = (String::new(), 0, 0);
    for (i, line) in head.lines().enumerate() {
        vertices += usize::from(line.starts_with("v "));
        match edit(vertices, line).filter(|_| line.starts_with("v ")) {
            Some(changed) => {
                first = if first == 0 { i + 1 } else { first };
                text += &changed;
            }
            None => text += line,
        }
        text.push('\n');
    }
    let path = scratch.folder("scenes").join(name);
    std::fs::write(&path, text).unwrap();
    (path, first)
}

/// 5.2, D11: a scene whose mesh file is missing fails naming the scene once and the field `mesh`.
#[test]
fn probe1_5_2_a_missing_mesh_is_named_with_its_field() {
    let scratch = Scratch::new();
    let path = scene(&scratch, "no-mesh", &scratch.input("scenes/nope.obj"), "");
    render_refuses(&scratch, &path, s(&path), &["mesh"]);
}

/// 5.4, D12: an OBJ with NaN on every 50th `v` line fails at the first of them, naming the file
/// and its line.
#[test]
fn probe1_5_4_nan_vertices_are_refused_by_file_line() {
    let scratch = Scratch::new();
    let (obj, line) = edited_head(&scratch, "nan.obj", |v, _| (v % 50 == 0).then(|| "v nan nan nan".to_owned()));
    assert!(line > 0);
    let path = scene(&scratch, "nan", &obj, "");
    render_refuses(&scratch, &path, s(&obj), &[&format!("line {line}:")]);
}

/// 5.8, D12: an OBJ face of `v` index 99999 (past the file's vertices) fails naming the file,
/// the line of the face and the index.
#[test]
fn probe1_5_8_a_face_index_out_of_range_is_refused_by_file_line() {
    let scratch = Scratch::new();
    let mut head = std::fs::read_to_string(scratch.input("head/head.obj")).unwrap();
    if !head.ends_with('\n') {
        head.push('\n');
    }
    head += "f 1/1/1 2/2/2 99999/3/3\n";
    let obj = scratch.folder("scenes").join("far.obj");
    std::fs::write(&obj, &head).unwrap();
    let path = scene(&scratch, "far", &obj, "");
    let line = format!("line {}:", head.lines().count());
    render_refuses(&scratch, &path, s(&obj), &[&line, "99999"]);
}

/// 5.11a, D12: a glTF whose POSITION accessor claims a million vertices over a 36-byte view
/// fails naming the file and `accessor 0`.
#[test]
fn probe1_5_11a_a_gltf_accessor_past_its_view_is_refused() {
    let scratch = Scratch::new();
    let mesh = scratch.folder("scenes").join("overrun.gltf");
    gltf(&mesh, GltfLie::Overrun);
    let path = scene(&scratch, "overrun", &mesh, "");
    render_refuses(&scratch, &path, s(&mesh), &["accessor 0"]);
}

/// 5.11b, D12: a glTF bufferView starting past its buffer's end fails naming the file and
/// `bufferView 2`.
#[test]
fn probe1_5_11b_a_gltf_buffer_view_past_its_buffer_is_refused() {
    let scratch = Scratch::new();
    let mesh = scratch.folder("scenes").join("offset.gltf");
    gltf(&mesh, GltfLie::Offset);
    let path = scene(&scratch, "offset", &mesh, "");
    render_refuses(&scratch, &path, s(&mesh), &["bufferView 2"]);
}

/// 5.14a, 5.14b, 5.14c, 5.14d, D11: a scene's normal map that is missing, a TOML file, a grey
/// PNG or a PNG header claiming 100000 x 100000 fails naming the scene once and the field
/// `normal_map.path`.
#[test]
fn probe1_5_14_a_bad_normal_map_is_named_with_its_field() {
    let scratch = Scratch::new();
    let folder = scratch.folder("scenes");
    std::fs::write(folder.join("not-an-image.toml"), "size = [1, 1]\n").unwrap();
    grey_png(&folder.join("grey.png"), 64, 64, 16, 30000);
    png_header_only(&folder.join("bomb-header.png"), 100_000, 100_000);
    for (name, map) in
        [("missing", "nope.png"), ("toml", "not-an-image.toml"), ("grey", "grey.png"), ("bomb", "bomb-header.png")]
    {
        let path = head_scene(&scratch, &format!("nm-{name}"), &folder.join(map));
        render_refuses(&scratch, &path, s(&path), &["normal_map.path"]);
    }
}

/// 5.14e, D11: a scene's missing albedo map fails naming the scene once and the field `albedo`.
#[test]
fn probe1_5_14e_a_missing_albedo_is_named_with_its_field() {
    let scratch = Scratch::new();
    let albedo = scratch.input("scenes/nope.png");
    let path =
        scene(&scratch, "albedo-missing", &scratch.input("head/head.obj"), &format!("albedo = \"{}\"", s(&albedo)));
    render_refuses(&scratch, &path, s(&path), &["albedo"]);
}

/// 5.23, 5.24, exit, D2: `--orbit --frames 0` is a usage error naming the flag; so is (or a
/// refused job, exit 1) `--frames 100000000000`, within 30 s (it aborted); no image is written.
#[test]
fn probe1_5_23_orbit_frame_counts_out_of_range_are_refused() {
    let scratch = Scratch::new();
    let map = scratch.input("molds/cheek/truth.png");
    let path = head_scene(&scratch, "head", &map);
    for (frames, want) in [("0", &[2][..]), ("100000000000", &[1, 2][..])] {
        let args = ["render", s(&path), "--orbit", "--frames", frames, "--out", "out/r.png"];
        scratch.expect(want).names("--frames").leaves_nothing_at(scratch.out("r.png")).timeout(30).run(&args);
    }
}
