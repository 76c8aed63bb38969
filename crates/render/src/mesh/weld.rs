//! Welding of vertices that a file splits per face corner (issue 41).
//!
//! A glTF primitive without indices, or an OBJ that repeats its `v` lines per face, gives every
//! triangle its own three vertices. Normals computed on such a mesh are the face normals, so it
//! renders and exports faceted. Before normals are computed, vertices without a normal from the
//! file are merged when their positions agree within [`position_tolerance`] and their UVs within
//! [`UV_TOLERANCE`]; vertices on a UV seam (one position, two UVs) stay apart, so each side keeps
//! its texture coordinate, but they share one normal ([`Mesh::smooth_normals`] sums over equal
//! positions).

use std::collections::HashMap;

use glam::{IVec3, Vec2, Vec3};

use super::Mesh;

/// Texture coordinates closer than this (in UV units, per axis) are one coordinate: a 65536-texel
/// map's texel is 1.5e-5 wide, and exporters write UVs as f32.
pub const UV_TOLERANCE: f32 = 1e-6;

/// Positions closer than this are one position: a millionth of the bounding box's diagonal (f32
/// holds about seven digits), never below `f32::MIN_POSITIVE`.
pub fn position_tolerance(mesh: &Mesh) -> f32 {
    let (min, max) = mesh.bounds();
    (1e-6 * (max - min).length()).max(f32::MIN_POSITIVE)
}

/// Per vertex, the first vertex whose position lies within `tol` of it (itself when none does):
/// the classes of equal positions. Positions are hashed into cells `tol` wide and compared with
/// the class representatives of the 27 cells around them, so near-equal positions on two sides of
/// a cell boundary still meet.
pub fn position_classes(positions: &[Vec3], tol: f32) -> Vec<u32> {
    let mut cells: HashMap<IVec3, Vec<u32>> = HashMap::new();
    let mut classes = Vec::with_capacity(positions.len());
    for (i, &p) in positions.iter().enumerate() {
        // Float to int casts saturate, so a far position cannot wrap into another's cell.
        let cell = (p / tol).floor().as_ivec3();
        let near = |j: &u32| positions[*j as usize].distance(p) <= tol;
        let found = neighbours(cell).find_map(|c| cells.get(&c).and_then(|reps| reps.iter().copied().find(near)));
        let class = found.unwrap_or_else(|| {
            cells.entry(cell).or_default().push(i as u32);
            i as u32
        });
        classes.push(class);
    }
    classes
}

fn neighbours(c: IVec3) -> impl Iterator<Item = IVec3> {
    (-1..=1).flat_map(move |x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| c.saturating_add(IVec3::new(x, y, z)))))
}

/// Per vertex, the vertex it merges into (itself when it is kept): vertices with `mergeable` set
/// that share a position class and a UV within [`UV_TOLERANCE`].
pub fn merge_targets(classes: &[u32], uvs: &[Vec2], mergeable: &[bool]) -> Vec<u32> {
    let mut kept: HashMap<u32, Vec<u32>> = HashMap::new();
    let same_uv = |a: Vec2, b: Vec2| (a - b).abs().max_element() <= UV_TOLERANCE;
    (0..classes.len())
        .map(|i| {
            if !mergeable[i] {
                return i as u32;
            }
            let reps = kept.entry(classes[i]).or_default();
            match reps.iter().copied().find(|&j| same_uv(uvs[j as usize], uvs[i])) {
                Some(j) => j,
                None => {
                    reps.push(i as u32);
                    i as u32
                }
            }
        })
        .collect()
}

impl Mesh {
    /// Area-weighted vertex normals summed over equal positions ([`position_classes`]): vertices
    /// split at a UV seam or per face corner get one normal, so the surface shades smooth. Zero
    /// area triangles add nothing; a position with no area around it gets +z.
    pub fn smooth_normals(&self) -> Vec<Vec3> {
        let classes = position_classes(&self.positions, position_tolerance(self));
        let mut sums = vec![Vec3::ZERO; self.positions.len()];
        for t in 0..self.triangle_count() {
            let [a, b, c] = self.triangle(t);
            let n = (self.positions[b] - self.positions[a]).cross(self.positions[c] - self.positions[a]);
            for v in [a, b, c] {
                sums[classes[v] as usize] += n;
            }
        }
        classes.iter().map(|&c| sums[c as usize].try_normalize().unwrap_or(Vec3::Z)).collect()
    }

    /// Merges the `mergeable` vertices that share a position and a UV ([`merge_targets`]),
    /// renumbering the triangles; gives, per kept vertex, its old index. Normals are kept as they
    /// are (the merged vertices' own are dropped).
    pub fn weld(&mut self, mergeable: &[bool]) -> Vec<usize> {
        let classes = position_classes(&self.positions, position_tolerance(self));
        let targets = merge_targets(&classes, &self.uvs, mergeable);
        let old: Vec<usize> = (0..targets.len()).filter(|&i| targets[i] as usize == i).collect();
        let mut new_index = vec![u32::MAX; targets.len()];
        for (n, &o) in old.iter().enumerate() {
            new_index[o] = n as u32;
        }
        for i in &mut self.indices {
            *i = new_index[targets[*i as usize] as usize];
        }
        self.positions = old.iter().map(|&o| self.positions[o]).collect();
        self.normals = old.iter().map(|&o| self.normals[o]).collect();
        self.uvs = old.iter().map(|&o| self.uvs[o]).collect();
        old
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classes_meet_across_a_cell_boundary() {
        let tol = 1e-3;
        // 0.0009999 and 0.0010001 lie in two cells but 2e-7 apart.
        let p = [Vec3::new(0.000_999_9, 0.0, 0.0), Vec3::new(0.001_000_1, 0.0, 0.0), Vec3::new(0.5, 0.0, 0.0)];
        assert_eq!(position_classes(&p, tol), vec![0, 0, 2]);
    }

    #[test]
    fn a_seam_keeps_both_uvs() {
        let classes = [0, 0, 0, 3];
        let uvs = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::ZERO, Vec2::ZERO];
        assert_eq!(merge_targets(&classes, &uvs, &[true; 4]), vec![0, 1, 0, 3]);
        // A vertex with its own normal from the file is never merged.
        assert_eq!(merge_targets(&classes, &uvs, &[true, true, false, true]), vec![0, 1, 2, 3]);
    }
}
