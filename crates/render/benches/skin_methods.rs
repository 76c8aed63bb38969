//! Accuracy against time of every skin diffuse method (issues 6 and 17): the committed skin
//! scenes ([`SCENES`]: the sample head, the head close up on the nose, a 6 mm sphere) drawn by
//! each [`Method`] of the table, each render's error against the exact texture-space reference
//! (FLIP mean on the tone-mapped sRGB images, relative RMSE on linear radiance) and its frame
//! time on this adapter relative to the base pass (the same scene, Lambert, no shadows).
//!
//! Frame times are GPU timestamps summed over a frame's passes (median of `FRAMES` frames after
//! one warm-up), so CPU-side table builds are not in them; the reference's CPU bake and scatter
//! are reported in their own column. On machines without a GPU the adapter is lavapipe (software
//! Vulkan on the CPU): the ratios say what each effect costs relative to the base pass there, not
//! real-time rates on hardware.
//!
//! Writes `target/<scene>[-unshadowed].{md,json}` (table, rows) and one PNG per method, and
//! `target/skin-methods.md` with every table. Settings:
//! - `SKIN_METHODS_SCENES=skin-sphere,skin-nose`: these scenes only;
//! - `SKIN_METHODS_UNSHADOWED=1` (or `0`): only without (with) the scene's shadows;
//! - `SKIN_METHODS_REFERENCE=N`: the reference's light map (2048; its half is a row too);
//! - `SKIN_METHODS_ONLY=lambert,lut-256`: these methods only (the reference always);
//! - `SKIN_METHODS_SIZE=WxH`: one image size for every scene (else each scene's own);
//! - `SKIN_METHODS_DOCS=1`: the tables into the book's "Skin scattering" chapter
//!   (`docs/book/src/skin-scattering.md`).
//!
//! The plot of error against time is `skinkit accuracy`'s rendering stage (plotters), which
//! measures the same methods on the sphere and the head.
//!
//! Run: `WGPU_BACKEND=vulkan cargo bench -p skinkit-render --bench skin_methods`.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use skinkit_render::compare::{self, Method};
use skinkit_render::effect::Effect;
use skinkit_render::renderer::{Encoding, Frame as Rendered, FrameOptions, Prepared, Renderer, Shading};
use skinkit_render::scene::Scene;

const FRAMES: usize = 7;

#[derive(serde::Serialize)]
struct Row {
    method: String,
    flip_mean: f32,
    rmse: f32,
    frame_ms: f64,
    relative_time: f64,
    cpu_setup_s: f64,
    passes: Vec<(String, f64)>,
}

/// The scenes measured by default, in `samples/scenes/`, with the label their tables carry.
const SCENES: [(&str, &str); 3] = [
    ("skin-compare", "Sample head"),
    ("skin-nose", "Sample head, close up on the nose"),
    ("skin-sphere", "Skin sphere of 6 mm radius"),
];

fn main() {
    if std::env::args().any(|a| a == "--list") {
        println!("skin_methods: bench");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let only = std::env::var("SKIN_METHODS_SCENES").ok();
    let modes: Vec<bool> = match std::env::var("SKIN_METHODS_UNSHADOWED").as_deref() {
        Ok("1") => vec![true],
        Ok("0") => vec![false],
        _ => vec![false, true],
    };
    let reference_size = std::env::var("SKIN_METHODS_REFERENCE").ok().and_then(|s| s.parse().ok()).unwrap_or(2048);
    let renderer = Renderer::new().unwrap_or_else(|e| panic!("{e}"));
    eprintln!("adapter: {}, reference light map {reference_size}", renderer.adapter_name());
    let out = root.join("target");
    std::fs::create_dir_all(&out).unwrap();
    let mut tables = Vec::new();
    for (name, label) in SCENES {
        if only.as_deref().is_some_and(|o| !o.split(',').any(|x| x.trim() == name)) {
            continue;
        }
        for &unshadowed in &modes {
            let stem = if unshadowed { format!("{name}-unshadowed") } else { name.to_owned() };
            let table = measure(
                &renderer,
                &root.join(format!("samples/scenes/{name}.toml")),
                label,
                unshadowed,
                reference_size,
                &out.join(&stem),
            );
            tables.push(table);
        }
    }
    let all = tables.join("\n");
    write(&out.join("skin-methods.md"), &all);
    if docs() {
        splice_doc(&root.join("docs/book/src/skin-scattering.md"), &all);
    }
}

/// `SKIN_METHODS_DOCS=1`: the tables go into the book.
fn docs() -> bool {
    std::env::var("SKIN_METHODS_DOCS").is_ok_and(|v| v == "1")
}

/// Every method of [`Method::table`] on one scene: renders, errors against the reference and
/// frame times, written to `stem.{md,json}` and one PNG per method; returns the table.
fn measure(
    renderer: &Renderer,
    scene_file: &Path,
    label: &str,
    unshadowed: bool,
    reference_size: u32,
    stem: &Path,
) -> String {
    let mut scene = Scene::load(scene_file).unwrap_or_else(|e| panic!("{e}"));
    if unshadowed {
        scene.effects.retain(|&e| e != Effect::Shadows && e != Effect::ShadowScattering);
    }
    let (width, height) = size().unwrap_or((scene.output.size[0], scene.output.size[1]));
    eprintln!("{}{}: {width}x{height}", scene_file.display(), if unshadowed { ", unshadowed" } else { "" });
    let options = |shading| FrameOptions { shading, ..FrameOptions::new(width, height, Encoding::Display) };
    let prepare = |shading| renderer.prepare(&scene, &options(shading)).unwrap_or_else(|e| panic!("{e}"));
    let base_ms = frame_ms(renderer, &mut prepare(Shading::Plain), &scene).0;
    eprintln!("base pass (Lambert, no shadows): {base_ms:.2} ms");
    let mut renders = Vec::new();
    let only = std::env::var("SKIN_METHODS_ONLY").ok();
    let wanted = |m: &Method| {
        matches!(m, Method::Reference { size } if *size == reference_size)
            || only.as_deref().is_none_or(|o| o.split(',').any(|x| x.trim() == m.name()))
    };
    for method in Method::table(reference_size).into_iter().filter(wanted) {
        let mut prepared = prepare(Shading::Method(method));
        let cpu_setup_s = prepared.times().skin.as_secs_f64();
        let (ms, passes) = frame_ms(renderer, &mut prepared, &scene);
        let images = draw(renderer, &mut prepared, &scene, (width, height));
        eprintln!("{:>16}: {ms:8.2} ms ({:.2}x base), cpu setup {cpu_setup_s:.2} s", method.name(), ms / base_ms);
        renders.push((method, images, ms, passes, cpu_setup_s));
    }
    let (_, reference, ..) = renders.last().expect("the table ends with the reference");
    let (ref_ldr, ref_hdr) = (reference.0.srgb_bytes.clone(), reference.1.pixels.clone());
    let rows: Vec<Row> = renders
        .iter()
        .map(|(method, (ldr, hdr), ms, passes, cpu)| Row {
            method: method.name(),
            flip_mean: compare::flip_mean(&ref_ldr, &ldr.srgb_bytes, width, height),
            rmse: compare::rmse(&ref_hdr, &hdr.pixels),
            frame_ms: *ms,
            relative_time: ms / base_ms,
            cpu_setup_s: *cpu,
            passes: passes.iter().map(|(n, d)| (n.clone(), d.as_secs_f64() * 1e3)).collect(),
        })
        .collect();
    let file = scene_file.file_name().and_then(|f| f.to_str()).unwrap_or("");
    let what = if unshadowed { ", unshadowed (the diffuse falloff alone)" } else { "" };
    let caption = format!("{label} (`samples/scenes/{file}`){what}");
    let table = markdown(&caption, &rows, base_ms, &renderer.adapter_name(), width, height, reference_size);
    println!("{table}");
    let with = |ext: &str| PathBuf::from(format!("{}.{ext}", stem.display()));
    write(&with("md"), &table);
    write(&with("json"), &serde_json::to_string_pretty(&rows).unwrap());
    write_pngs(stem, renders.iter().map(|(method, (ldr, _), ..)| (method.name(), ldr)), (width, height));
    eprintln!("wrote {}", with("{md,json}").display());
    table
}

/// Each method's display-encoded render as `stem-<method>.png`.
fn write_pngs<'a>(stem: &Path, renders: impl Iterator<Item = (String, &'a Rendered)>, (width, height): (u32, u32)) {
    for (name, ldr) in renders {
        let path = PathBuf::from(format!("{}-{name}.png", stem.display()));
        let samples: Vec<u16> =
            ldr.srgb_bytes.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]].map(u16::from)).collect();
        let layout = skinkit_maps::io::PngLayout::Rgb8;
        skinkit_maps::io::write_png(&path, width as usize, height as usize, layout, &samples).unwrap();
    }
}

/// Replaces the chapter's text between `<!-- skin-methods:start -->` and `<!-- skin-methods:end -->`.
fn splice_doc(doc: &Path, tables: &str) {
    let text = std::fs::read_to_string(doc).unwrap_or_else(|e| panic!("{}: {e}", doc.display()));
    let (start, end) = ("<!-- skin-methods:start -->", "<!-- skin-methods:end -->");
    let (Some(a), Some(b)) = (text.find(start), text.find(end)) else {
        panic!("{}: no {start} ... {end} markers", doc.display());
    };
    let spliced = format!("{}{start}\n{tables}{}", &text[..a], &text[b..]);
    write(&doc.to_path_buf(), &spliced);
    eprintln!("{}: tables updated", doc.display());
}

/// `SKIN_METHODS_SIZE=WxH`, when set: the image size for every scene (else each scene's own).
fn size() -> Option<(u32, u32)> {
    std::env::var("SKIN_METHODS_SIZE").ok().and_then(|s| {
        let (w, h) = s.split_once('x')?;
        Some((w.parse().ok()?, h.parse().ok()?))
    })
}

fn write(path: &PathBuf, text: &str) {
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// The LDR (Reinhard, sRGB) and HDR (linear) renders of one prepared method.
fn draw(renderer: &Renderer, prepared: &mut Prepared, scene: &Scene, size: (u32, u32)) -> (Rendered, Rendered) {
    let camera = &scene.cameras[0];
    let ldr = renderer.draw(prepared, camera).unwrap();
    renderer.retarget(scene, prepared, size, Encoding::Linear).unwrap();
    (ldr, renderer.draw(prepared, camera).unwrap())
}

/// Median GPU frame time (ms) over `FRAMES` frames after a warm-up, and the median frame's passes.
fn frame_ms(renderer: &Renderer, prepared: &mut Prepared, scene: &Scene) -> (f64, Vec<(String, Duration)>) {
    renderer.draw(prepared, &scene.cameras[0]).unwrap();
    let mut frames: Vec<(f64, Vec<(String, Duration)>)> = (0..FRAMES)
        .map(|_| {
            let t = Instant::now();
            match renderer.draw_timed(prepared).unwrap() {
                Some(passes) => (passes.iter().map(|(_, d)| d.as_secs_f64()).sum::<f64>() * 1e3, passes),
                None => (t.elapsed().as_secs_f64() * 1e3, Vec::new()),
            }
        })
        .collect();
    frames.sort_by(|a, b| a.0.total_cmp(&b.0));
    frames.swap_remove(FRAMES / 2)
}

fn markdown(
    caption: &str,
    rows: &[Row],
    base_ms: f64,
    adapter: &str,
    width: u32,
    height: u32,
    reference: u32,
) -> String {
    let mut s = format!(
        "{caption}, {width}x{height}, against the {reference}x{reference} \
         texture-space reference; {adapter}; base pass {base_ms:.1} ms.\n\n\
         | method | FLIP mean | relative RMSE | frame (ms) | x base pass | CPU setup (s) |\n\
         | --- | ---: | ---: | ---: | ---: | ---: |\n"
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {:.4} | {:.4} | {:.1} | {:.2} | {:.2} |\n",
            r.method, r.flip_mean, r.rmse, r.frame_ms, r.relative_time, r.cpu_setup_s
        ));
    }
    s
}
