//! A frame: a scene uploaded once ([`Gpu::prepare_with`]) and drawn into a target by walking its
//! pass graph in order ([`Gpu::draw`]); each pass encodes itself (`crate::pass`).

use super::timing::{PassTimer, timestamp_writes};
use super::{DEPTH_FORMAT, Gpu, GpuError, OutputFormat, Rendered, Result, Target};
use crate::graph::PassKind;
use crate::pass::shadow::ShadowResources;
use crate::pass::tsd::TsdResources;
use crate::pass::uniforms::{Globals, globals, light_raw};
use crate::passes::{self, Features, SkinSetup};
use crate::shading::{RenderInputs, ToneCurve};
use std::sync::atomic::Ordering;

/// A scene uploaded to the GPU by [`Gpu::prepare`], ready for [`Gpu::draw`].
pub struct PreparedScene {
    pub(crate) globals: Globals,
    pub(crate) uniforms: wgpu::Buffer,
    pub(crate) bind_group: wgpu::BindGroup,
    pub(crate) vertices: wgpu::Buffer,
    pub(crate) vertex_skin: wgpu::Buffer,
    pub(crate) indices: wgpu::Buffer,
    pub(crate) index_count: u32,
    pub(crate) background: [f32; 4],
    pub(crate) features: Features,
    /// The passes [`Gpu::draw`] runs, in order ([`SkinSetup::passes`]).
    pub(crate) passes: Vec<PassKind>,
    pub(crate) bounds: (glam::Vec3, f32),
    pub(crate) shadow: Option<ShadowResources>,
    pub(crate) tsd: Option<TsdResources>,
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
    pub(crate) fn set_camera(&mut self, camera: &crate::shading::Camera) {
        self.globals.scene.view_proj = camera.view_proj.to_cols_array_2d();
        self.globals.scene.eye = camera.eye.to_array();
    }

    /// Sets the tone curve of the next [`Gpu::draw`] (the target's format may still impose one).
    pub(crate) fn set_tone(&mut self, tone: ToneCurve) {
        self.globals.base.tone = tone_code(tone);
    }

    /// Replaces light `index` (below the scene's light count) for the next [`Gpu::draw`].
    pub fn set_light(&mut self, index: usize, light: &crate::shading::Light) {
        if index < self.globals.scene.light_count as usize {
            self.globals.scene.lights[index] = light_raw(light);
        }
    }
}

impl Gpu {
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
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
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
            (Some(tsd), _) => Some(tsd.maps[tsd.final_map].create_view(&Default::default())),
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
            readback: super::readback::readback_buffer(&self.device, width, height, format),
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

    /// Encodes every pass of `scene` in the order of [`PreparedScene::passes`] and waits;
    /// returns which of them ran (TSD culling may skip its passes).
    pub(crate) fn encode_and_submit(
        &self,
        scene: &PreparedScene,
        target: &Target,
        timer: Option<&PassTimer>,
    ) -> Result<Vec<bool>> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut globals = scene.globals;
        globals.base.tone = tone_code(target_curve(target.format, globals.base.tone));
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

    /// Draws the scene's mesh (both vertex buffers; a pipeline reading only the first ignores
    /// the second) with `group`.
    pub(crate) fn draw_mesh(&self, pass: &mut wgpu::RenderPass<'_>, scene: &PreparedScene, group: &wgpu::BindGroup) {
        pass.set_bind_group(0, group, &[]);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.set_vertex_buffer(1, scene.vertex_skin.slice(..));
        pass.set_index_buffer(scene.indices.slice(..), wgpu::IndexFormat::Uint32);
        pass.draw_indexed(0..scene.index_count, 0, 0..1);
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

pub(crate) fn tone_code(curve: ToneCurve) -> u32 {
    match curve {
        ToneCurve::None => 0,
        ToneCurve::Clamp => 1,
        ToneCurve::Reinhard => 2,
    }
}
