//! Every input the fuzzers (`fuzz/`, `scripts/fuzz.sh`) found to crash, hang or break a promise,
//! kept under `tests/fuzz-regressions/<target>/` and replayed through the same entry point
//! (`tests/fuzz/entries.rs`): each must now give `Ok` or a clean error, never a panic.

#[path = "fuzz/entries.rs"]
mod entries;

use std::path::Path;

/// The kept inputs of one target, sorted by name (none is fine: a target that never crashed).
fn inputs(target: &str) -> Vec<std::path::PathBuf> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz-regressions").join(target);
    let Ok(entries) = std::fs::read_dir(&folder) else { return Vec::new() };
    let mut files: Vec<_> = entries.map(|e| e.expect("readable folder entry").path()).filter(|p| p.is_file()).collect();
    files.sort();
    files
}

#[test]
fn every_kept_fuzz_input_gives_ok_or_a_clean_error() {
    let mut replayed = 0;
    for (target, entry) in entries::TARGETS {
        for path in inputs(target) {
            let data = std::fs::read(&path).expect("readable regression input");
            let outcome = std::panic::catch_unwind(|| entry(&data));
            match outcome {
                Ok(Ok(())) => {}
                Ok(Err(message)) => {
                    assert!(!message.trim().is_empty(), "{}: an error without a message", path.display());
                }
                Err(_) => panic!("{target}: {} still panics", path.display()),
            }
            replayed += 1;
        }
    }
    println!("{replayed} kept fuzz inputs replayed");
}

#[test]
fn every_regression_folder_names_a_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fuzz-regressions");
    let Ok(folders) = std::fs::read_dir(&root) else { return };
    for folder in folders {
        let name = folder.unwrap().file_name().to_string_lossy().into_owned();
        assert!(entries::TARGETS.iter().any(|(t, _)| *t == name), "tests/fuzz-regressions/{name} is not a fuzz target");
    }
}

/// Valid files of every kind come back `Ok` through their entry (those named `err-*` are refused),
/// so a passing replay is not a sign that every entry fails early. With `SKINKIT_FUZZ_SEEDS=<folder>` the same files are written
/// there as `<target>/<name>`: `scripts/fuzz.sh` starts each fuzzer from them.
#[test]
fn valid_inputs_come_back_ok_and_seed_the_fuzzers() {
    let folder = tempfile::tempdir().unwrap();
    let seeds = seeds::all(folder.path());
    let mut kinds = std::collections::BTreeSet::new();
    for (target, name, data) in &seeds {
        let entry = entries::TARGETS.iter().find(|(t, _)| t == target).expect("a known target").1;
        if name.starts_with("err-") {
            assert!(entry(data).is_err(), "{target}/{name} should be refused");
        } else {
            assert_eq!(entry(data), Ok(()), "{target}/{name}");
        }
        kinds.insert(*target);
    }
    assert_eq!(kinds.len(), entries::TARGETS.len(), "every target has a valid seed");
    // A bad input of each text kind is an error, not Ok.
    assert!(entries::rig_toml(b"[[light]]\ndirection = [0, 0, -1]\n").is_err());
    assert!(entries::uw_lights(b"2\n0 0 1\n").is_err());
    assert!(entries::coords(&seeds.iter().find(|s| s.0 == "photo").unwrap().2[1..]).is_err());
    if let Some(out) = std::env::var_os("SKINKIT_FUZZ_SEEDS") {
        for (target, name, data) in &seeds {
            let dir = Path::new(&out).join(target);
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(dir.join(name), data).unwrap();
        }
        println!("{} seeds written to {}", seeds.len(), Path::new(&out).display());
    }
}

/// Small valid inputs for every target, made with the project's own writers where it has them.
mod seeds {
    use std::path::Path;

    use skinkit_maps::io::{PngLayout, write_exr_rgb, write_normal_map, write_png};
    use skinkit_maps::{Grid, NormalEncoding, NormalMap, Vec3};
    use skinkit_render::skin::lut::{DiffuseLut, DiffuseLutSpec};
    use skinkit_render::skin::lut_file::write_diffuse;

    pub type Seed = (&'static str, String, Vec<u8>);

    fn repo_file(path: &str) -> Vec<u8> {
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)).unwrap()
    }

    pub fn all(tmp: &Path) -> Vec<Seed> {
        let mut out: Vec<Seed> = vec![
            ("rig_toml", "turntable-8.toml".into(), repo_file("calibration/turntable-8.toml")),
            ("rig_toml", "cheek.toml".into(), repo_file("samples/molds/cheek/rig.toml")),
            ("layout", "face.toml".into(), repo_file("samples/face/layout.toml")),
            ("scene", "head.toml".into(), repo_file("samples/scenes/head.toml")),
            ("scene", "skin-compare.toml".into(), repo_file("samples/scenes/skin-compare.toml")),
        ];
        let dirs = "0.5 0 0.866\n-0.25 0.433 0.866\n-0.25 -0.433 0.866\n0 0 1\n";
        out.push(("uw_lights", "lights.txt".into(), format!("4\n{dirs}").into_bytes()));
        out.push(("diligent_lights", "pair.txt".into(), format!("{dirs}\0{}", "1 0.9 0.8\n".repeat(4)).into_bytes()));
        out.push(("obj", "quad.obj".into(), QUAD_OBJ.as_bytes().to_vec()));
        out.push((
            "obj",
            "triangle.obj".into(),
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n".to_vec(),
        ));
        out.push(("gltf", "triangle.gltf".into(), gltf_json().into_bytes()));
        out.push(("gltf", "triangle.glb".into(), glb()));
        // An external buffer (missing here): gives the fuzzer URIs to mutate.
        out.push(("gltf", "err-external.gltf".into(), gltf_document(Some("triangle.bin"), 104).into_bytes()));
        out.extend(images(tmp));
        out
    }

    const QUAD_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0.2\nv -1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                            vn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";

    /// One triangle: positions, normals, UVs (3 x 12 + 3 x 12 + 3 x 8 bytes) and u16 indices.
    fn triangle_buffer() -> Vec<u8> {
        let floats: [f32; 24] =
            [0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.];
        let mut bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        bytes.truncate(72);
        bytes.extend([0f32, 0., 1., 0., 0., 1.].iter().flat_map(|f| f.to_le_bytes()));
        bytes.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()));
        bytes
    }

    fn gltf_document(buffer_uri: Option<&str>, length: usize) -> String {
        let uri = buffer_uri.map(|u| format!(r#""uri":"{u}","#)).unwrap_or_default();
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3}}]}}],
"buffers":[{{{uri}"byteLength":{length}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":36}},
{{"buffer":0,"byteOffset":72,"byteLength":24}},{{"buffer":0,"byteOffset":96,"byteLength":6}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC3"}},
{{"bufferView":2,"componentType":5126,"count":3,"type":"VEC2"}},
{{"bufferView":3,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
        )
    }

    fn gltf_json() -> String {
        let buffer = triangle_buffer();
        gltf_document(Some(&format!("data:application/octet-stream;base64,{}", base64(&buffer))), buffer.len())
    }

    /// The same triangle as a binary glTF: header, JSON chunk, BIN chunk (each padded to 4 bytes).
    fn glb() -> Vec<u8> {
        let buffer = triangle_buffer();
        let mut json = gltf_document(None, buffer.len()).into_bytes();
        json.resize(json.len().div_ceil(4) * 4, b' ');
        let mut bin = buffer;
        bin.resize(bin.len().div_ceil(4) * 4, 0);
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::with_capacity(total);
        out.extend(b"glTF");
        out.extend(2u32.to_le_bytes());
        out.extend((total as u32).to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out
    }

    fn base64(bytes: &[u8]) -> String {
        const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for chunk in bytes.chunks(3) {
            let n = chunk.iter().enumerate().fold(0u32, |acc, (i, &b)| acc | (b as u32) << (16 - 8 * i));
            for i in 0..4 {
                let c = if i <= chunk.len() { ABC[(n >> (18 - 6 * i) & 63) as usize] as char } else { '=' };
                s.push(c);
            }
        }
        s
    }

    /// A baseline TIFF: 4x3 8-bit RGB, uncompressed, one strip (the maps crate writes no TIFF).
    fn tiff() -> Vec<u8> {
        let (w, h) = (4u32, 3u32);
        let pixels: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
        let entries: [(u16, u16, u32, u32); 9] = [
            (256, 4, 1, w),                      // ImageWidth
            (257, 4, 1, h),                      // ImageLength
            (258, 3, 3, 8 + 2 + 9 * 12 + 4),     // BitsPerSample -> offset of three shorts
            (259, 3, 1, 1),                      // Compression: none
            (262, 3, 1, 2),                      // Photometric: RGB
            (273, 4, 1, 8 + 2 + 9 * 12 + 4 + 6), // StripOffsets
            (277, 3, 1, 3),                      // SamplesPerPixel
            (278, 4, 1, h),                      // RowsPerStrip
            (279, 4, 1, w * h * 3),              // StripByteCounts
        ];
        let mut out = b"II*\0".to_vec();
        out.extend(8u32.to_le_bytes());
        out.extend((entries.len() as u16).to_le_bytes());
        for (tag, kind, count, value) in entries {
            out.extend(tag.to_le_bytes());
            out.extend(kind.to_le_bytes());
            out.extend(count.to_le_bytes());
            if kind == 3 && count == 1 {
                out.extend((value as u16).to_le_bytes());
                out.extend([0, 0]);
            } else {
                out.extend(value.to_le_bytes());
            }
        }
        out.extend(0u32.to_le_bytes());
        out.extend([8u16, 8, 8].iter().flat_map(|b| b.to_le_bytes()));
        out.extend(pixels);
        out
    }

    /// `[format byte] + file`: 0 PNG, 1 TIFF, 2 EXR (see `entries::image_file`).
    fn tagged(format: u8, file: &[u8]) -> Vec<u8> {
        let mut v = vec![format];
        v.extend(file);
        v
    }

    fn images(tmp: &Path) -> Vec<Seed> {
        let read = |name: &str| std::fs::read(tmp.join(name)).unwrap();
        let (w, h) = (8, 6);
        let rgb16: Vec<u16> = (0..w * h * 3).map(|i| (i * 997 % 65536) as u16).collect();
        write_png(&tmp.join("rgb16.png"), w, h, PngLayout::Rgb16, &rgb16).unwrap();
        let grey8: Vec<u16> = (0..w * h).map(|i| (i * 37 % 256) as u16).collect();
        write_png(&tmp.join("grey8.png"), w, h, PngLayout::Gray8, &grey8).unwrap();
        write_exr_rgb(&tmp.join("rgb.exr"), w, h, |x, y| [x as f32 * 0.1, y as f32 * 0.2, 0.5]).unwrap();
        let normals = NormalMap::from_grid(Grid::from_fn(w, h, |x, y| Vec3::new(x as f32 - 4.0, y as f32 - 3.0, 9.0)));
        let up = NormalEncoding::default();
        write_normal_map(&tmp.join("normal.png"), &normals, up, 16).unwrap();
        write_normal_map(&tmp.join("normal.exr"), &normals, up, 16).unwrap();
        let coords: Vec<u16> = (0..w * h).flat_map(|i| [(i % 64) as u16, (i / 64) as u16, 0]).collect();
        write_png(&tmp.join("coords.png"), w, h, PngLayout::Rgb16, &coords).unwrap();
        let spec = DiffuseLutSpec { width: 8, height: 4, ..DiffuseLutSpec::default() };
        write_diffuse(&tmp.join("lut.exr"), &DiffuseLut::build(&spec).unwrap()).unwrap();
        let tif = tiff();
        vec![
            ("photo", "rgb16.png".into(), tagged(0, &read("rgb16.png"))),
            ("photo", "grey8.png".into(), tagged(0, &read("grey8.png"))),
            ("photo", "rgb8.tif".into(), tagged(1, &tif)),
            ("photo", "rgb.exr".into(), tagged(2, &read("rgb.exr"))),
            ("normal_map", "normal.png".into(), tagged(0, &read("normal.png"))),
            ("normal_map", "normal.tif".into(), tagged(1, &tif)),
            ("normal_map", "normal.exr".into(), tagged(2, &read("normal.exr"))),
            ("coverage_mask", "grey8.png".into(), tagged(0, &read("grey8.png"))),
            ("coverage_mask", "grey.exr".into(), tagged(2, &read("rgb.exr"))),
            ("coords", "coords.png".into(), read("coords.png")),
            ("lut_file", "diffuse.exr".into(), read("lut.exr")),
        ]
    }
}
