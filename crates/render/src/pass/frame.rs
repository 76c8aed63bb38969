//! A frame: a scene uploaded once ([`Gpu::prepare_with`]: its buffers and textures, then what
//! each pass allocates for later passes and prepares for itself) and drawn into a target by walking its passes in order
//! ([`Gpu::draw`]), each encoding itself ([`super::Pass`]), with GPU timestamps around each when
//! asked ([`Gpu::draw_timed_passes`]).

use super::base::tone_code;
use super::resources::Resources;
use super::setup::SkinSetup;
use super::uniforms::globals;
use super::{FrameEncoder, PreparedScene, Upload, geometry};
use crate::gpu::{Gpu, GpuError, OutputFormat, PassTimer, Rendered, Result, Target, timestamp_writes};
use crate::shading::{RenderInputs, ToneCurve};

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
        let bounds = geometry::bounding_sphere(&inputs.vertices);
        let globals = globals(inputs, skin);
        let uniforms = self.buffer(
            "base pass globals",
            bytemuck::bytes_of(&globals),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        let textures = self.skin_textures(inputs, skin);
        let vertices = self.buffer("vertices", bytemuck::cast_slice(&inputs.vertices), wgpu::BufferUsages::VERTEX);
        let skin_data: Vec<[f32; 2]> =
            if skin.vertex_skin.is_empty() { vec![[0.0; 2]; inputs.vertices.len()] } else { skin.vertex_skin.clone() };
        let vertex_skin = self.buffer("per-vertex skin", bytemuck::cast_slice(&skin_data), wgpu::BufferUsages::VERTEX);
        let indices = self.buffer("indices", bytemuck::cast_slice(&inputs.indices), wgpu::BufferUsages::INDEX);
        let passes = skin.passes();
        let upload = Upload { inputs, skin, uniforms: &uniforms, textures: &textures };
        let mut resources = Resources::default();
        for pass in &passes.0 {
            pass.allocate(self, &upload, &mut resources);
        }
        let states = passes.0.iter().map(|pass| pass.prepare(self, &upload, &resources)).collect();
        self.pop_scope(scope, "scene upload")?;
        Ok(PreparedScene {
            globals,
            uniforms,
            vertices,
            vertex_skin,
            indices,
            index_count: inputs.indices.len() as u32,
            background: inputs.background,
            features: skin.features,
            passes,
            states,
            bounds,
            resources,
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
    /// returns which of them ran ([`super::Pass::runs`]: TSD culling may skip its passes).
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
        // Every pass decides whether it runs before any encodes (a pass may note that it ran).
        let ran: Vec<bool> = scene.passes.0.iter().map(|pass| pass.runs(scene, target)).collect();
        for (slot, pass) in scene.passes.0.iter().enumerate().filter(|(slot, _)| ran[*slot]) {
            let writes = timestamp_writes(timer, slot as u32);
            let state = scene.states[slot].as_deref();
            let mut frame = FrameEncoder { encoder: &mut encoder, scene, target, state };
            pass.encode(self, &mut frame, writes);
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

impl Gpu {
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
}
