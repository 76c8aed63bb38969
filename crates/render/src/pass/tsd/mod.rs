//! Texture-space diffusion (Gosselin et al. 2004): what its three passes share (the names of the
//! textures they write, the bind group of the texture-space passes) and the culling that decides
//! whether they run this frame. The pre-pass allocates the texture-space depth, the light-map
//! pass the light maps of the ping-pong blur and the stretch map; each blur reads and writes them
//! by name. The vertex stage of the pre-pass and the light-map pass is `tsd.wgsl`.

use super::resources::Resources;
use super::setup::TsdSetup;
use super::shadow::SHADOW_MAP;
use super::translucent::SHADOW_OPACITY;
use super::{PreparedScene, Upload, geometry};
use crate::gpu::{Gpu, STRETCH_FORMAT, Target, extent};
use crate::skin::tsd::{LIGHT_MAP_NAMES, final_map, map_count};
use std::sync::atomic::{AtomicBool, Ordering};

/// The texture-space depth of the culling pre-pass.
pub(crate) const DEPTH: &str = "tsd depth";
/// The stretch map the light-map pass writes and every blur reads.
pub(crate) const STRETCH: &str = "tsd stretch map";
/// [`Culling`]'s name.
const CULLING: &str = "tsd culling";

/// Whether a light map from an earlier frame can be reused (distance culling).
struct Culling {
    /// Below this projected diameter in pixels an earlier frame's light map is reused.
    reuse_below_px: f32,
    /// Whether a light map from an earlier frame exists.
    drawn: AtomicBool,
}

/// The scene's texture-space diffusion settings (a TSD pass is listed only with them).
pub(crate) fn setup<'a>(upload: &Upload<'a>) -> &'a TsdSetup {
    upload.skin.tsd.as_ref().expect("a TSD pass is listed only with its settings")
}

/// The light map the base pass reads: the last blur's target.
pub(crate) fn final_light_map(tsd: &TsdSetup) -> &'static str {
    LIGHT_MAP_NAMES[final_map(tsd.kernel, tsd.blurs())]
}

/// The pre-pass's share: the texture-space depth and the culling state.
pub(crate) fn allocate_depth(gpu: &Gpu, tsd: &TsdSetup, resources: &mut Resources) {
    resources.put(DEPTH, gpu.depth_texture("tsd texture-space depth", tsd.size, tsd.size, false));
    resources.put(CULLING, Culling { reuse_below_px: tsd.reuse_below_px, drawn: AtomicBool::new(false) });
}

/// The light-map pass's share: as many light maps as the kernel needs, and the stretch map.
pub(crate) fn allocate_maps(gpu: &Gpu, tsd: &TsdSetup, resources: &mut Resources) {
    let map = |label: &str, format| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: extent(tsd.size, tsd.size),
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
    for name in &LIGHT_MAP_NAMES[..map_count(tsd.kernel)] {
        resources.put(name, map(&format!("tsd {name}"), gpu.light_map_format()));
    }
    resources.put(STRETCH, map("tsd stretch map", STRETCH_FORMAT));
}

/// The bind group of the texture-space passes: the mesh passes' one reading the shadow map (and
/// the translucent casters' opacity, when there is one) but no light map.
pub(crate) fn texture_space_group(gpu: &Gpu, upload: &Upload<'_>, resources: &Resources) -> wgpu::BindGroup {
    upload.bind_group(gpu, resources, Some(SHADOW_MAP), Some(SHADOW_OPACITY), None)
}

/// Whether texture-space diffusion runs this frame: the head is in the frustum, and it is not so
/// small on screen that an earlier frame's light map is reused.
pub(crate) fn runs(scene: &PreparedScene, target: &Target) -> bool {
    let culling = scene.resources.get::<Culling>(CULLING);
    let camera = glam::Mat4::from_cols_array_2d(&scene.globals.scene.view_proj);
    let eye = glam::Vec3::from_array(scene.globals.scene.eye);
    let (centre, radius) = scene.bounds;
    let visible = geometry::sphere_in_frustum(camera, centre, radius);
    let small = geometry::projected_diameter(camera, eye, centre, radius, target.height) < culling.reuse_below_px;
    visible && !(small && culling.drawn.load(Ordering::Relaxed))
}

/// Notes that this frame draws the light maps (a later frame may reuse them). The frame decides
/// which passes run before it encodes any, so this frame's passes all saw the flag as it was.
pub(crate) fn mark_drawn(scene: &PreparedScene) {
    scene.resources.get::<Culling>(CULLING).drawn.store(true, Ordering::Relaxed);
}
