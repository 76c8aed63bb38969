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

use crate::graph::PassKind;
use crate::passes::{self, Features, SkinSetup, Table};
use crate::shading::{
    GreenAxis, LightKind, MAX_LIGHTS, MAX_LOBES, RenderInputs, SpecularMode, Texture, ToneCurve, Vertex,
};
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};
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

/// Points `XDG_RUNTIME_DIR` at a private folder (`skinkit-runtime-UID` in the temporary folder,
/// mode 0700) when it is unset or not a folder, so that the Vulkan loader's window-system probe
/// does not print "XDG_RUNTIME_DIR is invalid or not set" on every run of a headless render.
/// Leaves a valid setting alone; does nothing off Unix.
///
/// # Safety
/// Changes the process environment: call it before any other thread is started (the first
/// statement of `main`), as [`std::env::set_var`] requires.
pub unsafe fn quiet_vulkan_loader() {
    #[cfg(unix)]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
        let valid = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir());
        if valid {
            return;
        }
        let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else { return };
        let dir = std::env::temp_dir().join(format!("skinkit-runtime-{uid}"));
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let private = std::fs::symlink_metadata(&dir)
            .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0);
        if private {
            // SAFETY: the caller guarantees no other thread runs (this function's contract).
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}

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
    vertex_skin: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    background: [f32; 4],
    features: Features,
    /// The passes [`Gpu::draw`] runs, in order ([`SkinSetup::passes`]).
    passes: Vec<PassKind>,
    bounds: (glam::Vec3, f32),
    shadow: Option<ShadowResources>,
    tsd: Option<TsdResources>,
}

/// The key light's shadow map and the bind group its pass draws with (one that does not sample
/// the map being written).
struct ShadowResources {
    depth: wgpu::Texture,
    bind_group: wgpu::BindGroup,
    /// Summed opacity of the translucent casters (with their buffers), when there are any.
    opacity: Option<wgpu::Texture>,
    casters: Vec<CasterBuffers>,
}

/// One translucent caster's positions, per-vertex opacity and indices.
struct CasterBuffers {
    positions: wgpu::Buffer,
    opacity: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// Texture-space diffusion: the UV-space depth of the culling pre-pass, two light maps for the
/// ping-pong blur, and the bind groups of each pass.
struct TsdResources {
    passes: u32,
    reuse_below_px: f32,
    depth: wgpu::Texture,
    maps: [wgpu::Texture; 2],
    /// The base bind group's layout, for the texture-space passes (no light map bound).
    bind_group: wgpu::BindGroup,
    /// Blur pass i reads `maps[i % 2]` and writes `maps[(i + 1) % 2]`.
    blur_groups: Vec<wgpu::BindGroup>,
    /// Whether a light map from an earlier frame exists (distance culling reuses it).
    ready: AtomicBool,
}

impl PreparedScene {
    /// The shader features this scene's base pass was compiled with.
    pub fn features(&self) -> Features {
        self.features
    }

    /// The passes [`Gpu::draw`] runs for this scene, in order.
    pub fn passes(&self) -> &[PassKind] {
        &self.passes
    }

    /// Their names.
    pub fn pass_names(&self) -> Vec<String> {
        self.passes.iter().map(|p| p.name()).collect()
    }
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
    blur_layout: wgpu::BindGroupLayout,
    blur_pipeline_layout: wgpu::PipelineLayout,
    blur_shader: wgpu::ShaderModule,
    pipelines: Mutex<Vec<(PipelineKey, wgpu::RenderPipeline)>>,
}

/// Which pipeline: the base pass for an output format and features, or one of the skin passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PipelineKey {
    Base(OutputFormat, Features),
    Shadow,
    Translucent,
    TsdPrepass(Features),
    LightMap(Features),
    Blur,
}

/// Light maps are Rgba16Float: filterable everywhere, HDR irradiance, kernel size in alpha.
const LIGHT_MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// The WGSL source of the base pass: the closed-form LUT fits, then base.wgsl.
pub const BASE_WGSL: &str =
    concat!(include_str!("../shaders/skin_fit.wgsl"), "\n", include_str!("../shaders/base.wgsl"));

/// The WGSL source of texture-space diffusion's Poisson blur.
pub const BLUR_WGSL: &str = include_str!("../shaders/tsd_blur.wgsl");

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
    skin: [f32; 4],
    blur: [f32; 4],
    shadow_view_proj: [[f32; 4]; 4],
    shadow: [f32; 4],
    shadow_lut: [f32; 4],
    sh: [[f32; 4]; 9],
    zonal: [f32; 4],
    tsd: [f32; 4],
    tsd_kernel: [f32; 4],
}

/// The `Blur` uniform of tsd_blur.wgsl.
#[repr(C)]
#[derive(Debug, Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct BlurRaw {
    params: [f32; 4],
    flags: [u32; 4],
}

/// Bytes of the base pass's uniform block (camera, lights, lobes, options).
pub const UNIFORM_BYTES: u64 = std::mem::size_of::<Globals>() as u64;

/// The layout of one uniform struct as Rust writes it, to check against the WGSL that reads it
/// (the naga-reflection test in `tests/wgsl.rs`).
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
            "Globals",
            Globals,
            [
                view_proj,
                eye,
                diffuse,
                counts,
                options,
                lights,
                lobes,
                skin,
                blur,
                shadow_view_proj,
                shadow,
                shadow_lut,
                sh,
                zonal,
                tsd,
                tsd_kernel
            ]
        ),
        layout!(BLUR_WGSL, "Blur", BlurRaw, [params, flags]),
    ]
}

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
            // Float32 filtering where the adapter has it (lavapipe does): exact LUTs.
            required_features: adapter.features()
                & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_FILTERABLE),
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
        let blur_layout = blur_bind_group_layout(&device);
        let blur_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("tsd blur layout"),
            bind_group_layouts: &[Some(&blur_layout)],
            immediate_size: 0,
        });
        let blur_shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("tsd_blur.wgsl"),
            source: wgpu::ShaderSource::Wgsl(BLUR_WGSL.into()),
        });
        Ok(Self {
            adapter,
            device,
            queue,
            layout,
            pipeline_layout,
            shader,
            blur_layout,
            blur_pipeline_layout,
            blur_shader,
            pipelines: Mutex::new(Vec::new()),
        })
    }

    /// The adapter's name and backend, e.g. "llvmpipe (LLVM 19.1.7, 256 bits) (Vulkan)".
    pub fn adapter_name(&self) -> String {
        let info = self.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    /// How many render pipelines this device has built so far. Shader modules are compiled once,
    /// in [`Gpu::new`], and each pipeline once per key and kept: a second render of a scene on the
    /// same `Gpu` builds none (what a session of several renders, like `skinkit demo`, relies on).
    pub fn pipelines_built(&self) -> usize {
        self.pipelines.lock().unwrap_or_else(|e| e.into_inner()).len()
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
        self.prepare_with(inputs, &SkinSetup::default())
    }

    /// [`Gpu::prepare`] with the skin effects of `skin`: its tables uploaded, its shadow map and
    /// texture-space light maps allocated, its pipelines chosen.
    ///
    /// # Errors
    /// As [`Gpu::prepare`], and a per-vertex skin array of the wrong length.
    pub fn prepare_with(&self, inputs: &RenderInputs, skin: &SkinSetup) -> Result<PreparedScene> {
        self.check(inputs)?;
        if !skin.vertex_skin.is_empty() && skin.vertex_skin.len() != inputs.vertices.len() {
            return Err(GpuError::BadMesh {
                vertices: inputs.vertices.len(),
                indices: skin.vertex_skin.len(),
                problem: "the per-vertex skin attributes do not match the vertex count",
            });
        }
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let bounds = passes::bounding_sphere(&inputs.vertices);
        let globals = globals(inputs, skin);
        let uniforms = self.buffer(
            "base pass globals",
            bytemuck::bytes_of(&globals),
            wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        );
        let textures = self.skin_textures(inputs, skin);
        let shadow = skin.shadow.as_ref().map(|s| self.shadow_resources(s, &textures, &uniforms));
        let shadow_views = shadow.as_ref().map(|s| {
            (s.depth.create_view(&Default::default()), s.opacity.as_ref().map(|o| o.create_view(&Default::default())))
        });
        let (shadow_view, opacity_view) = match &shadow_views {
            Some((depth, opacity)) => (Some(depth), opacity.as_ref()),
            None => (None, None),
        };
        let tsd = skin.tsd.as_ref().map(|t| self.tsd_resources(t, &textures, &uniforms, shadow_view, opacity_view));
        let light_map = match (&tsd, &textures.light_map) {
            (Some(tsd), _) => Some(tsd.maps[(tsd.passes % 2) as usize].create_view(&Default::default())),
            (None, Some(map)) => Some(map.create_view(&Default::default())),
            (None, None) => None,
        };
        let bind_group = self.create_bind_group(&textures, &uniforms, shadow_view, opacity_view, light_map.as_ref());
        let vertices = self.buffer("vertices", bytemuck::cast_slice(&inputs.vertices), wgpu::BufferUsages::VERTEX);
        let skin_data: Vec<[f32; 2]> =
            if skin.vertex_skin.is_empty() { vec![[0.0; 2]; inputs.vertices.len()] } else { skin.vertex_skin.clone() };
        let vertex_skin = self.buffer("per-vertex skin", bytemuck::cast_slice(&skin_data), wgpu::BufferUsages::VERTEX);
        let indices = self.buffer("indices", bytemuck::cast_slice(&inputs.indices), wgpu::BufferUsages::INDEX);
        self.pop_scope(scope, "scene upload")?;
        Ok(PreparedScene {
            globals,
            uniforms,
            bind_group,
            vertices,
            vertex_skin,
            indices,
            index_count: inputs.indices.len() as u32,
            background: inputs.background,
            features: skin.features,
            passes: skin.passes(),
            bounds,
            shadow,
            tsd,
        })
    }

    fn shadow_resources(
        &self,
        s: &passes::ShadowSetup,
        textures: &SceneTextures,
        uniforms: &wgpu::Buffer,
    ) -> ShadowResources {
        let depth = self.depth_texture("shadow map", s.map_size, s.map_size, true);
        let bind_group = self.create_bind_group(textures, uniforms, None, None, None);
        let opacity = (!s.translucent.is_empty()).then(|| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some("shadow opacity"),
                size: extent(s.map_size, s.map_size),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: LIGHT_MAP_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        });
        let casters = s
            .translucent
            .iter()
            .filter(|c| !c.indices.is_empty() && c.indices.iter().all(|&i| (i as usize) < c.positions.len()))
            .map(|c| CasterBuffers {
                positions: self.buffer(
                    "translucent positions",
                    bytemuck::cast_slice(&c.positions),
                    wgpu::BufferUsages::VERTEX,
                ),
                opacity: self.buffer(
                    "translucent opacity",
                    bytemuck::cast_slice(&vec![c.opacity; c.positions.len()]),
                    wgpu::BufferUsages::VERTEX,
                ),
                indices: self.buffer(
                    "translucent indices",
                    bytemuck::cast_slice(&c.indices),
                    wgpu::BufferUsages::INDEX,
                ),
                count: c.indices.len() as u32,
            })
            .collect();
        ShadowResources { depth, bind_group, opacity, casters }
    }

    fn tsd_resources(
        &self,
        tsd: &passes::TsdSetup,
        textures: &SceneTextures,
        uniforms: &wgpu::Buffer,
        shadow: Option<&wgpu::TextureView>,
        opacity: Option<&wgpu::TextureView>,
    ) -> TsdResources {
        let size = tsd.size;
        let depth = self.depth_texture("tsd texture-space depth", size, size, false);
        let map = |label| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent(size, size),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: LIGHT_MAP_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let maps = [map("tsd light map A"), map("tsd light map B")];
        let bind_group = self.create_bind_group(textures, uniforms, shadow, opacity, None);
        let sampler = |label, filter| {
            self.device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some(label),
                address_mode_u: wgpu::AddressMode::ClampToEdge,
                address_mode_v: wgpu::AddressMode::ClampToEdge,
                mag_filter: filter,
                min_filter: filter,
                ..Default::default()
            })
        };
        let nearest = sampler("tsd dilation sampler", wgpu::FilterMode::Nearest);
        let linear = sampler("tsd blur sampler", wgpu::FilterMode::Linear);
        let (a, b) = (tsd.kernel_scale[0], tsd.kernel_scale[1]);
        let blur_groups = (0..tsd.passes)
            .map(|i| {
                let raw =
                    BlurRaw { params: [1.0 / size as f32, 1.0 / size as f32, a, b], flags: [(i == 0) as u32, 0, 0, 0] };
                let buffer = self.buffer("tsd blur uniforms", bytemuck::bytes_of(&raw), wgpu::BufferUsages::UNIFORM);
                let view = maps[(i % 2) as usize].create_view(&Default::default());
                self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("tsd blur bind group"),
                    layout: &self.blur_layout,
                    entries: &[
                        wgpu::BindGroupEntry { binding: 0, resource: buffer.as_entire_binding() },
                        wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&view) },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: wgpu::BindingResource::Sampler(if i == 0 { &nearest } else { &linear }),
                        },
                    ],
                })
            })
            .collect();
        TsdResources {
            passes: tsd.passes,
            reuse_below_px: tsd.reuse_below_px,
            depth,
            maps,
            bind_group,
            blur_groups,
            ready: AtomicBool::new(false),
        }
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
        self.encode_and_submit(scene, target, None).map(|_| ())
    }

    /// [`Gpu::draw`] with GPU timestamps around every pass: the frame's GPU time (first pass's
    /// start to the last one's end), or `None` when the adapter has no `TIMESTAMP_QUERY` feature.
    ///
    /// # Errors
    /// A wgpu validation error, a failed wait or a failed readback of the timestamps.
    pub fn draw_timed(&self, scene: &PreparedScene, target: &Target) -> Result<Option<std::time::Duration>> {
        Ok(self.draw_timed_passes(scene, target)?.map(|passes| passes.iter().map(|(_, d)| *d).sum()))
    }

    /// [`Gpu::draw`] with each pass's GPU time, named as [`PreparedScene::pass_names`] names them;
    /// `None` without `TIMESTAMP_QUERY`.
    ///
    /// # Errors
    /// As [`Gpu::draw_timed`].
    pub fn draw_timed_passes(
        &self,
        scene: &PreparedScene,
        target: &Target,
    ) -> Result<Option<Vec<(String, std::time::Duration)>>> {
        if !self.has_timestamps() {
            self.draw(scene, target)?;
            return Ok(None);
        }
        let names = scene.pass_names();
        let timer = PassTimer::new(&self.device, names.len() as u32);
        let ran = self.encode_and_submit(scene, target, Some(&timer))?;
        let bytes = self.read_buffer(&timer.readback)?;
        let tick = |i: usize| u64::from_le_bytes(bytes[8 * i..8 * i + 8].try_into().unwrap());
        let period = self.queue.get_timestamp_period() as f64;
        let passes = names
            .into_iter()
            .enumerate()
            .map(|(i, name)| {
                let nanos = if ran[i] { tick(2 * i + 1).saturating_sub(tick(2 * i)) as f64 * period } else { 0.0 };
                (name, std::time::Duration::from_nanos(nanos as u64))
            })
            .collect();
        Ok(Some(passes))
    }

    /// Encodes every pass of `scene` in the order of [`PreparedScene::passes`] and waits;
    /// returns which of them ran (TSD culling may skip its passes).
    fn encode_and_submit(
        &self,
        scene: &PreparedScene,
        target: &Target,
        timer: Option<&PassTimer>,
    ) -> Result<Vec<bool>> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut globals = scene.globals;
        globals.options[0] = tone_code(target_curve(target.format, globals.options[0]));
        self.queue.write_buffer(&scene.uniforms, 0, bytemuck::bytes_of(&globals));
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame encoder") });
        let run_tsd = scene.tsd.as_ref().is_some_and(|tsd| self.tsd_runs(scene, tsd, target));
        let mut ran = Vec::with_capacity(scene.passes.len());
        for (slot, &kind) in scene.passes.iter().enumerate() {
            let writes = timestamp_writes(timer, slot as u32);
            let run = !kind.is_tsd() || run_tsd;
            ran.push(run);
            if run {
                self.encode_pass(&mut encoder, kind, scene, target, writes);
            }
        }
        if let Some(tsd) = scene.tsd.as_ref().filter(|_| run_tsd) {
            tsd.ready.store(true, Ordering::Relaxed);
        }
        if let Some(t) = timer {
            // Passes that were culled wrote no timestamps; resolving unwritten queries is
            // allowed and gives zeros, which `ran` masks.
            let count = 2 * ran.len() as u32;
            encoder.resolve_query_set(&t.queries, 0..count, &t.resolve, 0);
            encoder.copy_buffer_to_buffer(&t.resolve, 0, &t.readback, 0, 8 * count as u64);
        }
        self.queue.submit([encoder.finish()]);
        self.pop_scope(scope, "the frame's passes")?;
        self.wait()?;
        Ok(ran)
    }

    /// Whether texture-space diffusion runs this frame: the head is in the frustum, and it is
    /// not so small on screen that an earlier frame's light map is reused.
    fn tsd_runs(&self, scene: &PreparedScene, tsd: &TsdResources, target: &Target) -> bool {
        let camera = glam::Mat4::from_cols_array_2d(&scene.globals.view_proj);
        let eye = glam::Vec3::from_slice(&scene.globals.eye[..3]);
        let (centre, radius) = scene.bounds;
        let visible = passes::sphere_in_frustum(camera, centre, radius);
        let small = passes::projected_diameter(camera, eye, centre, radius, target.height) < tsd.reuse_below_px;
        visible && !(small && tsd.ready.load(Ordering::Relaxed))
    }

    /// Encodes one pass of the graph.
    fn encode_pass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        kind: PassKind,
        scene: &PreparedScene,
        target: &Target,
        writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let shadow = || scene.shadow.as_ref().expect("a shadow pass is listed only with its shadow map");
        let tsd = || scene.tsd.as_ref().expect("a TSD pass is listed only with its light maps");
        match kind {
            PassKind::ShadowMap => self.encode_shadow(encoder, scene, shadow(), writes),
            PassKind::TranslucentShadows => {
                let opacity = shadow().opacity.as_ref().expect("translucent shadows are listed with their map");
                self.encode_translucent(encoder, shadow(), opacity, writes);
            }
            PassKind::TsdPrepass => self.encode_tsd_prepass(encoder, scene, tsd(), writes),
            PassKind::TsdLightMap => self.encode_light_map(encoder, scene, tsd(), writes),
            PassKind::TsdBlur(i) => self.encode_blur(encoder, tsd(), i as usize, writes),
            PassKind::Base => {
                let pipeline = self.pipeline(PipelineKey::Base(target.format, scene.features));
                let mut pass = begin_pass(encoder, &target.color, &target.depth, scene.background, writes);
                pass.set_pipeline(&pipeline);
                self.draw_mesh(&mut pass, scene, &scene.bind_group);
            }
        }
    }

    fn encode_shadow(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PreparedScene,
        shadow: &ShadowResources,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let view = shadow.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadow map pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::Shadow));
        self.draw_mesh(&mut pass, scene, &shadow.bind_group);
    }

    /// Translucent casters into the opacity channels: cleared to 0, added up where the opaque
    /// depth does not hide them.
    fn encode_translucent(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shadow: &ShadowResources,
        opacity: &wgpu::Texture,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let depth = shadow.depth.create_view(&Default::default());
        let view = opacity.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("translucent shadows pass"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT)))],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::Translucent));
        pass.set_bind_group(0, &shadow.bind_group, &[]);
        for caster in &shadow.casters {
            pass.set_vertex_buffer(0, caster.positions.slice(..));
            pass.set_vertex_buffer(1, caster.opacity.slice(..));
            pass.set_index_buffer(caster.indices.slice(..), wgpu::IndexFormat::Uint32);
            pass.draw_indexed(0..caster.count, 0, 0..1);
        }
    }

    /// TSD's back-face pre-pass into the UV-space depth.
    fn encode_tsd_prepass(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PreparedScene,
        tsd: &TsdResources,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let depth_view = tsd.depth.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd back-face pre-pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(depth_attachment(&depth_view, wgpu::LoadOp::Clear(1.0))),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::TsdPrepass(scene.features)));
        self.draw_mesh(&mut pass, scene, &tsd.bind_group);
    }

    /// TSD's light map (depth "equal": only texels the pre-pass kept).
    fn encode_light_map(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &PreparedScene,
        tsd: &TsdResources,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let depth_view = tsd.depth.create_view(&Default::default());
        let view = tsd.maps[0].create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd light map"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL)))],
            depth_stencil_attachment: Some(depth_attachment(&depth_view, wgpu::LoadOp::Load)),
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::LightMap(scene.features)));
        self.draw_mesh(&mut pass, scene, &tsd.bind_group);
    }

    /// TSD blur `i`: over the whole map, from `maps[i % 2]` into the other (the first also
    /// dilates into the texels the light map left unwritten).
    fn encode_blur(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        tsd: &TsdResources,
        i: usize,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites>,
    ) {
        let view = tsd.maps[(i + 1) % 2].create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("tsd blur"),
            color_attachments: &[Some(colour_attachment(&view, wgpu::LoadOp::Clear(UNWRITTEN_TEXEL)))],
            depth_stencil_attachment: None,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline(PipelineKey::Blur));
        pass.set_bind_group(0, &tsd.blur_groups[i], &[]);
        pass.draw(0..3, 0..1);
    }

    /// Draws the scene's mesh (both vertex buffers; a pipeline reading only the first ignores
    /// the second) with `group`.
    fn draw_mesh(&self, pass: &mut wgpu::RenderPass<'_>, scene: &PreparedScene, group: &wgpu::BindGroup) {
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_vertex_buffer(1, scene.vertex_skin.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..scene.index_count, 0, 0..1);
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

    fn depth_texture(&self, label: &str, width: u32, height: u32, sampled: bool) -> wgpu::Texture {
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if sampled {
            usage |= wgpu::TextureUsages::TEXTURE_BINDING;
        }
        self.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(width, height),
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage,
            view_formats: &[],
        })
    }

    /// An RGB table as an Rgba32Float texture without mips (sampled with `textureSampleLevel`).
    fn upload_table(&self, label: &str, table: &Table) -> wgpu::Texture {
        let data: Vec<f32> = table.texels.iter().flat_map(|t| [t[0], t[1], t[2], 1.0]).collect();
        self.upload_rgba32(label, table.width, table.height, &data)
    }

    fn upload_rgba32(&self, label: &str, width: u32, height: u32, data: &[f32]) -> wgpu::Texture {
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

    /// Rgba32Float for tables where the device filters it, else Rgba16Float.
    pub fn table_format(&self) -> wgpu::TextureFormat {
        if self.device.features().contains(wgpu::Features::FLOAT32_FILTERABLE) {
            TABLE_FORMAT
        } else {
            wgpu::TextureFormat::Rgba16Float
        }
    }

    /// Every texture and sampler the base bind group holds; tables a scene does not read are
    /// 1x1 placeholders (never sampled: their shader branches are compiled out).
    fn skin_textures(&self, inputs: &RenderInputs, skin: &SkinSetup) -> SceneTextures {
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
    fn create_bind_group(
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

    /// The pipeline for `key`, built once.
    fn pipeline(&self, key: PipelineKey) -> wgpu::RenderPipeline {
        let mut cache = self.pipelines.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, p)) = cache.iter().find(|(k, _)| *k == key) {
            return p.clone();
        }
        let pipeline = self.build_pipeline(key);
        cache.push((key, pipeline.clone()));
        pipeline
    }

    fn build_pipeline(&self, key: PipelineKey) -> wgpu::RenderPipeline {
        if key == PipelineKey::Blur {
            return self.build_blur_pipeline();
        }
        let attributes = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2
        ];
        let skin_attributes = wgpu::vertex_attr_array![4 => Float32x2];
        let position_only =
            [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x3, offset: 0, shader_location: 0 }];
        let stride = std::mem::size_of::<Vertex>() as u64;
        let step_mode = wgpu::VertexStepMode::Vertex;
        let full_buffers = [
            Some(wgpu::VertexBufferLayout { array_stride: stride, step_mode, attributes: &attributes }),
            Some(wgpu::VertexBufferLayout { array_stride: 8, step_mode, attributes: &skin_attributes }),
        ];
        let shadow_buffers =
            [Some(wgpu::VertexBufferLayout { array_stride: stride, step_mode, attributes: &position_only })];
        let translucent_position = wgpu::vertex_attr_array![0 => Float32x3];
        let translucent_opacity = wgpu::vertex_attr_array![1 => Float32x3];
        let translucent_buffers = [
            Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode, attributes: &translucent_position }),
            Some(wgpu::VertexBufferLayout { array_stride: 12, step_mode, attributes: &translucent_opacity }),
        ];
        let features = match key {
            PipelineKey::Base(_, f) | PipelineKey::TsdPrepass(f) | PipelineKey::LightMap(f) => f,
            PipelineKey::Shadow | PipelineKey::Translucent | PipelineKey::Blur => Features::default(),
        };
        let constants = features.constants();
        let options = wgpu::PipelineCompilationOptions { constants: &constants, ..Default::default() };
        let depth = |write: bool, compare| {
            Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(write),
                depth_compare: Some(compare),
                stencil: Default::default(),
                bias: Default::default(),
            })
        };
        let (label, vertex_entry, buffers, fragment, target, depth_stencil): (_, _, &[_], _, _, _) = match key {
            PipelineKey::Base(format, _) => (
                "base pass pipeline",
                "vs_main",
                &full_buffers,
                Some("fs_main"),
                Some(format.texture_format()),
                depth(true, wgpu::CompareFunction::Less),
            ),
            PipelineKey::Shadow => (
                "shadow map pipeline",
                "vs_shadow",
                &shadow_buffers,
                None,
                None,
                depth(true, wgpu::CompareFunction::Less),
            ),
            PipelineKey::Translucent => (
                "translucent shadows pipeline",
                "vs_translucent",
                &translucent_buffers,
                Some("fs_translucent"),
                Some(LIGHT_MAP_FORMAT),
                depth(false, wgpu::CompareFunction::Less),
            ),
            PipelineKey::TsdPrepass(_) => (
                "tsd back-face pre-pass pipeline",
                "vs_texture_space",
                &full_buffers,
                Some("fs_tsd_prepass"),
                None,
                depth(true, wgpu::CompareFunction::Always),
            ),
            PipelineKey::LightMap(_) => (
                "tsd light map pipeline",
                "vs_texture_space",
                &full_buffers,
                Some("fs_light_map"),
                Some(LIGHT_MAP_FORMAT),
                depth(false, wgpu::CompareFunction::Equal),
            ),
            PipelineKey::Blur => unreachable!("built above"),
        };
        let targets =
            [target.map(|format| wgpu::ColorTargetState { format, blend: None, write_mask: wgpu::ColorWrites::ALL })];
        let targets: &[Option<wgpu::ColorTargetState>] = if target.is_some() { &targets } else { &[] };
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&self.pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.shader,
                entry_point: Some(vertex_entry),
                compilation_options: options.clone(),
                buffers,
            },
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil,
            multisample: Default::default(),
            fragment: fragment.map(|entry| wgpu::FragmentState {
                module: &self.shader,
                entry_point: Some(entry),
                compilation_options: options.clone(),
                targets,
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    fn build_blur_pipeline(&self) -> wgpu::RenderPipeline {
        self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("tsd blur pipeline"),
            layout: Some(&self.blur_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &self.blur_shader,
                entry_point: Some("vs_full_screen"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &self.blur_shader,
                entry_point: Some("fs_blur"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: LIGHT_MAP_FORMAT,
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

/// Two timestamps around each pass, resolved and copied to a mappable buffer.
struct PassTimer {
    queries: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
}

impl PassTimer {
    fn new(device: &wgpu::Device, passes: u32) -> Self {
        let count = 2 * passes.max(1);
        let buffer = |label, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: 8 * count as u64,
                usage,
                mapped_at_creation: false,
            })
        };
        Self {
            queries: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolve: buffer("timestamp resolve", wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC),
            readback: buffer("timestamp readback", wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST),
        }
    }
}

/// The timestamp writes of pass `slot` (queries 2 slot and 2 slot + 1).
fn timestamp_writes(timer: Option<&PassTimer>, slot: u32) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    timer.map(|t| wgpu::RenderPassTimestampWrites {
        query_set: &t.queries,
        beginning_of_pass_write_index: Some(2 * slot),
        end_of_pass_write_index: Some(2 * slot + 1),
    })
}

/// The textures and samplers of a scene's bind groups.
struct SceneTextures {
    normal: wgpu::Texture,
    albedo: wgpu::Texture,
    diffuse_lut: wgpu::Texture,
    shadow_lut: wgpu::Texture,
    zonal: wgpu::Texture,
    kernel: wgpu::Texture,
    light_map: Option<wgpu::Texture>,
    shadow_placeholder: wgpu::Texture,
    light_map_placeholder: wgpu::Texture,
    opacity_placeholder: wgpu::Texture,
    map_sampler: wgpu::Sampler,
    blurred_sampler: wgpu::Sampler,
    lut_sampler: wgpu::Sampler,
    shadow_sampler: wgpu::Sampler,
}

/// Tables (LUTs, zonal factors) are Rgba32Float where the device filters it (lavapipe and desktop
/// adapters, with `FLOAT32_FILTERABLE`), Rgba16Float elsewhere ([`Gpu::table_format`]).
const TABLE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

fn colour_attachment(view: &wgpu::TextureView, load: wgpu::LoadOp<wgpu::Color>) -> wgpu::RenderPassColorAttachment<'_> {
    wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
    }
}

/// What the light maps hold where no texel was drawn (the first blur dilates into them).
const UNWRITTEN_TEXEL: wgpu::Color = wgpu::Color { r: 0.0, g: 0.0, b: 0.0, a: 1.0 };

fn depth_attachment(view: &wgpu::TextureView, load: wgpu::LoadOp<f32>) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations { load, store: wgpu::StoreOp::Store }),
        stencil_ops: None,
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
                    ty: wgpu::BufferBindingType::Uniform,
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

fn blur_bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("tsd blur bind group layout"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 2,
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

/// The uniform block for `inputs` with the skin settings of `skin`.
fn globals(inputs: &RenderInputs, skin: &SkinSetup) -> Globals {
    let mut lights = [LightRaw { vector: [0.0; 4], radiance: [0.0; 4] }; MAX_LIGHTS];
    for (raw, light) in lights.iter_mut().zip(&inputs.lights) {
        *raw = light_raw(light);
    }
    let mut lobes = [LobeRaw { cx: [0.0; 4], cy: [0.0; 4], cz: [0.0; 4], n: [0.0; 4] }; MAX_LOBES];
    for (raw, lobe) in lobes.iter_mut().zip(&inputs.brdf.lobes) {
        *raw = LobeRaw { cx: vec4(lobe.cx, 0.0), cy: vec4(lobe.cy, 0.0), cz: vec4(lobe.cz, 0.0), n: vec4(lobe.n, 0.0) };
    }
    let map = |t: &Option<Table>| t.as_ref().map_or((0.0, 0.5), |t| (t.scale, t.offset));
    let (lut_scale, lut_offset) = map(&skin.diffuse_lut);
    let (shadow_scale, shadow_offset) = map(&skin.shadow_lut);
    let (zonal_scale, zonal_offset) = map(&skin.zonal);
    let key = skin.shadow.as_ref().map_or(MAX_LIGHTS as f32, |s| s.light as f32);
    let (shadow_view_proj, shadow, new_penumbra) = match &skin.shadow {
        Some(s) => (s.view_proj, [1.0 / s.map_size.max(1) as f32, s.filter as f32, s.texel, s.bias], s.new_penumbra),
        None => (glam::Mat4::IDENTITY, [1.0, 1.0, 0.0, 0.0], 1.0),
    };
    let (tsd, tsd_kernel) = match &skin.tsd {
        Some(t) => {
            let from_map = t.kernel_map.is_some();
            let kernel = if from_map {
                [t.kernel_scale[0], t.kernel_scale[1], 1.0, passes::MAX_KERNEL_TEXELS]
            } else {
                [passes::MAX_KERNEL_TEXELS, 0.0, 0.0, passes::MAX_KERNEL_TEXELS]
            };
            ([t.backface_bias, t.size as f32, t.kernel_mm, t.curvature_gain], kernel)
        }
        None => ([0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]),
    };
    let mut sh = [[0.0f32; 4]; 9];
    for (raw, c) in sh.iter_mut().zip(&skin.sh) {
        *raw = [c[0], c[1], c[2], 0.0];
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
        skin: [skin.curvature_scale, skin.mm_per_unit, lut_scale, lut_offset],
        blur: vec4(skin.normal_blur, key),
        shadow_view_proj: shadow_view_proj.to_cols_array_2d(),
        shadow,
        shadow_lut: [shadow_scale, shadow_offset, new_penumbra, 0.0],
        sh,
        zonal: [zonal_scale, zonal_offset, 0.0, 0.0],
        tsd,
        tsd_kernel,
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
