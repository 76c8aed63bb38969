//! Headless wgpu: the machinery the passes of [`crate::pass`] run on, knowing none of them. The
//! device and its checks (`device`), buffers, textures, tables and the bind group layout the mesh
//! passes share (`resources`, `table`), the caches of pipelines and of shader modules and layouts
//! (`pipelines`), readback to linear f32 pixels (`readback`) and the timestamp queries around each
//! pass (`timing`). A scene's upload and the frame's encoder walking its passes are
//! [`crate::pass`]'s.
//!
//! Without a GPU, Mesa's lavapipe (software Vulkan) runs everything: set `WGPU_BACKEND=vulkan`.
//! [`Gpu::new`] reads the backends from `WGPU_BACKEND` (default: the native backends compiled in:
//! Vulkan, Metal, DX12; the GL backend is left out because GL on llvmpipe cannot render to or
//! filter Rgba32Float) and fails with [`GpuError::NoAdapter`], one sentence with the fix, when
//! nothing is found.
//!
//! Textures (normal map, albedo) are uploaded as Rgba16Float, filterable everywhere without the
//! `FLOAT32_FILTERABLE` feature, with mip chains built on the CPU by
//! [`crate::shading::Texture::mip_chain`] (unnormalised averages: the shader renormalises, so
//! distant skin does not sparkle). A texture larger than the device's `max_texture_dimension_2d`
//! is an error naming the limit ([`GpuError::TextureTooLarge`]): the caller decides whether to
//! downscale.

mod device;
mod pipelines;
mod readback;
mod resources;
mod table;
mod timing;

pub use device::quiet_vulkan_loader;
pub(crate) use pipelines::{MESH_BUFFERS, MeshPipeline, POSITION_BUFFER, depth_state};
pub use readback::{Rendered, padded_row_bytes};
pub(crate) use resources::{DEPTH_FORMAT, OPACITY_FORMAT, STRETCH_FORMAT, colour_attachment, depth_attachment, extent};
pub use table::Table;
pub(crate) use timing::{PassTimer, timestamp_writes};

use std::any::Any;
use std::sync::{Arc, Mutex};

/// What can go wrong on the GPU side.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GpuError {
    /// No adapter on the enabled backends.
    #[error(
        "no GPU or software Vulkan driver found (backends tried: {backends}): install Mesa's \
         lavapipe (`apt-get install mesa-vulkan-drivers`) and set WGPU_BACKEND=vulkan"
    )]
    NoAdapter {
        /// The backends that were enabled.
        backends: String,
    },
    /// The adapter refused a device.
    #[error("the {adapter} adapter refused to create a device: {message}")]
    Device {
        /// Adapter name.
        adapter: String,
        /// wgpu's message.
        message: String,
    },
    /// Too many lights or lobes for the pass's uniform arrays.
    #[error("{what}: {count} given, the base pass shades at most {max}")]
    TooMany {
        /// "lights" or "Lafortune lobes".
        what: &'static str,
        /// How many were given.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// An output size of zero or above the device limit.
    #[error("output size {width}x{height} is not within 1..={limit} (device max_texture_dimension_2d)")]
    BadOutputSize {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
        /// The device limit.
        limit: u32,
    },
    /// A texture larger than the device allows.
    #[error(
        "{name} texture is {width}x{height} but this device allows at most {limit}x{limit} \
         (max_texture_dimension_2d): downscale it first"
    )]
    TextureTooLarge {
        /// "normal map" or "albedo".
        name: &'static str,
        /// Texture width.
        width: u32,
        /// Texture height.
        height: u32,
        /// The device limit.
        limit: u32,
    },
    /// A texture whose texel count does not match its size.
    #[error("{name} texture says {width}x{height} but holds {count} texels")]
    BadTexture {
        /// "normal map" or "albedo".
        name: &'static str,
        /// Stated width.
        width: u32,
        /// Stated height.
        height: u32,
        /// Texels held.
        count: usize,
    },
    /// A mesh index pointing past the vertices, or no triangles.
    #[error("mesh has {vertices} vertices and {indices} indices: {problem}")]
    BadMesh {
        /// Vertex count.
        vertices: usize,
        /// Index count.
        indices: usize,
        /// What is wrong.
        problem: &'static str,
    },
    /// wgpu reported a validation or out-of-memory error, or the readback failed.
    #[error("wgpu error during {stage}: {message}")]
    Wgpu {
        /// What was being done.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
}

/// Result alias for this module.
pub type Result<T> = std::result::Result<T, GpuError>;

/// The offscreen colour target's format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutputFormat {
    /// Rgba16Float, linear HDR.
    Hdr16,
    /// Rgba32Float, linear HDR (for EXR).
    #[default]
    Hdr32,
    /// Rgba8UnormSrgb: tone-mapped LDR, sRGB-encoded by the target (for PNG).
    Srgb8,
}

impl OutputFormat {
    pub(crate) fn texture_format(self) -> wgpu::TextureFormat {
        match self {
            Self::Hdr16 => wgpu::TextureFormat::Rgba16Float,
            Self::Hdr32 => wgpu::TextureFormat::Rgba32Float,
            Self::Srgb8 => wgpu::TextureFormat::Rgba8UnormSrgb,
        }
    }

    fn bytes_per_pixel(self) -> u32 {
        match self {
            Self::Hdr16 => 8,
            Self::Hdr32 => 16,
            Self::Srgb8 => 4,
        }
    }

    /// The bytes one `width x height` frame holds at its peak, on the device and the host (a
    /// software adapter keeps both in main memory): the colour target, the depth buffer, the
    /// readback buffer and its mapped copy, the linear f32 RGBA pixels and, for
    /// [`OutputFormat::Srgb8`], the encoded bytes. Checked against the memory limit before the
    /// target is created (issue 15: a 16384x16384 render reached 9.5 GB).
    pub(crate) fn frame_bytes(self, width: u32, height: u32) -> u64 {
        let bpp = u64::from(self.bytes_per_pixel());
        let srgb = if self == Self::Srgb8 { 4 } else { 0 };
        let per_pixel = bpp + 4 + 2 * bpp + 16 + srgb;
        (u64::from(width) * u64::from(height)).saturating_mul(per_pixel)
    }
}

/// An offscreen colour target and depth buffer from [`Gpu::create_target`].
pub struct Target {
    pub(crate) color: wgpu::Texture,
    pub(crate) depth: wgpu::Texture,
    /// Where [`Gpu::read`] copies the colour to map it, reused frame after frame.
    pub(crate) readback: wgpu::Buffer,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) format: OutputFormat,
}

/// A headless device with a cache of the passes' pipelines, shader modules and layouts (each
/// built once, the first time a pass asks for it).
pub struct Gpu {
    adapter: wgpu::Adapter,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    /// The bind group layout the mesh passes share.
    pub(crate) layout: wgpu::BindGroupLayout,
    pub(crate) pipeline_layout: wgpu::PipelineLayout,
    /// Pipelines by the key their pass gives (pass, features, target format).
    pipelines: Mutex<Vec<(String, wgpu::RenderPipeline)>>,
    /// Shader modules and layouts by name ([`Gpu::shared`]).
    shared: Mutex<Vec<(&'static str, Arc<dyn Any + Send + Sync>)>>,
}

#[cfg(test)]
mod tests {
    use super::OutputFormat;

    #[test]
    fn a_frame_costs_its_target_depth_readback_and_pixels() {
        // Rgba32Float: 16 target + 4 depth + 2 x 16 buffer and mapped copy + 16 f32 pixels.
        assert_eq!(OutputFormat::Hdr32.frame_bytes(3, 2), 6 * (16 + 4 + 32 + 16));
        assert_eq!(OutputFormat::Srgb8.frame_bytes(1, 1), 4 + 4 + 8 + 16 + 4);
        // The largest output side neither overflows nor falls below the 9.5 GB measured there.
        assert!(OutputFormat::Hdr16.frame_bytes(16384, 16384) > 9_500_000_000);
        assert_eq!(OutputFormat::Hdr32.frame_bytes(u32::MAX, u32::MAX), u64::MAX, "saturates");
    }
}
