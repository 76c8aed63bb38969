//! Readback: a target copied into a mappable buffer (rows padded to wgpu's copy alignment),
//! mapped, and unpacked to linear f32 RGBA.

use super::{DEPTH_FORMAT, Gpu, GpuError, OutputFormat, Result, Target, extent};

/// A rendered image read back from the GPU.
#[derive(Debug, Clone, PartialEq)]
pub struct Rendered {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGBA, row 0 at the top (for [`OutputFormat::Srgb8`] the stored bytes decoded).
    pub pixels: Vec<[f32; 4]>,
    /// The sRGB-encoded RGBA8 bytes for [`OutputFormat::Srgb8`] (ready for PNG), else empty.
    pub srgb_bytes: Vec<u8>,
}

impl Gpu {
    /// Read `target` back as linear f32 RGBA (and sRGB bytes for [`OutputFormat::Srgb8`]).
    ///
    /// # Errors
    /// A wgpu validation error or a failed map.
    pub fn read(&self, target: &Target) -> Result<Rendered> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback encoder") });
        copy_to_buffer(&mut encoder, target);
        self.queue.submit([encoder.finish()]);
        self.pop_scope(scope, "readback")?;
        self.unpack_readback(target)
    }

    /// Maps the target's readback buffer (already filled by a submitted copy) and unpacks it.
    pub(crate) fn unpack_readback(&self, target: &Target) -> Result<Rendered> {
        let bytes = self.read_buffer(&target.readback)?;
        Ok(unpack(&bytes, target.width, target.height, target.format))
    }

    /// Map `buffer`, wait, and copy its bytes out.
    pub(crate) fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
        let (sender, receiver) = std::sync::mpsc::channel();
        buffer.map_async(wgpu::MapMode::Read, .., move |r| {
            let _ = sender.send(r);
        });
        let readback_error = |message: String| GpuError::Wgpu { stage: "readback", message };
        self.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| readback_error(e.to_string()))?;
        receiver.recv().map_err(|e| readback_error(e.to_string()))?.map_err(|e| readback_error(e.to_string()))?;
        let bytes = buffer.get_mapped_range(..).map_err(|e| readback_error(e.to_string()))?.to_vec();
        buffer.unmap();
        Ok(bytes)
    }
}

/// A mappable buffer that holds one `width` x `height` image of `format`, its rows padded to
/// `COPY_BYTES_PER_ROW_ALIGNMENT` (256 bytes). A target owns one, so reading frames back
/// allocates nothing per frame.
pub(crate) fn readback_buffer(device: &wgpu::Device, width: u32, height: u32, format: OutputFormat) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: padded_row_bytes(width, format) as u64 * height as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Copies the target's colour into its readback buffer.
fn copy_to_buffer(encoder: &mut wgpu::CommandEncoder, target: &Target) {
    encoder.copy_texture_to_buffer(
        target.color.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &target.readback,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded_row_bytes(target.width, target.format)),
                rows_per_image: Some(target.height),
            },
        },
        extent(target.width, target.height),
    );
}

/// Bytes per row of a readback buffer: the tight row rounded up to the copy alignment.
pub fn padded_row_bytes(width: u32, format: OutputFormat) -> u32 {
    let tight = width * format.bytes_per_pixel();
    tight.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

/// Strip the row padding and convert to linear f32 RGBA.
fn unpack(bytes: &[u8], width: u32, height: u32, format: OutputFormat) -> Rendered {
    let padded = padded_row_bytes(width, format) as usize;
    let tight = (width * format.bytes_per_pixel()) as usize;
    let rows: Vec<&[u8]> = (0..height as usize).map(|y| &bytes[y * padded..y * padded + tight]).collect();
    let mut srgb_bytes = Vec::new();
    let pixels = match format {
        OutputFormat::Hdr32 => rows
            .iter()
            .flat_map(|row| row.chunks_exact(16))
            .map(|px| std::array::from_fn(|c| f32::from_le_bytes(px[4 * c..4 * c + 4].try_into().unwrap())))
            .collect(),
        OutputFormat::Hdr16 => rows
            .iter()
            .flat_map(|row| row.chunks_exact(8))
            .map(|px| std::array::from_fn(|c| half::f16::from_le_bytes([px[2 * c], px[2 * c + 1]]).to_f32()))
            .collect(),
        OutputFormat::Srgb8 => {
            srgb_bytes = rows.concat();
            srgb_bytes.chunks_exact(4).map(|px| std::array::from_fn(|c| decode_srgb8(px[c], c == 3))).collect()
        }
    };
    Rendered { width, height, pixels, srgb_bytes }
}

/// An sRGB-encoded byte back to linear (alpha is stored linearly).
fn decode_srgb8(byte: u8, alpha: bool) -> f32 {
    let c = byte as f32 / 255.0;
    if alpha {
        c
    } else if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

impl Gpu {
    /// An offscreen colour target with its depth buffer.
    ///
    /// # Errors
    /// [`GpuError::BadOutputSize`] for a zero size or one above the device limit.
    pub fn create_target(&self, width: u32, height: u32, format: OutputFormat) -> Result<Target> {
        let limit = self.max_texture_side();
        if width == 0 || height == 0 || width > limit || height > limit {
            return Err(GpuError::BadOutputSize { width, height, limit });
        }
        Ok(Target {
            color: self.texture("base pass colour target", width, height, format.texture_format()),
            depth: self.texture("base pass depth", width, height, DEPTH_FORMAT),
            readback: readback_buffer(&self.device, width, height, format),
            width,
            height,
            format,
        })
    }
}
