//! The fuzzed entry points, shared by the libFuzzer targets in `fuzz/` and by the regression test
//! `tests/fuzz_regressions.rs` (which replays every kept crash input through the same code).
//!
//! Each entry takes arbitrary bytes and calls the public library functions the `skinkit` binary
//! calls on a file of that kind: from bytes where the library has a `parse`/`decode` function,
//! otherwise through a file in a fresh temporary folder (the readers that only take a path). An
//! entry returns `Ok` or the library's error message; a panic, an abort, a hang or a blown memory
//! limit is the bug the fuzzer looks for. Where a result comes back, the entry also checks what
//! the library promises about it (a rig reads back equal from its own TOML, decoded normals are
//! unit or invalid, tangent frames are finite and unit), so a wrong value counts as a crash too.

use std::io::Cursor;
use std::path::{Path, PathBuf};

use skinkit_capture::{Rig, import};
use skinkit_maps::io::{decode_photo, read_normal_map, read_photo, read_scalar_map};
use skinkit_maps::{Channels, GreenAxis, Grid, Limits, NormalEncoding, Samples};
use skinkit_render::frames::{FrameMethod, tangents};
use skinkit_render::mesh::{LoadedMesh, Mesh};
use skinkit_render::scene::Scene;
use skinkit_render::skin::lut_file;
use skinkit_stitch::layout::Layout;

/// What an entry returns: `Ok`, or the message of a clean error.
pub type Outcome = Result<(), String>;

/// A fuzz entry: the bytes in, `Ok` or a clean error out.
pub type Entry = fn(&[u8]) -> Outcome;

/// Every target: its name (the `fuzz/fuzz_targets/<name>.rs` file and the regression folder) and
/// its entry.
pub const TARGETS: &[(&str, Entry)] = &[
    ("rig_toml", rig_toml),
    ("diligent_lights", diligent_lights),
    ("uw_lights", uw_lights),
    ("layout", layout),
    ("scene", scene),
    ("obj", obj),
    ("gltf", gltf),
    ("photo", photo),
    ("normal_map", normal_map),
    ("coverage_mask", coverage_mask),
    ("coords", coords),
    ("lut_file", lut_file),
];

/// Largest image the image targets accept: 2048 x 2048 pixels (64 MiB as RGBA f32). The CLI's
/// default is 16384 x 16384 ([`Limits::default`]); the check is the same code, and a smaller
/// limit keeps a fuzzer's input that claims a huge image from spending seconds on an allowed
/// decode (that cost is the limit's purpose, not a bug).
pub const FUZZ_LIMITS: Limits = Limits { max_pixels: 2048 * 2048 };

fn text(data: &[u8]) -> Result<&str, String> {
    // The file readers refuse non-UTF-8 text the same way (`read_to_string`).
    std::str::from_utf8(data).map_err(|e| format!("not UTF-8: {e}"))
}

/// Rig TOML (`skinkit rig check`, `capture --rig`): parse, then the checks `rig check` prints,
/// then the TOML the rig writes must read back to the same rig.
pub fn rig_toml(data: &[u8]) -> Outcome {
    let rig = Rig::parse(text(data)?, "fuzz.toml").map_err(|e| e.to_string())?;
    let c = rig.conditioning();
    let _ = (c.warning(), rig.directions_matrix(), rig.intensities());
    let again = Rig::parse(&rig.to_toml_string(), "fuzz-again.toml")
        .unwrap_or_else(|e| panic!("a parsed rig's own TOML does not read back: {e}"));
    assert_eq!(again, rig, "a rig's TOML reads back to a different rig");
    Ok(())
}

/// DiLiGenT `light_directions.txt` and `light_intensities.txt` (`skinkit rig import --diligent`):
/// the bytes before the first NUL are the directions, the rest the intensities.
pub fn diligent_lights(data: &[u8]) -> Outcome {
    let split = data.iter().position(|&b| b == 0).unwrap_or(data.len());
    let (dirs, ints) = (&data[..split], data.get(split + 1..).unwrap_or(&[]));
    let rig = import::parse_diligent(dirs, "light_directions.txt", ints, "light_intensities.txt")
        .map_err(|e| e.to_string())?;
    let _ = rig.conditioning();
    Ok(())
}

/// UW/Seitz `lights.txt` (`skinkit rig import --uw`).
pub fn uw_lights(data: &[u8]) -> Outcome {
    let rig = import::parse_uw_lights(data, "lights.txt").map_err(|e| e.to_string())?;
    let _ = rig.conditioning();
    Ok(())
}

/// A face layout (`skinkit stitch`): parse and validate. The exemplar and coverage files it names
/// are not read (they would be files of the machine; the image targets fuzz those readers).
pub fn layout(data: &[u8]) -> Outcome {
    Layout::parse(text(data)?, Path::new("/nonexistent/fuzz/layout.toml")).map(drop).map_err(|e| e.to_string())
}

/// A render scene (`skinkit render`): parse and validate (the mesh and maps it names are the
/// `obj`, `gltf` and `normal_map` targets).
pub fn scene(data: &[u8]) -> Outcome {
    Scene::parse(text(data)?, Path::new("/nonexistent/fuzz/scene.toml")).map(drop).map_err(|e| e.to_string())
}

/// An OBJ mesh, then its tangent frames both ways (what `render` does with it).
pub fn obj(data: &[u8]) -> Outcome {
    let loaded = Mesh::parse_obj(&mut Cursor::new(data), "fuzz.obj").map_err(|e| e.to_string())?;
    check_mesh(&loaded);
    Ok(())
}

/// glTF JSON or GLB bytes, then tangent frames. External buffers resolve against an empty
/// temporary folder (a relative URI finds nothing there; data URIs and the GLB blob are read).
pub fn gltf(data: &[u8]) -> Outcome {
    let folder = scratch();
    let loaded = Mesh::parse_gltf(data, Some(folder.path()), "fuzz.glb").map_err(|e| e.to_string())?;
    check_mesh(&loaded);
    Ok(())
}

fn check_mesh(loaded: &LoadedMesh) {
    let mesh = &loaded.mesh;
    mesh.validate().unwrap_or_else(|e| panic!("a loaded mesh fails validate: {e}"));
    for method in [FrameMethod::Paper, FrameMethod::MikkTSpace] {
        let frames = tangents(mesh, method);
        assert_eq!(frames.len(), mesh.positions.len());
        for (v, t) in frames.iter().enumerate() {
            let unit = (t.truncate().length() - 1.0).abs() < 1e-3;
            assert!(t.is_finite() && unit && t.w.abs() == 1.0, "{method:?} vertex {v}: tangent {t}");
        }
    }
}

/// A fresh temporary folder (removed when dropped).
fn scratch() -> tempfile::TempDir {
    tempfile::Builder::new().prefix("skinkit-fuzz").tempdir().expect("cannot make a temporary folder")
}

/// The image extension a first byte chooses, and the file's bytes (the rest). The readers pick
/// the EXR path by extension and sniff PNG/TIFF signatures.
fn image_file(data: &[u8]) -> (&'static str, &[u8]) {
    let ext = match data.first().map(|b| b % 3) {
        Some(0) | None => "png",
        Some(1) => "tif",
        _ => "exr",
    };
    (ext, data.get(1..).unwrap_or(&[]))
}

/// Writes `bytes` to `<folder>/input.<ext>`.
fn write_input(folder: &Path, ext: &str, bytes: &[u8]) -> PathBuf {
    let path = folder.join(format!("input.{ext}"));
    std::fs::write(&path, bytes).expect("cannot write a temporary file");
    path
}

/// A photo (`capture`, `batch`): PNG, TIFF or EXR through `read_photo`.
pub fn photo(data: &[u8]) -> Outcome {
    let (ext, bytes) = image_file(data);
    let folder = scratch();
    let photo = read_photo(&write_input(folder.path(), ext, bytes), &FUZZ_LIMITS).map_err(|e| e.to_string())?;
    let per_pixel = if photo.channels() == Channels::Gray { 1 } else { 3 };
    assert_eq!(photo.samples().len(), photo.width() * photo.height() * per_pixel);
    let _ = photo.luminance();
    Ok(())
}

/// A normal map (`synth`, `render`, `stitch` exemplars): every texel unit or invalid (zero).
pub fn normal_map(data: &[u8]) -> Outcome {
    let (ext, bytes) = image_file(data);
    let green = if data.first().is_some_and(|b| b & 0x80 != 0) { GreenAxis::Down } else { GreenAxis::Up };
    let folder = scratch();
    let path = write_input(folder.path(), ext, bytes);
    let map = read_normal_map(&path, NormalEncoding { green }, &FUZZ_LIMITS).map_err(|e| e.to_string())?;
    for (i, n) in map.as_slice().iter().enumerate() {
        assert!(
            *n == skinkit_maps::Vec3::ZERO || (n.length() - 1.0).abs() < 1e-4,
            "texel {i}: {n} is neither unit nor zero"
        );
    }
    Ok(())
}

/// A layout's coverage mask (a grey image, `read_scalar_map`).
pub fn coverage_mask(data: &[u8]) -> Outcome {
    let (ext, bytes) = image_file(data);
    let folder = scratch();
    let map = read_scalar_map(&write_input(folder.path(), ext, bytes), &FUZZ_LIMITS).map_err(|e| e.to_string())?;
    assert_eq!(map.as_slice().len(), map.width() * map.height());
    Ok(())
}

/// The coordinate map of `synth --coords` read back by `synth replay`: decoded as the binary's
/// `read_coords` does (a 16-bit RGB PNG, R = x, G = y), then replayed onto a 64 x 48 source, so
/// coordinates outside the source must come back as an error.
pub fn coords(data: &[u8]) -> Outcome {
    let photo = decode_photo(Path::new("coords.png"), Cursor::new(data), &FUZZ_LIMITS).map_err(|e| e.to_string())?;
    let (Channels::Rgb, Samples::U16(samples)) = (photo.channels(), photo.samples()) else {
        return Err("not a coordinate map (a 16-bit RGB PNG)".into());
    };
    let texels = samples.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32]).collect();
    let coords = Grid::from_vec(photo.width(), photo.height(), texels).map_err(|e| e.to_string())?;
    let source = Grid::from_fn(64, 48, |x, y| (x, y));
    let replayed = skinkit_synth::replay(&coords, &source).map_err(|e| e.to_string())?;
    for (c, r) in coords.as_slice().iter().zip(replayed.as_slice()) {
        assert_eq!([c[0] as usize, c[1] as usize], [r.0, r.1]);
    }
    Ok(())
}

/// A pre-integrated skin table (`skinkit lut`, the renderer's table cache): an EXR.
pub fn lut_file(data: &[u8]) -> Outcome {
    let table = lut_file::decode(data, "fuzz.exr").map_err(|e| e.to_string())?;
    assert_eq!(table.texels.len(), table.width * table.height);
    Ok(())
}
