//! Texture-space diffusion (Gosselin et al. 2004): the resources its three passes share (the
//! texture-space depth, the two light maps of the ping-pong blur, their bind groups), and the
//! culling that decides whether they run this frame. The vertex stage of the pre-pass and the
//! light-map pass is `tsd.wgsl`.

use super::{PreparedScene, geometry, setup};
use crate::gpu::{Gpu, STRETCH_FORMAT, Target, extent};
use std::sync::atomic::{AtomicBool, Ordering};

/// Texture-space diffusion: the UV-space depth of the culling pre-pass, two light maps for the
/// ping-pong blur, and the bind groups of each pass.
pub(crate) struct TsdResources {
    /// The light map the base pass reads (the last blur's target).
    pub(crate) final_map: usize,
    pub(crate) reuse_below_px: f32,
    pub(crate) depth: wgpu::Texture,
    /// [`crate::skin::tsd::LIGHT_MAP_NAMES`], as many as the kernel needs.
    pub(crate) maps: Vec<wgpu::Texture>,
    /// The stretch map the light-map pass writes and every blur reads.
    pub(crate) stretch: wgpu::Texture,
    /// The base bind group's layout, for the texture-space passes (no light map bound).
    pub(crate) bind_group: wgpu::BindGroup,
    /// Per blur pass, its bind group and the map it writes ([`crate::skin::tsd::blur_maps`]).
    pub(crate) blur_groups: Vec<(wgpu::BindGroup, usize)>,
    /// Whether a light map from an earlier frame exists (distance culling reuses it).
    pub(crate) ready: AtomicBool,
}

impl Gpu {
    /// The light maps and their depth for `tsd`, with `bind_group` for the texture-space passes
    /// (one that reads the shadow map, and the translucent casters' opacity, when there is one);
    /// the blur's bind groups are the blur pass's to add.
    pub(crate) fn tsd_resources(&self, tsd: &setup::TsdSetup, bind_group: wgpu::BindGroup) -> TsdResources {
        let size = tsd.size;
        let depth = self.depth_texture("tsd texture-space depth", size, size, false);
        let map = |label: &str, format| {
            self.device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: extent(size, size),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let maps: Vec<wgpu::Texture> = crate::skin::tsd::LIGHT_MAP_NAMES[..crate::skin::tsd::map_count(tsd.kernel)]
            .iter()
            .map(|name| map(&format!("tsd {name}"), self.light_map_format()))
            .collect();
        let stretch = map("tsd stretch map", STRETCH_FORMAT);
        TsdResources {
            final_map: crate::skin::tsd::final_map(tsd.kernel, tsd.blurs()),
            reuse_below_px: tsd.reuse_below_px,
            depth,
            maps,
            stretch,
            bind_group,
            blur_groups: Vec::new(),
            ready: AtomicBool::new(false),
        }
    }

    /// Whether texture-space diffusion runs this frame: the head is in the frustum, and it is
    /// not so small on screen that an earlier frame's light map is reused.
    pub(crate) fn tsd_runs(&self, scene: &PreparedScene, tsd: &TsdResources, target: &Target) -> bool {
        let camera = glam::Mat4::from_cols_array_2d(&scene.globals.scene.view_proj);
        let eye = glam::Vec3::from_array(scene.globals.scene.eye);
        let (centre, radius) = scene.bounds;
        let visible = geometry::sphere_in_frustum(camera, centre, radius);
        let small = geometry::projected_diameter(camera, eye, centre, radius, target.height) < tsd.reuse_below_px;
        visible && !(small && tsd.ready.load(Ordering::Relaxed))
    }
}
