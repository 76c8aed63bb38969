//! What the skin effects hand the GPU: which shader features a scene's base pass compiles
//! ([`Features`], the WGSL override constants), the tables it samples, and the settings of the
//! key light's shadow map and of texture-space diffusion ([`SkinSetup`]); plus the geometry those
//! passes need (the mesh's bounding sphere, the key light's projection, the frustum test of the
//! TSD culling pre-pass, the Poisson kernel's spread).
//!
//! [`crate::load`] builds a [`SkinSetup`] from a scene; [`crate::gpu::Gpu::prepare_with`] uploads
//! it and [`crate::gpu::Gpu::draw`] runs the passes it asks for, and only those.

use glam::{Mat4, Vec3, Vec4};

use crate::shading::{Light, LightKind, Texture, Vertex};

pub use crate::graph::{DiffuseMode, Features};

/// An RGB float table for the GPU, with the affine map from its parameter to a texture coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major RGB, row 0 at the top.
    pub texels: Vec<[f32; 3]>,
    /// `coordinate = parameter * scale + offset` for the table's second axis (v for LUTs indexed
    /// by N.L or s along u; u for the zonal table).
    pub scale: f32,
    /// See `scale`.
    pub offset: f32,
}

impl Table {
    /// The affine map putting `lo` on the centre of the first texel and `hi` on the last of `n`.
    pub(crate) fn centred_map(lo: f32, hi: f32, n: u32) -> (f32, f32) {
        if n <= 1 || hi <= lo {
            return (0.0, 0.5);
        }
        let n = n as f32;
        let scale = (n - 1.0) / (n * (hi - lo));
        (scale, 0.5 / n - lo * scale)
    }
}

/// The key light's shadow map.
#[derive(Debug, Clone, PartialEq)]
pub struct ShadowSetup {
    /// Index of the light (below the scene's light count).
    pub light: usize,
    /// Shadow map side.
    pub map_size: u32,
    /// Box filter side (odd), or with shadow scattering the taps on its disc.
    pub filter: u32,
    /// Normal-offset bias in texels.
    pub bias: f32,
    /// Shadow scattering's disc of taps on the receiver: its radius in mesh units (0 without).
    pub disc_radius: f32,
    /// The light's view-projection (wgpu depth 0..1).
    pub view_proj: Mat4,
    /// One shadow-map texel in mesh units (at the mesh's centre for a point light).
    pub texel: f32,
    /// Shadow scattering: the sharp penumbra's share of the filtered one.
    pub new_penumbra: f32,
    /// Translucent casters drawn into the map's opacity channels.
    pub translucent: Vec<TranslucentCaster>,
}

/// A translucent shadow caster as the shadow pass draws it.
#[derive(Debug, Clone, PartialEq)]
pub struct TranslucentCaster {
    /// Positions in object space.
    pub positions: Vec<[f32; 3]>,
    /// Triangle list.
    pub indices: Vec<u32>,
    /// Opacity per channel.
    pub opacity: [f32; 3],
}

/// Texture-space diffusion's settings.
#[derive(Debug, Clone, PartialEq)]
pub struct TsdSetup {
    /// Light map side.
    pub size: u32,
    /// How the light map is blurred.
    pub kernel: crate::skin::options::TsdKernel,
    /// Blur passes (with the Gaussians, per Gaussian: `crate::skin::tsd::blur_count`).
    pub passes: u32,
    /// An artist's kernel map (red channel in [0, 1)), if any.
    pub kernel_map: Option<Texture>,
    /// (a, b) of radius = a * k + b, in texels of this light map.
    pub kernel_scale: [f32; 2],
    /// The derived kernel: Poisson radius in mm for flat skin (with the Gaussians, the radius
    /// every pass scales, [`crate::skin::tsd::GAUSSIANS_KERNEL_MM`]).
    pub kernel_mm: f32,
    /// Derived kernel: radius x (1 + gain * 1/r), mm.
    pub curvature_gain: f32,
    /// Back-face pre-pass bias.
    pub backface_bias: f32,
    /// Distance culling threshold in pixels of projected diameter.
    pub reuse_below_px: f32,
}

impl TsdSetup {
    /// The blur passes this setup runs.
    pub fn blurs(&self) -> u32 {
        crate::skin::tsd::blur_count(self.kernel, self.passes)
    }
}

pub use crate::skin::poisson::{
    MAX_KERNEL_TEXELS, POISSON, poisson_axis_variance, poisson_mean, poisson_second_moment,
};

/// Everything the skin effects add to a base-pass scene; the default adds nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinSetup {
    /// The pipeline's features.
    pub features: Features,
    /// Per vertex: 1/r in 1/mm and mm per UV unit (empty: zeros).
    pub vertex_skin: Vec<[f32; 2]>,
    /// Scale on 1/r.
    pub curvature_scale: f32,
    /// Millimetres per mesh unit.
    pub mm_per_unit: f32,
    /// Per-channel blend toward the blurred normal.
    pub normal_blur: Vec3,
    /// Mip level of the blurred normal sample.
    pub blur_mip: f32,
    /// The diffuse LUT (x: N.L, y: 1/r).
    pub diffuse_lut: Option<Table>,
    /// The shadow LUT (x: s, y: penumbra width in mm).
    pub shadow_lut: Option<Table>,
    /// The zonal table (x: 1/r, rows l = 0, 1, 2).
    pub zonal: Option<Table>,
    /// Environment radiance SH (9 RGB coefficients).
    pub sh: [[f32; 3]; 9],
    /// The key light's shadow map.
    pub shadow: Option<ShadowSetup>,
    /// Texture-space diffusion.
    pub tsd: Option<TsdSetup>,
    /// A light map given by the caller (the CPU reference), for [`DiffuseMode::LightMap`]
    /// without TSD passes.
    pub light_map: Option<Texture>,
}

impl SkinSetup {
    /// The passes the GPU runs for this setup, in order (the one order,
    /// `crate::graph::ordered_passes`; for a scene's setup the same list as its graph's).
    pub fn passes(&self) -> Vec<crate::graph::PassKind> {
        let translucent = self.shadow.as_ref().is_some_and(|s| !s.translucent.is_empty());
        crate::graph::ordered_passes(self.shadow.is_some(), translucent, self.tsd.as_ref().map(TsdSetup::blurs))
    }
}

impl Default for SkinSetup {
    fn default() -> Self {
        Self {
            features: Features::default(),
            vertex_skin: Vec::new(),
            curvature_scale: 1.0,
            mm_per_unit: 1.0,
            normal_blur: Vec3::ZERO,
            blur_mip: 0.0,
            diffuse_lut: None,
            shadow_lut: None,
            zonal: None,
            sh: [[0.0; 3]; 9],
            shadow: None,
            tsd: None,
            light_map: None,
        }
    }
}

/// The bounding sphere of the vertices (centre of the box, largest distance); finite positions
/// only, a unit sphere at the origin when none are.
pub fn bounding_sphere(vertices: &[Vertex]) -> (Vec3, f32) {
    let finite = vertices.iter().map(|v| Vec3::from(v.position)).filter(|p| p.is_finite());
    let (lo, hi) = finite.clone().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p), hi.max(p)));
    if !lo.is_finite() {
        return (Vec3::ZERO, 1.0);
    }
    let centre = 0.5 * (lo + hi);
    let radius = finite.map(|p| p.distance(centre)).fold(0.0f32, f32::max);
    (centre, radius.max(1e-6))
}

/// The key light's view-projection bounding the mesh's sphere tightly (the chapter's advice),
/// and the size of one of `map_size` texels in mesh units: orthographic for a directional light,
/// perspective from the light for a point light (a point inside the sphere falls back to a wide
/// frustum looking at the centre).
pub fn light_view_proj(light: &Light, centre: Vec3, radius: f32, map_size: u32) -> (Mat4, f32) {
    match light.kind {
        LightKind::Directional { toward } => {
            let dir = toward.try_normalize().unwrap_or(Vec3::Z);
            let eye = centre + dir * (2.0 * radius);
            let view = Mat4::look_at_rh(eye, centre, any_up(dir));
            let proj = Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.5 * radius, 3.5 * radius);
            (proj * view, 2.0 * radius / map_size.max(1) as f32)
        }
        LightKind::Point { position } => {
            let to_centre = centre - position;
            let distance = to_centre.length();
            let dir = to_centre.try_normalize().unwrap_or(-Vec3::Z);
            let half_angle = if distance > radius * 1.01 { (radius / distance).asin() } else { 80f32.to_radians() };
            let near = (distance - radius).max(radius * 1e-3);
            let far = distance + radius;
            let view = Mat4::look_at_rh(position, position + dir, any_up(dir));
            let proj = Mat4::perspective_rh(2.0 * half_angle, 1.0, near, far);
            let texel = 2.0 * distance.max(radius) * half_angle.tan() / map_size.max(1) as f32;
            (proj * view, texel)
        }
    }
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() < 0.9 { Vec3::Y } else { Vec3::X }
}

/// Whether a sphere is at least partly inside the frustum of `view_proj` (the TSD frustum
/// culling test; planes from the matrix's rows, Gribb-Hartmann, wgpu depth 0..1).
pub(crate) fn sphere_in_frustum(view_proj: Mat4, centre: Vec3, radius: f32) -> bool {
    let m = view_proj.transpose();
    let (r0, r1, r2, r3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    let planes = [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r2, r3 - r2];
    let p = Vec4::new(centre.x, centre.y, centre.z, 1.0);
    planes.iter().all(|plane| {
        let len = plane.truncate().length();
        len == 0.0 || plane.dot(p) / len >= -radius
    })
}

/// The sphere's projected diameter in pixels for an image `height` pixels tall (the TSD distance
/// culling measure); infinite when the camera is inside it.
pub(crate) fn projected_diameter(view_proj: Mat4, eye: Vec3, centre: Vec3, radius: f32, height: u32) -> f32 {
    let distance = eye.distance(centre);
    if distance <= radius {
        return f32::INFINITY;
    }
    radius / distance * focal_from(view_proj) * height as f32
}

/// The vertical focal scale of a perspective view-projection (cot(fov/2)): the length of the
/// matrix's second row in its spatial part.
pub(crate) fn focal_from(view_proj: Mat4) -> f32 {
    view_proj.row(1).truncate().length()
}

/// Per vertex mm per UV unit: the square root of the summed world areas (mm^2) of its triangles
/// over their summed UV areas; vertices of zero-UV-area triangles only take the mesh's mean.
pub fn uv_stretch(vertices: &[Vertex], indices: &[u32], mm_per_unit: f32) -> Vec<f32> {
    let mut world = vec![0.0f64; vertices.len()];
    let mut uv = vec![0.0f64; vertices.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if a >= vertices.len() || b >= vertices.len() || c >= vertices.len() {
            continue;
        }
        let p = |i: usize| Vec3::from(vertices[i].position) * mm_per_unit;
        let t = |i: usize| glam::Vec2::from(vertices[i].uv);
        let area_world = 0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length() as f64;
        let area_uv = 0.5 * (t(b) - t(a)).perp_dot(t(c) - t(a)).abs() as f64;
        if !(area_world.is_finite() && area_uv.is_finite()) || area_uv < 1e-14 {
            continue;
        }
        for i in [a, b, c] {
            world[i] += area_world;
            uv[i] += area_uv;
        }
    }
    let (tw, tu) = (world.iter().sum::<f64>(), uv.iter().sum::<f64>());
    let mean = if tu > 0.0 { (tw / tu).sqrt() } else { 1.0 };
    world.iter().zip(&uv).map(|(&w, &u)| if u > 0.0 { (w / u).sqrt() as f32 } else { mean as f32 }).collect()
}
