//! The CPU reference of the base shading in `src/pass/base/base.wgsl` and `common.wgsl` (Haro et al.
//! 2001, section 5): the same inputs, the same steps, in plain Rust, so GPU renders can be
//! compared per pixel.
//!
//! Per vertex ([`shade_vertex`]): the light and view vectors are computed in object space,
//! normalised, and taken into the vertex's texture space (tangent, bitangent = cross(N, T) * w,
//! normal): the paper's section 5.1. With [`SpecularMode::Vertex`] the Lafortune lobes are also
//! evaluated here against the vertex normal, as the paper had to (section 5.2).
//!
//! Per pixel ([`shade_fragment`]): the interpolated vectors are renormalised, the normal-map texel
//! is decoded (green flipped for green-down maps; a zero texel means "no detail" and reads as the
//! unperturbed normal), and the Lafortune BRDF is evaluated in the frame of the map's normal:
//! `sum over lights of E * f(l, v) * max(0, n.l)` with `E = colour * intensity` (divided by the
//! squared distance for point lights) and `rho_d = brdf.diffuse * albedo texel`.
//!
//! Tone mapping ([`tone_map`]): multiply by the exposure; HDR outputs (EXR) stop there and stay
//! linear; LDR outputs (PNG) then apply [`ToneCurve`] (clamp to 1, or Reinhard `c / (1 + c)` per
//! channel) and the sRGB encoding ([`srgb_encode`], done by the Rgba8UnormSrgb target on the GPU).
//!
//! [`render_cpu`] is a tiny rasteriser with the GPU's conventions (pixel centres at +0.5, row 0 at
//! the top, perspective-correct interpolation, depth test `less`, no culling). It samples textures
//! bilinearly at mip level 0 with repeat addressing, so it matches the GPU where textures are
//! magnified (the test scenes); triangles with a vertex behind the camera are dropped, not clipped.
//! Texture coordinates follow the image convention: v = 0 is the first (top) row.

use crate::brdf::Lafortune;
use glam::{Mat4, Vec2, Vec3, Vec4};
use rayon::prelude::*;

/// Most lights one pass shades (the WGSL uniform arrays have this length).
pub const MAX_LIGHTS: usize = 4;
/// Most Lafortune lobes one pass evaluates.
pub(crate) const MAX_LOBES: usize = 4;

/// One mesh vertex as the GPU reads it (48 bytes, `#[repr(C)]`). `tangent.w` is the handedness:
/// bitangent = cross(normal, tangent.xyz) * tangent.w (MikkTSpace convention).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    /// Object-space position (object space is world space: the base pass has no model matrix).
    pub position: [f32; 3],
    /// Unit vertex normal.
    pub normal: [f32; 3],
    /// Tangent (direction of increasing u) and handedness.
    pub tangent: [f32; 4],
    /// Texture coordinates, v = 0 at the top row of the maps.
    pub uv: [f32; 2],
}

/// Where a light is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Infinitely far away; the vector points from the surface toward the light.
    Directional {
        /// Direction toward the light (need not be unit).
        toward: Vec3,
    },
    /// A point light; irradiance falls off with the squared distance.
    Point {
        /// Position in object space.
        position: Vec3,
    },
}

/// A light: where it is, its colour and intensity (irradiance `colour * intensity` for a
/// directional light, `colour * intensity / d^2` for a point light).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Direction or position.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Scale on the colour.
    pub intensity: f32,
}

/// A camera as the shaders see it: the view-projection matrix (wgpu depth range 0..1) and the
/// eye position for view vectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Object space to clip space.
    pub view_proj: Mat4,
    /// Eye position in object space.
    pub eye: Vec3,
}

/// Which way the map's green channel points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GreenAxis {
    /// +y is up in the image (OpenGL, glTF, Blender, skinkit's own maps).
    #[default]
    Up,
    /// +y is down (DirectX, Unreal): the decoder flips y.
    Down,
}

/// Where the Lafortune lobes are evaluated (a scene's `specular = "pixel"` or `"vertex"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SpecularMode {
    /// Every lobe per pixel against the normal map's normal.
    #[default]
    Pixel,
    /// Lobes per vertex against the vertex normal, interpolated (the paper's 2001 look); the
    /// diffuse term stays per pixel.
    Vertex,
}

/// The LDR curve applied after the exposure.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ToneCurve {
    /// Keep linear HDR values (EXR output).
    #[default]
    None,
    /// Clamp each channel to [0, 1].
    Clamp,
    /// Reinhard per channel: `c / (1 + c)`.
    Reinhard,
}

/// A linear RGBA float texture, row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major texels.
    pub texels: Vec<[f32; 4]>,
}

impl Texture {
    /// A texture from a function of (x, y).
    pub fn from_fn(width: u32, height: u32, f: impl Fn(u32, u32) -> [f32; 4]) -> Self {
        let texels = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect();
        Self { width, height, texels }
    }

    /// A 1x1 texture.
    pub fn solid(rgba: [f32; 4]) -> Self {
        Self::from_fn(1, 1, |_, _| rgba)
    }

    /// The flat normal map (every texel (0, 0, 1)).
    pub fn flat_normals() -> Self {
        Self::solid([0.0, 0.0, 1.0, 0.0])
    }

    /// A normal map's vectors (invalid normals stay (0, 0, 0)).
    pub fn from_normal_map(map: &skinkit_maps::NormalMap) -> Self {
        Self::from_fn(map.width() as u32, map.height() as u32, |x, y| {
            let n = map.get(x as usize, y as usize);
            [n.x, n.y, n.z, 0.0]
        })
    }

    /// The same texture rounded to f16, as the GPU stores it (Rgba16Float).
    pub fn quantized_f16(&self) -> Self {
        let round = |v: f32| half::f16::from_f32(v).to_f32();
        Self { width: self.width, height: self.height, texels: self.texels.iter().map(|t| t.map(round)).collect() }
    }

    fn texel(&self, x: i64, y: i64) -> Vec4 {
        let x = x.rem_euclid(self.width as i64) as usize;
        let y = y.rem_euclid(self.height as i64) as usize;
        Vec4::from(self.texels[y * self.width as usize + x])
    }

    /// Bilinear sample with repeat addressing, texel centres at (i + 0.5) / size (the GPU's
    /// rule). Non-finite coordinates read texel (0, 0).
    pub fn sample(&self, uv: Vec2) -> Vec4 {
        if self.texels.is_empty() {
            return Vec4::ZERO;
        }
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        let x = uv.x as f64 * self.width as f64 - 0.5;
        let y = uv.y as f64 * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// The next mip level: each texel the plain average of its 2x2 parents (edge texels reused
    /// for odd sizes). For normal maps this averages the unnormalised vectors, so a bumpy region
    /// becomes a shorter, smoother vector that the shader renormalises: distant skin does not
    /// sparkle (normal-aware filtering without extra storage).
    pub(crate) fn downsample(&self) -> Self {
        let width = (self.width / 2).max(1);
        let height = (self.height / 2).max(1);
        Self::from_fn(width, height, |x, y| {
            let clamp_x = |i: u32| (i.min(self.width - 1)) as i64;
            let clamp_y = |i: u32| (i.min(self.height - 1)) as i64;
            let (x0, x1) = (clamp_x(2 * x), clamp_x(2 * x + 1));
            let (y0, y1) = (clamp_y(2 * y), clamp_y(2 * y + 1));
            let sum = self.texel(x0, y0) + self.texel(x1, y0) + self.texel(x0, y1) + self.texel(x1, y1);
            (sum * 0.25).to_array()
        })
    }

    /// The full mip chain, level 0 (a copy of `self`) down to 1x1.
    pub fn mip_chain(&self) -> Vec<Texture> {
        let mut levels = vec![self.clone()];
        while let Some(last) = levels.last().filter(|t| t.width > 1 || t.height > 1) {
            let next = last.downsample();
            levels.push(next);
        }
        levels
    }
}

/// Everything one base-pass render needs, shared by [`render_cpu`] and `gpu::Gpu::render`.
#[derive(Debug, Clone)]
pub struct RenderInputs {
    /// Mesh vertices.
    pub vertices: Vec<Vertex>,
    /// Triangle list indices.
    pub indices: Vec<u32>,
    /// The camera.
    pub camera: Camera,
    /// At most [`MAX_LIGHTS`] lights.
    pub lights: Vec<Light>,
    /// The BRDF, at most `MAX_LOBES` lobes.
    pub brdf: Lafortune,
    /// Normal map vectors in texture space (decoded to [-1, 1]; zero = no detail).
    pub normal_map: Texture,
    /// The normal map's green convention.
    pub green: GreenAxis,
    /// Linear albedo multiplying `brdf.diffuse`.
    pub albedo: Texture,
    /// Where the lobes are evaluated.
    pub specular: SpecularMode,
    /// Multiplies the radiance before the tone curve.
    pub exposure: f32,
    /// LDR curve, or [`ToneCurve::None`] for linear output.
    pub tone: ToneCurve,
    /// Colour where no triangle covers the pixel (linear RGBA, not tone mapped).
    pub background: [f32; 4],
}

/// The shading state shared by the vertex and fragment steps.
#[derive(Debug, Clone, Copy)]
pub struct ShadingParams<'a> {
    /// Eye position for view vectors.
    pub eye: Vec3,
    /// Lights (only the first [`MAX_LIGHTS`] are used).
    pub lights: &'a [Light],
    /// The BRDF (only the first `MAX_LOBES` lobes are used).
    pub brdf: &'a Lafortune,
    /// Normal map.
    pub normal_map: &'a Texture,
    /// Green convention.
    pub green: GreenAxis,
    /// Albedo texture.
    pub albedo: &'a Texture,
    /// Lobes per pixel or per vertex.
    pub specular: SpecularMode,
}

impl RenderInputs {
    /// The shading parameters of these inputs.
    pub fn params(&self) -> ShadingParams<'_> {
        ShadingParams {
            eye: self.camera.eye,
            lights: &self.lights,
            brdf: &self.brdf,
            normal_map: &self.normal_map,
            green: self.green,
            albedo: &self.albedo,
            specular: self.specular,
        }
    }
}

/// What the vertex step hands to the rasteriser: clip position and the interpolated values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexOutput {
    /// Clip-space position.
    pub clip: Vec4,
    /// Values interpolated across the triangle.
    pub varyings: Varyings,
}

/// Interpolated per-pixel inputs of [`shade_fragment`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Varyings {
    /// Texture coordinates.
    pub uv: Vec2,
    /// Unit view vector in the vertex's texture space (unnormalised after interpolation).
    pub view_ts: Vec3,
    /// Unit light vectors in texture space, one per light slot.
    pub lights_ts: [Vec3; MAX_LIGHTS],
    /// Object-space position (point-light falloff).
    pub world: Vec3,
    /// Radiance of the per-vertex lobes ([`SpecularMode::Vertex`]), else zero.
    pub vertex_specular: Vec3,
}

impl Varyings {
    /// `a * wa + b * wb + c * wc`, field by field.
    pub fn blend(a: &Self, b: &Self, c: &Self, w: Vec3) -> Self {
        let mix3 = |x: Vec3, y: Vec3, z: Vec3| x * w.x + y * w.y + z * w.z;
        let mut lights_ts = [Vec3::ZERO; MAX_LIGHTS];
        for (i, l) in lights_ts.iter_mut().enumerate() {
            *l = mix3(a.lights_ts[i], b.lights_ts[i], c.lights_ts[i]);
        }
        Self {
            uv: a.uv * w.x + b.uv * w.y + c.uv * w.z,
            view_ts: mix3(a.view_ts, b.view_ts, c.view_ts),
            lights_ts,
            world: mix3(a.world, b.world, c.world),
            vertex_specular: mix3(a.vertex_specular, b.vertex_specular, c.vertex_specular),
        }
    }
}

/// `v / |v|`, or `fallback` when `v` is (nearly) zero or not finite.
pub fn normalize_or(v: Vec3, fallback: Vec3) -> Vec3 {
    let len = v.length();
    if len > 1e-12 && len.is_finite() { v / len } else { fallback }
}

/// An orthonormal (tangent, bitangent, normal) frame: the tangent is made perpendicular to the
/// normal (Gram-Schmidt) and falls back to any perpendicular when degenerate; the bitangent is
/// `cross(n, t) * sign(w)`.
pub fn tangent_frame(normal: Vec3, tangent: Vec4) -> (Vec3, Vec3, Vec3) {
    let n = normalize_or(normal, Vec3::Z);
    let t = perpendicular_part(tangent.truncate(), n);
    let sign = if tangent.w < 0.0 { -1.0 } else { 1.0 };
    (t, n.cross(t) * sign, n)
}

/// The unit part of `v` perpendicular to the unit `n`, or `any_perpendicular` when `v` is
/// (nearly) parallel to `n`, zero or not finite. The threshold is relative (1e-4 of |v|), so a
/// tangent parallel to the normal up to rounding does not normalise rounding noise.
pub(crate) fn perpendicular_part(v: Vec3, n: Vec3) -> Vec3 {
    let p = v - n * n.dot(v);
    let len = p.length();
    if len > 1e-4 * v.length() && len.is_finite() { p / len } else { any_perpendicular(n) }
}

/// A unit vector perpendicular to the unit `n` (deterministic choice).
fn any_perpendicular(n: Vec3) -> Vec3 {
    let axis = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    normalize_or(axis - n * n.dot(axis), Vec3::Y)
}

/// The unit vector from `world` toward the light, and the light's irradiance there.
pub(crate) fn light_at(light: &Light, world: Vec3) -> (Vec3, Vec3) {
    let radiance = light.color * light.intensity;
    match light.kind {
        LightKind::Directional { toward } => (normalize_or(toward, Vec3::Z), radiance),
        LightKind::Point { position } => {
            let d = position - world;
            let d2 = d.length_squared().max(1e-12);
            (normalize_or(d, Vec3::Z), radiance / d2)
        }
    }
}

/// The vertex step: clip position, texture-space light and view vectors, and per-vertex lobes.
pub fn shade_vertex(params: &ShadingParams, view_proj: Mat4, vertex: &Vertex) -> VertexOutput {
    let world = Vec3::from(vertex.position);
    let (t, b, n) = tangent_frame(vertex.normal.into(), vertex.tangent.into());
    let to_ts = |d: Vec3| Vec3::new(d.dot(t), d.dot(b), d.dot(n));
    let view_ts = to_ts(normalize_or(params.eye - world, n));
    let mut lights_ts = [Vec3::ZERO; MAX_LIGHTS];
    let mut vertex_specular = Vec3::ZERO;
    for (slot, light) in lights_ts.iter_mut().zip(params.lights) {
        let (l, irradiance) = light_at(light, world);
        *slot = to_ts(l);
        if params.specular == SpecularMode::Vertex {
            let lobes = lobes_sum(params.brdf, *slot, view_ts);
            vertex_specular += irradiance * lobes * slot.z.max(0.0);
        }
    }
    VertexOutput {
        clip: view_proj * world.extend(1.0),
        varyings: Varyings { uv: vertex.uv.into(), view_ts, lights_ts, world, vertex_specular },
    }
}

fn lobes_sum(brdf: &Lafortune, l: Vec3, v: Vec3) -> Vec3 {
    brdf.lobes.iter().take(MAX_LOBES).map(|lobe| lobe.eval(l, v)).sum()
}

/// Decode a normal-map texel: flip green for green-down maps and normalise; a zero (invalid or
/// fully cancelled) texel reads as the unperturbed normal (0, 0, 1).
pub fn decode_normal(texel: Vec4, green: GreenAxis) -> Vec3 {
    let mut n = texel.truncate();
    if green == GreenAxis::Down {
        n.y = -n.y;
    }
    normalize_or(n, Vec3::Z)
}

/// Express texture-space `d` in the frame whose z is the map normal `n` (x follows the texture's
/// u direction projected onto the perturbed surface).
pub(crate) fn to_normal_frame(n: Vec3, d: Vec3) -> Vec3 {
    let t = perpendicular_part(Vec3::X, n);
    let b = n.cross(t);
    Vec3::new(d.dot(t), d.dot(b), d.dot(n))
}

/// The fragment step: linear radiance of one pixel from its interpolated inputs.
pub fn shade_fragment(params: &ShadingParams, input: &Varyings) -> Vec3 {
    let n = decode_normal(params.normal_map.sample(input.uv), params.green);
    let albedo = params.albedo.sample(input.uv).truncate();
    let rho = params.brdf.diffuse * albedo / std::f32::consts::PI;
    let v = to_normal_frame(n, normalize_or(input.view_ts, Vec3::Z));
    let mut radiance = input.vertex_specular;
    for (i, light) in params.lights.iter().take(MAX_LIGHTS).enumerate() {
        let (_, irradiance) = light_at(light, input.world);
        let l = to_normal_frame(n, normalize_or(input.lights_ts[i], Vec3::Z));
        let mut f = rho;
        if params.specular == SpecularMode::Pixel {
            f += lobes_sum(params.brdf, l, v);
        }
        radiance += irradiance * f * l.z.max(0.0);
    }
    radiance
}

/// Exposure then the tone curve (see the module docs).
pub fn tone_map(radiance: Vec3, exposure: f32, curve: ToneCurve) -> Vec3 {
    let c = (radiance * exposure).max(Vec3::ZERO);
    match curve {
        ToneCurve::None => c,
        ToneCurve::Clamp => c.min(Vec3::ONE),
        ToneCurve::Reinhard => c / (Vec3::ONE + c),
    }
}

/// The sRGB transfer function for a linear value in [0, 1] (clamped).
pub fn srgb_encode(linear: f32) -> f32 {
    let c = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    if c <= 0.0031308 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// A covered pixel: depth and the blended varyings.
#[derive(Clone, Copy)]
struct Fragment {
    depth: f32,
    varyings: Varyings,
}

/// Render `inputs` on the CPU: linear RGBA per pixel, row 0 at the top, tone mapped as the GPU
/// does (exposure and curve; the sRGB encoding of LDR targets is left to the caller, as the
/// GPU's Rgba8UnormSrgb target stores it). Textures are rounded to f16 first, as uploaded.
pub fn render_cpu(inputs: &RenderInputs, width: u32, height: u32) -> Vec<[f32; 4]> {
    let normal_map = inputs.normal_map.quantized_f16();
    let albedo = inputs.albedo.quantized_f16();
    let params = ShadingParams { normal_map: &normal_map, albedo: &albedo, ..inputs.params() };
    let outputs: Vec<VertexOutput> =
        inputs.vertices.iter().map(|v| shade_vertex(&params, inputs.camera.view_proj, v)).collect();
    let fragments = rasterize(&outputs, &inputs.indices, width, height);
    fragments
        .par_iter()
        .map(|fragment| match fragment {
            None => inputs.background,
            Some(f) => {
                let c = tone_map(shade_fragment(&params, &f.varyings), inputs.exposure, inputs.tone);
                [c.x, c.y, c.z, 1.0]
            }
        })
        .collect()
}

/// Screen position (pixels, y down), NDC depth and 1/w of a clip position.
fn to_screen(clip: Vec4, width: u32, height: u32) -> Option<(Vec2, f32, f32)> {
    if clip.w <= 1e-6 || !clip.is_finite() {
        return None;
    }
    let inv_w = 1.0 / clip.w;
    let ndc = clip.truncate() * inv_w;
    let x = (ndc.x * 0.5 + 0.5) * width as f32;
    let y = (0.5 - ndc.y * 0.5) * height as f32;
    Some((Vec2::new(x, y), ndc.z, inv_w))
}

fn edge(a: Vec2, b: Vec2, p: Vec2) -> f32 {
    (b - a).perp_dot(p - a)
}

/// The depth-tested fragments of all triangles, one slot per pixel.
fn rasterize(vertices: &[VertexOutput], indices: &[u32], width: u32, height: u32) -> Vec<Option<Fragment>> {
    let mut target: Vec<Option<Fragment>> = vec![None; (width * height) as usize];
    for tri in indices.chunks_exact(3) {
        let Some(corners) = triangle_corners(vertices, tri) else {
            continue;
        };
        rasterize_triangle(&corners, width, height, &mut target);
    }
    target
}

type Corner<'a> = (Vec2, f32, f32, &'a Varyings);

fn triangle_corners<'a>(vertices: &'a [VertexOutput], tri: &[u32]) -> Option<[Corner<'a>; 3]> {
    let corner = |i: u32| -> Option<Corner<'a>> {
        let v = vertices.get(i as usize)?;
        // The viewport size only scales x and y: use 1x1 here, rescale in the caller.
        let (p, z, inv_w) = to_screen(v.clip, 1, 1)?;
        Some((p, z, inv_w, &v.varyings))
    };
    Some([corner(tri[0])?, corner(tri[1])?, corner(tri[2])?])
}

fn rasterize_triangle(corners: &[Corner; 3], width: u32, height: u32, target: &mut [Option<Fragment>]) {
    let scale = Vec2::new(width as f32, height as f32);
    let p = corners.map(|c| c.0 * scale);
    let area = edge(p[0], p[1], p[2]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    let lo = p[0].min(p[1]).min(p[2]).max(Vec2::ZERO);
    let hi = p[0].max(p[1]).max(p[2]).min(scale);
    for y in lo.y.floor() as u32..hi.y.ceil() as u32 {
        for x in lo.x.floor() as u32..hi.x.ceil() as u32 {
            let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let b = Vec3::new(edge(p[1], p[2], centre), edge(p[2], p[0], centre), edge(p[0], p[1], centre)) / area;
            if b.min_element() < 0.0 {
                continue;
            }
            let depth = b.x * corners[0].1 + b.y * corners[1].1 + b.z * corners[2].1;
            let slot = &mut target[(y * width + x) as usize];
            if !(0.0..=1.0).contains(&depth) || slot.is_some_and(|f| f.depth <= depth) {
                continue;
            }
            let persp = b * Vec3::new(corners[0].2, corners[1].2, corners[2].2);
            let persp = persp / persp.element_sum();
            let varyings = Varyings::blend(corners[0].3, corners[1].3, corners[2].3, persp);
            *slot = Some(Fragment { depth, varyings });
        }
    }
}

/// A unit UV sphere centred on the origin, `segments` around (u from +z toward +x) and `rings`
/// from the north pole (v = 0) to the south pole, with analytic normals and tangents along +u:
/// the test and benchmark scene whose shading has a closed form per pixel.
pub fn uv_sphere(segments: u32, rings: u32) -> (Vec<Vertex>, Vec<u32>) {
    use std::f32::consts::PI;
    let mut vertices = Vec::with_capacity(((segments + 1) * (rings + 1)) as usize);
    for r in 0..=rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.sin(), theta.cos(), theta.sin() * phi.cos());
            vertices.push(Vertex {
                position: n.into(),
                normal: n.into(),
                tangent: Vec4::new(phi.cos(), 0.0, -phi.sin(), 1.0).into(),
                uv: [s as f32 / segments as f32, r as f32 / rings as f32],
            });
        }
    }
    let row = segments + 1;
    let indices = (0..rings)
        .flat_map(|r| (0..segments).map(move |s| r * row + s))
        .flat_map(|a| [a, a + row, a + 1, a + 1, a + row, a + row + 1])
        .collect();
    (vertices, indices)
}

impl Camera {
    /// A perspective camera looking from `eye` at `target` (right-handed, y up, wgpu depth range).
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, fov_y_degrees: f32, aspect: f32) -> Self {
        let view = Mat4::look_at_rh(eye, target, up);
        let distance = (target - eye).length().max(1e-3);
        let proj = Mat4::perspective_rh(fov_y_degrees.to_radians(), aspect, distance * 0.01, distance * 100.0);
        Self { view_proj: proj * view, eye }
    }
}
