//! Headless wgpu: the device, offscreen targets, the base pass of `shaders/base.wgsl` (Haro et al.
//! 2001, section 5, per-pixel on today's hardware) and readback to linear f32 pixels.
//!
//! Without a GPU, Mesa's lavapipe (software Vulkan) runs everything: set `WGPU_BACKEND=vulkan`.
//! [`Gpu::new`] reads the backends from `WGPU_BACKEND` (default: the native backends compiled in:
//! Vulkan, Metal, DX12; the GL backend is left out because GL on llvmpipe cannot render to or
//! filter Rgba32Float) and fails with [`GpuError::NoAdapter`], one sentence with the fix, when
//! nothing is found.
//!
//! Textures (normal map, albedo) are uploaded as Rgba16Float, filterable everywhere without the
//! `FLOAT32_FILTERABLE` feature, with mip chains built on the CPU by [`Texture::mip_chain`]
//! (unnormalised averages: the shader renormalises, so distant skin does not sparkle). A texture
//! larger than the device's `max_texture_dimension_2d` is an error naming the limit
//! ([`GpuError::TextureTooLarge`]): the caller decides whether to downscale.

use crate::shading::{
    GreenAxis, LightKind, MAX_LIGHTS, MAX_LOBES, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex,
};
use std::sync::Mutex;
use wgpu::util::DeviceExt;

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
    fn texture_format(self) -> wgpu::TextureFormat {
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
}

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

/// A scene uploaded to the GPU by [`Gpu::prepare`], ready for [`Gpu::draw`].
pub struct PreparedScene {
    globals: Globals,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    background: [f32; 4],
}

impl PreparedScene {
    /// Moves the camera: the next [`Gpu::draw`] uses `camera` (nothing is re-uploaded but the
    /// uniform block, which every draw writes anyway).
    pub fn set_camera(&mut self, camera: &crate::shading::Camera) {
        self.globals.view_proj = camera.view_proj.to_cols_array_2d();
        self.globals.eye = vec4(camera.eye, self.globals.eye[3]);
    }

    /// Replaces light `index` (below the scene's light count) for the next [`Gpu::draw`].
    pub fn set_light(&mut self, index: usize, light: &crate::shading::Light) {
        if index < self.globals.counts[0] as usize {
            self.globals.lights[index] = light_raw(light);
        }
    }
}

/// An offscreen colour target and depth buffer from [`Gpu::create_target`].
pub struct Target {
    color: wgpu::Texture,
    depth: wgpu::Texture,
    width: u32,
    height: u32,
    format: OutputFormat,
}

/// A headless device with the base pass.
pub struct Gpu {
    adapter: wgpu::Adapter,
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    pipeline_layout: wgpu::PipelineLayout,
    shader: wgpu::ShaderModule,
    pipelines: Mutex<Vec<(OutputFormat, wgpu::RenderPipeline)>>,
}

/// The WGSL source of the base pass.
pub const BASE_WGSL: &str = include_str!("../shaders/base.wgsl");

/// One light as the shader reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LightRaw {
    vector: [f32; 4],
    radiance: [f32; 4],
}

/// One lobe as the shader reads it.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct LobeRaw {
    cx: [f32; 4],
    cy: [f32; 4],
    cz: [f32; 4],
    n: [f32; 4],
}

/// The `Globals` uniform of base.wgsl (512 bytes).
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Globals {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    diffuse: [f32; 4],
    counts: [u32; 4],
    options: [u32; 4],
    lights: [LightRaw; MAX_LIGHTS],
    lobes: [LobeRaw; MAX_LOBES],
}

/// Bytes of the base pass's uniform block (camera, lights, lobes, options).
pub const UNIFORM_BYTES: u64 = std::mem::size_of::<Globals>() as u64;

impl Gpu {
    /// Open the first adapter on the backends named by `WGPU_BACKEND` (or the native ones).
    ///
    /// # Errors
    /// [`GpuError::NoAdapter`] when no adapter exists, [`GpuError::Device`] when it refuses.
    pub fn new() -> Result<Self> {
        let desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        let backends = backend_names(desc.backends);
        let instance = wgpu::Instance::new(desc);
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
            ..Default::default()
        };
        let adapter =
            pollster::block_on(instance.request_adapter(&options)).map_err(|_| GpuError::NoAdapter { backends })?;
        let device_desc = wgpu::DeviceDescriptor {
            label: Some("skinkit device"),
            // Timestamps where the adapter has them (lavapipe does): per-pass GPU times.
            required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
            required_limits: adapter.limits(),
            ..Default::default()
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&device_desc))
            .map_err(|e| GpuError::Device { adapter: adapter.get_info().name, message: e.to_string() })?;
        let layout = bind_group_layout(&device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("base pass layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("base.wgsl"),
            source: wgpu::ShaderSource::Wgsl(BASE_WGSL.into()),
        });
        Ok(Self { adapter, device, queue, layout, pipeline_layout, shader, pipelines: Mutex::new(Vec::new()) })
    }

    /// The adapter's name and backend, e.g. "llvmpipe (LLVM 19.1.7, 256 bits) (Vulkan)".
    pub fn adapter_name(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    /// The largest texture side the device accepts.
    pub fn max_texture_side(&self) -> u32 {
        self.device.limits().max_texture_dimension_2d
    }

    /// Render `inputs` at `width` x `height` into `format` and read the pixels back:
    /// [`Gpu::prepare`], [`Gpu::create_target`], [`Gpu::draw`] and [`Gpu::read`] in one call.
    ///
    /// # Errors
    /// Bad sizes, too many lights or lobes, textures above the device limit, an invalid mesh, or
    /// a wgpu validation error.
    pub fn render(&self, inputs: &RenderInputs, width: u32, height: u32, format: OutputFormat) -> Result<Rendered> {
        let target = self.create_target(width, height, format)?;
        let scene = self.prepare(inputs)?;
        self.draw(&scene, &target)?;
        self.read(&target)
    }

    /// Upload a scene: mesh buffers, textures with their mip chains, uniforms, bind group.
    ///
    /// # Errors
    /// Too many lights or lobes, textures above the device limit, an invalid mesh, or a wgpu
    /// validation error.
    pub fn prepare(&self, inputs: &RenderInputs) -> Result<PreparedScene> {
        self.check(inputs)?;
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let globals = globals(inputs);
        let uniforms = self.buffer(
            "base pass globals",
            bytemuck::bytes_of(&globals),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let bind_group = self.create_bind_group(inputs, &uniforms);
        let vertices = self.buffer("vertices", bytemuck::cast_slice(&inputs.vertices), wgpu::BufferUsages::VERTEX);
        let indices = self.buffer("indices", bytemuck::cast_slice(&inputs.indices), wgpu::BufferUsages::INDEX);
        self.pop_scope(scope, "scene upload")?;
        Ok(PreparedScene {
            globals,
            uniforms,
            bind_group,
            vertices,
            indices,
            index_count: inputs.indices.len() as u32,
            background: inputs.background,
        })
    }

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
            width,
            height,
            format,
        })
    }

    /// Draw the base pass of `scene` into `target`, submit, and wait for the GPU to finish.
    ///
    /// # Errors
    /// A wgpu validation error or a failed wait.
    pub fn draw(&self, scene: &PreparedScene, target: &Target) -> Result<()> {
        self.encode_and_submit(scene, target, None)
    }

    /// [`Gpu::draw`] with GPU timestamps around the pass: the pass's GPU time, or `None` when the
    /// adapter has no `TIMESTAMP_QUERY` feature.
    ///
    /// # Errors
    /// A wgpu validation error, a failed wait or a failed readback of the timestamps.
    pub fn draw_timed(&self, scene: &PreparedScene, target: &Target) -> Result<Option<std::time::Duration>> {
        if !self.has_timestamps() {
            self.draw(scene, target)?;
            return Ok(None);
        }
        let timer = PassTimer::new(&self.device);
        self.encode_and_submit(scene, target, Some(&timer))?;
        let bytes = self.read_buffer(&timer.readback)?;
        let ticks: [u64; 2] = std::array::from_fn(|i| u64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap()));
        let nanos = ticks[1].saturating_sub(ticks[0]) as f64 * self.queue.get_timestamp_period() as f64;
        Ok(Some(std::time::Duration::from_nanos(nanos as u64)))
    }

    fn encode_and_submit(&self, scene: &PreparedScene, target: &Target, timer: Option<&PassTimer>) -> Result<()> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut globals = scene.globals;
        globals.options[0] = tone_code(target_curve(target.format, globals.options[0]));
        self.queue.write_buffer(&scene.uniforms, 0, bytemuck::bytes_of(&globals));
        let pipeline = self.pipeline(target.format);
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("base pass encoder") });
        {
            let timestamps = timer.map(|t| wgpu::RenderPassTimestampWrites {
                query_set: &t.queries,
                beginning_of_pass_write_index: Some(0),
                end_of_pass_write_index: Some(1),
            });
            let mut pass = begin_pass(&mut encoder, &target.color, &target.depth, scene.background, timestamps);
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &scene.bind_group, &[]);
            pass.set_vertex_buffer(0, scene.vertices.slice(..));
            pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..scene.index_count, 0, 0..1);
        }
        if let Some(t) = timer {
            encoder.resolve_query_set(&t.queries, 0..2, &t.resolve, 0);
            encoder.copy_buffer_to_buffer(&t.resolve, 0, &t.readback, 0, 16);
        }
        self.queue.submit([encoder.finish()]);
        self.pop_scope(scope, "the base pass")?;
        self.wait()
    }

    /// Read `target` back as linear f32 RGBA (and sRGB bytes for [`OutputFormat::Srgb8`]).
    ///
    /// # Errors
    /// A wgpu validation error or a failed map.
    pub fn read(&self, target: &Target) -> Result<Rendered> {
        let (width, height, format) = (target.width, target.height, target.format);
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback encoder") });
        let readback = self.copy_to_buffer(&mut encoder, &target.color, width, height, format);
        self.queue.submit([encoder.finish()]);
        self.pop_scope(scope, "readback")?;
        let bytes = self.read_buffer(&readback)?;
        Ok(unpack(&bytes, width, height, format))
    }

    /// Whether [`Gpu::draw_timed`] can measure GPU time (the `TIMESTAMP_QUERY` feature).
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Whether the adapter can filter Rgba32Float textures (lavapipe can; WebGPU needs the
    /// `FLOAT32_FILTERABLE` feature for it, which is why maps are uploaded as Rgba16Float).
    pub fn rgba32float_filterable(&self) -> bool {
        self.adapter
            .get_texture_format_features(wgpu::TextureFormat::Rgba32Float)
            .flags
            .contains(wgpu::TextureFormatFeatureFlags::FILTERABLE)
    }

    fn pop_scope(&self, scope: wgpu::ErrorScopeGuard, stage: &'static str) -> Result<()> {
        match pollster::block_on(scope.pop()) {
            Some(error) => Err(GpuError::Wgpu { stage, message: error.to_string() }),
            None => Ok(()),
        }
    }

    fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Wgpu { stage: "waiting for the GPU", message: e.to_string() })
    }

    fn check(&self, inputs: &RenderInputs) -> Result<()> {
        let limit = self.max_texture_side();
        check_count("lights", inputs.lights.len(), MAX_LIGHTS)?;
        check_count("Lafortune lobes", inputs.brdf.lobes.len(), MAX_LOBES)?;
        check_texture("normal map", &inputs.normal_map, limit)?;
        check_texture("albedo", &inputs.albedo, limit)?;
        check_mesh(&inputs.vertices, &inputs.indices)
    }

    fn buffer(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.device.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents, usage })
    }

    fn texture(&self, label: &str, width: u32, height: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if format != DEPTH_FORMAT {
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
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
    fn upload_texture(&self, label: &str, texture: &Texture) -> wgpu::Texture {
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

    fn create_bind_group(&self, inputs: &RenderInputs, uniforms: &wgpu::Buffer) -> wgpu::BindGroup {
        let normal = self.upload_texture("normal map", &inputs.normal_map);
        let albedo = self.upload_texture("albedo", &inputs.albedo);
        let sampler = self.device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("map sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let normal_view = normal.create_view(&Default::default());
        let albedo_view = albedo.create_view(&Default::default());
        self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("base pass bind group"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&normal_view) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&albedo_view) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::Sampler(&sampler) },
            ],
        })
    }

    /// The base pipeline for `format`, built once.
    fn pipeline(&self, format: OutputFormat) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = cache.iter().find(|(f, _)| *f == format) {
            return p.clone();
        }
        let pipeline = self.build_pipeline(format);
        cache.push((format, pipeline.clone()));
        pipeline
    }

    fn build_pipeline(&self, format: OutputFormat) -> wgpu::RenderPipeline {
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2
        ];
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("base pass pipeline"),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Vertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &self.shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: format.texture_format(),
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// Copy the target into a mappable buffer whose rows are padded to
    /// `COPY_BYTES_PER_ROW_ALIGNMENT` (256 bytes).
    fn copy_to_buffer(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::Texture,
        width: u32,
        height: u32,
        format: OutputFormat,
    ) -> wgpu::Buffer {
        let padded = padded_row_bytes(width, format);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded as u64 * height as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            target.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            extent(width, height),
        );
        buffer
    }

    /// Map `buffer`, wait, and copy its bytes out.
    fn read_buffer(&self, buffer: &wgpu::Buffer) -> Result<Vec<u8>> {
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

/// Two timestamps around one pass, resolved and copied to a mappable buffer.
struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl PassTimer {
    fn new(device: &wgpu::Device) -> Self {
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 16,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("base pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2,
            }),
            resolve: buffer("timestamp resolve", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer("timestamp readback", wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
        }
    }
}

/// The enabled backends for the error message, e.g. "vulkan, gl", or what an empty set means.
fn backend_names(backends: wgpu::Backends) -> String {
    let names: Vec<String> = backends.iter_names().map(|(name, _)| name.to_lowercase()).collect();
    if names.is_empty() { "none, WGPU_BACKEND is set but empty".to_string() } else { names.join(", ") }
}

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

fn extent(width: u32, height: u32) -> wgpu::Extent3d {
    wgpu::Extent3d { width, height, depth_or_array_layers: 1 }
}

/// Bytes per row of a readback buffer: the tight row rounded up to the copy alignment.
pub fn padded_row_bytes(width: u32, format: OutputFormat) -> u32 {
    let tight = width * format.bytes_per_pixel();
    tight.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}

fn check_count(what: &'static str, count: usize, max: usize) -> Result<()> {
    if count > max {
        return Err(GpuError::TooMany { what, count, max });
    }
    Ok(())
}

fn check_texture(name: &'static str, texture: &Texture, limit: u32) -> Result<()> {
    let (width, height) = (texture.width, texture.height);
    if width as usize * height as usize != texture.texels.len() || width == 0 || height == 0 {
        let count = texture.texels.len();
        return Err(GpuError::BadTexture { name, width, height, count });
    }
    if width > limit || height > limit {
        return Err(GpuError::TextureTooLarge { name, width, height, limit });
    }
    Ok(())
}

fn check_mesh(vertices: &[Vertex], indices: &[u32]) -> Result<()> {
    let problem = if indices.is_empty() || !indices.len().is_multiple_of(3) {
        Some("the index count must be a non-zero multiple of 3")
    } else if indices.iter().any(|&i| i as usize >= vertices.len()) {
        Some("an index points past the last vertex")
    } else {
        None
    };
    match problem {
        Some(problem) => Err(GpuError::BadMesh { vertices: vertices.len(), indices: indices.len(), problem }),
        None => Ok(()),
    }
}

fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    let both = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
    let texture = |binding| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    };
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("base pass bind group layout"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: both,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            texture(1),
            texture(2),
            wgpu::BindGroupLayoutEntry {
                binding: 3,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}

fn begin_pass<'e>(
    encoder: &'e mut wgpu::CommandEncoder,
    target: &wgpu::Texture,
    depth: &wgpu::Texture,
    background: [f32; 4],
    timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
) -> wgpu::RenderPass<'e> {
    let target_view = target.create_view(&Default::default());
    let depth_view = depth.create_view(&Default::default());
    let [r, g, b, a] = background.map(f64::from);
    encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("base pass"),
        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
            view: &target_view,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a }),
                store: wgpu::StoreOp::Store,
            },
        })],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view: &depth_view,
            depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
            stencil_ops: None,
        }),
        timestamp_writes,
        occlusion_query_set: None,
        multiview_mask: None,
    })
}

fn vec4(v: glam::Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// A light as the shader reads it.
fn light_raw(light: &crate::shading::Light) -> LightRaw {
    let vector = match light.kind {
        LightKind::Directional { toward } => vec4(toward, 0.0),
        LightKind::Point { position } => vec4(position, 1.0),
    };
    LightRaw { vector, radiance: vec4(light.color * light.intensity, 0.0) }
}

/// The uniform block for `inputs`.
fn globals(inputs: &RenderInputs) -> Globals {
    let mut lights = [LightRaw { vector: [0.0; 4], radiance: [0.0; 4] }; MAX_LIGHTS];
    for (raw, light) in lights.iter_mut().zip(&inputs.lights) {
        *raw = light_raw(light);
    }
    let mut lobes = [LobeRaw { cx: [0.0; 4], cy: [0.0; 4], cz: [0.0; 4], n: [0.0; 4] }; MAX_LOBES];
    for (raw, lobe) in lobes.iter_mut().zip(&inputs.brdf.lobes) {
        *raw = LobeRaw { cx: vec4(lobe.cx, 0.0), cy: vec4(lobe.cy, 0.0), cz: vec4(lobe.cz, 0.0), n: vec4(lobe.n, 0.0) };
    }
    Globals {
        view_proj: inputs.camera.view_proj.to_cols_array_2d(),
        eye: vec4(inputs.camera.eye, inputs.exposure),
        diffuse: vec4(inputs.brdf.diffuse, 0.0),
        counts: [
            inputs.lights.len().min(MAX_LIGHTS) as u32,
            inputs.brdf.lobes.len().min(MAX_LOBES) as u32,
            (inputs.specular == SpecularMode::Vertex) as u32,
            (inputs.green == GreenAxis::Down) as u32,
        ],
        options: [tone_code(inputs.tone), 0, 0, 0],
        lights,
        lobes,
    }
}

/// The curve a target of `format` applies for the scene's curve `code`: the scene's curve, but an
/// sRGB target needs one (None becomes Clamp).
fn target_curve(format: OutputFormat, code: u32) -> ToneCurve {
    match (format, code) {
        (OutputFormat::Srgb8, 0) => ToneCurve::Clamp,
        (_, 1) => ToneCurve::Clamp,
        (_, 2) => ToneCurve::Reinhard,
        _ => ToneCurve::None,
    }
}

fn tone_code(curve: ToneCurve) -> u32 {
    match curve {
        ToneCurve::None => 0,
        ToneCurve::Clamp => 1,
        ToneCurve::Reinhard => 2,
    }
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
