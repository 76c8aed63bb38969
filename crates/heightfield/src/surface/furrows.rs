//! Furrows: families of parallel grooves that cross each other, the fine line pattern of skin.
//!
//! Line `k` of a family sits at offset `k * spacing + jitter_k` across the family's direction. It
//! wanders sideways by `waviness * sin(w_k v + psi_k)` (`v` the distance along the line) and its
//! depth is modulated along it by `1 - m (1 + cos(w'_k v + chi_k)) / 2`, so grooves come in
//! segments. Per-line random values come from a stateless hash of the line index, so any line of
//! the unbounded family can be evaluated without a table.

use glam::DVec2;

use super::{HeightSample, hash, kernel};
use crate::params::FurrowFamily;

/// Salts of the per-line random values.
const JITTER: u64 = 1;
const DEPTH: u64 = 2;
const WAVE_PHASE: u64 = 3;
const WAVE_LENGTH: u64 = 4;
const MOD_PHASE: u64 = 5;
const MOD_LENGTH: u64 = 6;

pub(crate) struct Furrows {
    p: FurrowFamily,
    /// Hash key of the family's lattice of lines.
    key: u64,
    /// Unit vector along the lines.
    along: DVec2,
    /// Unit vector across the lines.
    across: DVec2,
    half_width: f64,
    /// Largest distance from a line's nominal position at which it can still touch a point.
    reach: f64,
}

/// One line's random shape.
struct Line {
    offset: f64,
    depth: f64,
    wave_k: f64,
    wave_phase: f64,
    mod_k: f64,
    mod_phase: f64,
}

impl Furrows {
    pub(crate) fn new(p: &FurrowFamily, seed: u64, family: usize) -> Self {
        let along = DVec2::from_angle(p.angle_deg.to_radians());
        let half_width = 0.5 * p.width_mm;
        let reach = half_width + p.waviness_mm + p.jitter * p.spacing_mm;
        let key = hash::family_key(seed, family as u64);
        Furrows { p: p.clone(), key, along, across: along.perp(), half_width, reach }
    }

    /// Summed height and gradient of every line of the family touching `pt`.
    #[inline]
    pub(crate) fn eval(&self, pt: DVec2) -> HeightSample {
        let mut s = HeightSample::default();
        if self.p.depth_mm == 0.0 {
            return s;
        }
        let u = pt.dot(self.across);
        let v = pt.dot(self.along);
        let first = ((u - self.reach) / self.p.spacing_mm).floor() as i64;
        let last = ((u + self.reach) / self.p.spacing_mm).ceil() as i64;
        for k in first..=last {
            // The offset alone decides whether the line can reach `pt`; draw the rest only then.
            let key = hash::item_key(self.key, k);
            let offset = self.offset(key, k);
            if (u - offset).abs() < self.half_width + self.p.waviness_mm {
                s += self.eval_line(&self.line(key, offset), u, v);
            }
        }
        s
    }

    fn offset(&self, key: u64, k: i64) -> f64 {
        (k as f64 + self.p.jitter * hash::signed(key, JITTER)) * self.p.spacing_mm
    }

    fn line(&self, key: u64, offset: f64) -> Line {
        let r = |salt| hash::unit(key, salt);
        let rs = |salt| hash::signed(key, salt);
        let tau = std::f64::consts::TAU;
        // Wavelengths vary by +-30 % per line so neighbouring grooves do not wave in step.
        let wavelength = |salt| self.p.wavelength_mm * (1.0 + 0.3 * rs(salt));
        Line {
            offset,
            depth: self.p.depth_mm * (1.0 + 0.3 * rs(DEPTH)),
            wave_k: tau / wavelength(WAVE_LENGTH),
            wave_phase: tau * r(WAVE_PHASE),
            mod_k: tau / wavelength(MOD_LENGTH),
            mod_phase: tau * r(MOD_PHASE),
        }
    }

    /// One groove at across-coordinate `u` and along-coordinate `v`.
    fn eval_line(&self, line: &Line, u: f64, v: f64) -> HeightSample {
        let (wave_sin, wave_cos) = (line.wave_k * v + line.wave_phase).sin_cos();
        let t = (u + self.p.waviness_mm * wave_sin - line.offset) / self.half_width;
        let (k, dk_dq) = kernel::bump(t * t);
        if k == 0.0 {
            return HeightSample::default();
        }
        // d t / d(u, v)
        let dt = DVec2::new(1.0, self.p.waviness_mm * line.wave_k * wave_cos) / self.half_width;
        let (mod_sin, mod_cos) = (line.mod_k * v + line.mod_phase).sin_cos();
        let m = self.p.depth_variation;
        let depth = line.depth * (1.0 - 0.5 * m * (1.0 + mod_cos));
        let d_depth_dv = line.depth * 0.5 * m * line.mod_k * mod_sin;
        // h = -depth(v) * K(t^2); gradient in (u, v), then rotated back to (x, y).
        let grad_uv = -depth * dk_dq * 2.0 * t * dt - DVec2::new(0.0, d_depth_dv * k);
        HeightSample { height: -depth * k, gradient: self.across * grad_uv.x + self.along * grad_uv.y }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_constant_groove_has_the_kernel_profile() {
        let p = FurrowFamily {
            angle_deg: 90.0,
            spacing_mm: 1000.0,
            width_mm: 0.2,
            depth_mm: 0.05,
            jitter: 0.0,
            waviness_mm: 0.0,
            wavelength_mm: 1.0,
            depth_variation: 0.0,
        };
        let f = Furrows::new(&p, 9, 0);
        // Lines run along +y, so `across` is -x; line 0 passes through the origin.
        let key = hash::item_key(f.key, 0);
        let depth0 = f.line(key, f.offset(key, 0)).depth;
        for x in [-0.15, -0.09, -0.03, 0.0, 0.05, 0.099] {
            let s = f.eval(DVec2::new(x, 3.7));
            let q: f64 = (x / 0.1) * (x / 0.1);
            let expect = if q < 1.0 { -depth0 * (1.0 - q).powi(3) } else { 0.0 };
            assert!((s.height - expect).abs() < 1e-15, "x={x}: {} vs {expect}", s.height);
            assert!(s.gradient.y.abs() < 1e-15);
        }
    }
}
