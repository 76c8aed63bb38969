//! The pass order exists once: for every sample scene and every effect combination the rules
//! allow, the passes `--explain` lists ([`skinkit_render::pass::explain::plan`]) are the passes the GPU encoder ran, read
//! back from their timestamps, in the same order. Needs an adapter (lavapipe); skips with a
//! message without one or without timestamp queries.

use std::path::{Path, PathBuf};

use skinkit_render::effect::{self, Effect};
use skinkit_render::gpu::{Gpu, OutputFormat};
use skinkit_render::load;
use skinkit_render::pass::build;
use skinkit_render::pass::graph::PassGraph;
use skinkit_render::scene::Scene;

const SIZE: u32 = 48;

fn samples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/scenes")
}

fn gpu() -> Option<Gpu> {
    match Gpu::new() {
        Ok(gpu) if gpu.has_timestamps() => Some(gpu),
        Ok(_) => {
            eprintln!("skipping: the adapter has no timestamp queries");
            None
        }
        Err(e) => {
            eprintln!("skipping: {e}");
            None
        }
    }
}

/// Renders `scene` once with timestamps and checks the passes that ran against the plan's.
fn check(gpu: &Gpu, scene: &Scene, what: &str) {
    let loaded = load::load(scene, SIZE, SIZE, gpu.max_texture_side()).unwrap_or_else(|e| panic!("{what}: {e}"));
    let graph = PassGraph::build(scene);
    let plan = skinkit_render::pass::explain::plan(scene, &loaded, &graph, SIZE, SIZE, OutputFormat::Srgb8);
    let explained: Vec<String> = plan.passes.iter().map(|p| p.name.clone()).collect();
    let skin = build::setup(scene, &loaded, &graph).unwrap_or_else(|e| panic!("{what}: {e}"));
    let prepared = gpu.prepare_with(&loaded.inputs, &skin).unwrap_or_else(|e| panic!("{what}: {e}"));
    let target = gpu.create_target(SIZE, SIZE, OutputFormat::Srgb8).unwrap();
    let timed = gpu.draw_timed_passes(&prepared, &target).unwrap().expect("the adapter has timestamps");
    let ran: Vec<String> = timed.iter().map(|(name, _)| name.clone()).collect();
    assert_eq!(ran, explained, "{what}");
    assert_eq!(prepared.passes(), &graph.passes, "{what}");
    // What the passes read and write, as --explain names it, is a resource of the plan; what
    // they allocated for each other is written by one of them.
    let planned: Vec<&str> = plan.resources.iter().map(|r| r.name.as_str()).collect();
    for pass in &plan.passes {
        for name in pass.reads.iter().chain(&pass.writes) {
            assert!(planned.contains(&name.as_str()), "{what}: {} names {name:?}, not in {planned:?}", pass.name);
        }
    }
    for name in prepared.resource_names() {
        assert!(plan.passes.iter().any(|p| p.writes.iter().any(|w| w == name)), "{what}: no pass writes {name:?}");
    }
    assert!(timed.iter().map(|(_, d)| *d).sum::<std::time::Duration>() > std::time::Duration::ZERO, "{what}");
}

/// A copy of skin-compare.toml with `effects`, a sky for `sh-ambient`, small TSD maps and,
/// with `lens`, a translucent caster.
fn combination(effects: &[Effect], lens: Option<&Path>) -> Scene {
    let file = samples().join("skin-compare.toml");
    let text = std::fs::read_to_string(&file).unwrap();
    let list: Vec<String> = effects.iter().map(|e| format!("\"{e}\"")).collect();
    let mut text: String = text
        .lines()
        .map(|l| if l.starts_with("effects = ") { format!("effects = [{}]", list.join(", ")) } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n");
    text = text.replacen("[[light]]", "[environment]\nsky = [0.3, 0.3, 0.4]\nground = [0.1, 0.1, 0.1]\n\n[[light]]", 1);
    text.push_str("\n[tsd]\nsize = 128\npasses = 2\n");
    if let Some(lens) = lens {
        text.push_str(&format!("\n[[translucent]]\nmesh = \"{}\"\nopacity = [0.5, 0.3, 0.2]\n", lens.display()));
    }
    Scene::parse(&text, &file).unwrap_or_else(|e| panic!("{effects:?}: {e}"))
}

#[test]
fn every_allowed_effect_combination_runs_the_passes_explain_lists() {
    let Some(gpu) = gpu() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let lens = tmp.path().join("lens.obj");
    std::fs::write(
        &lens,
        "v -30 -30 120\nv 30 -30 120\nv 30 30 120\nv -30 30 120\nvt 0 0\nf 1/1 2/1 3/1\nf 1/1 3/1 4/1\n",
    )
    .unwrap();
    let combinations = effect::allowed_combinations();
    assert_eq!(combinations.len(), 48);
    for effects in &combinations {
        check(&gpu, &combination(effects, None), &format!("{effects:?}"));
        // The debug view redraws the colour whatever drew the shadows: once is enough.
        if effects.contains(&Effect::Shadows) && !effects.contains(&Effect::DebugFrames) {
            check(&gpu, &combination(effects, Some(&lens)), &format!("{effects:?} with a translucent caster"));
        }
    }
}

#[test]
fn every_sample_scene_runs_the_passes_explain_lists() {
    let Some(gpu) = gpu() else { return };
    let mut files: Vec<PathBuf> = std::fs::read_dir(samples())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for file in files {
        let mut scene = Scene::load(&file).unwrap_or_else(|e| panic!("{e}"));
        if scene.normal_map.as_ref().is_some_and(|m| !m.path.exists()) {
            // A fresh clone has no demo output: the graph does not depend on the map.
            eprintln!("{}: its normal map is not made yet; checking the graph without it", file.display());
            scene.normal_map = None;
        }
        check(&gpu, &scene, &file.display().to_string());
    }
}
