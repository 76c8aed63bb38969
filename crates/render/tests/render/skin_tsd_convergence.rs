//! Texture-space diffusion converges toward the exact texture-space reference: on the committed
//! skin scenes (the sample head of `skin-compare.toml` with the nose's shadow, and the 6 mm
//! sphere of `skin-sphere.toml`), its error does not grow with blur passes or with the light
//! map's size, and the profile's Gaussians per channel (the default kernel) beat Gosselin's
//! single kernel. Needs an adapter (lavapipe in CI); never skips.

use std::path::Path;

use skinkit_render::compare::{self, Method};
use skinkit_render::gpu::{Gpu, OutputFormat};
use skinkit_render::load::{self, Loaded};
use skinkit_render::pass::setup::SkinSetup;
use skinkit_render::scene::Scene;
use skinkit_render::shading::{RenderInputs, ToneCurve};
use skinkit_render::skin::options::TsdKernel;

/// The image side: enough pixels for the terminator and the shadow edge, cheap on lavapipe.
const SIDE: u32 = 256;

/// Linear radiance of `setup` drawn over `loaded`.
fn draw(gpu: &Gpu, inputs: &RenderInputs, setup: &SkinSetup) -> Vec<[f32; 4]> {
    let inputs = RenderInputs { tone: ToneCurve::None, ..inputs.clone() };
    let target = gpu.create_target(SIDE, SIDE, OutputFormat::Hdr32).unwrap();
    let prepared = gpu.prepare_with(&inputs, setup).unwrap_or_else(|e| panic!("{e}"));
    gpu.draw(&prepared, &target).unwrap();
    gpu.read(&target).unwrap().pixels
}

/// Relative RMSE of each method against the reference at 1024 texels, on `scene`.
fn errors(gpu: &Gpu, scene: &str, methods: &[Method]) -> Vec<f32> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scene = Scene::load(&root.join("samples/scenes").join(scene)).unwrap_or_else(|e| panic!("{e}"));
    let loaded: Loaded = load::load(&scene, SIDE, SIDE, gpu.max_texture_side()).unwrap_or_else(|e| panic!("{e}"));
    let setup = |m: &Method| m.setup(&scene, &loaded).unwrap_or_else(|e| panic!("{}: {e}", m.name()));
    let reference = draw(gpu, &loaded.inputs, &setup(&Method::Reference { size: 1024 }));
    methods.iter().map(|m| compare::rmse(&reference, &draw(gpu, &loaded.inputs, &setup(m)))).collect()
}

/// `later` is not above `first` by more than 5 % (plus a floor for lavapipe's rounding).
fn not_above(first: f32, later: f32) -> bool {
    later <= first * 1.05 + 2e-4
}

// Measured here (256x256 against the 1024 reference): the head with its shadow 0.0120, 0.0120,
// 0.0123, 0.0125 for 1, 2, 4, 8 passes and 0.0115, 0.0120, 0.0115 at 512, 1024, 2048 texels;
// the sphere 0.0171, 0.0162, 0.0156, 0.0154 and 0.0234, 0.0171, 0.0159; the single kernel
// 0.0149 and 0.0553.
#[test]
fn tsd_error_does_not_grow_with_passes_or_light_map_size() {
    let gpu = Gpu::new().unwrap_or_else(|e| panic!("{e}"));
    let tsd = |kernel, passes, size| Method::Tsd { kernel, passes, size };
    let mut methods: Vec<Method> = [1, 2, 4, 8].map(|p| tsd(TsdKernel::Gaussians, p, 1024)).to_vec();
    methods.extend([512, 2048].map(|s| tsd(TsdKernel::Gaussians, 1, s)));
    methods.push(tsd(TsdKernel::Single, 1, 1024));
    for scene in ["skin-compare.toml", "skin-sphere.toml"] {
        let e = errors(&gpu, scene, &methods);
        println!(
            "{scene}: passes 1, 2, 4, 8 at 1024: {:?}; 1 pass at 512, 2048: {:?}; single kernel {}",
            &e[..4],
            &e[4..6],
            e[6]
        );
        for (p, later) in [2, 4, 8].iter().zip(&e[1..4]) {
            assert!(not_above(e[0], *later), "{scene}: {p} passes {later} against one pass {}", e[0]);
        }
        // 512, 1024, 2048 in order.
        let by_size = [e[4], e[0], e[5]];
        for pair in by_size.windows(2) {
            assert!(not_above(pair[0], pair[1]), "{scene}: light-map sizes 512, 1024, 2048: {by_size:?}");
        }
        assert!(e[0] < e[6], "{scene}: the Gaussians ({}) must beat the single kernel ({})", e[0], e[6]);
    }
}
