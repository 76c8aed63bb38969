//! GPU time per pass: two timestamps around each pass of the graph, resolved and read back.

use super::{Gpu, PreparedScene, Result, Target};

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

/// Two timestamps around each pass, resolved and copied to a mappable buffer.
pub(crate) struct PassTimer {
    pub(crate) queries: wgpu::QuerySet,
    pub(crate) resolve: wgpu::Buffer,
    pub(crate) readback: wgpu::Buffer,
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
pub(crate) fn timestamp_writes(timer: Option<&PassTimer>, slot: u32) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
    timer.map(|t| wgpu::RenderPassTimestampWrites {
        query_set: &t.queries,
        beginning_of_pass_write_index: Some(2 * slot),
        end_of_pass_write_index: Some(2 * slot + 1),
    })
}
