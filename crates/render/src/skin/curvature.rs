//! Per-vertex curvature `1/r` in 1/mm, the second index of the pre-integrated diffuse table
//! (Penner and Borshukov 2011, section 1.3: "curvature must be smooth", and
//! `docs/references.md`: the LUT's `1/r` has `r` in millimetres, and per-vertex curvature
//! precomputed from the mesh is smoother than the per-triangle derivative form).
//!
//! # The estimator
//! Mean curvature from the cotangent Laplace-Beltrami operator with mixed Voronoi areas (Meyer,
//! Desbrun, Schroeder and Barr 2003, "Discrete differential-geometry operators for triangulated
//! 2-manifolds", sections 3.3-3.5):
//!
//! `K(x_i) = 1 / (2 A_mixed) * sum_j (cot a_ij + cot b_ij) (x_i - x_j) = 2 H n`
//!
//! so `|H| = |K| / 2`, signed positive where `K` points along the outward vertex normal (convex:
//! a sphere of radius `r` gives `+1/r`, a cylinder of radius `R` gives `1/(2R)`). `A_mixed` is the
//! Voronoi area of a non-obtuse triangle's corner, else half the triangle's area for its obtuse
//! corner and a quarter for the other two (the paper's figure 4 pseudo-code). Lengths are in mesh
//! units; the result is divided by `mm_per_unit`.
//!
//! # Concave and saddle regions: `|H|`
//! [`vertex_curvature`] returns `|H|`. Equation 1.1 is a ring integral over `x` in a symmetric
//! domain whose weight `R(2 r sin(|x|/2))` and whose normal rotation (by `x` on a convex ring,
//! by `-x` on a concave one) are both symmetric under `x -> -x`: a concave ring of radius `r`
//! softens the terminator exactly as a convex one does (the LUT knows nothing of occlusion or
//! inter-reflection in either case). `max(H, 0)` would make creases (nose-cheek fold, lip corners)
//! look harder than flat skin. Saddles have small `|H|` and get little wrap, as mean curvature
//! says. [`signed_mean_curvature`] keeps the sign for callers that want it.
//!
//! # The shader's derivative form
//! The paper's real-time alternative (its listing) is per pixel,
//! `1/r = length(fwidth(N)) / length(fwidth(P))`, with `P` in mesh units, so it is then divided by
//! `mm_per_unit` to be 1/mm. It is constant across a triangle of a flat-shaded mesh and shows
//! facet seams; it lives in the shader, not here.
//!
//! # Hard cases
//! - Vertices at the same position up to `WELD_TOLERANCE` (UV seams, pole fans) are welded first, so a seam is
//!   not a boundary and both copies get the same value.
//! - Triangles with an index out of range, a repeated (welded) corner, a non-finite corner, or a
//!   zero or non-finite area are skipped; cotangents are clamped to `[-COT_LIMIT, COT_LIMIT]`
//!   so slivers cannot dominate.
//! - Boundary vertices (an edge used by one triangle) carry no valid estimate (the one-ring is
//!   open): they take the mean of their interior neighbours, spreading inward-out for a few rings;
//!   a boundary vertex with no interior vertex within `BOUNDARY_RINGS` rings gets 0.
//! - Isolated vertices, non-finite positions, and a non-finite or non-positive `mm_per_unit`
//!   give 0. Every output is finite and non-negative.

use std::collections::HashMap;

use glam::Vec3;

/// Largest cotangent magnitude used (an angle of about 0.06 degrees).
pub(crate) const COT_LIMIT: f32 = 1000.0;

/// Vertices closer than this fraction of the mesh's extent (largest absolute coordinate) are
/// one vertex: UV-seam copies computed with rounding (`sin(2 pi)` is not 0 in f32) still weld.
pub(crate) const WELD_TOLERANCE: f32 = 1e-5;

/// How many rings of neighbours a boundary vertex looks through for interior values.
pub(crate) const BOUNDARY_RINGS: usize = 4;

/// `|H|` per vertex in 1/mm (see the module docs): the pre-integrated LUT's `1/r`.
pub fn vertex_curvature(positions: &[Vec3], indices: &[u32], mm_per_unit: f32) -> Vec<f32> {
    vertex_curvature_smoothed(positions, indices, mm_per_unit, 0)
}

/// [`vertex_curvature`] followed by `smooth_iterations` passes of one-ring averaging (each vertex
/// becomes the mean of itself and its welded neighbours), for meshes whose curvature is noisy.
pub fn vertex_curvature_smoothed(
    positions: &[Vec3],
    indices: &[u32],
    mm_per_unit: f32,
    smooth_iterations: usize,
) -> Vec<f32> {
    if !(mm_per_unit.is_finite() && mm_per_unit > 0.0) {
        return vec![0.0; positions.len()];
    }
    let mesh = Welded::new(positions, indices);
    let mut h: Vec<f32> = mesh.mean_curvature().into_iter().map(|h| h.map_or(f32::NAN, f32::abs)).collect();
    mesh.fill_boundary(&mut h);
    for _ in 0..smooth_iterations {
        h = mesh.smooth(&h);
    }
    let per_mm = |h: f32| {
        let v = h / mm_per_unit;
        if v.is_finite() { v } else { 0.0 }
    };
    mesh.weld.iter().map(|&w| per_mm(h[w])).collect()
}

/// Signed mean curvature `H` per vertex in 1/mesh unit (positive convex), `NaN` where the
/// estimator has no value (boundary, isolated or non-finite vertices).
pub fn signed_mean_curvature(positions: &[Vec3], indices: &[u32]) -> Vec<f32> {
    let mesh = Welded::new(positions, indices);
    let h = mesh.mean_curvature();
    mesh.weld.iter().map(|&w| h[w].unwrap_or(f32::NAN)).collect()
}

/// The mesh with bit-identical positions merged, and the triangles worth using.
struct Welded {
    /// Welded id of each input vertex.
    weld: Vec<usize>,
    /// Position of each welded vertex.
    points: Vec<Vec3>,
    /// Triangles of welded ids with finite, non-zero area and three distinct corners.
    triangles: Vec<[usize; 3]>,
}

impl Welded {
    fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let (weld, points) = weld(positions);
        let triangles = indices
            .chunks_exact(3)
            .filter_map(|t| {
                let corner = |k: u32| weld.get(k as usize).copied();
                let tri = [corner(t[0])?, corner(t[1])?, corner(t[2])?];
                usable(&points, tri).then_some(tri)
            })
            .collect();
        Self { weld, points, triangles }
    }

    /// Signed mean curvature per welded vertex, `None` for boundary or isolated vertices.
    fn mean_curvature(&self) -> Vec<Option<f32>> {
        let n = self.points.len();
        let (mut laplace, mut area, mut normal) = (vec![Vec3::ZERO; n], vec![0.0f32; n], vec![Vec3::ZERO; n]);
        for &tri in &self.triangles {
            let p = tri.map(|k| self.points[k]);
            let cot = corner_cotangents(p);
            let areas = mixed_areas(p, cot);
            let face = (p[1] - p[0]).cross(p[2] - p[0]);
            for c in 0..3 {
                let (a, b) = ((c + 1) % 3, (c + 2) % 3);
                // Edge (a, b) is opposite corner c: weight cot(c) for both its ends.
                let w = cot[c];
                laplace[tri[a]] += w * (p[a] - p[b]);
                laplace[tri[b]] += w * (p[b] - p[a]);
                area[tri[c]] += areas[c];
                normal[tri[c]] += face;
            }
        }
        let boundary = self.boundary_vertices();
        (0..n)
            .map(|v| {
                if boundary[v] || area[v] <= 0.0 {
                    return None;
                }
                let k = laplace[v] / (2.0 * area[v]);
                let h = 0.5 * k.length();
                let sign = if k.dot(normal[v]) < 0.0 { -1.0 } else { 1.0 };
                (h.is_finite()).then_some(sign * h)
            })
            .collect()
    }

    /// Vertices on an edge that only one usable triangle has.
    fn boundary_vertices(&self) -> Vec<bool> {
        let mut edges: HashMap<(usize, usize), u32> = HashMap::new();
        for t in &self.triangles {
            for c in 0..3 {
                let (a, b) = (t[c], t[(c + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let mut boundary = vec![false; self.points.len()];
        for (&(a, b), &count) in &edges {
            if count == 1 {
                boundary[a] = true;
                boundary[b] = true;
            }
        }
        boundary
    }

    /// Welded neighbours of every welded vertex, sorted (a fixed order for the averages).
    fn neighbours(&self) -> Vec<Vec<usize>> {
        let mut rings = vec![Vec::new(); self.points.len()];
        for t in &self.triangles {
            for c in 0..3 {
                let (a, b) = (t[c], t[(c + 1) % 3]);
                rings[a].push(b);
                rings[b].push(a);
            }
        }
        for ring in &mut rings {
            ring.sort_unstable();
            ring.dedup();
        }
        rings
    }

    /// Replaces the NaN entries (no estimate) by the mean of their valid neighbours, ring after
    /// ring; what is still unknown after [`BOUNDARY_RINGS`] rings becomes 0.
    fn fill_boundary(&self, h: &mut [f32]) {
        let rings = self.neighbours();
        for _ in 0..BOUNDARY_RINGS {
            let filled: Vec<(usize, f32)> = (0..h.len())
                .filter(|&v| h[v].is_nan())
                .filter_map(|v| {
                    let known: Vec<f32> = rings[v].iter().map(|&u| h[u]).filter(|x| !x.is_nan()).collect();
                    (!known.is_empty()).then(|| (v, known.iter().sum::<f32>() / known.len() as f32))
                })
                .collect();
            if filled.is_empty() {
                break;
            }
            for (v, x) in filled {
                h[v] = x;
            }
        }
        for x in h.iter_mut().filter(|x| !x.is_finite()) {
            *x = 0.0;
        }
    }

    /// One pass of one-ring averaging (self included).
    fn smooth(&self, h: &[f32]) -> Vec<f32> {
        let rings = self.neighbours();
        (0..h.len())
            .map(|v| {
                let sum: f32 = h[v] + rings[v].iter().map(|&u| h[u]).sum::<f32>();
                sum / (rings[v].len() + 1) as f32
            })
            .collect()
    }
}

/// Merges vertices closer than [`WELD_TOLERANCE`] times the extent of the finite positions
/// (first come, first kept; a hash grid of that cell size finds the candidates). Returns the
/// welded id of every vertex and the kept positions. Non-finite positions each stay alone.
fn weld(positions: &[Vec3]) -> (Vec<usize>, Vec<Vec3>) {
    let finite = positions.iter().filter(|p| p.is_finite());
    let extent = finite.fold(0.0f32, |m, p| m.max(p.abs().max_element()));
    let eps = (WELD_TOLERANCE * extent).max(f32::MIN_POSITIVE);
    let cell = |p: Vec3| (p / eps).floor().as_ivec3().to_array();
    let mut grid: HashMap<[i32; 3], Vec<usize>> = HashMap::new();
    let mut points: Vec<Vec3> = Vec::new();
    let ids = positions
        .iter()
        .map(|&p| {
            if !p.is_finite() {
                points.push(p);
                return points.len() - 1;
            }
            let c = cell(p);
            let near = neighbour_cells(c)
                .find_map(|k| grid.get(&k)?.iter().copied().find(|&id| (points[id] - p).abs().max_element() <= eps));
            near.unwrap_or_else(|| {
                points.push(p);
                grid.entry(c).or_default().push(points.len() - 1);
                points.len() - 1
            })
        })
        .collect();
    (ids, points)
}

/// The 27 cells around `c` (itself included), in a fixed order.
fn neighbour_cells(c: [i32; 3]) -> impl Iterator<Item = [i32; 3]> {
    (-1..=1).flat_map(move |dz| (-1..=1).flat_map(move |dy| (-1..=1).map(move |dx| [c[0] + dx, c[1] + dy, c[2] + dz])))
}

/// Three distinct corners, finite, with a non-zero area relative to the edge lengths.
fn usable(points: &[Vec3], t: [usize; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return false;
    }
    let p = t.map(|k| points[k]);
    if !p.iter().all(|q| q.is_finite()) {
        return false;
    }
    let twice_area = (p[1] - p[0]).cross(p[2] - p[0]).length();
    let scale = (p[1] - p[0]).length_squared().max((p[2] - p[0]).length_squared());
    twice_area.is_finite() && twice_area > 1e-12 * scale && scale > 0.0
}

/// The cotangent of each corner's angle, clamped to `±COT_LIMIT`.
fn corner_cotangents(p: [Vec3; 3]) -> [f32; 3] {
    std::array::from_fn(|c| {
        let (u, v) = (p[(c + 1) % 3] - p[c], p[(c + 2) % 3] - p[c]);
        let cot = u.dot(v) / u.cross(v).length();
        if cot.is_finite() { cot.clamp(-COT_LIMIT, COT_LIMIT) } else { 0.0 }
    })
}

/// Meyer et al.'s mixed area of each corner of one triangle.
fn mixed_areas(p: [Vec3; 3], cot: [f32; 3]) -> [f32; 3] {
    let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
    if let Some(obtuse) = (0..3).find(|&c| cot[c] < 0.0) {
        return std::array::from_fn(|c| if c == obtuse { 0.5 * area } else { 0.25 * area });
    }
    std::array::from_fn(|c| {
        let (a, b) = ((c + 1) % 3, (c + 2) % 3);
        // Voronoi part of corner c: edges c-a (opposite b) and c-b (opposite a).
        ((p[a] - p[c]).length_squared() * cot[b] + (p[b] - p[c]).length_squared() * cot[a]) / 8.0
    })
}
