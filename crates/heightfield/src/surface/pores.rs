//! Pores: smooth dimples scattered by a Poisson-disc (dart-throwing) process, found per query point
//! through a uniform cell index so only nearby pores are evaluated.

use glam::DVec2;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use super::{HeightSample, kernel};
use crate::params::PoreParams;

/// Dart-throwing attempts per requested pore before giving up (the packing saturates near a
/// covered fraction of 0.55 of the discs of diameter `min_distance`).
const ATTEMPTS_PER_PORE: usize = 30;

/// One pore: a dimple `-depth * (1 - r^2/radius^2)^3` centred at `centre` (mm, y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pore {
    pub centre: DVec2,
    pub radius_mm: f64,
    pub depth_mm: f64,
}

impl Pore {
    /// Height and gradient of this pore alone at `p`.
    #[inline]
    pub fn eval(&self, p: DVec2) -> HeightSample {
        let d = p - self.centre;
        let inv_r2 = 1.0 / (self.radius_mm * self.radius_mm);
        let (k, dk) = kernel::bump(d.length_squared() * inv_r2);
        HeightSample { height: -self.depth_mm * k, gradient: d * (-self.depth_mm * dk * 2.0 * inv_r2) }
    }
}

/// An axis-aligned rectangle in mm: `min` and `max` corners.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rect {
    pub min: DVec2,
    pub max: DVec2,
}

impl Rect {
    fn size(&self) -> DVec2 {
        self.max - self.min
    }
}

/// Pores and their cell index.
pub(crate) struct PoreField {
    pores: Vec<Pore>,
    grid: CellGrid,
    /// For each cell, the range of `order` holding its pores (CSR layout).
    starts: Vec<u32>,
    order: Vec<u32>,
    /// The largest pore radius.
    reach: f64,
}

impl PoreField {
    /// Scatters pores over `rect` (the field plus a margin, so border texels see their neighbours).
    pub(crate) fn new(p: &PoreParams, rect: Rect, rng: &mut ChaCha8Rng) -> Self {
        let target = (p.density_per_mm2 * rect.size().x * rect.size().y).round() as usize;
        let pores: Vec<Pore> = if target == 0 || p.depth_mm == 0.0 {
            Vec::new()
        } else {
            let centres = poisson_disc(rect, target, p.min_distance_mm, rng);
            centres.into_iter().map(|c| vary(p, c, rng)).collect()
        };
        let reach = pores.iter().map(|q| q.radius_mm).fold(p.radius_mm, f64::max);
        let grid = CellGrid::new(rect, 2.0 * reach, 4 * pores.len() + 1);
        let (starts, order) = grid.bucket(pores.iter().map(|q| q.centre));
        PoreField { pores, grid, starts, order, reach }
    }

    pub(crate) fn pores(&self) -> &[Pore] {
        &self.pores
    }

    /// Summed height and gradient of every pore reaching `p`: those in the cells overlapping the
    /// square of half-side `reach` around `p` (at most 2x2 cells, as cells are `2 reach` wide).
    #[inline]
    pub(crate) fn eval(&self, p: DVec2) -> HeightSample {
        let mut s = HeightSample::default();
        if self.pores.is_empty() {
            return s;
        }
        let (x0, y0) = self.grid.cell_of(p - self.reach);
        let (x1, y1) = self.grid.cell_of(p + self.reach);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.grid.cols + x;
                for &i in &self.order[self.starts[c] as usize..self.starts[c + 1] as usize] {
                    s += self.pores[i as usize].eval(p);
                }
            }
        }
        s
    }
}

/// Radius and depth of one pore, each scaled by `1 + variation * U(-1, 1)`.
fn vary(p: &PoreParams, centre: DVec2, rng: &mut ChaCha8Rng) -> Pore {
    let mut scale = || 1.0 + p.variation * rng.random_range(-1.0..1.0);
    let radius_mm = p.radius_mm * scale();
    let depth_mm = p.depth_mm * scale();
    Pore { centre, radius_mm, depth_mm }
}

/// A uniform grid of square cells over a rectangle, clamping outside points to the border cells.
struct CellGrid {
    origin: DVec2,
    cell: f64,
    cols: usize,
    rows: usize,
}

impl CellGrid {
    /// Cells at least `min_cell` wide and no more numerous than about `max_cells` (so a tiny
    /// radius over a huge field does not allocate a huge index). Lookups of a disc of radius
    /// `min_cell` or less about a point then touch at most the 3x3 cells around its own.
    fn new(rect: Rect, min_cell: f64, max_cells: usize) -> Self {
        let size = rect.size();
        let cell = min_cell.max((size.x * size.y / max_cells.max(1) as f64).sqrt());
        let cols = ((size.x / cell).ceil() as usize).max(1);
        let rows = ((size.y / cell).ceil() as usize).max(1);
        CellGrid { origin: rect.min, cell, cols, rows }
    }

    #[inline]
    fn cell_of(&self, p: DVec2) -> (usize, usize) {
        let c = ((p - self.origin) / self.cell).floor();
        let clamp = |v: f64, n: usize| if v < 0.0 { 0 } else { (v as usize).min(n - 1) };
        (clamp(c.x, self.cols), clamp(c.y, self.rows))
    }

    /// CSR buckets: `starts[c]..starts[c + 1]` indexes `order`, the items of cell `c` in input order.
    fn bucket(&self, points: impl Iterator<Item = DVec2> + Clone) -> (Vec<u32>, Vec<u32>) {
        let mut starts = vec![0u32; self.cols * self.rows + 1];
        let cells: Vec<usize> = points.map(|p| self.cell_of(p)).map(|(x, y)| y * self.cols + x).collect();
        for &c in &cells {
            starts[c + 1] += 1;
        }
        for c in 1..starts.len() {
            starts[c] += starts[c - 1];
        }
        let mut fill = starts.clone();
        let mut order = vec![0u32; cells.len()];
        for (i, &c) in cells.iter().enumerate() {
            order[fill[c] as usize] = i as u32;
            fill[c] += 1;
        }
        (starts, order)
    }
}

/// Up to `target` points uniformly in `rect`, no two closer than `min_distance` (dart throwing
/// with a background grid; sequential, so the result depends only on the RNG).
pub(crate) fn poisson_disc(rect: Rect, target: usize, min_distance: f64, rng: &mut ChaCha8Rng) -> Vec<DVec2> {
    // About one point per cell at most: the background grid is a Vec per cell.
    let grid = CellGrid::new(rect, min_distance, target + 1);
    let mut cells: Vec<Vec<u32>> = vec![Vec::new(); grid.cols * grid.rows];
    let mut points = Vec::with_capacity(target);
    let min_sq = min_distance * min_distance;
    for _ in 0..target.saturating_mul(ATTEMPTS_PER_PORE) {
        if points.len() == target {
            break;
        }
        let p = rect.min + DVec2::new(rng.random::<f64>(), rng.random::<f64>()) * rect.size();
        let (cx, cy) = grid.cell_of(p);
        if min_distance > 0.0 && too_close(&grid, &cells, &points, p, (cx, cy), min_sq) {
            continue;
        }
        cells[cy * grid.cols + cx].push(points.len() as u32);
        points.push(p);
    }
    points
}

fn too_close(
    grid: &CellGrid,
    cells: &[Vec<u32>],
    points: &[DVec2],
    p: DVec2,
    (cx, cy): (usize, usize),
    min_sq: f64,
) -> bool {
    for y in cy.saturating_sub(1)..(cy + 2).min(grid.rows) {
        for x in cx.saturating_sub(1)..(cx + 2).min(grid.cols) {
            if cells[y * grid.cols + x].iter().any(|&i| points[i as usize].distance_squared(p) < min_sq) {
                return true;
            }
        }
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn rect(w: f64, h: f64) -> Rect {
        Rect { min: DVec2::new(-w / 2.0, -h / 2.0), max: DVec2::new(w / 2.0, h / 2.0) }
    }

    #[test]
    fn poisson_disc_honours_min_distance_against_brute_force() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let pts = poisson_disc(rect(6.0, 4.0), 150, 0.25, &mut rng);
        assert!(pts.len() > 120, "only {} points", pts.len());
        let mut closest = f64::INFINITY;
        for (i, a) in pts.iter().enumerate() {
            for b in &pts[i + 1..] {
                closest = closest.min(a.distance(*b));
            }
        }
        assert!(closest >= 0.25, "closest pair {closest}");
        assert!(pts.iter().all(|p| p.abs().x <= 3.0 && p.abs().y <= 2.0));
    }

    #[test]
    fn index_finds_the_same_pores_as_a_linear_scan() {
        let p =
            PoreParams { density_per_mm2: 8.0, radius_mm: 0.1, depth_mm: 0.03, variation: 0.5, min_distance_mm: 0.05 };
        let field = PoreField::new(&p, rect(3.0, 2.0), &mut ChaCha8Rng::seed_from_u64(2));
        assert!(field.pores().len() > 30);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..500 {
            let q = DVec2::new(rng.random_range(-1.8..1.8), rng.random_range(-1.2..1.2));
            let brute = field.pores().iter().fold(HeightSample::default(), |s, pore| s + pore.eval(q));
            let fast = field.eval(q);
            assert!((brute.height - fast.height).abs() < 1e-15);
            assert!((brute.gradient - fast.gradient).length() < 1e-12);
        }
    }
}
