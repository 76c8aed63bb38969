//! The viewer's offscreen path ([`ViewSession`]): it draws every effect the scene lists, and
//! switching one off (what its number key does) changes the image. Needs an adapter (lavapipe);
//! skips with a message without one.

use std::path::Path;

use skinkit_render::effect::Effect;
use skinkit_render::renderer::{Encoding, Frame as Rendered, FrameOptions, Renderer};
use skinkit_render::scene::Scene;
use skinkit_render::view::{Toggles, ViewSession};

const SIZE: u32 = 96;

fn changed(a: &Rendered, b: &Rendered) -> usize {
    a.srgb_bytes.iter().zip(&b.srgb_bytes).filter(|(x, y)| x.abs_diff(**y) > 2).count()
}

#[test]
fn toggling_one_effect_changes_the_frame() {
    let renderer = match Renderer::new() {
        Ok(renderer) => renderer,
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
    let camera = scene.cameras[0];
    let options = FrameOptions::new(SIZE, SIZE, Encoding::Display);
    let mut session = ViewSession::new(&renderer, scene.clone(), options).unwrap();
    let mut toggles = Toggles::all_on(&scene);
    let all = session.frame(&renderer, &toggles, &camera, None).unwrap();
    let lit = all.srgb_bytes.chunks_exact(4).filter(|p| p[..3].iter().any(|&c| c > 8)).count();
    assert!(lit > (SIZE * SIZE / 10) as usize, "the head covers {lit} pixels");
    for effect in [Effect::Shadows, Effect::Tsd] {
        toggles.flip(effect);
        let without = session.frame(&renderer, &toggles, &camera, None).unwrap();
        assert!(changed(&all, &without) > 50, "{effect} off changed {} samples", changed(&all, &without));
        toggles.flip(effect);
    }
    // Back on: the same frame as before, from the cached preparation.
    let again = session.frame(&renderer, &toggles, &camera, None).unwrap();
    assert_eq!(changed(&all, &again), 0);
}
