//! A face map on the user's own mesh (issue 41): the mesh as the stitcher needs it (positions in
//! millimetres, UVs, triangles), seed points picked in 3-D mapped onto its UV layout, and each
//! region's physical scale measured from the mesh.
//!
//! The stitcher does not read mesh files (it does not depend on the renderer, DESIGN.md): the
//! caller loads the mesh and builds a [`Surface`] from its arrays and its `mm_per_unit`. UVs use
//! the workspace convention, `v = 0` at the top row of the map (the renderer's loaders flip OBJ's
//! `v` on reading).
//!
//! - [`Surface::nearest_uv`]: a 3-D point (in mesh units, as picked in Blender) goes to the
//!   nearest point of the surface, and that point's barycentric coordinates on its triangle
//!   interpolate the triangle's UVs.
//! - [`Surface::region_scales`]: over the triangles of each region (a triangle belongs to the
//!   region of the texel under its UV centroid), the surface area in mm² against the UV area in
//!   texels gives `mm_per_texel = sqrt(area_mm2 / area_texels)`, so an exemplar resampled to it
//!   keeps its pores' size in millimetres on the user's texel density.
//!
//! Triangles with zero UV area (a collapsed unwrap) or zero surface area add nothing to either
//! sum and are never the nearest triangle; a region with no triangle of positive UV area gets no
//! scale (`None`), never a NaN.

use glam::DVec3;
use skinkit_maps::Grid;

use crate::layout::uv_to_texel;
use crate::{Error, Result};

/// UV areas below this (in UV units squared) count as zero: a triangle a millionth of a texel of
/// a 32768-texel map.
const MIN_UV_AREA: f64 = 1e-18;

/// A mesh in millimetres with its UV layout.
#[derive(Clone, PartialEq)]
pub struct Surface {
    /// The mesh file, for messages.
    pub origin: String,
    /// Vertex positions in mm (mesh units times `mm_per_unit`).
    pub positions_mm: Vec<DVec3>,
    /// Vertex UVs, `v = 0` at the top row.
    pub uvs: Vec<[f64; 2]>,
    /// Three vertex indices per triangle.
    pub triangles: Vec<[u32; 3]>,
    /// Millimetres per mesh unit (3-D seed points are given in mesh units).
    pub mm_per_unit: f64,
}

impl std::fmt::Debug for Surface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Surface({} vertices, {} triangles, {} mm per unit)",
            self.uvs.len(),
            self.triangles.len(),
            self.mm_per_unit
        )
    }
}

/// One region's scale measured on the mesh.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RegionScale {
    /// Surface area of the region's triangles, mm².
    pub area_mm2: f64,
    /// UV area of the same triangles, texels.
    pub area_texels: f64,
    /// `sqrt(area_mm2 / area_texels)`.
    pub mm_per_texel: f64,
    /// Triangles counted.
    pub triangles: usize,
}

impl Surface {
    /// A surface from a mesh's arrays; `origin` names the mesh in messages.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-positive or non-finite `mm_per_unit`, arrays of two
    /// lengths, an index out of range, a non-finite value, or no triangle with UV area.
    pub fn new(
        origin: &str,
        positions: &[[f32; 3]],
        uvs: &[[f32; 2]],
        indices: &[u32],
        mm_per_unit: f64,
    ) -> Result<Surface> {
        let bad = |m: String| Err(Error::InvalidParameter(format!("{origin}: {m}")));
        if !(mm_per_unit.is_finite() && mm_per_unit > 0.0) {
            return bad(format!("mm_per_unit: {mm_per_unit} must be a finite number > 0 (millimetres per mesh unit)"));
        }
        if positions.len() != uvs.len() || !indices.len().is_multiple_of(3) {
            return bad(format!(
                "{} positions, {} uvs and {} indices do not make triangles",
                positions.len(),
                uvs.len(),
                indices.len()
            ));
        }
        if let Some(i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return bad(format!("index {i} names no vertex ({} vertices)", positions.len()));
        }
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if let Some(v) = (0..uvs.len()).find(|&v| !finite(&positions[v]) || !finite(&uvs[v])) {
            return bad(format!("vertex {v} has a non-finite position or uv"));
        }
        let surface = Surface {
            origin: origin.to_owned(),
            positions_mm: positions.iter().map(|p| DVec3::from(p.map(f64::from)) * mm_per_unit).collect(),
            uvs: uvs.iter().map(|t| t.map(f64::from)).collect(),
            triangles: indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            mm_per_unit,
        };
        if !(0..surface.triangles.len()).any(|t| surface.uv_area(t) > MIN_UV_AREA) {
            return bad("no triangle has a UV area: the mesh has no usable UV layout".into());
        }
        Ok(surface)
    }

    /// The UV area of triangle `t` (UV units squared).
    fn uv_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles[t].map(|i| self.uvs[i as usize]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
    }

    /// The UV centroids of the triangles with UV area (where their texels are).
    pub fn uv_centroids(&self) -> Vec<[f64; 2]> {
        (0..self.triangles.len())
            .filter(|&t| self.uv_area(t) > MIN_UV_AREA)
            .map(|t| {
                let [a, b, c] = self.triangles[t].map(|i| self.uvs[i as usize]);
                [0, 1].map(|k| (a[k] + b[k] + c[k]) / 3.0)
            })
            .collect()
    }

    /// The UV of the surface point nearest `point` (in mesh units); `None` when it is not finite.
    pub fn nearest_uv(&self, point: [f64; 3]) -> Option<[f64; 2]> {
        let p = DVec3::from(point) * self.mm_per_unit;
        if !p.is_finite() {
            return None;
        }
        let mut best: Option<(f64, usize, DVec3)> = None;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.triangles[t].map(|i| self.positions_mm[i as usize]);
            if self.uv_area(t) <= MIN_UV_AREA || (b - a).cross(c - a).length_squared() == 0.0 {
                continue;
            }
            let bary = closest_on_triangle(p, a, b, c);
            let d = (a * bary.x + b * bary.y + c * bary.z).distance_squared(p);
            if best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, t, bary));
            }
        }
        let (_, t, bary) = best?;
        let [a, b, c] = self.triangles[t].map(|i| self.uvs[i as usize]);
        Some([0, 1].map(|k| a[k] * bary.x + b[k] * bary.y + c[k] * bary.z))
    }

    /// Each region's scale over the triangles whose UV centroid lies on a texel of `labels`
    /// labelled with it (labels of `regions` or more, such as no region, count for none).
    pub fn region_scales(&self, labels: &Grid<u16>, regions: usize) -> Vec<Option<RegionScale>> {
        let (w, h) = labels.size();
        let mut sums = vec![(0.0, 0.0, 0usize); regions];
        for t in 0..self.triangles.len() {
            let uv_area = self.uv_area(t);
            let [a, b, c] = self.triangles[t].map(|i| self.positions_mm[i as usize]);
            let area_mm2 = 0.5 * (b - a).cross(c - a).length();
            if uv_area <= MIN_UV_AREA || !area_mm2.is_finite() {
                continue;
            }
            let [ua, ub, uc] = self.triangles[t].map(|i| self.uvs[i as usize]);
            let centroid = [0, 1].map(|k| (ua[k] + ub[k] + uc[k]) / 3.0);
            let [x, y] = uv_to_texel(centroid, w, h);
            let label = usize::from(*labels.get(x as usize, y as usize));
            if let Some(s) = sums.get_mut(label) {
                *s = (s.0 + area_mm2, s.1 + uv_area * (w * h) as f64, s.2 + 1);
            }
        }
        sums.into_iter()
            .map(|(area_mm2, area_texels, triangles)| {
                (area_texels > 0.0 && area_mm2 > 0.0).then(|| RegionScale {
                    area_mm2,
                    area_texels,
                    mm_per_texel: (area_mm2 / area_texels).sqrt(),
                    triangles,
                })
            })
            .collect()
    }
}

/// Barycentric coordinates of the point of triangle `abc` nearest `p` (Ericson, Real-Time
/// Collision Detection, 5.1.5: the Voronoi regions of the vertices, then of the edges, then the
/// face). The triangle must have area.
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return DVec3::X;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return DVec3::Y;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return DVec3::new(1.0 - v, v, 0.0);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return DVec3::Z;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return DVec3::new(1.0 - w, 0.0, w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return DVec3::new(0.0, 1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    DVec3::new(1.0 - v - w, v, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 x 1 plane in z = 0 (mesh units), two quads split at x = 1: the left quad on
    /// u in [0, 0.25], the right one on u in [0.25, 1] (a non-uniform texel density); v runs
    /// down the map as y runs up (`v = 1 - y`). One more triangle with zero UV area.
    fn plane() -> Surface {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0], [2.0, 0.0, 0.0], [2.0, 1.0, 0.0]];
        let uv = |x: f32, y: f32| [if x <= 1.0 { 0.25 * x } else { 0.25 + 0.75 * (x - 1.0) }, 1.0 - y];
        let uvs: Vec<[f32; 2]> = p.iter().map(|q: &[f32; 3]| uv(q[0], q[1])).collect();
        let indices = [0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2, 0, 0, 1];
        Surface::new("plane.obj", &p, &uvs, &indices, 10.0).unwrap()
    }

    #[test]
    fn region_scales_follow_the_area_ratio() {
        let (w, h) = (100, 100);
        let labels = Grid::from_fn(w, h, |x, _| u16::from(x >= 25));
        let scales = plane().region_scales(&labels, 3);
        // Left: 10 mm x 10 mm on 25 x 100 texels; right: 10 x 10 mm on 75 x 100 texels.
        let left = scales[0].unwrap();
        assert_eq!(left.triangles, 2);
        assert!((left.area_mm2 - 100.0).abs() < 1e-9 && (left.area_texels - 2500.0).abs() < 1e-6);
        assert!((left.mm_per_texel - 0.2).abs() < 1e-9, "{left:?}");
        let right = scales[1].unwrap();
        assert!((right.mm_per_texel - (100.0f64 / 7500.0).sqrt()).abs() < 1e-9, "{right:?}");
        // A region without triangles has no scale, not a NaN.
        assert_eq!(scales[2], None);
    }

    #[test]
    fn a_3d_point_lands_on_its_surface_point_uv() {
        let s = plane();
        // Above the right quad at (1.5, 0.2): u = 0.25 + 0.75 * 0.5, v = 1 - 0.2.
        let [u, v] = s.nearest_uv([1.5, 0.2, 3.0]).unwrap();
        assert!((u - 0.625).abs() < 1e-6 && (v - 0.8).abs() < 1e-6, "{u} {v}");
        // Off the plane's edge: clamped to the nearest edge point (x = 2, y = 0.5).
        let [u, v] = s.nearest_uv([2.5, 0.5, 0.0]).unwrap();
        assert!((u - 1.0).abs() < 1e-6 && (v - 0.5).abs() < 1e-6, "{u} {v}");
        assert_eq!(s.nearest_uv([f64::NAN, 0.0, 0.0]), None);
    }

    #[test]
    fn bad_meshes_are_refused_naming_the_file() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let flat = [[0.5, 0.5]; 3];
        let e = Surface::new("m.obj", &p, &flat, &[0, 1, 2], 1.0).unwrap_err().to_string();
        assert!(e.contains("m.obj") && e.contains("no triangle has a UV area"), "{e}");
        let uvs = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let e = Surface::new("m.obj", &p, &uvs, &[0, 1, 2], 0.0).unwrap_err().to_string();
        assert!(e.contains("mm_per_unit"), "{e}");
        let e = Surface::new("m.obj", &p, &uvs, &[0, 1, 7], 1.0).unwrap_err().to_string();
        assert!(e.contains("index 7"), "{e}");
    }
}
