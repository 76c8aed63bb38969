//! One [`Gpu`] is a session: a second render of a scene on it compiles no shader and builds no
//! pipeline (shader modules are made once, in `Gpu::new`; pipelines once per key). Needs an
//! adapter (lavapipe); skips with a message without one.

use std::path::Path;

use skinkit_render::gpu::{Gpu, OutputFormat};
use skinkit_render::load;
use skinkit_render::pass::build;
use skinkit_render::pass::graph::PassGraph;
use skinkit_render::scene::Scene;

/// Everything `skinkit render` does for one image, from the scene file on.
fn render_once(gpu: &Gpu, file: &Path) -> Vec<u8> {
    let scene = Scene::load(file).unwrap();
    let loaded = load::load(&scene, 64, 64, gpu.max_texture_side()).unwrap();
    let graph = PassGraph::build(&scene);
    let skin = build::setup(&scene, &loaded, &graph).unwrap();
    let prepared = gpu.prepare_with(&loaded.inputs, &skin).unwrap();
    let target = gpu.create_target(64, 64, OutputFormat::Srgb8).unwrap();
    gpu.draw(&prepared, &target).unwrap();
    gpu.read(&target).unwrap().srgb_bytes
}

#[test]
fn the_second_render_of_a_scene_builds_no_pipeline() {
    let gpu = match Gpu::new() {
        Ok(gpu) => gpu,
        Err(e) => {
            eprintln!("skipping: {e}");
            return;
        }
    };
    assert_eq!(gpu.pipelines_built(), 0, "Gpu::new compiles shader modules, builds no pipeline");
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/scenes/skin-compare.toml");
    let first = render_once(&gpu, &file);
    let built = gpu.pipelines_built();
    // The shadow map's and the base pass's.
    assert_eq!(built, 2);
    let second = render_once(&gpu, &file);
    assert_eq!(gpu.pipelines_built(), built, "the second render built a pipeline");
    assert_eq!(first, second);
}
