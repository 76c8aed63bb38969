//! A scene's textures and samplers and the bind group the mesh passes share: the maps, the
//! tables a scene's effects build (1x1 placeholders for the others, never sampled: their shader
//! branches are compiled out), and the views of what the passes write that later passes read.

use super::setup::SkinSetup;
use crate::gpu::{Gpu, Table};
use crate::shading::RenderInputs;

impl Gpu {
    /// Every texture and sampler the base bind group holds; tables a scene does not read are
    /// 1x1 placeholders (never sampled: their shader branches are compiled out).
    pub(crate) fn skin_textures(&self, inputs: &RenderInputs, skin: &SkinSetup) -> SceneTextures {
        let placeholder = || self.upload_rgba32("unused table", 1, 1, &[0.0, 0.0, 0.0, 1.0]);
        let table = |label, t: &Option<Table>| t.as_ref().map_or_else(placeholder, |t| self.upload_table(label, t));
        let clamp_sampler = |label, filter, lod_min_clamp| {
            self.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: filter,
                min_filter: filter,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                lod_min_clamp,
                ..Default::default()
            })
        };
        let repeat_sampler = |label, lod_min_clamp: f32| {
            self.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::Repeat,
                address_mode_v: wgpu::AddressMode::Repeat,
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                mipmap_filter: wgpu::MipmapFilterMode::Linear,
                lod_min_clamp,
                ..Default::default()
            })
        };
        let normal = self.upload_texture("normal map", &inputs.normal_map);
        let blur_mip = skin.blur_mip.clamp(0.0, (normal.mip_level_count() - 1) as f32);
        SceneTextures {
            normal,
            albedo: self.upload_texture("albedo", &inputs.albedo),
            diffuse_lut: table("diffuse LUT", &skin.diffuse_lut),
            shadow_lut: table("shadow LUT", &skin.shadow_lut),
            zonal: table("zonal table", &skin.zonal),
            kernel: match skin.tsd.as_ref().and_then(|t| t.kernel_map.as_ref()) {
                Some(map) => self.upload_texture("tsd kernel map", map),
                None => placeholder(),
            },
            light_map: skin
                .light_map
                .as_ref()
                .filter(|_| skin.tsd.is_none())
                .map(|m| self.upload_texture("light map", m)),
            shadow_placeholder: self.depth_texture("unused shadow map", 1, 1, true),
            map_sampler: repeat_sampler("map sampler", 0.0),
            blurred_sampler: repeat_sampler("blurred normal sampler", blur_mip),
            lut_sampler: clamp_sampler("table sampler", wgpu::FilterMode::Linear, 0.0),
            shadow_sampler: self.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("shadow compare sampler"),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                // Each tap compares bilinearly (a one-texel tent): the box of taps stays a ramp
                // across a straight edge, without the staircase of nearest compares.
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                compare: Some(wgpu::CompareFunction::LessEqual),
                ..Default::default()
            }),
            light_map_placeholder: placeholder(),
            opacity_placeholder: placeholder(),
        }
    }

    /// The base bind group; `shadow` and `light_map` are left as placeholders when `None` (the
    /// shadow pass must not sample the map it writes, nor the TSD passes the map they write).
    pub(crate) fn create_bind_group(
        &self,
        textures: &SceneTextures,
        uniforms: &wgpu::Buffer,
        shadow: Option<&wgpu::TextureView>,
        opacity: Option<&wgpu::TextureView>,
        light_map: Option<&wgpu::TextureView>,
    ) -> wgpu::BindGroup {
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let (normal, albedo) = (view(&textures.normal), view(&textures.albedo));
        let (diffuse_lut, shadow_lut, zonal, kernel) =
            (view(&textures.diffuse_lut), view(&textures.shadow_lut), view(&textures.zonal), view(&textures.kernel));
        let shadow_placeholder = view(&textures.shadow_placeholder);
        let light_map_placeholder = view(&textures.light_map_placeholder);
        let given_light_map = textures.light_map.as_ref().map(view);
        let light_map = light_map.or(given_light_map.as_ref()).unwrap_or(&light_map_placeholder);
        let shadow = shadow.unwrap_or(&shadow_placeholder);
        let opacity_placeholder = view(&textures.opacity_placeholder);
        let opacity = opacity.unwrap_or(&opacity_placeholder);
        let tex = |binding, view| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::TextureView(view) };
        let smp =
            |binding, sampler| wgpu::BindGroupEntry { binding, resource: wgpu::BindingResource::Sampler(sampler) };
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("base pass bind group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                tex(1, &normal),
                tex(2, &albedo),
                smp(3, &textures.map_sampler),
                tex(4, &diffuse_lut),
                tex(5, &shadow_lut),
                tex(6, &zonal),
                tex(7, shadow),
                smp(8, &textures.shadow_sampler),
                tex(9, light_map),
                smp(10, &textures.lut_sampler),
                smp(11, &textures.blurred_sampler),
                tex(12, &kernel),
                tex(13, opacity),
            ],
        })
    }
}

/// The textures and samplers of a scene's bind groups.
pub(crate) struct SceneTextures {
    pub(crate) normal: wgpu::Texture,
    pub(crate) albedo: wgpu::Texture,
    pub(crate) diffuse_lut: wgpu::Texture,
    pub(crate) shadow_lut: wgpu::Texture,
    pub(crate) zonal: wgpu::Texture,
    pub(crate) kernel: wgpu::Texture,
    pub(crate) light_map: Option<wgpu::Texture>,
    pub(crate) shadow_placeholder: wgpu::Texture,
    pub(crate) light_map_placeholder: wgpu::Texture,
    pub(crate) opacity_placeholder: wgpu::Texture,
    pub(crate) map_sampler: wgpu::Sampler,
    pub(crate) blurred_sampler: wgpu::Sampler,
    pub(crate) lut_sampler: wgpu::Sampler,
    pub(crate) shadow_sampler: wgpu::Sampler,
}
