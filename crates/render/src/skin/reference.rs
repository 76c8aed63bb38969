//! The slow, exact texture-space reference of subsurface scattering that every real-time skin
//! effect (pre-integrated skin, Penner and Borshukov 2011; texture-space diffusion, Gosselin et
//! al. 2004 and d'Eon and Luebke, GPU Gems 3 chapter 14) is measured against.
//!
//! # Bake ([`bake`])
//! The mesh is rasterised into its UV layout (a `size x size` light map, `v = 0` the top row,
//! texel centres at `(i + 0.5) / size`; a texel is covered when its centre lies in a triangle's
//! UV image, edges included; where UV charts overlap the first triangle in index order keeps the
//! texel). Each covered texel stores:
//! - its world position in mm (mesh units times `mm_per_unit`);
//! - the shading normal: the interpolated vertex normal, perturbed by the normal map through the
//!   interpolated tangent frame as [`crate::shading`] does (`B = cross(N, T) * sign(T.w)`, the map
//!   decoded by [`crate::shading::decode_normal`] with the inputs' green axis);
//! - its footprint: the parallelogram `(dP/du, dP/dv) / size` of its triangle's UV-to-position
//!   Jacobian ([`crate::frames::triangle_partials`]), kept as an equal-area rectangle in the
//!   triangle's plane ([`Footprint`]) and as `area_mm2`;
//! - the irradiance `E = sum_lights colour * intensity * max(0, n.l) * V`, point lights divided
//!   by the squared distance in mesh units (`crate::shading::light_at`). `V` is exact for lights
//!   flagged in `shadows`: a ray from the texel toward the light, started `RAY_OFFSET` times the
//!   mesh's size off the surface along the geometric normal, is tested against every triangle
//!   (its own excepted) through a bounding-volume hierarchy ([`Bvh`], median splits). Every light
//!   in the inputs is used (the GPU passes stop at [`crate::shading::MAX_LIGHTS`]).
//!
//! # Scatter ([`scatter`])
//! For every covered texel `i`, per channel,
//!
//! `M_i = sum_j E_j W_ij / sum_j W_ij`,  `W_ij = integral over texel j of R(|p_i - q|) dq`
//!
//! over the covered texels `j` within [`support_mm`] (`3.5 sigma` of the profile's widest
//! Gaussian: 9.53 mm for the 2-D profile, where that Gaussian has fallen to
//! `exp(-6.125) = 2.2e-3` of its peak and keeps 99.78 % of its 2-D mass, so at most 0.017 % of the
//! red profile's energy, and none of green's or blue's above 1e-5, is cut), with distances in 3-D
//! (mm). Dividing by the summed weights is the LUT's own normalisation (equation 1.1 divides by
//! the ring's summed weights): flat, uniformly lit skin keeps exactly `E`.
//!
//! `W_ij` integrates the profile over the texel rather than sampling `R(d_ij) A_j`: the profile's
//! narrowest Gaussian (sigma 0.08 mm) is far below any practical texel (0.3-1 mm on a head), and a
//! point sample of it at `d = 0` weighs `A_j / (2 pi 0.0064)`, several times its true mass, which
//! skews the normalised mix toward the narrow lobes: across a light edge on a plane, point-sampled
//! weights miss the cumulative marginal by up to 0.18 at 0.625 mm texels and 0.086 at 0.3125 mm,
//! the texel integrals by 7e-5 (`tests/render/skin_reference.rs`). For each Gaussian of variance `v` the
//! integral over the texel's rectangle (sides `a`, `b` along its axes) is separable in 3-D:
//! `exp(-dz^2 / 2v) * B(dx, a) * B(dy, b)` with `(dx, dy, dz)` the offset in the rectangle's frame
//! and `B(x, a)` the mass of the 1-D Gaussian on `[x - a/2, x + a/2]` (from `erfc`, or, when
//! `a < sigma`, the midpoint rule with its second- and fourth-order terms: relative error below
//! 5e-5 within two sigma; it took the 512-texel head's scatter from 72 s to 49 s). It
//! is exact for flat rectangular texels and tends to `R(d) A_j` for small ones; Gaussians below
//! `exp(-20)` of their peak over the whole texel are skipped. With [`crate::skin::profile::Normalisation::OneD`] each
//! Gaussian's integral is scaled by its normalisation relative to the 2-D one.
//!
//! Texels whose shading normal faces away from the receiver's (`n_i . n_j < 0`) are left out: the
//! stand-in for a geodesic distance, so light does not bleed through lips, eyelids and ears that
//! are close in 3-D but far along the skin. Sums run over a uniform grid of cells, cells in a
//! fixed order and texels in index order within a cell: the result has the same bits whatever
//! the thread count.
//!
//! # Speed
//! [`scatter_exact`] evaluates every pair with [`texel_weight`] in f64 (libm `exp` and `erfc`)
//! over a hashed grid: the oracle. [`scatter_texels`] computes the same sums in f32, four source
//! texels at a time in SSE2 (the private `fast` module), within 1e-5 relative of the oracle
//! (`tests/render/skin_reference.rs`). Both cost per texel the number of texels within the support,
//! which grows with the square of the light map's size. [`scatter`], the reference the renderer
//! and the benchmarks use, sums each Gaussian over clusters of texels no wider than half its
//! sigma (the private `cluster` module: the Gaussian widened by each cluster's own variance, and
//! the light's lean within it as a dipole), so its cost per texel stays nearly flat. Against the
//! texel sums on bumpy spheres: rms 6e-4 of the mean on a 6 mm sphere, 1e-4 on a 20 mm one; a
//! lit edge on a plane within 8e-5 of the profile's marginal. On the sample head (two shadowed
//! lights, 2 cores), the texel sums then the clusters: 512 texels 6.1 s and 10 s (few clusters
//! form at 0.64 mm texels), 1024 texels 65 s and 40 s, 2048 texels (4.15M covered) about 1000 s
//! (the scaling) and 163 s. The reference converges: at 1024 texels it is within 1.2e-3 (rms,
//! of the mean) of itself at 2048 on the sample head and 4.6e-5 on the 6 mm sphere
//! (`tests/render/skin_reference_convergence.rs`).
//!
//! # Textures ([`ReferenceBake::to_texture`], [`dilate`])
//! Results go to an RGBA [`Texture`] (alpha 1 covered, 0 not), and [`dilate`] fills uncovered
//! texels next to covered ones with their covered neighbours' mean so bilinear fetches across UV
//! seams read skin, not black.
//!
//! # Hard cases
//! Triangles with an index out of range or a non-finite corner cover nothing and cast no shadow;
//! triangles with zero UV area cover nothing but still cast shadows; a non-finite or non-positive `mm_per_unit` or `size = 0` gives a bake with no
//! covered texel. Missing `shadows` entries count as `false`. Every output is finite.

use std::collections::HashMap;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::frames::triangle_partials;
use crate::shading::{self, Light, RenderInputs, Texture, Vertex};
use crate::skin::profile::{Profile, WEIGHTS};

mod bvh;
mod cluster;
mod fast;

pub use bvh::Bvh;

/// Shadow rays start this fraction of the mesh's bounding-box diagonal off the surface.
pub(crate) const RAY_OFFSET: f32 = 1e-4;

/// The support radius in units of the widest Gaussian's standard deviation.
pub(crate) const SUPPORT_SIGMAS: f64 = 3.5;

/// Below `a / sigma` of this, a texel's 1-D Gaussian mass uses the corrected midpoint rule
/// ([`midpoint_correction`]); above, differences of `erfc`.
const MIDPOINT_RATIO: f64 = 1.0;

/// A Gaussian is skipped where it is below `exp(-SKIP_EXPONENT)` of its peak over the texel.
const SKIP_EXPONENT: f64 = 20.0;

/// The radius beyond which [`scatter`] ignores texels: `SUPPORT_SIGMAS` times the profile's widest
/// standard deviation, in mm (9.53 mm for the 2-D profile).
pub fn support_mm(profile: &Profile) -> f64 {
    SUPPORT_SIGMAS * profile.variance(WEIGHTS.len() - 1).sqrt()
}

/// A texel's footprint on the surface: a rectangle centred on the texel's position.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Footprint {
    /// Unit direction of the first side (along `dP/du`).
    pub u_axis: Vec3,
    /// Unit direction of the second side, perpendicular to `u_axis` in the triangle's plane.
    pub v_axis: Vec3,
    /// Length of the first side, mm.
    pub u_mm: f32,
    /// Length of the second side, mm (`area / u_mm`).
    pub v_mm: f32,
}

/// The baked light map: per texel, row-major, `size * size` entries (uncovered ones are zero).
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceBake {
    /// Width and height in texels.
    pub size: u32,
    /// Whether a triangle covers the texel centre.
    pub covered: Vec<bool>,
    /// World position, mm.
    pub position_mm: Vec<Vec3>,
    /// Unit shading normal (normal map applied).
    pub normal: Vec<Vec3>,
    /// Surface area the texel covers, mm^2.
    pub area_mm2: Vec<f32>,
    /// The rectangle [`scatter`] integrates the profile over.
    pub footprint: Vec<Footprint>,
    /// Irradiance per channel (shadowed where asked).
    pub irradiance: Vec<[f32; 3]>,
}

impl ReferenceBake {
    /// A bake of `size x size` texels with nothing covered.
    pub fn empty(size: u32) -> Self {
        let n = (size as usize).pow(2);
        Self {
            size,
            covered: vec![false; n],
            position_mm: vec![Vec3::ZERO; n],
            normal: vec![Vec3::ZERO; n],
            area_mm2: vec![0.0; n],
            footprint: vec![Footprint::default(); n],
            irradiance: vec![[0.0; 3]; n],
        }
    }

    /// Number of covered texels.
    pub fn covered_count(&self) -> usize {
        self.covered.iter().filter(|&&c| c).count()
    }

    /// `values` (one per texel) as an RGBA texture: alpha 1 where covered, 0 elsewhere.
    pub fn to_texture(&self, values: &[[f32; 3]]) -> Texture {
        Texture::from_fn(self.size, self.size, |x, y| {
            let i = (y * self.size + x) as usize;
            match (self.covered.get(i), values.get(i)) {
                (Some(true), Some(&[r, g, b])) => [r, g, b, 1.0],
                _ => [0.0; 4],
            }
        })
    }
}

/// Bakes positions, normals, footprints and irradiance of `inputs`' mesh into a `size x size`
/// light map (see the module docs). `shadows[k]` says whether light `k` is ray-traced.
pub fn bake(inputs: &RenderInputs, shadows: &[bool], mm_per_unit: f32, size: u32) -> ReferenceBake {
    if size == 0 || !(mm_per_unit.is_finite() && mm_per_unit > 0.0) {
        return ReferenceBake::empty(size);
    }
    let triangles = sound_triangles(&inputs.vertices, &inputs.indices);
    let hits = rasterise_uv(&inputs.vertices, &triangles, size);
    let bvh = Bvh::new(triangles.iter().map(|t| t.map(|k| Vec3::from(inputs.vertices[k as usize].position))).collect());
    let offset = RAY_OFFSET * bvh.diagonal();
    let texels: Vec<Option<Texel>> = hits
        .par_iter()
        .map(|hit| {
            hit.map(|(tri, bary)| {
                let corners = triangles[tri as usize].map(|k| &inputs.vertices[k as usize]);
                let mut texel = Texel::new(inputs, &corners, bary, mm_per_unit, size);
                texel.irradiance = irradiance(&inputs.lights, shadows, &texel, &bvh, tri, offset);
                texel
            })
        })
        .collect();
    assemble(size, texels)
}

/// Triangles whose indices are in range and whose corners are finite.
fn sound_triangles(vertices: &[Vertex], indices: &[u32]) -> Vec<[u32; 3]> {
    let finite = |v: &Vertex| Vec3::from(v.position).is_finite() && Vec2::from(v.uv).is_finite();
    indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| t.iter().all(|&k| vertices.get(k as usize).is_some_and(finite)))
        .collect()
}

/// For each texel, the first triangle whose UV image contains its centre, with barycentrics.
fn rasterise_uv(vertices: &[Vertex], triangles: &[[u32; 3]], size: u32) -> Vec<Option<(u32, Vec3)>> {
    let mut hits = vec![None; (size as usize).pow(2)];
    let scale = size as f32;
    for (index, tri) in triangles.iter().enumerate() {
        let p = tri.map(|k| Vec2::from(vertices[k as usize].uv) * scale);
        let area = (p[1] - p[0]).perp_dot(p[2] - p[0]);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        let lo = p[0].min(p[1]).min(p[2]).max(Vec2::ZERO).floor();
        let hi = p[0].max(p[1]).max(p[2]).min(Vec2::splat(scale)).ceil();
        for y in lo.y as u32..hi.y as u32 {
            for x in lo.x as u32..hi.x as u32 {
                let slot = &mut hits[(y * size + x) as usize];
                if slot.is_some() {
                    continue;
                }
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let edge = |a: Vec2, b: Vec2| (b - a).perp_dot(c - a) / area;
                let bary = Vec3::new(edge(p[1], p[2]), edge(p[2], p[0]), edge(p[0], p[1]));
                if bary.min_element() >= 0.0 {
                    *slot = Some((index as u32, bary));
                }
            }
        }
    }
    hits
}

/// What the bake computes for one covered texel.
struct Texel {
    /// Mesh units (for lights and rays).
    world: Vec3,
    normal: Vec3,
    geometric: Vec3,
    area_mm2: f32,
    footprint: Footprint,
    mm_per_unit: f32,
    irradiance: [f32; 3],
}

impl Texel {
    fn new(inputs: &RenderInputs, corners: &[&Vertex; 3], bary: Vec3, mm_per_unit: f32, size: u32) -> Self {
        let mix3 =
            |f: &dyn Fn(&Vertex) -> Vec3| f(corners[0]) * bary.x + f(corners[1]) * bary.y + f(corners[2]) * bary.z;
        let world = mix3(&|v| Vec3::from(v.position));
        let p = corners.map(|v| Vec3::from(v.position));
        let face = (p[1] - p[0]).cross(p[2] - p[0]);
        let interpolated = shading::normalize_or(mix3(&|v| Vec3::from(v.normal)), shading::normalize_or(face, Vec3::Z));
        let geometric = shading::normalize_or(face, interpolated);
        let geometric = if geometric.dot(interpolated) < 0.0 { -geometric } else { geometric };
        let uvs = corners.map(|v| Vec2::from(v.uv));
        let uv = uvs[0] * bary.x + uvs[1] * bary.y + uvs[2] * bary.z;
        let normal = mapped_normal(inputs, corners, bary, interpolated, uv);
        let (footprint, area_mm2) = footprint(p, uvs, mm_per_unit, size);
        Self { world, normal, geometric, area_mm2, footprint, mm_per_unit, irradiance: [0.0; 3] }
    }
}

/// The interpolated normal perturbed by the normal map through the interpolated tangent frame.
fn mapped_normal(inputs: &RenderInputs, corners: &[&Vertex; 3], bary: Vec3, normal: Vec3, uv: Vec2) -> Vec3 {
    let tangent: Vec4 = corners.iter().zip(bary.to_array()).map(|(v, w)| Vec4::from(v.tangent) * w).sum();
    let (t, b, n) = shading::tangent_frame(normal, tangent);
    let m = shading::decode_normal(inputs.normal_map.sample(uv), inputs.green);
    shading::normalize_or(t * m.x + b * m.y + n * m.z, n)
}

/// The texel's rectangle and area in mm from its triangle's UV-to-position Jacobian.
fn footprint(p: [Vec3; 3], uv: [Vec2; 3], mm_per_unit: f32, size: u32) -> (Footprint, f32) {
    let Some(partials) = triangle_partials(p, uv) else {
        return (Footprint::default(), 0.0);
    };
    let scale = mm_per_unit / size as f32;
    let (du, dv) = (partials.du * scale, partials.dv * scale);
    let area = du.cross(dv).length();
    let u_mm = du.length();
    if !(area.is_finite() && area > 0.0 && u_mm > 0.0) {
        return (Footprint::default(), 0.0);
    }
    let u_axis = du / u_mm;
    let v_axis = shading::perpendicular_part(dv, u_axis);
    (Footprint { u_axis, v_axis, u_mm, v_mm: area / u_mm }, area)
}

/// `sum over lights of E * max(0, n.l) * V` at one texel.
fn irradiance(lights: &[Light], shadows: &[bool], texel: &Texel, bvh: &Bvh, own: u32, offset: f32) -> [f32; 3] {
    let mut sum = Vec3::ZERO;
    for (k, light) in lights.iter().enumerate() {
        let (l, e) = shading::light_at(light, texel.world);
        let cosine = texel.normal.dot(l).max(0.0);
        if cosine <= 0.0 {
            continue;
        }
        if shadows.get(k).copied().unwrap_or(false) && !visible(light, texel, bvh, own, offset) {
            continue;
        }
        sum += e * cosine;
    }
    let sum = if sum.is_finite() { sum } else { Vec3::ZERO };
    sum.to_array()
}

/// Whether nothing lies between the texel and the light.
fn visible(light: &Light, texel: &Texel, bvh: &Bvh, own: u32, offset: f32) -> bool {
    let origin = texel.world + texel.geometric * offset;
    let (direction, t_max) = match light.kind {
        shading::LightKind::Directional { toward } => (shading::normalize_or(toward, Vec3::Z), f32::INFINITY),
        shading::LightKind::Point { position } => {
            let d = position - origin;
            (shading::normalize_or(d, Vec3::Z), d.length())
        }
    };
    !bvh.occluded(origin, direction, t_max, own)
}

/// Spreads the per-texel results into the bake's arrays.
fn assemble(size: u32, texels: Vec<Option<Texel>>) -> ReferenceBake {
    let mut out = ReferenceBake::empty(size);
    for (i, texel) in texels.into_iter().enumerate() {
        let Some(t) = texel else { continue };
        out.covered[i] = true;
        out.position_mm[i] = t.world * t.mm_per_unit;
        out.normal[i] = t.normal;
        out.area_mm2[i] = t.area_mm2;
        out.footprint[i] = t.footprint;
        out.irradiance[i] = t.irradiance;
    }
    out
}

/// Scattered irradiance `M_i` per texel (zero where not covered): see the module docs. Each
/// Gaussian summed over sources as coarse as it allows (the private `cluster` module): the cost
/// per texel does not grow with the light map's size.
pub fn scatter(bake: &ReferenceBake, profile: &Profile) -> Vec<[f32; 3]> {
    cluster::scatter(bake, profile)
}

/// The sums of [`scatter_exact`] texel by texel, in f32 and SSE2 (the private `fast` module):
/// within 1e-5 relative of it, at a cost per texel that grows with the square of the light map's
/// size.
pub fn scatter_texels(bake: &ReferenceBake, profile: &Profile) -> Vec<[f32; 3]> {
    fast::scatter(bake, profile)
}

/// The brute-force oracle for [`scatter`]: every pair's weight from [`texel_weight`] in f64, over
/// a hashed grid. Several times slower; kept to check the fast path.
pub fn scatter_exact(bake: &ReferenceBake, profile: &Profile) -> Vec<[f32; 3]> {
    let support = support_mm(profile);
    let grid = Grid::new(bake, support);
    let kernel = Kernel::new(profile);
    (0..bake.covered.len())
        .into_par_iter()
        .map(|i| if bake.covered[i] { scatter_one(bake, &grid, &kernel, support, i) } else { [0.0; 3] })
        .collect()
}

fn scatter_one(bake: &ReferenceBake, grid: &Grid, kernel: &Kernel, support: f64, i: usize) -> [f32; 3] {
    let p = bake.position_mm[i];
    let n = bake.normal[i];
    let (mut light, mut total) = ([0.0f64; 3], [0.0f64; 3]);
    for j in grid.near(p) {
        let j = j as usize;
        let d = p - bake.position_mm[j];
        if d.length_squared() as f64 > support * support || n.dot(bake.normal[j]) < 0.0 {
            continue;
        }
        let w = kernel.texel_weight(d, &bake.footprint[j]);
        let e = bake.irradiance[j];
        for c in 0..3 {
            light[c] += e[c] as f64 * w[c];
            total[c] += w[c];
        }
    }
    let e = bake.irradiance[i];
    std::array::from_fn(|c| {
        let m = if total[c] > 0.0 { (light[c] / total[c]) as f32 } else { e[c] };
        if m.is_finite() { m } else { 0.0 }
    })
}

/// The weight of one source texel: the profile integrated over its footprint.
struct Kernel {
    /// Per Gaussian: variance (mm^2), standard deviation, and its normalisation relative to the
    /// 2-D one.
    gaussians: Vec<(f64, f64, f64)>,
}

impl Kernel {
    fn new(profile: &Profile) -> Self {
        let gaussians = (0..WEIGHTS.len())
            .map(|k| {
                let v = profile.variance(k);
                (v, v.sqrt(), profile.gaussian(k, 0.0) * 2.0 * std::f64::consts::PI * v)
            })
            .collect();
        Self { gaussians }
    }

    fn texel_weight(&self, offset: Vec3, f: &Footprint) -> [f64; 3] {
        let d2 = offset.length_squared() as f64;
        let dx = offset.dot(f.u_axis) as f64;
        let dy = offset.dot(f.v_axis) as f64;
        let dz2 = (d2 - dx * dx - dy * dy).max(0.0);
        let (a, b) = (f.u_mm as f64, f.v_mm as f64);
        let nearest = (d2.sqrt() - 0.5 * a.hypot(b)).max(0.0);
        let mut out = [0.0; 3];
        for (k, &(v, sigma, scale)) in self.gaussians.iter().enumerate() {
            if nearest * nearest > 2.0 * v * SKIP_EXPONENT {
                continue;
            }
            let g = if a.max(b) < MIDPOINT_RATIO * sigma {
                // Both sides small: one exponential for the whole offset.
                let density = (-d2 / (2.0 * v)).exp() / (2.0 * std::f64::consts::PI * v);
                let (cx, cy) = (midpoint_correction(dx / sigma, a / sigma), midpoint_correction(dy / sigma, b / sigma));
                a * b * density * cx * cy
            } else {
                (-dz2 / (2.0 * v)).exp() * box_mass(dx, a, sigma) * box_mass(dy, b, sigma)
            };
            let g = scale * g;
            for c in 0..3 {
                out[c] += WEIGHTS[k][c] * g;
            }
        }
        out
    }
}

/// Texel weight of the profile for a source texel with footprint `f` seen from `offset` (mm,
/// receiver minus source): `integral over the footprint of R(|offset - q|) dq` per channel.
pub fn texel_weight(profile: &Profile, offset: Vec3, f: &Footprint) -> [f64; 3] {
    Kernel::new(profile).texel_weight(offset, f)
}

/// Mass of the 1-D normal distribution N(0, sigma^2) on `[x - a/2, x + a/2]`.
fn box_mass(x: f64, a: f64, sigma: f64) -> f64 {
    if a < MIDPOINT_RATIO * sigma {
        let t = x / sigma;
        let density = (-0.5 * t * t).exp() / (sigma * (2.0 * std::f64::consts::PI).sqrt());
        return a * density * midpoint_correction(t, a / sigma);
    }
    let s = sigma * std::f64::consts::SQRT_2;
    let x = x.abs();
    0.5 * (libm::erfc((x - 0.5 * a) / s) - libm::erfc((x + 0.5 * a) / s))
}

/// `integral of f over [x - a/2, x + a/2] / (a f(x))` for a Gaussian `f` of standard deviation
/// sigma, `t = x / sigma`, `r = a / sigma`: the midpoint rule's `a^3/24 f''` and `a^5/1920 f''''`
/// terms (`f''/f = (t^2 - 1) / sigma^2`, `f''''/f = (t^4 - 6 t^2 + 3) / sigma^4`). The next term,
/// `r^6 (t^6 - 15 t^4 + 45 t^2 - 15) / 322560`, is below 5e-5 for `r <= 1`, `|t| <= 2`.
fn midpoint_correction(t: f64, r: f64) -> f64 {
    let (t2, r2) = (t * t, r * r);
    1.0 + r2 / 24.0 * (t2 - 1.0) + r2 * r2 / 1920.0 * (t2 * t2 - 6.0 * t2 + 3.0)
}

/// Covered texels bucketed in cubes of a fraction of the support's size.
struct Grid {
    cell: f64,
    /// Cells on each side of a texel's own that can hold texels within the support.
    reach: i32,
    support: f64,
    cells: HashMap<[i32; 3], Vec<u32>>,
}

/// Cells per support radius: finer cells drop more candidates beyond the support (the 27 cells
/// of side `r` hold 2.9 times the texels of a disc of radius `r` on a surface).
const CELLS_PER_SUPPORT: f64 = 3.0;

impl Grid {
    fn new(bake: &ReferenceBake, support: f64) -> Self {
        let cell = support / CELLS_PER_SUPPORT;
        let mut cells: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
        for (i, &p) in bake.position_mm.iter().enumerate() {
            if bake.covered[i] && p.is_finite() {
                cells.entry(Self::key(p, cell)).or_default().push(i as u32);
            }
        }
        Self { cell, reach: CELLS_PER_SUPPORT.ceil() as i32, support, cells }
    }

    fn key(p: Vec3, cell: f64) -> [i32; 3] {
        p.to_array().map(|x| (x as f64 / cell).floor() as i32)
    }

    /// Texels in the cells around `p` whose box comes within the support, in a fixed order.
    fn near(&self, p: Vec3) -> impl Iterator<Item = u32> + '_ {
        let c = Self::key(p, self.cell);
        let q = p.to_array().map(f64::from);
        let r = self.reach;
        (-r..=r)
            .flat_map(move |dz| (-r..=r).flat_map(move |dy| (-r..=r).map(move |dx| [c[0] + dx, c[1] + dy, c[2] + dz])))
            .filter(move |k| self.box_distance2(*k, q) <= self.support * self.support)
            .filter_map(|k| self.cells.get(&k))
            .flatten()
            .copied()
    }

    /// Squared distance from `q` to cell `k`'s box.
    fn box_distance2(&self, k: [i32; 3], q: [f64; 3]) -> f64 {
        (0..3)
            .map(|a| {
                let lo = k[a] as f64 * self.cell;
                let d = (lo - q[a]).max(q[a] - (lo + self.cell)).max(0.0);
                d * d
            })
            .sum()
    }
}

/// `passes` rounds of filling: every texel with alpha 0 next to (8-neighbourhood, within the
/// image: no wrap, so unrelated map edges do not mix) at least one texel with alpha > 0 takes
/// their mean colour and alpha 1.
pub fn dilate(texture: &Texture, passes: u32) -> Texture {
    let mut current = texture.clone();
    for _ in 0..passes {
        current = dilate_once(&current);
    }
    current
}

fn dilate_once(t: &Texture) -> Texture {
    let (w, h) = (t.width as i64, t.height as i64);
    let at = |x: i64, y: i64| t.texels[(y * w + x) as usize];
    Texture::from_fn(t.width, t.height, |x, y| {
        let (x, y) = (x as i64, y as i64);
        let here = at(x, y);
        if here[3] > 0.0 {
            return here;
        }
        let mut sum = Vec3::ZERO;
        let mut count = 0;
        for (nx, ny) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (x + dx, y + dy))) {
            if (0..w).contains(&nx) && (0..h).contains(&ny) && at(nx, ny)[3] > 0.0 {
                sum += Vec4::from(at(nx, ny)).truncate();
                count += 1;
            }
        }
        if count == 0 {
            return here;
        }
        let mean = sum / count as f32;
        [mean.x, mean.y, mean.z, 1.0]
    })
}
