//! The one uniform block of the mesh passes ([`Globals`], `Globals` in common.wgsl): the part
//! every pass reads ([`SceneUniforms`]), then each pass's own named struct, declared beside its
//! pass ([`super::base::BaseUniforms`], [`super::shadow::ShadowUniforms`], ...). One buffer and
//! one binding, written once per frame; [`uniform_layouts`] lists every struct's Rust layout for
//! the naga-reflection test (`tests/render/wgsl.rs`) to check against the WGSL.
//!
//! Why one block lists the mesh passes' parts: they are one shader module (`BASE_WGSL`), whose
//! `Globals` declares each part once, and one binding keeps that module's bind group shared by
//! every mesh pass. A pass with a module of its own (the blur, the debug view) owns its uniform
//! buffer instead and appears nowhere here; that is the way for a new pass.

use super::base::{self, BaseUniforms, LobeRaw};
use super::blur::BlurUniforms;
use super::light_map::{self, LightMapUniforms};
use super::setup::SkinSetup;
use super::shadow::{self, ShadowUniforms};
use super::tsd_prepass::{self, PrepassUniforms};
use super::{BASE_WGSL, BLUR_WGSL};
use crate::shading::{GreenAxis, LightKind, MAX_LIGHTS, RenderInputs};

/// One light as the shader reads it (`Light` in common.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct LightRaw {
    /// xyz: direction toward the light (w = 0) or position (w = 1).
    pub(crate) vector: [f32; 4],
    /// rgb: colour * intensity.
    pub(crate) radiance: [f32; 4],
}

/// What every mesh pass reads (`SceneUniforms` in common.wgsl).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct SceneUniforms {
    pub(crate) view_proj: [[f32; 4]; 4],
    pub(crate) eye: [f32; 3],
    pub(crate) exposure: f32,
    pub(crate) light_count: u32,
    pub(crate) green_down: u32,
    pub(crate) key_light: u32,
    pub(crate) mm_per_unit: f32,
    pub(crate) lights: [LightRaw; MAX_LIGHTS],
}

/// The uniform block of the mesh passes (832 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub(crate) struct Globals {
    pub(crate) scene: SceneUniforms,
    pub(crate) base: BaseUniforms,
    pub(crate) shadow: ShadowUniforms,
    pub(crate) prepass: PrepassUniforms,
    pub(crate) light_map: LightMapUniforms,
}

/// Bytes of the mesh passes' uniform block (camera, lights, lobes, each pass's settings).
pub const UNIFORM_BYTES: u64 = std::mem::size_of::<Globals>() as u64;

pub(crate) fn vec4(v: glam::Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// A light as the shader reads it.
pub(crate) fn light_raw(light: &crate::shading::Light) -> LightRaw {
    let vector = match light.kind {
        LightKind::Directional { toward } => vec4(toward, 0.0),
        LightKind::Point { position } => vec4(position, 1.0),
    };
    LightRaw { vector, radiance: vec4(light.color * light.intensity, 0.0) }
}

/// The uniform block for `inputs` with the skin settings of `skin`: each pass fills its part.
pub(crate) fn globals(inputs: &RenderInputs, skin: &SkinSetup) -> Globals {
    let mut lights = [LightRaw { vector: [0.0; 4], radiance: [0.0; 4] }; MAX_LIGHTS];
    for (raw, light) in lights.iter_mut().zip(&inputs.lights) {
        *raw = light_raw(light);
    }
    Globals {
        scene: SceneUniforms {
            view_proj: inputs.camera.view_proj.to_cols_array_2d(),
            eye: inputs.camera.eye.to_array(),
            exposure: inputs.exposure,
            light_count: inputs.lights.len().min(MAX_LIGHTS) as u32,
            green_down: (inputs.green == GreenAxis::Down) as u32,
            key_light: skin.shadow.as_ref().map_or(MAX_LIGHTS, |s| s.light) as u32,
            mm_per_unit: skin.mm_per_unit,
            lights,
        },
        base: base::uniforms(inputs, skin),
        shadow: shadow::uniforms(skin.shadow.as_ref()),
        prepass: tsd_prepass::uniforms(skin.tsd.as_ref()),
        light_map: light_map::uniforms(skin.tsd.as_ref()),
    }
}

/// The layout of one uniform struct as Rust writes it, to check against the WGSL that reads it
/// (the naga-reflection test in `tests/render/wgsl.rs`).
#[derive(Debug, Clone)]
pub struct UniformLayout {
    /// The WGSL source declaring the struct.
    pub source: &'static str,
    /// The struct's name in the WGSL.
    pub name: &'static str,
    /// `size_of` of the Rust struct.
    pub size: usize,
    /// Each field's name and `offset_of`, in declaration order.
    pub members: Vec<(&'static str, usize)>,
}

/// The layouts of every uniform struct the passes upload.
pub fn uniform_layouts() -> Vec<UniformLayout> {
    macro_rules! layout {
        ($source:expr, $name:literal, $ty:ty, [$($field:ident),* $(,)?]) => {
            UniformLayout {
                source: $source,
                name: $name,
                size: std::mem::size_of::<$ty>(),
                members: vec![$((stringify!($field), std::mem::offset_of!($ty, $field))),*],
            }
        };
    }
    vec![
        layout!(BASE_WGSL, "Light", LightRaw, [vector, radiance]),
        layout!(BASE_WGSL, "Lobe", LobeRaw, [cx, cy, cz, n]),
        layout!(
            BASE_WGSL,
            "SceneUniforms",
            SceneUniforms,
            [view_proj, eye, exposure, light_count, green_down, key_light, mm_per_unit, lights]
        ),
        layout!(
            BASE_WGSL,
            "BaseUniforms",
            BaseUniforms,
            [
                diffuse,
                lobe_count,
                normal_blur,
                vertex_specular,
                tone,
                curvature_scale,
                lut_scale,
                lut_offset,
                zonal_scale,
                zonal_offset,
                shadow_lut_scale,
                shadow_lut_offset,
                new_penumbra,
                pad0,
                pad1,
                pad2,
                lobes,
                sh
            ]
        ),
        layout!(
            BASE_WGSL,
            "ShadowUniforms",
            ShadowUniforms,
            [view_proj, inv_size, taps, texel, normal_offset, disc_radius, pad0, pad1, pad2]
        ),
        layout!(BASE_WGSL, "PrepassUniforms", PrepassUniforms, [backface_bias, pad0, pad1, pad2]),
        layout!(
            BASE_WGSL,
            "LightMapUniforms",
            LightMapUniforms,
            [size, kernel_mm, curvature_gain, max_radius, kernel_from_map, pad0, pad1, pad2]
        ),
        layout!(BASE_WGSL, "Globals", Globals, [scene, base, shadow, prepass, light_map]),
        layout!(
            BLUR_WGSL,
            "BlurUniforms",
            BlurUniforms,
            [
                inv_size,
                a,
                b,
                dilate,
                tap_variance,
                tap_mean,
                source_scale,
                irradiance_weight,
                axis_variance,
                pad0,
                pad1,
                radius_table
            ]
        ),
    ]
}
