//! Face regions as a label map: every texel goes to the region of its nearest seed point
//! (Haro et al. 2001, section 4.2: "the regions are defined by a user by selecting a few points").
//!
//! * Distances are Euclidean in texels between texel centres. A face UV map does **not** wrap:
//!   its left and right edges are different places on the head (and usually lie outside the UV
//!   charts), so the partition is computed on the plain rectangle. (Synthesis output is toroidal,
//!   the face map is not.)
//! * Seed points are texels ([`SeedPoint`]). Each point owns a *cell* (the texels nearest to it);
//!   a region is the union of the cells of its points, so a region with two far-apart points (two
//!   cheeks of one mold) has two parts. Ties go to the lowest region index, then to the lowest
//!   point index: the result never depends on thread count or on the order of the points.
//! * Since a point is at distance 0 from its own texel, every point keeps at least that texel
//!   unless another point sits on the same texel. A layout refuses coincident points
//!   ([`crate::Error::CoincidentPoints`]); through this API they are accepted and the point of
//!   the higher region index (then higher point index) gets no texels. A region all of whose
//!   points are covered that way has an empty [`RegionArea`] (`texels == 0`, `bbox == None`) and
//!   [`Partition::synthesis_rect`] returns `None` for it: there is nothing to synthesise.
//! * [`crate::curve`] replaces the straight cell boundaries by random curves;
//!   [`Partition::build`] does both.

use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::curve::{self, CurveParams};
use crate::{Error, Result};

/// A seed point: the texel `(x, y)` (row 0 at the top) and the region it belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SeedPoint {
    /// Index of the region in the layout.
    pub region: usize,
    /// Column of the texel.
    pub x: u32,
    /// Row of the texel (0 at the top).
    pub y: u32,
}

/// A rectangle of texels: `width x height` with top-left texel `(x, y)`, as [`Grid::crop`] takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Rect {
    pub x: usize,
    pub y: usize,
    pub width: usize,
    pub height: usize,
}

impl Rect {
    /// The rectangle grown by `margin` texels on every side, clamped to a `map_width x map_height`
    /// map.
    pub fn grown(self, margin: usize, map_width: usize, map_height: usize) -> Rect {
        let x0 = self.x.saturating_sub(margin);
        let y0 = self.y.saturating_sub(margin);
        let x1 = (self.x + self.width).saturating_add(margin).min(map_width);
        let y1 = (self.y + self.height).saturating_add(margin).min(map_height);
        Rect { x: x0, y: y0, width: x1.saturating_sub(x0), height: y1.saturating_sub(y0) }
    }

    /// Whether texel `(x, y)` lies inside.
    pub fn contains(&self, x: usize, y: usize) -> bool {
        x >= self.x && y >= self.y && x < self.x + self.width && y < self.y + self.height
    }

    /// Number of texels.
    pub fn area(&self) -> usize {
        self.width * self.height
    }

    /// The smallest rectangle holding both.
    fn union(self, other: Rect) -> Rect {
        let x0 = self.x.min(other.x);
        let y0 = self.y.min(other.y);
        let x1 = (self.x + self.width).max(other.x + other.width);
        let y1 = (self.y + self.height).max(other.y + other.height);
        Rect { x: x0, y: y0, width: x1 - x0, height: y1 - y0 }
    }
}

/// What a region covers in the label map.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegionArea {
    /// Number of texels labelled with the region (covered texels only, see [`Partition::restrict_to`]).
    pub texels: usize,
    /// Bounding box of those texels; `None` when the region has none.
    pub bbox: Option<Rect>,
}

/// A label map (region index per texel) with each region's area.
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    labels: Grid<u16>,
    areas: Vec<RegionArea>,
}

impl Partition {
    /// The nearest-point partition of a `width x height` map into `region_count` regions
    /// (straight boundaries).
    ///
    /// # Errors
    /// As [`check_seeds`].
    pub fn nearest(width: usize, height: usize, region_count: usize, seeds: &[SeedPoint]) -> Result<Partition> {
        check_seeds(width, height, region_count, seeds)?;
        Ok(Partition::from_cells(&nearest_cells(width, height, seeds), seeds, region_count))
    }

    /// The partition with every straight boundary replaced by a random curve
    /// ([`crate::curve`]); amplitude 0 gives [`Partition::nearest`].
    ///
    /// # Errors
    /// As [`check_seeds`] and [`CurveParams::validate`].
    pub fn build(
        width: usize,
        height: usize,
        region_count: usize,
        seeds: &[SeedPoint],
        curve: &CurveParams,
    ) -> Result<Partition> {
        let cells = curve::curved_cells(width, height, seeds, curve)?;
        check_seeds(width, height, region_count, seeds)?;
        Ok(Partition::from_cells(&cells, seeds, region_count))
    }

    /// The region label map of a cell map (cell `i` belongs to `seeds[i].region`).
    ///
    /// Panics when a cell index is not an index of `seeds` (a bug: cell maps come from this crate).
    pub fn from_cells(cells: &Grid<u16>, seeds: &[SeedPoint], region_count: usize) -> Partition {
        let labels = cells.map(|&c| seeds[c as usize].region as u16);
        let areas = region_areas(&labels, None, region_count);
        Partition { labels, areas }
    }

    /// Recomputes the regions' areas over the texels where `coverage` is true only (texels
    /// outside the UV charts cost nothing to synthesise). Labels are kept everywhere, so the
    /// spline still has a region for every texel.
    ///
    /// # Errors
    /// When `coverage` is not the map's size.
    pub fn restrict_to(&mut self, coverage: &Grid<bool>) -> Result<()> {
        if coverage.size() != self.labels.size() {
            return Err(Error::InvalidParameter(format!(
                "coverage mask is {}x{} but the map is {}x{}",
                coverage.width(),
                coverage.height(),
                self.labels.width(),
                self.labels.height()
            )));
        }
        self.areas = region_areas(&self.labels, Some(coverage), self.areas.len());
        Ok(())
    }

    /// Region index per texel.
    pub fn labels(&self) -> &Grid<u16> {
        &self.labels
    }

    /// Area of each region, indexed by region.
    pub fn areas(&self) -> &[RegionArea] {
        &self.areas
    }

    /// `(width, height)` of the map.
    pub fn size(&self) -> (usize, usize) {
        self.labels.size()
    }

    /// The rectangle a region must be synthesised over: its bounding box grown by `margin`
    /// texels (the spline needs about `3 * 2^L` past the boundary), clamped to the map. `None`
    /// for a region with no texels.
    pub fn synthesis_rect(&self, region: usize, margin: usize) -> Option<Rect> {
        let (w, h) = self.size();
        self.areas.get(region)?.bbox.map(|b| b.grown(margin, w, h))
    }

    /// The region's mask over `rect`: 1 where the texel belongs to `region`, else 0.
    ///
    /// Panics when `rect` does not fit in the map.
    pub fn mask(&self, region: usize, rect: Rect) -> Grid<f32> {
        let (w, h) = self.size();
        assert!(rect.x + rect.width <= w && rect.y + rect.height <= h, "rect {rect:?} outside {w}x{h}");
        Grid::from_fn(rect.width, rect.height, |x, y| {
            f32::from(*self.labels.get(rect.x + x, rect.y + y) as usize == region)
        })
    }
}

/// Checks seed points against the map: at least one point, every point inside the map, every
/// region index below `region_count`, at most `u16::MAX` points and regions, non-zero size.
///
/// # Errors
/// [`Error::InvalidParameter`] naming the point and its values.
pub fn check_seeds(width: usize, height: usize, region_count: usize, seeds: &[SeedPoint]) -> Result<()> {
    let bad = |m: String| Err(Error::InvalidParameter(m));
    if width == 0 || height == 0 {
        return bad(format!("map size {width}x{height} has no texels"));
    }
    if seeds.is_empty() {
        return bad("no seed points: a partition needs at least one".into());
    }
    if seeds.len() > usize::from(u16::MAX) || region_count > usize::from(u16::MAX) {
        return bad(format!("{} seed points in {region_count} regions: at most {} of each", seeds.len(), u16::MAX));
    }
    for (i, s) in seeds.iter().enumerate() {
        if s.x as usize >= width || s.y as usize >= height {
            return bad(format!("seed point {i} at ({}, {}) lies outside the {width}x{height} map", s.x, s.y));
        }
        if s.region >= region_count {
            return bad(format!("seed point {i} names region {} but there are {region_count}", s.region));
        }
    }
    Ok(())
}

/// The nearest-point cell map: index of the nearest seed point per texel (squared distances in
/// integers, so exact), ties to the lowest `(region, point index)`. Blocks of texels whose
/// nearest point is clear by a margin are filled at once.
pub fn nearest_cells(width: usize, height: usize, seeds: &[SeedPoint]) -> Grid<u16> {
    let order = tie_order(seeds);
    let sites: Vec<(u16, [f64; 2])> =
        order.iter().map(|&i| (i as u16, [f64::from(seeds[i].x), f64::from(seeds[i].y)])).collect();
    let uniform = |cx: f64, cy: f64, r: f64, _: &mut ()| {
        let (best, d1, d2) = two_nearest(&sites, [cx, cy]);
        (d2.sqrt() - d1.sqrt() > 2.0 * r + 1e-6).then_some(best)
    };
    fill_blocks(width, height, || (), uniform, |x, y, _| nearest_seed(x as i64, y as i64, seeds, &order))
}

/// Side of the square blocks of [`fill_blocks`].
pub(crate) const BLOCK: usize = 16;

/// Fills a label map block by block: `uniform(cx, cy, r, state)` may give one label for every
/// texel within `r` of the block centre `(cx, cy)` (then the block is filled with it); otherwise
/// the block is split into blocks of [`SUB_BLOCK`] asked the same way, and `texel(x, y, state)`
/// labels each texel of those that stay undecided. Bands of [`BLOCK`] rows run in parallel, each
/// with its own `state()`; every texel's label depends only on its position, so the result is
/// the same on any thread count.
pub(crate) fn fill_blocks<S>(
    width: usize,
    height: usize,
    state: impl Fn() -> S + Sync,
    uniform: impl Fn(f64, f64, f64, &mut S) -> Option<u16> + Sync,
    texel: impl Fn(usize, usize, &mut S) -> u16 + Sync,
) -> Grid<u16> {
    let mut cells = Grid::filled(width, height, 0u16);
    cells.as_mut_slice().par_chunks_mut(width * BLOCK).enumerate().for_each(|(band, rows)| {
        let mut s = state();
        let mut band = Band { rows, width, y0: band * BLOCK };
        let bh = band.rows.len() / width;
        for x0 in (0..width).step_by(BLOCK) {
            let bw = BLOCK.min(width - x0);
            if band.try_uniform(x0, 0, bw, bh, &mut s, &uniform) {
                continue;
            }
            for sy in (0..bh).step_by(SUB_BLOCK) {
                for sx in (x0..x0 + bw).step_by(SUB_BLOCK) {
                    let (sw, sh) = (SUB_BLOCK.min(x0 + bw - sx), SUB_BLOCK.min(bh - sy));
                    if !band.try_uniform(sx, sy, sw, sh, &mut s, &uniform) {
                        band.per_texel(sx, sy, sw, sh, &mut s, &texel);
                    }
                }
            }
        }
    });
    cells
}

/// Side of the blocks [`fill_blocks`] splits an undecided block into.
pub(crate) const SUB_BLOCK: usize = 4;

/// A band of rows of a label map being filled.
struct Band<'a> {
    rows: &'a mut [u16],
    width: usize,
    y0: usize,
}

impl Band<'_> {
    /// Fills the `w x h` block at `(x0, dy0)` (row `dy0` of the band) if `uniform` decides it.
    fn try_uniform<S>(
        &mut self,
        x0: usize,
        dy0: usize,
        w: usize,
        h: usize,
        s: &mut S,
        uniform: &impl Fn(f64, f64, f64, &mut S) -> Option<u16>,
    ) -> bool {
        let (hx, hy) = ((w - 1) as f64 / 2.0, (h - 1) as f64 / 2.0);
        let Some(label) = uniform(x0 as f64 + hx, (self.y0 + dy0) as f64 + hy, hx.hypot(hy), s) else {
            return false;
        };
        for dy in dy0..dy0 + h {
            self.rows[dy * self.width + x0..dy * self.width + x0 + w].fill(label);
        }
        true
    }

    fn per_texel<S>(
        &mut self,
        x0: usize,
        dy0: usize,
        w: usize,
        h: usize,
        s: &mut S,
        texel: &impl Fn(usize, usize, &mut S) -> u16,
    ) {
        for dy in dy0..dy0 + h {
            for x in x0..x0 + w {
                self.rows[dy * self.width + x] = texel(x, self.y0 + dy, s);
            }
        }
    }
}

/// The nearest of `sites` (in tie order) to `p` and the squared distances to the nearest and
/// the second nearest.
pub(crate) fn two_nearest(sites: &[(u16, [f64; 2])], p: [f64; 2]) -> (u16, f64, f64) {
    let mut best = (0u16, f64::INFINITY, f64::INFINITY);
    for &(i, q) in sites {
        let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
        if d < best.1 {
            best = (i, d, best.1);
        } else if d < best.2 {
            best.2 = d;
        }
    }
    best
}

/// Point indices sorted by `(region, index)`: scanning in this order and keeping only strictly
/// smaller distances gives the documented tie-break.
pub(crate) fn tie_order(seeds: &[SeedPoint]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..seeds.len()).collect();
    order.sort_by_key(|&i| (seeds[i].region, i));
    order
}

/// Index of the seed nearest to texel `(x, y)` (exact integer distances).
fn nearest_seed(x: i64, y: i64, seeds: &[SeedPoint], order: &[usize]) -> u16 {
    let mut best = (i64::MAX, 0usize);
    for &i in order {
        let (dx, dy) = (x - i64::from(seeds[i].x), y - i64::from(seeds[i].y));
        let d = dx * dx + dy * dy;
        if d < best.0 {
            best = (d, i);
        }
    }
    best.1 as u16
}

/// Texel count and bounding box per region, over covered texels when `coverage` is given.
fn region_areas(labels: &Grid<u16>, coverage: Option<&Grid<bool>>, region_count: usize) -> Vec<RegionArea> {
    let per_row: Vec<Vec<RegionArea>> =
        (0..labels.height()).into_par_iter().map(|y| row_areas(labels, coverage, region_count, y)).collect();
    let empty = vec![RegionArea { texels: 0, bbox: None }; region_count];
    per_row.into_iter().fold(empty, |acc, row| acc.iter().zip(&row).map(|(a, b)| merge(*a, *b)).collect())
}

/// The areas of one row: per region the texel count and the first and last column.
fn row_areas(labels: &Grid<u16>, coverage: Option<&Grid<bool>>, region_count: usize, y: usize) -> Vec<RegionArea> {
    let mut count = vec![0usize; region_count];
    let mut first = vec![usize::MAX; region_count];
    let mut last = vec![0usize; region_count];
    let covered = coverage.map(|c| c.row(y));
    let mut x = 0;
    for run in labels.row(y).chunk_by(|a, b| a == b) {
        let r = usize::from(run[0]);
        let inside: Vec<usize> = match covered {
            // Without a mask the whole run counts: its ends are enough.
            None => vec![x, x + run.len() - 1],
            Some(c) => (x..x + run.len()).filter(|&t| c[t]).collect(),
        };
        if let (Some(&a), Some(&b)) = (inside.first(), inside.last()) {
            count[r] += if covered.is_none() { run.len() } else { inside.len() };
            first[r] = first[r].min(a);
            last[r] = last[r].max(b);
        }
        x += run.len();
    }
    (0..region_count)
        .map(|r| RegionArea {
            texels: count[r],
            bbox: (count[r] > 0).then(|| Rect { x: first[r], y, width: last[r] + 1 - first[r], height: 1 }),
        })
        .collect()
}

/// Two areas of the same region together.
fn merge(a: RegionArea, b: RegionArea) -> RegionArea {
    let bbox = match (a.bbox, b.bbox) {
        (Some(p), Some(q)) => Some(p.union(q)),
        (p, q) => p.or(q),
    };
    RegionArea { texels: a.texels + b.texels, bbox }
}
