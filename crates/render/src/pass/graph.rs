//! The pass graph: what a scene's effects and lights build, decided once per render.
//!
//! [`PassGraph::build`] turns the scene's [`Effect`]s and lights into the base pass's shader
//! features (each effect a WGSL override, compiled out when absent), which light draws the one
//! shadow map (the first with `shadows = true`, and only when `shadows` is listed) and at which
//! size, which tables are built (the diffuse LUT only for `preintegrated`, the shadow LUT only for
//! `shadow-scattering`, the zonal table only for `sh-ambient` over a pre-integrated diffuse), and
//! the frame's passes (`PassList::of`, the one list, which the GPU encoder, its timestamps
//! and `--explain` walk). What was asked and cannot be built (a `shadows` effect with no
//! shadow-casting light) is a note, never a silent omission.

use crate::effect::Effect;
use crate::scene::Scene;
use crate::skin::options::{Analytic, CurvatureSource};

/// The key light's shadow map, its size and filter decided once.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ShadowMapPlan {
    /// Index of the light that draws it.
    pub light: usize,
    /// Side in texels.
    pub size: u32,
    /// Box filter side, or with shadow scattering the taps on its disc.
    pub filter: u32,
}

/// Texture-space diffusion's light maps.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TsdPlan {
    /// Light map side in texels.
    pub size: u32,
    /// How the light map is blurred.
    pub kernel: crate::skin::options::TsdKernel,
    /// Blur passes.
    pub blurs: u32,
}

/// What a scene's effects and lights decide.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PassGraph {
    /// The base pass's shader features.
    pub features: Features,
    /// The key light's shadow map, if one is drawn.
    pub shadow: Option<ShadowMapPlan>,
    /// Whether the diffuse LUT is built (read by the base pass).
    pub diffuse_lut: bool,
    /// Whether the shadow-scattering LUT is built.
    pub shadow_lut: bool,
    /// Whether the skin's zonal table is built (SH ambient with a pre-integrated diffuse).
    pub zonal_table: bool,
    /// Whether per-vertex curvature is computed from the mesh.
    pub vertex_curvature: bool,
    /// Texture-space diffusion, if it runs.
    pub tsd: Option<TsdPlan>,
    /// The passes, in execution order.
    pub passes: super::PassList,
    /// Why something asked for is not built (no shadow-casting light, extra shadow lights).
    pub notes: Vec<String>,
}

impl PassGraph {
    /// The graph of `scene`: only what its effects and lights ask for.
    pub fn build(scene: &Scene) -> PassGraph {
        let mut notes = Vec::new();
        let pre = &scene.skin.preintegrated;
        let diffuse = diffuse_mode(scene);
        let key_light = key_light(scene, &mut notes);
        let shadows = key_light.is_some();
        let shadow_scattering = shadows && scene.has(Effect::ShadowScattering);
        let translucent_shadows = shadows && !scene.translucent.is_empty();
        if !shadows && !scene.translucent.is_empty() {
            notes.push("[[translucent]] casters tint only the key light's shadow map, and none is drawn".into());
        }
        let sh_ambient = scene.has(Effect::ShAmbient);
        let derivative = diffuse.reads_curvature() && pre.curvature == CurvatureSource::Derivative;
        let zonal_table = sh_ambient && diffuse.reads_curvature();
        let tsd = (diffuse == DiffuseMode::LightMap).then_some(TsdPlan {
            size: scene.skin.tsd.size,
            kernel: scene.skin.tsd.kernel,
            blurs: crate::skin::tsd::blur_count(scene.skin.tsd.kernel, scene.skin.tsd.passes),
        });
        let vertex_curvature = (diffuse.reads_curvature() && !derivative) || zonal_table || tsd.is_some();
        let shadow = key_light.map(|light| {
            let options = &scene.skin.shadow;
            match shadow_scattering {
                true => ShadowMapPlan { light, size: options.map_size, filter: options.scatter_taps },
                false => ShadowMapPlan { light, size: options.map_size, filter: options.filter },
            }
        });
        PassGraph {
            features: Features {
                diffuse,
                derivative_curvature: derivative,
                sh_ambient,
                shadows,
                shadow_scattering,
                translucent_shadows,
            },
            shadow,
            diffuse_lut: diffuse == DiffuseMode::Lut,
            shadow_lut: shadow_scattering,
            zonal_table,
            vertex_curvature,
            tsd,
            passes: super::PassList::of(&super::Shape {
                shadow_map: shadows,
                translucent: translucent_shadows,
                tsd_blurs: tsd.map(|t| t.blurs),
                effects: scene.effects.clone(),
            }),
            notes,
        }
    }

    /// The pass names, in order.
    pub fn pass_names(&self) -> Vec<String> {
        self.passes.names()
    }
}

fn diffuse_mode(scene: &Scene) -> DiffuseMode {
    let decider = scene.effects.iter().copied().find(|e| e.decides_diffuse());
    match decider {
        Some(Effect::Preintegrated) => DiffuseMode::Lut,
        Some(Effect::PreintegratedAnalytic) => match scene.skin.preintegrated.analytic {
            Analytic::Own => DiffuseMode::OwnFit,
            Analytic::Blog => DiffuseMode::Blog,
        },
        Some(Effect::Tsd) => DiffuseMode::LightMap,
        _ => DiffuseMode::Lambert,
    }
}

/// The light that draws the shadow map, with a note for every light whose request is not met.
fn key_light(scene: &Scene, notes: &mut Vec<String>) -> Option<usize> {
    let casters: Vec<usize> = scene.lights.iter().enumerate().filter(|(_, l)| l.shadows).map(|(i, _)| i).collect();
    let listed = scene.has(Effect::Shadows);
    match (listed, casters.first()) {
        (true, Some(&key)) => {
            for &other in &casters[1..] {
                notes.push(format!("light[{other}] asks for shadows: one shadow map is drawn, for light[{key}]"));
            }
            Some(key)
        }
        (true, None) => {
            notes.push(format!(
                "effect `{}`: no light has `shadows = true`, so no shadow map is drawn",
                Effect::Shadows
            ));
            None
        }
        (false, _) => {
            for &i in &casters {
                notes.push(format!(
                    "light[{i}] asks for shadows but `effects` does not list `{}`: drawn unshadowed",
                    Effect::Shadows
                ));
            }
            None
        }
    }
}
/// Where the base pass takes its diffuse term from (the `DIFFUSE_MODE` override).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DiffuseMode {
    /// `max(0, N.L)`.
    #[default]
    Lambert,
    /// The pre-integrated LUT D(N.L, 1/r) with per-channel normals.
    Lut,
    /// The blog's closed-form curves.
    Blog,
    /// Our fit to the LUT.
    OwnFit,
    /// A light map in texture space (TSD's blurred one, or the CPU reference).
    LightMap,
}

impl DiffuseMode {
    fn code(self) -> f64 {
        match self {
            Self::Lambert => 0.0,
            Self::Lut => 1.0,
            Self::Blog => 2.0,
            Self::OwnFit => 3.0,
            Self::LightMap => 4.0,
        }
    }

    /// Whether the mode reads 1/r.
    pub(crate) fn reads_curvature(self) -> bool {
        matches!(self, Self::Lut | Self::Blog | Self::OwnFit)
    }
}

/// The shader features of one base-pass pipeline: every combination compiles its own pipeline,
/// with what it does not use folded away.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, serde::Serialize)]
pub struct Features {
    /// The diffuse term.
    pub diffuse: DiffuseMode,
    /// 1/r from screen-space derivatives instead of the vertex attribute.
    pub derivative_curvature: bool,
    /// Order-2 SH ambient light.
    pub sh_ambient: bool,
    /// The key light through its shadow map.
    pub shadows: bool,
    /// The shadow-scattering LUT on the key light's penumbra.
    pub shadow_scattering: bool,
    /// Translucent casters tint the key light (the shadow map's opacity channels).
    pub translucent_shadows: bool,
}

impl Features {
    /// The pipeline-overridable constants of the mesh passes' WGSL (`pass/common.wgsl`).
    pub fn constants(&self) -> [(&'static str, f64); 6] {
        let flag = |b: bool| if b { 1.0 } else { 0.0 };
        [
            ("DIFFUSE_MODE", self.diffuse.code()),
            ("CURVATURE_MODE", flag(self.derivative_curvature)),
            ("SH_AMBIENT", flag(self.sh_ambient)),
            ("SHADOWS", flag(self.shadows)),
            ("SHADOW_SCATTERING", flag(self.shadow_scattering)),
            ("TRANSLUCENT_SHADOWS", flag(self.translucent_shadows)),
        ]
    }
}
