//! The 3x3 algebra of the per-pixel fits: weighted normal equations accumulated in f32, solved
//! and conditioned in f64 (closed forms, no allocation, no iteration).

use glam::Vec3;

/// A symmetric 3x3 matrix stored as xx, xy, xz, yy, yz, zz, and a right-hand side.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Normal3 {
    pub(crate) m: [f32; 6],
    pub(crate) b: [f32; 3],
}

impl Normal3 {
    /// Adds `w * L L^T` to the matrix and `w * r * L` to the right-hand side.
    #[inline(always)]
    pub(crate) fn add(&mut self, l: Vec3, w: f32, r: f32) {
        let (wx, wy, wz) = (w * l.x, w * l.y, w * l.z);
        self.m[0] += wx * l.x;
        self.m[1] += wx * l.y;
        self.m[2] += wx * l.z;
        self.m[3] += wy * l.y;
        self.m[4] += wy * l.z;
        self.m[5] += wz * l.z;
        self.b[0] += wx * r;
        self.b[1] += wy * r;
        self.b[2] += wz * r;
    }

    /// `M^-1 b` by the adjugate in f64; `None` when `M` is singular to working precision.
    pub(crate) fn solve(&self) -> Option<Vec3> {
        let [a, b, c, d, e, f] = self.m.map(|v| v as f64);
        // Cofactors of the symmetric matrix [[a b c] [b d e] [c e f]].
        let (c00, c01, c02) = (d * f - e * e, c * e - b * f, b * e - c * d);
        let (c11, c12, c22) = (a * f - c * c, b * c - a * e, a * d - b * b);
        let det = a * c00 + b * c01 + c * c02;
        let scale = a.abs().max(d.abs()).max(f.abs());
        if !(det.is_finite() && det > 1e-12 * scale * scale * scale) {
            return None;
        }
        let [x, y, z] = self.b.map(|v| v as f64);
        let g = [
            (c00 * x + c01 * y + c02 * z) / det,
            (c01 * x + c11 * y + c12 * z) / det,
            (c02 * x + c12 * y + c22 * z) / det,
        ];
        let g = Vec3::new(g[0] as f32, g[1] as f32, g[2] as f32);
        g.is_finite().then_some(g)
    }

    /// `sigma_max / sigma_min` of the direction matrix whose Gram matrix this is (infinite when
    /// singular): the square root of the eigenvalue ratio, eigenvalues in closed form.
    pub(crate) fn condition(&self) -> f64 {
        let (lo, hi) = symmetric_eigen_range(self.m.map(|v| v as f64));
        if lo > hi * 1e-15 && lo > 0.0 { (hi / lo).sqrt() } else { f64::INFINITY }
    }
}

/// Smallest and largest eigenvalue of a symmetric 3x3 matrix (xx, xy, xz, yy, yz, zz), by the
/// trigonometric solution of the characteristic cubic.
fn symmetric_eigen_range(m: [f64; 6]) -> (f64, f64) {
    let [a, b, c, d, e, f] = m;
    let off = b * b + c * c + e * e;
    if off == 0.0 {
        return (a.min(d).min(f), a.max(d).max(f));
    }
    let q = (a + d + f) / 3.0;
    let p2 = (a - q).powi(2) + (d - q).powi(2) + (f - q).powi(2) + 2.0 * off;
    let p = (p2 / 6.0).sqrt();
    // B = (A - q I) / p; det(B) / 2 = cos(3 phi).
    let (ba, bd, bf, bb, bc, be) = ((a - q) / p, (d - q) / p, (f - q) / p, b / p, c / p, e / p);
    let det_b = ba * (bd * bf - be * be) - bb * (bb * bf - be * bc) + bc * (bb * be - bd * bc);
    let phi = (det_b / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    (lo, hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solve_recovers_a_known_vector() {
        let lights = [Vec3::new(0.3, 0.1, 0.95), Vec3::new(-0.4, 0.2, 0.89), Vec3::new(0.05, -0.5, 0.86)];
        let g = Vec3::new(0.2, -0.1, 0.6);
        let mut n = Normal3::default();
        for l in lights {
            let l = l.normalize();
            n.add(l, 1.0, l.dot(g));
        }
        assert!((n.solve().unwrap() - g).length() < 1e-5);
    }

    #[test]
    fn singular_systems_give_none_and_infinite_condition() {
        let mut n = Normal3::default();
        n.add(Vec3::Z, 1.0, 0.5);
        n.add(Vec3::Z, 2.0, 0.5);
        assert!(n.solve().is_none());
        assert!(n.condition().is_infinite());
    }

    #[test]
    fn eigen_range_matches_nalgebra() {
        let m = [2.0, 0.3, -0.2, 1.5, 0.1, 0.7];
        let full = nalgebra::Matrix3::new(m[0], m[1], m[2], m[1], m[3], m[4], m[2], m[4], m[5]);
        let eig = full.symmetric_eigenvalues();
        let (lo, hi) = symmetric_eigen_range(m);
        assert!((lo - eig.min()).abs() < 1e-12 && (hi - eig.max()).abs() < 1e-12, "{lo} {hi} {eig}");
    }
}
