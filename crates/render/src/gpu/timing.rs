//! GPU time per pass: two timestamps around each pass of a frame, resolved and read back
//! ([`crate::pass`]'s frame encoder writes them and reads them).

/// Two timestamps around each pass, resolved and copied to a mappable buffer.
pub(crate) struct PassTimer {
    pub(crate) queries: wgpu::QuerySet,
    pub(crate) resolve: wgpu::Buffer,
    pub(crate) readback: wgpu::Buffer,
}

impl PassTimer {
    pub(crate) fn new(device: &wgpu::Device, passes: u32) -> Self {
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
