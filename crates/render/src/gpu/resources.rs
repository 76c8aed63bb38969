//! GPU resources: buffers, textures with their mip chains, the tables, and the one bind group the
//! mesh passes share (its layout, its textures and samplers, placeholders for what a pass does not
//! read).

use super::Gpu;
use super::Table;
use crate::shading::Texture;
use wgpu::util::DeviceExt;

/// TSD's light maps where the device filters Rgba32Float ([`Gpu::light_map_format`]): HDR
/// irradiance, kernel size in alpha.
const LIGHT_MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
/// The shadow's opacity map of translucent casters: filterable everywhere.
pub(crate) const OPACITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// TSD's stretch map: per texel, how much wider than the light map's isotropic kernel the blur
/// is along u and along v.
pub(crate) const STRETCH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg16Float;

pub(crate) const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Tables (LUTs, zonal factors) are Rgba32Float where the device filters it (lavapipe and desktop
/// adapters, with `FLOAT32_FILTERABLE`), Rgba16Float elsewhere ([`Gpu::table_format`]).
const TABLE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

impl Gpu {
    /// Rgba32Float for tables where the device filters it, else Rgba16Float.
    pub(crate) fn table_format(&self) -> wgpu::TextureFormat {
        if self.device.features().contains(wgpu::Features::FLOAT32_FILTERABLE) {
            TABLE_FORMAT
        } else {
            wgpu::TextureFormat::Rgba16Float
        }
    }

    /// Rgba32Float for TSD's light maps where the device filters it, else Rgba16Float. Every
    /// blur pass rounds the map to its format, and a half float's rounding (lavapipe truncates)
    /// darkens it by about 2^-12 per pass: red, which goes through every pass of the widest
    /// Gaussians, lost 0.4 % more at 8 passes per Gaussian than at one on the sample head.
    pub(crate) fn light_map_format(&self) -> wgpu::TextureFormat {
        if self.device.features().contains(wgpu::Features::FLOAT32_FILTERABLE) {
            LIGHT_MAP_FORMAT
        } else {
            wgpu::TextureFormat::Rgba16Float
        }
    }

    pub(crate) fn buffer(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
    }

    pub(crate) fn texture(&self, label: &str, width: u32, height: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if format != DEPTH_FORMAT {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        self.attachment(label, width, height, format, usage)
    }

    /// A single-level 2-D texture that a pass draws into.
    fn attachment(
        &self,
        label: &str,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
        usage: wgpu::TextureUsages,
    ) -> wgpu::Texture {
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(width, height),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    }

    /// Upload `texture` as Rgba16Float with its full CPU-built mip chain.
    pub(crate) fn upload_texture(&self, label: &str, texture: &Texture) -> wgpu::Texture {
        let levels = texture.mip_chain();
        let data: Vec<u16> = levels
            .iter()
            .flat_map(|level| level.texels.iter().flatten())
            .map(|&v| half::f16::from_f32(v).to_bits())
            .collect();
        self.device.create_texture_with_data(
            &self.queue,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: extent(texture.width, texture.height),
                mip_level_count: levels.len() as u32,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytemuck::cast_slice(&data),
        )
    }

    pub(crate) fn depth_texture(&self, label: &str, width: u32, height: u32, sampled: bool) -> wgpu::Texture {
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if sampled {
            usage |= wgpu::TextureUsages::TEXTURE_BINDING;
        }
        self.attachment(label, width, height, DEPTH_FORMAT, usage)
    }

    /// An RGB table as an Rgba32Float texture without mips (sampled with `textureSampleLevel`).
    pub(crate) fn upload_table(&self, label: &str, table: &Table) -> wgpu::Texture {
        let data: Vec<f32> = table.texels.iter().flat_map(|t| [t[0], t[1], t[2], 1.0]).collect();
        self.upload_rgba32(label, table.width, table.height, &data)
    }

    pub(crate) fn upload_rgba32(&self, label: &str, width: u32, height: u32, data: &[f32]) -> wgpu::Texture {
        let format = self.table_format();
        let halves: Vec<u16>;
        let bytes: &[u8] = if format == TABLE_FORMAT {
            bytemuck::cast_slice(data)
        } else {
            halves = data.iter().map(|&v| half::f16::from_f32(v).to_bits()).collect();
            bytemuck::cast_slice(&halves)
        };
        self.device.create_texture_with_data(
            &self.queue,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: extent(width, height),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            bytes,
        )
    }
}

pub(crate) fn colour_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
    }
}

pub(crate) fn depth_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<f32>,
) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
        stencil_ops: None,
    }
}

pub(crate) fn extent(width: u32, height: u32) -> wgpu::Extent3d {
    wgpu::Extent3d { width, height, depth_or_array_layers: 1 }
}

pub(crate) fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let both = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
    let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    let float = wgpu::TextureSampleType::Float { filterable: true };
    let sampler = |binding, kind| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(kind),
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("base pass bind group layout"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: both,
                ty: wgpu::BindingType::Buffer {
                    // Storage, not uniform: see `globals` in common.wgsl (lavapipe's inlining).
                    ty: wgpu::BufferBindingType::Storage { read_only: true },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            texture(1, float),
            texture(2, float),
            sampler(3, wgpu::SamplerBindingType::Filtering),
            texture(4, float),
            texture(5, float),
            texture(6, float),
            texture(7, wgpu::TextureSampleType::Depth),
            sampler(8, wgpu::SamplerBindingType::Comparison),
            texture(9, float),
            sampler(10, wgpu::SamplerBindingType::Filtering),
            sampler(11, wgpu::SamplerBindingType::Filtering),
            texture(12, float),
            texture(13, float),
        ],
    })
}
