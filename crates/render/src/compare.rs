//! Every way skinkit draws skin's diffuse light, side by side: Lambert, the blog's closed form,
//! our fit, the pre-integrated LUT at several sizes (and as the paper's ring defines it), texture-space diffusion at several blur
//! counts and light-map sizes, and the exact texture-space reference ([`crate::skin::reference`]) they
//! are all measured against. [`Method::setup`] turns one method and a scene into what the GPU
//! draws; [`flip_mean`] and [`rmse`] give the errors of a render against the reference's.
//!
//! Every method draws the scene's key light through the same shadow map (a scene with no
//! shadow-casting light draws none); the pre-integrated methods add shadow scattering, as the
//! paper's complete local model does.

use crate::effect::Effect;
use crate::load::{LoadError, Loaded};
use crate::pass::build;
use crate::pass::graph::PassGraph;
use crate::pass::setup::{DiffuseMode, SkinSetup};
use crate::scene::Scene;
use crate::skin::options::{Analytic, TsdKernel};
use crate::skin::profile::{Domain, Profile};
use crate::skin::reference;

/// One way of drawing the diffuse term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "method", rename_all = "kebab-case")]
pub enum Method {
    /// `max(0, N.L)`, no scattering.
    Lambert,
    /// The blog's closed-form curves.
    Blog,
    /// Our fit of the LUT.
    OwnFit,
    /// The pre-integrated LUT, `size x size`.
    Lut {
        /// Texels per side.
        size: u32,
    },
    /// The pre-integrated LUT as the paper defines it (the full ring, not the sphere).
    RingLut {
        /// Texels per side.
        size: u32,
    },
    /// Texture-space diffusion.
    Tsd {
        /// How the light map is blurred.
        kernel: TsdKernel,
        /// Blur passes (per Gaussian with [`TsdKernel::Gaussians`]).
        passes: u32,
        /// Light-map side.
        size: u32,
    },
    /// The exact texture-space convolution (CPU), its light map `size` texels wide.
    Reference {
        /// Light-map side.
        size: u32,
    },
}

impl Method {
    /// A short name for tables and file names, e.g. `lut-64`, `tsd-2x1024`.
    pub fn name(&self) -> String {
        match self {
            Self::Lambert => "lambert".into(),
            Self::Blog => "blog-fit".into(),
            Self::OwnFit => "own-fit".into(),
            Self::Lut { size } => format!("lut-{size}"),
            Self::RingLut { size } => format!("lut-ring-{size}"),
            Self::Tsd { kernel: TsdKernel::Gaussians, passes, size } => format!("tsd-{passes}x{size}"),
            Self::Tsd { kernel: TsdKernel::Single, passes, size } => format!("tsd-single-{passes}x{size}"),
            Self::Reference { size } => format!("reference-{size}"),
        }
    }

    /// The methods of the accuracy-against-time table: the reference at half its size (its own
    /// error), then the reference last.
    pub fn table(reference_size: u32) -> Vec<Method> {
        let mut methods = vec![Self::Lambert, Self::Blog, Self::OwnFit];
        methods.extend([32, 64, 256].map(|size| Self::Lut { size }));
        methods.push(Self::RingLut { size: 256 });
        // Passes at one size, sizes at one and at four passes: the error must not grow with either.
        let tsd = |kernel, passes, size| Self::Tsd { kernel, passes, size };
        methods.extend([1, 2, 4, 8].map(|passes| tsd(TsdKernel::Gaussians, passes, 1024)));
        for size in [512, 2048] {
            methods.extend([1, 4].map(|passes| tsd(TsdKernel::Gaussians, passes, size)));
        }
        // Gosselin's single kernel of the luminance variance, for comparison.
        methods.extend([1, 2, 4, 8].map(|passes| tsd(TsdKernel::Single, passes, 1024)));
        methods.push(Self::Reference { size: (reference_size / 2).max(1) });
        methods.push(Self::Reference { size: reference_size });
        methods
    }

    /// The scene with this method's effects (the scene's own `shadows` kept) and settings.
    pub fn scene(&self, scene: &Scene) -> Scene {
        let mut scene = scene.clone();
        let shadows = scene.has(Effect::Shadows);
        let ambient = scene.has(Effect::ShAmbient);
        let mut effects: Vec<Effect> = Vec::new();
        match self {
            Self::Lambert | Self::Reference { .. } => {}
            Self::Blog | Self::OwnFit => {
                effects.push(Effect::PreintegratedAnalytic);
                scene.skin.preintegrated.analytic = if *self == Self::Blog { Analytic::Blog } else { Analytic::Own };
            }
            Self::Lut { size } | Self::RingLut { size } => {
                effects.push(Effect::Preintegrated);
                scene.skin.preintegrated.lut_size = [*size, *size];
                if matches!(self, Self::RingLut { .. }) {
                    scene.skin.preintegrated.domain = Domain::Full;
                }
            }
            Self::Tsd { kernel, passes, size } => {
                effects.push(Effect::Tsd);
                scene.skin.tsd.kernel = *kernel;
                scene.skin.tsd.passes = *passes;
                scene.skin.tsd.size = *size;
            }
        }
        let preintegrated = matches!(self, Self::Blog | Self::OwnFit | Self::Lut { .. } | Self::RingLut { .. });
        if shadows {
            effects.push(Effect::Shadows);
            if preintegrated {
                effects.push(Effect::ShadowScattering);
            }
        }
        if ambient {
            effects.push(Effect::ShAmbient);
        }
        debug_assert!(crate::effect::check_rules(&effects, true).is_ok(), "{effects:?}");
        scene.effects = effects;
        scene
    }

    /// What the GPU draws for this method: the method's scene through the pass graph, or for the
    /// reference its CPU light map (baked with exact ray-cast shadows for the key light,
    /// scattered with the full profile, dilated across UV borders) drawn as the diffuse term.
    ///
    /// # Errors
    /// As [`crate::pass::build::setup`].
    pub fn setup(&self, scene: &Scene, loaded: &Loaded) -> Result<SkinSetup, LoadError> {
        let scene = self.scene(scene);
        let graph = PassGraph::build(&scene);
        let mut built = build::setup(&scene, loaded, &graph)?;
        if let Self::Reference { size } = self {
            let (bake, scattered) = reference_light_map(&scene, loaded, *size);
            built.light_map = Some(reference::dilate(&bake.to_texture(&scattered), 4));
            built.features.diffuse = DiffuseMode::LightMap;
        }
        Ok(built)
    }
}

/// The exact texture-space reference of `scene` at `size x size` texels: the bake (the key light,
/// the one the pass graph gives the shadow map, ray-cast; the others unshadowed) and its
/// scattered irradiance under the default profile.
pub fn reference_light_map(scene: &Scene, loaded: &Loaded, size: u32) -> (reference::ReferenceBake, Vec<[f32; 3]>) {
    let graph = PassGraph::build(scene);
    let key = graph.shadow.map(|s| s.light);
    let shadows: Vec<bool> = (0..loaded.inputs.lights.len()).map(|i| key == Some(i)).collect();
    let bake = reference::bake(&loaded.inputs, &shadows, scene.mm_per_unit, size);
    let scattered = reference::scatter(&bake, &Profile::default());
    (bake, scattered)
}

/// Mean FLIP (LDR, NVIDIA's nv-flip at 67 pixels per degree: a 0.7 m view of a 24-inch 4K
/// screen) of two sRGB-encoded RGBA8 images of one size.
pub fn flip_mean(reference: &[u8], test: &[u8], width: u32, height: u32) -> f32 {
    let rgb = |rgba: &[u8]| -> Vec<u8> { rgba.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect() };
    let (r, t) = (rgb(reference), rgb(test));
    let r = nv_flip::FlipImageRgb8::with_data(width, height, &r);
    let t = nv_flip::FlipImageRgb8::with_data(width, height, &t);
    let error = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean()
}

/// Root-mean-square difference of linear RGB over the pixels that are not black in either image
/// (the head, not the background), relative to the reference's mean over them.
pub fn rmse(reference: &[[f32; 4]], test: &[[f32; 4]]) -> f32 {
    let (mut sum, mut level, mut n) = (0.0f64, 0.0f64, 0usize);
    for (r, t) in reference.iter().zip(test) {
        if r[..3].iter().chain(&t[..3]).all(|&v| v == 0.0) {
            continue;
        }
        for c in 0..3 {
            sum += ((r[c] - t[c]) as f64).powi(2);
            level += r[c] as f64;
        }
        n += 3;
    }
    if n == 0 || level <= 0.0 {
        return 0.0;
    }
    ((sum / n as f64).sqrt() / (level / n as f64)) as f32
}
