//! What the skin effects hand the GPU ([`SkinSetup`]): which shader features a scene's passes
//! compile ([`Features`], the WGSL override constants), the tables the base pass samples, and the
//! settings of the key light's shadow map and of texture-space diffusion. [`super::build`] makes
//! one from a scene's graph; [`crate::gpu::Gpu::prepare_with`] uploads it and
//! [`crate::gpu::Gpu::draw`] runs the passes it asks for, and only those.

use glam::{Mat4, Vec3};

use crate::gpu::Table;
use crate::shading::Texture;

pub use super::graph::{DiffuseMode, Features};

/// The key light's shadow map.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowSetup {
    /// Index of the light (below the scene's light count).
    pub light: usize,
    /// Shadow map side.
    pub map_size: u32,
    /// Box filter side (odd), or with shadow scattering the taps on its disc.
    pub filter: u32,
    /// Normal-offset bias in texels.
    pub bias: f32,
    /// Shadow scattering's disc of taps on the receiver: its radius in mesh units (0 without).
    pub disc_radius: f32,
    /// The light's view-projection (wgpu depth 0..1).
    pub view_proj: Mat4,
    /// One shadow-map texel in mesh units (at the mesh's centre for a point light).
    pub texel: f32,
    /// Shadow scattering: the sharp penumbra's share of the filtered one.
    pub new_penumbra: f32,
    /// Translucent casters drawn into the map's opacity channels.
    pub translucent: Vec<TranslucentCaster>,
}

/// A translucent shadow caster as the shadow pass draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslucentCaster {
    /// Positions in object space.
    pub positions: Vec<[f32; 3]>,
    /// Triangle list.
    pub indices: Vec<u32>,
    /// Opacity per channel.
    pub opacity: [f32; 3],
}

/// Texture-space diffusion's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct TsdSetup {
    /// Light map side.
    pub size: u32,
    /// How the light map is blurred.
    pub kernel: crate::skin::options::TsdKernel,
    /// Blur passes (with the Gaussians, per Gaussian: `crate::skin::tsd::blur_count`).
    pub passes: u32,
    /// An artist's kernel map (red channel in [0, 1)), if any.
    pub kernel_map: Option<Texture>,
    /// (a, b) of radius = a * k + b, in texels of this light map.
    pub kernel_scale: [f32; 2],
    /// The derived kernel: Poisson radius in mm for flat skin (with the Gaussians, the radius
    /// every pass scales, [`crate::skin::tsd::GAUSSIANS_KERNEL_MM`]).
    pub kernel_mm: f32,
    /// Derived kernel: radius x (1 + gain * 1/r), mm.
    pub curvature_gain: f32,
    /// Back-face pre-pass bias.
    pub backface_bias: f32,
    /// Distance culling threshold in pixels of projected diameter.
    pub reuse_below_px: f32,
}

impl TsdSetup {
    /// The blur passes this setup runs.
    pub fn blurs(&self) -> u32 {
        crate::skin::tsd::blur_count(self.kernel, self.passes)
    }
}

pub use crate::skin::poisson::{
    MAX_KERNEL_TEXELS, POISSON, poisson_axis_variance, poisson_mean, poisson_second_moment,
};

/// Everything the skin effects add to a base-pass scene; the default adds nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinSetup {
    /// The pipeline's features.
    pub features: Features,
    /// Per vertex: 1/r in 1/mm and mm per UV unit (empty: zeros).
    pub vertex_skin: Vec<[f32; 2]>,
    /// Scale on 1/r.
    pub curvature_scale: f32,
    /// Millimetres per mesh unit.
    pub mm_per_unit: f32,
    /// Per-channel blend toward the blurred normal.
    pub normal_blur: Vec3,
    /// Mip level of the blurred normal sample.
    pub blur_mip: f32,
    /// The diffuse LUT (x: N.L, y: 1/r).
    pub diffuse_lut: Option<Table>,
    /// The shadow LUT (x: s, y: penumbra width in mm).
    pub shadow_lut: Option<Table>,
    /// The zonal table (x: 1/r, rows l = 0, 1, 2).
    pub zonal: Option<Table>,
    /// Environment radiance SH (9 RGB coefficients).
    pub sh: [[f32; 3]; 9],
    /// The key light's shadow map.
    pub shadow: Option<ShadowSetup>,
    /// Texture-space diffusion.
    pub tsd: Option<TsdSetup>,
    /// The scene's effects (what passes only an effect adds read, as the debug view).
    pub effects: Vec<crate::effect::Effect>,
    /// A light map given by the caller (the CPU reference), for [`DiffuseMode::LightMap`]
    /// without TSD passes.
    pub light_map: Option<Texture>,
}

impl SkinSetup {
    /// What decides this setup's passes (for a scene's setup, the same as its graph's).
    pub(crate) fn shape(&self) -> super::Shape {
        super::Shape {
            shadow_map: self.shadow.is_some(),
            translucent: self.shadow.as_ref().is_some_and(|s| !s.translucent.is_empty()),
            tsd_blurs: self.tsd.as_ref().map(TsdSetup::blurs),
            effects: self.effects.clone(),
        }
    }

    /// The passes the GPU runs for this setup, in order ([`super::PassList::of`]).
    pub fn passes(&self) -> super::PassList {
        super::PassList::of(&self.shape())
    }
}

impl Default for SkinSetup {
    fn default() -> Self {
        Self {
            features: Features::default(),
            vertex_skin: Vec::new(),
            curvature_scale: 1.0,
            mm_per_unit: 1.0,
            normal_blur: Vec3::ZERO,
            blur_mip: 0.0,
            diffuse_lut: None,
            shadow_lut: None,
            zonal: None,
            sh: [[0.0; 3]; 9],
            shadow: None,
            tsd: None,
            light_map: None,
            effects: Vec::new(),
        }
    }
}
