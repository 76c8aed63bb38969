//! `skinkit export gltf`: a scene's skin as glTF 2.0 for other tools (`skinkit_render::export`
//! does the work; this module parses, checks the outputs, shows progress and writes).
//!
//! `--out head.glb` writes one binary file; `--out head.gltf` writes the JSON with `head.bin`,
//! `head-albedo.png` and `head-normal.png` beside it. The files are one output set: all of them
//! appear (each written to a temporary file, then renamed) or none do.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use serde::Serialize;
use skinkit_maps::{OutputSet, io};
use skinkit_render::export::{self, Container, ExportOptions, ExportSummary, NormalBits};
use skinkit_render::scene::{Albedo, Scene};

use crate::output::Output;

/// Export formats.
#[derive(clap::Subcommand, Debug)]
pub enum Command {
    /// Write a scene's mesh (positions in metres, normals, MikkTSpace tangents, UVs), its albedo as
    /// baseColorTexture, its normal map as normalTexture and a roughness from its skin lobes as
    /// glTF 2.0: one .glb, or a .gltf with its .bin and PNG files beside it.
    Gltf(GltfArgs),
}

/// `skinkit export gltf`.
#[derive(clap::Args, Debug)]
pub struct GltfArgs {
    /// The scene file (TOML).
    #[arg(long, value_name = "SCENE")]
    pub scene: PathBuf,
    /// The output: FILE.glb (one file) or FILE.gltf (with FILE.bin, FILE-albedo.png and
    /// FILE-normal.png beside it).
    #[arg(long, value_name = "FILE", value_parser = gltf_path)]
    pub out: PathBuf,
    /// Bit depth of the normal texture: 8 (what every viewer reads) or 16 (valid PNG, finer, but
    /// some viewers quantise it to 8 bits).
    #[arg(long, value_name = "BITS", default_value = "8", value_parser = normal_bits)]
    pub normal_bits: NormalBits,
}

/// A `--out` value: a path ending in `.glb` or `.gltf` with a file name before it.
fn gltf_path(text: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(text);
    let has_stem = path.file_stem().is_some_and(|s| !s.is_empty());
    match Container::from_path(&path) {
        Some(_) if has_stem => Ok(path),
        _ => Err(format!("`{text}` is not a .glb or .gltf file name")),
    }
}

/// A `--normal-bits` value: 8 or 16.
fn normal_bits(text: &str) -> Result<NormalBits, String> {
    text.trim().parse::<u32>().ok().and_then(NormalBits::from_bits).ok_or_else(|| format!("`{text}` is not 8 or 16"))
}

/// What `--json` prints.
#[derive(Debug, Serialize)]
struct Report {
    scene: String,
    container: Container,
    files: Vec<WrittenFile>,
    #[serde(flatten)]
    summary: ExportSummary,
    seconds: f64,
}

/// One written file.
#[derive(Debug, Serialize)]
struct WrittenFile {
    path: String,
    bytes: usize,
}

pub fn run(command: Command, out: &Output) -> Result<i32> {
    match command {
        Command::Gltf(args) => gltf(args, out),
    }
}

fn gltf(args: GltfArgs, out: &Output) -> Result<i32> {
    let start = Instant::now();
    let container = Container::from_path(&args.out).context("--out: not a .glb or .gltf file")?;
    let stem = args.out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let scene = Scene::load(&args.scene)?;
    let dir = args.out.parent().map(Path::to_path_buf).unwrap_or_default();
    check_outputs(&args, &scene, &dir, &stem, container)?;
    let options = ExportOptions { container, stem, normal_bits: args.normal_bits };
    let bar = out.progress(0, "export");
    let exported = export::export(&scene, &options, &bar)?;
    bar.clear();
    exported.summary.warnings.iter().for_each(|w| out.warn(w));
    let mut set = OutputSet::files();
    let mut files = Vec::new();
    for (i, file) in exported.files.iter().enumerate() {
        // The main file is `--out` as spelt (`HEAD.GLB` stays so); side files are named by the library.
        let path = if i == 0 { args.out.clone() } else { dir.join(&file.name) };
        set.write_file(&path, |p| write_bytes(p, &file.bytes))
            .with_context(|| format!("cannot write {}", role(&path)))?;
        files.push(WrittenFile { path: path.display().to_string(), bytes: file.bytes.len() });
    }
    out.swept(&set.commit().context("cannot finish writing the export")?);
    let report = Report {
        scene: args.scene.display().to_string(),
        container,
        files,
        summary: exported.summary,
        seconds: start.elapsed().as_secs_f64(),
    };
    out.result(&report, || human(&report));
    Ok(0)
}

/// Refuses, before any work, an output that is a folder, one of the scene's inputs or another
/// output (the side files of a `.gltf` included).
fn check_outputs(args: &GltfArgs, scene: &Scene, dir: &Path, stem: &str, container: Container) -> Result<()> {
    let mut inputs =
        vec![("the scene".to_owned(), args.scene.clone()), ("the scene's mesh".to_owned(), scene.mesh.clone())];
    if let Some(Albedo::Map(p)) = &scene.albedo {
        inputs.push(("the scene's albedo".to_owned(), p.clone()));
    }
    inputs.extend(scene.normal_map.iter().map(|n| ("the scene's normal map".to_owned(), n.path.clone())));
    let mut paths = vec![args.out.clone()];
    if container == Container::Gltf {
        paths.push(dir.join(format!("{stem}.bin")));
        if matches!(scene.albedo, Some(Albedo::Map(_))) {
            paths.push(dir.join(format!("{stem}-albedo.png")));
        }
        if scene.normal_map.is_some() {
            paths.push(dir.join(format!("{stem}-normal.png")));
        }
    }
    let outputs: Vec<(&str, &Path)> = paths.iter().map(|p| ("--out", p.as_path())).collect();
    Ok(skinkit_maps::gate::output_files(&outputs, &inputs)?)
}

/// What an exported file is, in errors: the model (`.glb`, `.gltf`), its buffer (`.bin`) or one
/// of its textures.
fn role(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("glb" | "gltf") => "the exported model",
        Some("bin") => "the exported model's buffer",
        _ => "an exported texture",
    }
}

/// Writes `bytes` to `path` atomically.
fn write_bytes(path: &Path, bytes: &[u8]) -> skinkit_maps::Result<()> {
    io::write_atomic(path, |w| {
        w.write_all(bytes).map_err(|error| skinkit_maps::Error::Io { path: path.to_owned(), error })
    })
}

fn human(r: &Report) -> String {
    let s = &r.summary;
    let texture = |t: Option<export::TextureInfo>| {
        t.map_or("none".to_owned(), |t| format!("{}x{} {}-bit", t.width, t.height, t.bits))
    };
    let mut text = format!(
        "exported {} ({} vertices, {} triangles, {} m per unit; albedo {}, normal map {}; roughness {:.3}) in {:.2} s",
        r.scene,
        s.vertices,
        s.triangles,
        s.metres_per_unit,
        texture(s.albedo),
        texture(s.normal),
        s.roughness.roughness,
        r.seconds
    );
    for f in &r.files {
        text.push_str(&format!("\n  {}  {} bytes", f.path, f.bytes));
    }
    text
}
