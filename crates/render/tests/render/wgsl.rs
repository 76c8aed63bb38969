//! Every WGSL source parses and validates with naga (CPU only, no adapter needed): the standalone
//! `shaders/*.wgsl`, and the modules assembled from the passes' files in `src/pass/`, of which
//! every file must be part.

use crate::common::validate;
use std::path::PathBuf;

/// The WGSL files under `folder` of the crate, its subfolders included (each pass has its own).
fn wgsl_files(folder: &str) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut folders = vec![PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(folder)];
    while let Some(dir) = folders.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display())) {
            let path = entry.unwrap().path();
            match path.is_dir() {
                true => folders.push(path),
                false if path.extension().is_some_and(|e| e == "wgsl") => files.push(path),
                false => {}
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_standalone_wgsl_file_validates() {
    let files = wgsl_files("shaders");
    assert!(!files.is_empty(), "no shaders found");
    for path in files {
        if let Err(message) = validate(&std::fs::read_to_string(&path).unwrap()) {
            panic!("{}: {message}", path.display());
        }
    }
}

#[test]
fn the_assembled_pass_modules_validate() {
    for (name, source) in [
        ("BASE_WGSL", skinkit_render::pass::BASE_WGSL),
        ("BLUR_WGSL", skinkit_render::pass::BLUR_WGSL),
        ("DEBUG_WGSL", skinkit_render::pass::DEBUG_WGSL),
    ] {
        if let Err(message) = validate(source) {
            panic!("{name}: {message}");
        }
    }
}

#[test]
fn every_pass_wgsl_file_is_in_an_assembled_module() {
    // A pass file left out of `pass::BASE_WGSL` would be neither compiled nor validated.
    let files = wgsl_files("src/pass");
    assert!(files.len() >= 7, "{files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let assembled =
            [skinkit_render::pass::BASE_WGSL, skinkit_render::pass::BLUR_WGSL, skinkit_render::pass::DEBUG_WGSL];
        assert!(assembled.iter().any(|m| m.contains(&text)), "{} is in no assembled module", path.display());
    }
}

#[test]
fn base_pass_has_its_entry_points() {
    let module = validate(skinkit_render::pass::BASE_WGSL).unwrap();
    let names: Vec<&str> = module.entry_points.iter().map(|e| e.name.as_str()).collect();
    assert!(names.contains(&"vs_main") && names.contains(&"fs_main"), "{names:?}");
}

#[test]
fn validator_rejects_a_broken_shader() {
    // The oracle itself must be able to fail: a type error is caught.
    let broken = "@fragment fn fs() -> @location(0) vec4<f32> { let x: f32 = vec2<f32>(1.0); return vec4<f32>(x); }";
    assert!(validate(broken).is_err());
}

#[test]
fn every_uniform_struct_matches_its_wgsl_layout() {
    let layouts = skinkit_render::pass::uniform_layouts();
    // One named struct per pass, and the block the mesh passes share.
    for name in [
        "Globals",
        "SceneUniforms",
        "BaseUniforms",
        "ShadowUniforms",
        "PrepassUniforms",
        "LightMapUniforms",
        "BlurUniforms",
    ] {
        assert!(layouts.iter().any(|l| l.name == name), "no layout for {name}");
    }
    for layout in layouts {
        let module = validate(layout.source).unwrap();
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, ty)| match (&ty.name, &ty.inner) {
                (Some(name), naga::TypeInner::Struct { members, span }) if name == layout.name => {
                    Some((members.clone(), *span))
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("no struct {} in its WGSL", layout.name));
        assert_eq!(span as usize, layout.size, "{}: WGSL size against size_of", layout.name);
        let wgsl: Vec<(String, usize)> =
            members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize)).collect();
        let rust: Vec<(String, usize)> = layout.members.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(wgsl, rust, "{}: member names and offsets, WGSL against Rust", layout.name);
    }
}

#[test]
fn the_layout_check_catches_a_moved_member() {
    // The oracle can fail: a WGSL struct with two members swapped does not match.
    let swapped = "struct BlurUniforms { inv_size: vec2<f32>, b: f32, a: f32, dilate: u32, pad0: u32, pad1: u32, \
                   pad2: u32, }\n@group(0) @binding(0) var<uniform> u: BlurUniforms;\n\
                   @fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(u.a); }";
    let module = validate(swapped).unwrap();
    let blur = skinkit_render::pass::uniform_layouts().into_iter().find(|l| l.name == "BlurUniforms").unwrap();
    let names: Vec<String> = module
        .types
        .iter()
        .find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, .. } => Some(members.iter().map(|m| m.name.clone().unwrap()).collect()),
            _ => None,
        })
        .unwrap();
    let rust: Vec<String> = blur.members.iter().map(|(n, _)| n.to_string()).collect();
    assert_ne!(names, rust);
}

#[test]
fn blur_radius_table_constants_match_the_rust_side() {
    use skinkit_render::skin::tsd::{RADIUS_TABLE_LEN, RADIUS_TABLE_MAX_VARIANCE};
    let source = skinkit_render::pass::BLUR_WGSL;
    for line in [
        format!("const RADIUS_TABLE_LEN: u32 = {RADIUS_TABLE_LEN}u;"),
        format!("const RADIUS_TABLE_MAX_VARIANCE: f32 = {RADIUS_TABLE_MAX_VARIANCE:?};"),
        format!("radius_table: array<vec4<f32>, {}>,", RADIUS_TABLE_LEN / 2),
    ] {
        assert!(source.contains(&line), "blur.wgsl lacks `{line}`");
    }
}
