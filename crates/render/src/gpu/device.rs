//! The device: opening an adapter, what it can do, its error scopes, and the checks of a scene's
//! sizes against its limits before anything is uploaded.

use super::{Gpu, GpuError, Result};
use crate::shading::{MAX_LIGHTS, MAX_LOBES, RenderInputs, Texture, Vertex};
use std::sync::Mutex;

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
        let layout = super::resources::bind_group_layout(&device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("base pass layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        Ok(Self {
            adapter,
            device,
            queue,
            layout,
            pipeline_layout,
            pipelines: Mutex::new(Vec::new()),
            shared: Mutex::new(Vec::new()),
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

    pub(crate) fn pop_scope(&self, scope: wgpu::ErrorScopeGuard, stage: &'static str) -> Result<()> {
        match pollster::block_on(scope.pop()) {
            Some(error) => Err(GpuError::Wgpu { stage, message: error.to_string() }),
            None => Ok(()),
        }
    }

    pub(crate) fn wait(&self) -> Result<()> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Wgpu { stage: "waiting for the GPU", message: e.to_string() })
    }

    pub(crate) fn check(&self, inputs: &RenderInputs) -> Result<()> {
        let limit = self.max_texture_side();
        check_count("lights", inputs.lights.len(), MAX_LIGHTS)?;
        check_count("Lafortune lobes", inputs.brdf.lobes.len(), MAX_LOBES)?;
        check_texture("normal map", &inputs.normal_map, limit)?;
        check_texture("albedo", &inputs.albedo, limit)?;
        check_mesh(&inputs.vertices, &inputs.indices)
    }
}

/// The enabled backends for the error message, e.g. "vulkan, gl", or what an empty set means.
fn backend_names(backends: wgpu::Backends) -> String {
    let names: Vec<String> = backends.iter_names().map(|(name, _)| name.to_lowercase()).collect();
    if names.is_empty() { "none, WGPU_BACKEND is set but empty".to_string() } else { names.join(", ") }
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
