//! The viewer's offscreen path ([`ViewSession`]): it draws every effect the scene lists, and
//! switching one off (what its number key does) changes the image. Needs an adapter (lavapipe);
//! skips with a message without one.

use std::path::Path;

use skinkit_render::effect::Effect;
use skinkit_render::gpu::{Gpu, OutputFormat, Rendered};
use skinkit_render::load;
use skinkit_render::scene::Scene;
use skinkit_render::view::{Toggles, ViewSession};

const SIZE: u32 = 96;

fn changed(a: &Rendered, b: &Rendered) -> usize {
    a.srgb_bytes.iter().zip(&b.srgb_bytes).filter(|(x, y)| x.abs_diff(**y) > 2).count()
}

#[test]
fn toggling_one_effect_changes_the_frame() {
    let gpu = match Gpu::new() {
        Ok(gpu) => gpu,
        Err(e) => {
            eprintln!("skipping: {e}");
            return;
        }
    };
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/scenes/skin-compare.toml");
    let text = std::fs::read_to_string(&file).unwrap().replace(
        "effects = [\"preintegrated\", \"shadows\", \"shadow-scattering\"]",
        "effects = [\"shadows\", \"tsd\"]\n[tsd]\nsize = 256\npasses = 2",
    );
    let scene = Scene::parse(&text, &file).unwrap();
    assert_eq!(scene.effects, [Effect::Shadows, Effect::Tsd]);
    let loaded = load::load(&scene, SIZE, SIZE, gpu.max_texture_side()).unwrap();
    let camera = load::gpu_camera(&scene.cameras[0], SIZE, SIZE);
    let target = gpu.create_target(SIZE, SIZE, OutputFormat::Srgb8).unwrap();
    let mut session = ViewSession::new(scene.clone(), loaded);
    let mut toggles = Toggles::all_on(&scene);
    let all = session.frame(&gpu, &toggles, &camera, None, &target).unwrap();
    let lit = all.srgb_bytes.chunks_exact(4).filter(|p| p[..3].iter().any(|&c| c > 8)).count();
    assert!(lit > (SIZE * SIZE / 10) as usize, "the head covers {lit} pixels");
    for effect in [Effect::Shadows, Effect::Tsd] {
        toggles.flip(effect);
        let without = session.frame(&gpu, &toggles, &camera, None, &target).unwrap();
        assert!(changed(&all, &without) > 50, "{effect} off changed {} samples", changed(&all, &without));
        toggles.flip(effect);
    }
    // Back on: the same frame as before, from the cached preparation.
    let again = session.frame(&gpu, &toggles, &camera, None, &target).unwrap();
    assert_eq!(changed(&all, &again), 0);
}
