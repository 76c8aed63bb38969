//! Per-vertex texture-space frames: the tangent basis that takes light and view vectors into the
//! normal map's space (Haro et al. 2001, section 5.1, equations 2-6), computed two ways.
//!
//! - [`FrameMethod::Paper`]: per triangle, the partials `dU = dP/du` and `dV = dP/dv` from the
//!   normals of the `xuv`, `yuv` and `zuv` planes (equations 3-5): `<A, B, C> = e1 x e2` with
//!   `e = (dx, du, dv)`, so `dx/du = -B/A` and `dx/dv = -C/A` (equation 2; the extracted text
//!   garbles the subscripts). `A` is the same for the three planes: twice the signed UV area.
//!   The partials and `N_uv = dU x dV` are summed over a vertex's triangles and normalised
//!   (equation 6 is the matrix of the three).
//! - [`FrameMethod::MikkTSpace`]: what Blender, Substance and glTF bake normal maps against (via
//!   the `bevy_mikktspace` port).
//!
//! Both give one `Vec4` per vertex, the format the shaders take: `xyz` the unit tangent `T`
//! (along `+u`, orthogonal to the vertex normal `N`) and `w = ±1` the handedness, with the
//! bitangent `B = cross(N, T) * w` (glTF's rule).
//!
//! # Which way the bitangent points
//! skinkit's UVs put `v = 0` at the TOP of the image ([`crate::mesh`]). A green-up normal map
//! (skinkit's in-memory convention, [`skinkit_maps::GreenAxis::Up`]) has `+y` pointing UP the
//! image, which is toward DECREASING `v`. So `B` is the 3-D direction in which `v` decreases,
//! `-dP/dv`: this is MikkTSpace run on OpenGL-style coordinates `(u, 1 - v)`, exactly the frame a
//! baker with bottom-left UVs (Blender) uses for its green-up maps. Decoding a texel is then
//! `n_object = T * n.x + B * n.y + N * n.z` ([`to_object`]). An unmirrored layout (image up on
//! the surface's "up" seen from outside) has `w = +1`; a mirrored one `w = -1`. Getting this
//! wrong turns pores into bumps; `tests/render/frames.rs` pushes a known bump through the whole path.
//!
//! # Hard cases
//! Triangles with zero UV area or zero 3-D area contribute nothing. When a vertex's accumulated
//! tangent is zero or parallel to `N`, the tangent is taken from the bitangent
//! (`T = cross(B, N)`), else it is [`Vec3::any_orthonormal_vector`] of `N` (deterministic), with
//! `w = +1` when nothing says otherwise. Every output is finite with a unit `xyz`.

use glam::{Vec2, Vec3, Vec4};

use crate::mesh::Mesh;

/// How per-vertex tangent frames are built (scene files say `"paper"` or `"mikktspace"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FrameMethod {
    /// Haro et al. 2001, equations 2-6: summed per-triangle partials.
    #[default]
    Paper,
    /// Mikkelsen's tangent space, as normal-map bakers use.
    MikkTSpace,
}

/// Below this, an accumulated vector is treated as zero (inputs are unit-scale directions).
const TINY: f32 = 1e-12;

/// One triangle's texture-space partials: `dP/du`, `dP/dv` (skinkit's top-origin `v`) and the
/// signed UV area (doubled).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Partials {
    /// `dP/du`: the 3-D direction (and rate) in which `u` increases.
    pub du: Vec3,
    /// `dP/dv`: the 3-D direction in which `v` increases (toward the image bottom).
    pub dv: Vec3,
    /// `A` of equations 3-5: `du1 * dv2 - dv1 * du2`.
    pub uv_area2: f32,
}

/// The partials of one triangle (equations 2-5), or `None` when its UV area is zero.
pub fn triangle_partials(p: [Vec3; 3], uv: [Vec2; 3]) -> Option<Partials> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (t1, t2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let a = t1.x * t2.y - t1.y * t2.x;
    // Relative to the UV edge lengths, so tiny but well-shaped charts still count.
    let scale = t1.length_squared().max(t2.length_squared());
    if !a.is_finite() || a.abs() <= 1e-7 * scale {
        return None;
    }
    // From <A, B, C> = (dx1, du1, dv1) x (dx2, du2, dv2), per coordinate:
    // B = dv1 dx2 - dx1 dv2, C = dx1 du2 - du1 dx2; dx/du = -B/A, dx/dv = -C/A.
    let du = (e1 * t2.y - e2 * t1.y) / a;
    let dv = (e2 * t1.x - e1 * t2.x) / a;
    (du.is_finite() && dv.is_finite()).then_some(Partials { du, dv, uv_area2: a })
}

/// Per-vertex tangents `(T, w)` for `mesh` (see the module docs for the convention).
///
/// # Panics
/// If `mesh` fails [`Mesh::validate`] (the loaders only return valid meshes).
pub fn tangents(mesh: &Mesh, method: FrameMethod) -> Vec<Vec4> {
    match method {
        FrameMethod::Paper => paper_tangents(mesh),
        FrameMethod::MikkTSpace => mikktspace_tangents(mesh),
    }
}

/// The bitangent of a tangent: `cross(N, T) * w`, the image-up direction.
pub fn bitangent(normal: Vec3, tangent: Vec4) -> Vec3 {
    normal.cross(tangent.truncate()) * tangent.w
}

/// Takes a green-up texture-space vector (a decoded normal-map texel) into object space.
pub fn to_object(normal: Vec3, tangent: Vec4, n_tex: Vec3) -> Vec3 {
    tangent.truncate() * n_tex.x + bitangent(normal, tangent) * n_tex.y + normal * n_tex.z
}

/// Takes an object-space vector into green-up texture space (the transpose of [`to_object`]:
/// the paper's per-vertex step for light and view vectors).
pub fn to_texture(normal: Vec3, tangent: Vec4, v: Vec3) -> Vec3 {
    Vec3::new(tangent.truncate().dot(v), bitangent(normal, tangent).dot(v), normal.dot(v))
}

/// Sums of the paper's partials at one vertex.
#[derive(Clone, Copy, Default)]
struct Sums {
    du: Vec3,
    /// Sum of `-dP/dv`: the image-up direction.
    up: Vec3,
    /// Sum of `N_uv = dU x dV_up`.
    n_uv: Vec3,
}

fn paper_tangents(mesh: &Mesh) -> Vec<Vec4> {
    let mut sums = vec![Sums::default(); mesh.positions.len()];
    for t in 0..mesh.triangle_count() {
        let idx = mesh.triangle(t);
        let p = idx.map(|i| mesh.positions[i]);
        if (p[1] - p[0]).cross(p[2] - p[0]).length_squared() <= 0.0 {
            continue;
        }
        let Some(partials) = triangle_partials(p, idx.map(|i| mesh.uvs[i])) else { continue };
        let up = -partials.dv;
        for i in idx {
            sums[i].du += partials.du;
            sums[i].up += up;
            sums[i].n_uv += partials.du.cross(up);
        }
    }
    sums.iter()
        .zip(&mesh.normals)
        .map(|(s, &n)| {
            let w = if s.n_uv.dot(n) < 0.0 { -1.0 } else { 1.0 };
            orthonormal_frame(n, s.du, s.up, w)
        })
        .collect()
}

/// Gram-Schmidt of an accumulated tangent against the unit normal, with the fallbacks of the
/// module docs. `up` is the accumulated image-up bitangent, used when the tangent is unusable.
fn orthonormal_frame(normal: Vec3, tangent: Vec3, up: Vec3, w: f32) -> Vec4 {
    let n = normal.try_normalize().unwrap_or(Vec3::Z);
    let t = reject(tangent, n)
        .or_else(|| reject(up, n).map(|b| (b.cross(n) * w).normalize()))
        .unwrap_or_else(|| n.any_orthonormal_vector());
    t.extend(w)
}

/// The unit part of `v` orthogonal to the unit `n`, if it is not (nearly) zero.
fn reject(v: Vec3, n: Vec3) -> Option<Vec3> {
    if !v.is_finite() {
        return None;
    }
    let len = v.length();
    let r = v - n * n.dot(v);
    // Parallel to N (within about 1e-4 rad) counts as no direction at all.
    (len > TINY && r.length() > 1e-4 * len).then(|| r.normalize())
}

/// The mesh as MikkTSpace sees it: OpenGL-style texture coordinates `(u, 1 - v)`, and one slot
/// per vertex filled by its lowest-numbered face (deterministic).
struct MikkInput<'a> {
    mesh: &'a Mesh,
    out: Vec<Option<(usize, Vec4)>>,
}

impl bevy_mikktspace::Geometry for MikkInput<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangle_count()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.triangle(face)[vert]].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.triangle(face)[vert]].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.mesh.uvs[self.mesh.triangle(face)[vert]];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent(&mut self, space: Option<bevy_mikktspace::TangentSpace>, face: usize, vert: usize) {
        let slot = &mut self.out[self.mesh.triangle(face)[vert]];
        let Some(space) = space else { return };
        if slot.is_none_or(|(first, _)| face < first) {
            *slot = Some((face, Vec4::from_array(space.tangent_encoded())));
        }
    }
}

fn mikktspace_tangents(mesh: &Mesh) -> Vec<Vec4> {
    let mut input = MikkInput { mesh, out: vec![None; mesh.positions.len()] };
    // The error type has no variants: generation cannot fail.
    let _ = bevy_mikktspace::generate_tangents(&mut input);
    input
        .out
        .iter()
        .zip(&mesh.normals)
        .map(|(t, &n)| {
            let t = t.map_or(Vec4::ZERO, |(_, t)| t);
            let w = if t.w < 0.0 { -1.0 } else { 1.0 };
            orthonormal_frame(n, t.truncate(), Vec3::ZERO, w)
        })
        .collect()
}
