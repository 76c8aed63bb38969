//! Cast shadows: a ray marched over the height grid (bilinear between texel centres) from a texel
//! toward its light, skipping blocks whose maximum height the ray already clears.

use glam::DVec3;

/// Texels per side of a block of the maximum-height index.
const BLOCK: usize = 16;
/// March step in texels.
const STEP: f64 = 0.5;
/// Height tolerance in texel pitches: bilinear interpolation of a curved surface overshoots by
/// about curvature * pitch^2 / 8, and a grazing ray must not shadow the texel it starts from.
const BIAS_TEXELS: f64 = 0.05;

/// The height grid and its block maxima.
pub(crate) struct ShadowCaster<'a> {
    heights: &'a [f32],
    width: usize,
    height: usize,
    mm_per_texel: f64,
    /// Maximum over each block dilated by one texel toward +col and +row (the bilinear support of
    /// any point inside the block).
    block_max: Vec<f32>,
    blocks_x: usize,
    global_max: f32,
    bias: f64,
}

/// A ray in texel coordinates: `(col, row) + t * dir`, height `z0 + t * rise` (mm), up to `t_max`.
struct Ray {
    col: f64,
    row: f64,
    dir: [f64; 2],
    z0: f64,
    rise: f64,
    t_max: f64,
}

impl<'a> ShadowCaster<'a> {
    pub(crate) fn new(heights: &'a [f32], width: usize, height: usize, mm_per_texel: f64) -> Self {
        let blocks_x = width.div_ceil(BLOCK);
        let blocks_y = height.div_ceil(BLOCK);
        let mut block_max = vec![f32::NEG_INFINITY; blocks_x * blocks_y];
        for by in 0..blocks_y {
            for bx in 0..blocks_x {
                let rows = by * BLOCK..((by + 1) * BLOCK + 1).min(height);
                let cols = bx * BLOCK..((bx + 1) * BLOCK + 1).min(width);
                let m = rows.flat_map(|r| heights[r * width + cols.start..r * width + cols.end].iter().copied());
                block_max[by * blocks_x + bx] = m.fold(f32::NEG_INFINITY, f32::max);
            }
        }
        let global_max = block_max.iter().copied().fold(f32::NEG_INFINITY, f32::max);
        let bias = BIAS_TEXELS * mm_per_texel;
        ShadowCaster { heights, width, height, mm_per_texel, block_max, blocks_x, global_max, bias }
    }

    /// Whether texel `(col, row)` at `point` (mm) sees a light in direction `dir` (unit, camera
    /// frame), or at `light` (mm) when it is a point light.
    pub(crate) fn visible(&self, col: usize, row: usize, point: DVec3, dir: DVec3, light: Option<DVec3>) -> bool {
        let horizontal = (dir.x * dir.x + dir.y * dir.y).sqrt();
        if horizontal < 1e-9 {
            return true; // straight overhead: nothing on a heightfield rises above the ray
        }
        let t_max = match light {
            Some(p) => ((p.x - point.x).powi(2) + (p.y - point.y).powi(2)).sqrt() / self.mm_per_texel,
            None => f64::INFINITY,
        };
        let ray = Ray {
            col: col as f64,
            row: row as f64,
            // Rows grow against y.
            dir: [dir.x / horizontal, -dir.y / horizontal],
            z0: point.z,
            rise: dir.z / horizontal * self.mm_per_texel,
            t_max,
        };
        self.march(&ray)
    }

    fn march(&self, ray: &Ray) -> bool {
        let (w_max, h_max) = ((self.width - 1) as f64, (self.height - 1) as f64);
        let mut t = STEP;
        while t <= ray.t_max {
            let (c, r) = (ray.col + t * ray.dir[0], ray.row + t * ray.dir[1]);
            if !(0.0..=w_max).contains(&c) || !(0.0..=h_max).contains(&r) {
                return true;
            }
            let z = ray.z0 + t * ray.rise;
            if ray.rise >= 0.0 && z > self.global_max as f64 + self.bias {
                return true;
            }
            let t_exit = self.block_exit(ray, c, r, t);
            let z_exit = ray.z0 + t_exit.min(ray.t_max) * ray.rise;
            if z.min(z_exit) > self.block_max_at(c, r) as f64 + self.bias {
                // Jump to the first step on or past the border: every step before it lies in this
                // block, which the ray clears. Staying on the lattice of steps keeps the result
                // identical to a plain march.
                t = ((t_exit / STEP).ceil() * STEP).max(t + STEP);
                continue;
            }
            if self.bilinear(c, r) > z + self.bias {
                return false;
            }
            t += STEP;
        }
        true
    }

    /// The ray parameter where it leaves the block holding `(c, r)`.
    fn block_exit(&self, ray: &Ray, c: f64, r: f64, t: f64) -> f64 {
        let axis_exit = |pos: f64, d: f64| {
            let start = (pos as usize / BLOCK * BLOCK) as f64;
            if d > 0.0 {
                (start + BLOCK as f64 - pos) / d
            } else if d < 0.0 {
                (pos - start) / -d
            } else {
                f64::INFINITY
            }
        };
        t + axis_exit(c, ray.dir[0]).min(axis_exit(r, ray.dir[1]))
    }

    fn block_max_at(&self, c: f64, r: f64) -> f32 {
        self.block_max[(r as usize / BLOCK) * self.blocks_x + c as usize / BLOCK]
    }

    fn bilinear(&self, c: f64, r: f64) -> f64 {
        let (c0, r0) = (c as usize, r as usize);
        let (c1, r1) = ((c0 + 1).min(self.width - 1), (r0 + 1).min(self.height - 1));
        let (fc, fr) = (c - c0 as f64, r - r0 as f64);
        let h = |c: usize, r: usize| self.heights[r * self.width + c] as f64;
        let top = h(c0, r0) * (1.0 - fc) + h(c1, r0) * fc;
        let bottom = h(c0, r1) * (1.0 - fc) + h(c1, r1) * fc;
        top * (1.0 - fr) + bottom * fr
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same march without block skipping, as an oracle.
    fn brute(s: &ShadowCaster, col: usize, row: usize, dir: DVec3) -> bool {
        let horizontal = (dir.x * dir.x + dir.y * dir.y).sqrt();
        let d = [dir.x / horizontal, -dir.y / horizontal];
        let z0 = s.heights[row * s.width + col] as f64;
        let mut t = STEP;
        loop {
            let (c, r) = (col as f64 + t * d[0], row as f64 + t * d[1]);
            if c < 0.0 || r < 0.0 || c > (s.width - 1) as f64 || r > (s.height - 1) as f64 {
                return true;
            }
            if s.bilinear(c, r) > z0 + t * dir.z / horizontal * s.mm_per_texel + s.bias {
                return false;
            }
            t += STEP;
        }
    }

    #[test]
    fn block_skipping_agrees_with_a_plain_march() {
        let (w, h) = (70, 50);
        let heights: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                0.3 * (x * 0.37).sin() * (y * 0.23).cos() + if (x - 40.0).abs() < 2.0 { 1.5 } else { 0.0 }
            })
            .collect();
        let s = ShadowCaster::new(&heights, w, h, 0.1);
        let mut shadowed = 0;
        for dir in [DVec3::new(0.9, 0.1, 0.3), DVec3::new(-0.5, -0.7, 0.4), DVec3::new(0.2, -0.95, 0.1)] {
            let dir = dir.normalize();
            for row in 0..h {
                for col in 0..w {
                    let z = heights[row * w + col] as f64;
                    let fast = s.visible(col, row, DVec3::new(0.0, 0.0, z), dir, None);
                    assert_eq!(fast, brute(&s, col, row, dir), "texel ({col}, {row}) dir {dir}");
                    shadowed += usize::from(!fast);
                }
            }
        }
        assert!(shadowed > 500, "only {shadowed} shadowed texels: the test geometry is too easy");
    }
}
