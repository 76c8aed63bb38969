//! Pseudo-inverses of subsets of the rig's lights, and their per-solve cache.

use std::collections::HashMap;
use std::sync::OnceLock;

use glam::Vec3;
use nalgebra::{Matrix3, Vector3};

use super::DENSE_MAX_LIGHTS;
use crate::readings::condition_of;

/// The pseudo-inverse of one subset of lights, with what the confidence needs.
#[derive(Clone, Debug)]
pub(super) struct SubsetSolve {
    /// Column of `P` for each light in the subset, in light order.
    pub(super) cols: Vec<[f32; 3]>,
    /// `L^T L` of the subset: xx, xy, xz, yy, yz, zz.
    pub(super) gram: [f32; 6],
    /// `sigma_max / sigma_min` of the subset's direction matrix (infinite when singular).
    pub(super) condition: f64,
    /// Whether the subset may be used (condition within bounds).
    pub(super) usable: bool,
}

impl SubsetSolve {
    /// Solves for the subset `bits` of `lights` (f64, then stored as f32).
    pub(super) fn new(lights: &[Vec3], bits: u128, max_condition: f64) -> Self {
        let used: Vec<Vector3<f64>> = lights
            .iter()
            .enumerate()
            .filter(|(i, _)| bits >> i & 1 == 1)
            .map(|(_, l)| Vector3::new(l.x as f64, l.y as f64, l.z as f64))
            .collect();
        let gram: Matrix3<f64> = used.iter().map(|l| l * l.transpose()).sum();
        let condition = condition_of(&gram);
        let usable = used.len() >= 3 && condition.is_finite() && condition <= max_condition;
        let inverse = gram.try_inverse().filter(|_| usable);
        let cols = match inverse {
            Some(inv) => used.iter().map(|l| (inv * l).map(|v| v as f32).into()).collect(),
            None => Vec::new(),
        };
        let g = gram.map(|v| v as f32);
        let gram = [g[(0, 0)], g[(0, 1)], g[(0, 2)], g[(1, 1)], g[(1, 2)], g[(2, 2)]];
        SubsetSolve { cols, gram, condition, usable: inverse.is_some() }
    }

    /// `g^T (L^T L) g`, the squared norm of the fitted readings.
    #[inline]
    pub(super) fn fitted_sq(&self, g: [f32; 3]) -> f32 {
        gram_form(&self.gram, g)
    }
}

/// `g^T G g` for the symmetric 3x3 `G` stored as xx, xy, xz, yy, yz, zz.
#[inline(always)]
pub(super) fn gram_form(m: &[f32; 6], g: [f32; 3]) -> f32 {
    let [x, y, z] = g;
    m[0] * x * x + m[3] * y * y + m[5] * z * z + 2.0 * (m[1] * x * y + m[2] * x * z + m[4] * y * z)
}

/// Subset pseudo-inverses shared by all workers (dense table) or kept per worker (bounded map).
pub(super) struct Subsets<'a> {
    pub(super) lights: &'a [Vec3],
    pub(super) max_condition: f64,
    pub(super) dense: Vec<OnceLock<SubsetSolve>>,
    pub(super) capacity: usize,
}

impl<'a> Subsets<'a> {
    pub(super) fn new(lights: &'a [Vec3], max_condition: f64, capacity: usize) -> Self {
        let dense = if lights.len() <= DENSE_MAX_LIGHTS {
            (0..1usize << lights.len()).map(|_| OnceLock::new()).collect()
        } else {
            Vec::new()
        };
        Subsets { lights, max_condition, dense, capacity }
    }

    /// The condition number of subset `bits` when the subsets are in the dense table.
    pub(super) fn dense_condition(&self, bits: u128) -> Option<f64> {
        let entry = self.dense.get(bits as usize)?;
        Some(entry.get_or_init(|| SubsetSolve::new(self.lights, bits, self.max_condition)).condition)
    }

    /// The solve for subset `bits`, from the dense table or the worker's `local` map.
    pub(super) fn get<'s>(&'s self, bits: u128, local: &'s mut HashMap<u128, SubsetSolve>) -> &'s SubsetSolve {
        if !self.dense.is_empty() {
            return self.dense[bits as usize].get_or_init(|| SubsetSolve::new(self.lights, bits, self.max_condition));
        }
        if local.len() >= self.capacity && !local.contains_key(&bits) {
            local.clear();
        }
        local.entry(bits).or_insert_with(|| SubsetSolve::new(self.lights, bits, self.max_condition))
    }
}
