//! The clustered evaluation behind [`super::scatter`]: the reference's sums with each Gaussian
//! summed over sources as coarse as it allows, so the cost per receiver stops growing with the
//! light map's size (the texel-by-texel path, [`super::scatter_texels`], grows as its square).
//!
//! - **Clusters.** Covered texels are merged bottom-up in UV blocks of 2x2, 4x4, ... texels.
//!   A block is a cluster when its children are, their normals lie within [`MAX_NORMAL_SPREAD`]
//!   of the block's mean, and its extent (the radius around its area-weighted centroid) is at
//!   most [`MAX_EXTENT`] times that of its children side by side: a block straddling a UV seam,
//!   whose pieces lie far apart on the head, is not one. A cluster keeps its area, centroid,
//!   normal, area-weighted mean irradiance and the in-plane variance of its area around the
//!   centroid.
//! - **Cuts.** For each Gaussian of standard deviation `sigma` the sources are the largest
//!   clusters whose radius is at most [`RADIUS_PER_SIGMA`] `sigma`, found top-down; texels wider
//!   than that stay texels, integrated over their footprint as [`super::scatter_exact`] does.
//! - **Moments.** The reference integrates each Gaussian over each texel, its light constant on
//!   the texel. Over a cluster with centroid `c`, area `A`, in-plane variance `m` per axis (the
//!   texels' own boxes included) and light `E_j` on texel `j`, the Taylor series of the Gaussian
//!   about `c` gives `sum_j E_j w_j = A Ebar G_{v+m}(d) + G(d) (D . d) / v + ...`, `d` the
//!   receiver's offset from `c` and `D = sum_j A_j E_j (c_j - c)` the light's lean within the
//!   cluster: the mean light with the Gaussian widened by the cluster's own variance, plus a
//!   dipole. A cluster no wider than half a sigma leaves terms of order `(m / v)^2`.
//! - **Sums.** Per Gaussian, sources in tiers of doubling reach (the Gaussian's skip radius plus
//!   the source's own size), each tier sorted by cells of its reach; each receiver cell gathers
//!   the sources within reach of its box once, in (tier, cell, index) order, eight at a time into
//!   independent f32 lanes. Receivers are summed in f64 in a fixed order: the same bits whatever
//!   the thread count. The tree holds about 200 bytes a texel (1.1 GB at 2048 texels).
//!
//! Measured against the texel path: see "Speed" in the parent module's docs.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::fast::{self, exp_neg};
use super::{ReferenceBake, support_mm};
use crate::skin::profile::{Profile, WEIGHTS};

/// A cluster serves a Gaussian when its radius is at most this many of its standard deviations.
pub(crate) const RADIUS_PER_SIGMA: f64 = 0.5;

/// A source is left out where its Gaussian is below `exp(-SKIP_EXPONENT)` (6e-6) of its peak:
/// the light lost is far below the clusters' own error (the texel path keeps `exp(-20)`).
const SKIP_EXPONENT: f64 = 12.0;

/// A block is a cluster only when every child's normal is within this cosine of the mean normal.
pub(crate) const MAX_NORMAL_SPREAD: f32 = 0.9;

/// A block is a cluster only when its radius is at most this many times twice its widest
/// child's (children side by side: at most 1; a block whose children lie apart, across a UV
/// seam, more).
pub(crate) const MAX_EXTENT: f64 = 1.25;

/// Grid cells per reach: smaller cells gather fewer far sources but share each list less.
const CELLS_PER_REACH: f64 = 2.0;

/// Receivers are grouped in cells at least this wide (mm), so the narrow Gaussians' short
/// reach does not leave one receiver per gathered list.
const MIN_RECEIVER_CELL_MM: f64 = 1.0;

/// One node of the cluster tree: a covered texel (level 0) or a merged block.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Block coordinates at this node's level.
    block: [u32; 2],
    centroid: DVec3,
    /// Area-weighted sum of the children's normals (not normalised).
    normal_sum: DVec3,
    area: f64,
    /// Area-weighted mean irradiance.
    irradiance: [f64; 3],
    /// Per channel, `sum of area * irradiance * (texel - centroid)` over the node's texels: how
    /// the light leans within it (mm^3 times irradiance).
    dipole: [DVec3; 3],
    /// In-plane variance of the area about the centroid, per axis (mm^2).
    variance: f64,
    /// Largest distance from the centroid to any point of the node (mm).
    radius: f64,
    coherent: bool,
    /// Indices of the children (up to a 2x2 block) in the next finer level; at level 0,
    /// `children[0]` is the texel's index.
    children: [u32; 4],
    count: u32,
}

/// The cluster tree, finest level first.
struct Tree {
    levels: Vec<Vec<Node>>,
}

impl Tree {
    fn new(bake: &ReferenceBake) -> Self {
        let mut levels = vec![leaves(bake)];
        while levels.last().is_some_and(|l| l.len() > 1) {
            let next = merge(levels.last().expect("non-empty"));
            levels.push(next);
        }
        Self { levels }
    }

    /// The sources serving a Gaussian of standard deviation `sigma`: top-down, the coarsest
    /// coherent nodes with a radius of at most `RADIUS_PER_SIGMA sigma`.
    fn cut(&self, sigma: f64) -> Vec<(usize, u32)> {
        let limit = RADIUS_PER_SIGMA * sigma;
        let mut out = Vec::new();
        let Some(top) = self.levels.len().checked_sub(1) else { return out };
        let mut stack: Vec<(usize, u32)> = (0..self.levels[top].len() as u32).rev().map(|i| (top, i)).collect();
        while let Some((level, i)) = stack.pop() {
            let node = &self.levels[level][i as usize];
            if level == 0 || (node.coherent && node.radius <= limit) {
                out.push((level, i));
            } else {
                stack.extend(node.children[..node.count as usize].iter().rev().map(|&c| (level - 1, c)));
            }
        }
        out
    }
}

/// Level 0: one node per covered texel with a finite position and a footprint, in index order.
fn leaves(bake: &ReferenceBake) -> Vec<Node> {
    let size = bake.size;
    (0..bake.covered.len())
        .filter(|&i| bake.covered[i] && bake.position_mm[i].is_finite() && bake.area_mm2[i] > 0.0)
        .map(|i| {
            let f = bake.footprint[i];
            let (a, b) = (f.u_mm as f64, f.v_mm as f64);
            Node {
                block: [i as u32 % size, i as u32 / size],
                centroid: bake.position_mm[i].as_dvec3(),
                normal_sum: bake.normal[i].as_dvec3() * bake.area_mm2[i] as f64,
                area: bake.area_mm2[i] as f64,
                irradiance: bake.irradiance[i].map(f64::from),
                dipole: [DVec3::ZERO; 3],
                variance: (a * a + b * b) / 24.0,
                radius: 0.5 * a.hypot(b),
                coherent: true,
                children: [i as u32, 0, 0, 0],
                count: 0,
            }
        })
        .collect()
}

/// The next coarser level: `finer`'s nodes grouped by their 2x2 parent block, in row-major
/// block order.
fn merge(finer: &[Node]) -> Vec<Node> {
    let mut groups: BTreeMap<[u32; 2], Vec<u32>> = BTreeMap::new();
    for (i, node) in finer.iter().enumerate() {
        groups.entry([node.block[1] >> 1, node.block[0] >> 1]).or_default().push(i as u32);
    }
    groups.into_iter().map(|(key, children)| parent([key[1], key[0]], &children, finer)).collect()
}

/// One parent node over `children` (indices into `finer`).
fn parent(block: [u32; 2], children: &[u32], finer: &[Node]) -> Node {
    let nodes: Vec<&Node> = children.iter().map(|&c| &finer[c as usize]).collect();
    let area: f64 = nodes.iter().map(|n| n.area).sum();
    let centroid = nodes.iter().map(|n| n.centroid * n.area).sum::<DVec3>() / area;
    let normal_sum: DVec3 = nodes.iter().map(|n| n.normal_sum).sum();
    let irradiance = std::array::from_fn(|c| nodes.iter().map(|n| n.irradiance[c] * n.area).sum::<f64>() / area);
    let dipole = std::array::from_fn(|c| {
        nodes.iter().map(|n| n.dipole[c] + (n.centroid - centroid) * (n.area * n.irradiance[c])).sum::<DVec3>()
    });
    let variance =
        nodes.iter().map(|n| n.area * (0.5 * (n.centroid - centroid).length_squared() + n.variance)).sum::<f64>()
            / area;
    let radius = nodes.iter().map(|n| (n.centroid - centroid).length() + n.radius).fold(0.0, f64::max);
    let mean = normal_sum.normalize_or_zero();
    let coherent = nodes.iter().all(|n| n.coherent)
        && nodes.iter().all(|n| n.normal_sum.normalize_or_zero().dot(mean) >= MAX_NORMAL_SPREAD as f64)
        && radius <= MAX_EXTENT * 2.0 * nodes.iter().map(|n| n.radius).fold(0.0, f64::max)
        && centroid.is_finite();
    Node {
        block,
        centroid,
        normal_sum,
        area,
        irradiance,
        dipole,
        variance,
        radius,
        coherent,
        children: std::array::from_fn(|k| children.get(k).copied().unwrap_or(0)),
        count: children.len() as u32,
    }
}

/// Lanes of the inner loop's independent sums (two SSE or one AVX vector once vectorised).
const LANES: usize = 8;

/// [`LANES`] point sources side by side, so the inner loop runs over fixed-size arrays.
#[derive(Clone, Copy, Default)]
struct Block {
    p: [[f32; LANES]; 3],
    n: [[f32; LANES]; 3],
    e: [[f32; LANES]; 3],
    /// Per channel and axis: the dipole over the area and the Gaussian's variance.
    lean: [[[f32; LANES]; 3]; 3],
    /// `scale * area / (2 pi v')`: the sample's weight at distance 0 (0 for padding).
    peak: [f32; LANES],
    /// `-1 / (2 v')`.
    exponent: [f32; LANES],
}

/// A point source: a cluster, or a texel narrow enough for the Gaussian.
#[derive(Clone, Copy, Default)]
struct Point {
    p: Vec3,
    n: Vec3,
    e: [f32; 3],
    lean: [Vec3; 3],
    peak: f32,
    exponent: f32,
}

/// The point sources of one Gaussian near one receiver cell, in blocks of [`LANES`].
#[derive(Default)]
struct Points {
    blocks: Vec<Block>,
    len: usize,
}

impl Points {
    fn push(&mut self, s: &Point) {
        let l = self.len % LANES;
        if l == 0 {
            self.blocks.push(Block::default());
        }
        let b = self.blocks.last_mut().expect("pushed above");
        for a in 0..3 {
            b.p[a][l] = s.p[a];
            b.n[a][l] = s.n[a];
            b.e[a][l] = s.e[a];
            for c in 0..3 {
                b.lean[c][a][l] = s.lean[c][a];
            }
        }
        b.peak[l] = s.peak;
        b.exponent[l] = s.exponent;
        self.len += 1;
    }

    /// `(sum of w E, sum of w)` for a receiver at `p` with normal `n`, sources beyond
    /// `support2` or across opposed normals left out.
    fn sums(&self, p: Vec3, n: Vec3, support2: f32) -> ([f64; 3], f64) {
        let mut acc = [[0.0f32; LANES]; 4];
        for b in &self.blocks {
            for l in 0..LANES {
                let d = [p.x - b.p[0][l], p.y - b.p[1][l], p.z - b.p[2][l]];
                let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                let facing = n.x * b.n[0][l] + n.y * b.n[1][l] + n.z * b.n[2][l];
                let w = b.peak[l] * exp_neg(d2 * b.exponent[l]);
                let w = if d2 <= support2 && facing >= 0.0 { w } else { 0.0 };
                for c in 0..3 {
                    let lean = d[0] * b.lean[c][0][l] + d[1] * b.lean[c][1][l] + d[2] * b.lean[c][2][l];
                    acc[c][l] += w * (b.e[c][l] + lean);
                }
                acc[3][l] += w;
            }
        }
        let sum = |x: &[f32; LANES]| x.iter().map(|&v| v as f64).sum::<f64>();
        ([sum(&acc[0]), sum(&acc[1]), sum(&acc[2])], sum(&acc[3]))
    }
}

/// Sources whose reach is at most `reach`, sorted by cells of `reach / CELLS_PER_REACH`.
struct Tier {
    cell: f64,
    reach: f64,
    /// Sorted `(cell, (own reach, point))` and `(cell, (own reach, texel))` entries.
    points: Vec<([i32; 3], (f32, Point))>,
    boxes: Vec<([i32; 3], (f32, fast::Source))>,
}

impl Tier {
    fn new(reach: f64) -> Self {
        Self { cell: reach / CELLS_PER_REACH, reach, points: Vec::new(), boxes: Vec::new() }
    }

    /// The entries of `sorted` in the cells that can hold a source within this tier's reach of
    /// the box `lo..hi`, in (cell, index) order.
    fn near<'a, T>(&self, sorted: &'a [([i32; 3], T)], lo: DVec3, hi: DVec3) -> impl Iterator<Item = &'a T> + 'a {
        let from = key(lo - DVec3::splat(self.reach), self.cell);
        let to = key(hi + DVec3::splat(self.reach), self.cell);
        let rows: Vec<(usize, usize)> = (from[0]..=to[0])
            .flat_map(|z| (from[1]..=to[1]).map(move |y| (z, y)))
            .map(|(z, y)| {
                let (first, last) = ([z, y, from[2]], [z, y, to[2]]);
                (sorted.partition_point(|e| e.0 < first), sorted.partition_point(|e| e.0 <= last))
            })
            .filter(|(s, e)| s < e)
            .collect();
        rows.into_iter().flat_map(move |(s, e)| sorted[s..e].iter().map(|x| &x.1))
    }
}

/// The sources of one Gaussian in tiers of doubling reach: a stretched texel or a wide cluster
/// is found through coarser cells without widening every receiver's search.
struct Sources {
    k: usize,
    support: f64,
    /// Receivers are grouped in cells of the first tier's size.
    cell: f64,
    tiers: Vec<Tier>,
}

impl Sources {
    fn new(bake: &ReferenceBake, tree: &Tree, kernel: &fast::Kernel, profile: &Profile, k: usize) -> Self {
        let v = profile.variance(k);
        let sigma = v.sqrt();
        let scale = profile.gaussian(k, 0.0) * 2.0 * std::f64::consts::PI * v;
        let support = support_mm(profile);
        let skip_radius = |spread: f64| (2.0 * spread * SKIP_EXPONENT).sqrt();
        let mut entries: Vec<(f64, DVec3, Result<Point, fast::Source>)> = Vec::new();
        for (level, i) in tree.cut(sigma) {
            let node = &tree.levels[level][i as usize];
            if level == 0 && node.radius > RADIUS_PER_SIGMA * sigma {
                let reach = skip_radius(v) + node.radius;
                entries.push((reach, node.centroid, Err(fast::source(bake, kernel, node.children[0] as usize))));
                continue;
            }
            let spread = v + node.variance;
            let point = Point {
                p: node.centroid.as_vec3(),
                n: node.normal_sum.normalize_or_zero().as_vec3(),
                e: node.irradiance.map(|e| e as f32),
                lean: node.dipole.map(|d| (d / (node.area * v)).as_vec3()),
                peak: (scale * node.area / (2.0 * std::f64::consts::PI * spread)) as f32,
                exponent: (-0.5 / spread) as f32,
            };
            entries.push((skip_radius(spread), node.centroid, Ok(point)));
        }
        // The first tier holds the typical source (the median reach).
        let mut reaches: Vec<f64> = entries.iter().map(|e| e.0.min(support)).collect();
        let base = if reaches.is_empty() {
            support
        } else {
            let middle = reaches.len() / 2;
            *reaches.select_nth_unstable_by(middle, f64::total_cmp).1
        };
        let base = base.max(1e-3 * support);
        let mut tiers: Vec<Tier> = Vec::new();
        for (reach, at, source) in entries {
            let reach = reach.min(support);
            let t = (reach / base).log2().ceil().max(0.0) as usize;
            while tiers.len() <= t {
                tiers.push(Tier::new((base * 2f64.powi(tiers.len() as i32)).min(support)));
            }
            let tier = &mut tiers[t];
            let key = key(at, tier.cell);
            match source {
                Ok(point) => tier.points.push((key, (reach as f32, point))),
                Err(texel) => tier.boxes.push((key, (reach as f32, texel))),
            }
        }
        for tier in &mut tiers {
            // Stable: within a cell, the cut's order.
            tier.points.sort_by_key(|e| e.0);
            tier.boxes.sort_by_key(|e| e.0);
        }
        Self { k, support, cell: (base / CELLS_PER_REACH).max(MIN_RECEIVER_CELL_MM), tiers }
    }

    /// `(receiver index, (sum of g E, sum of g))` for the receivers of one cell.
    fn receive(
        &self,
        kernel: &fast::Kernel,
        bake: &ReferenceBake,
        c: [i32; 3],
        receivers: &[u32],
    ) -> Vec<(u32, [f64; 4])> {
        let lo = DVec3::new(c[2] as f64, c[1] as f64, c[0] as f64) * self.cell;
        let hi = lo + DVec3::splat(self.cell);
        let inside = |p: Vec3, reach: f32| {
            let p = p.as_dvec3();
            let reach = reach as f64 * (1.0 + 1e-4) + 1e-4;
            (lo - p).max(p - hi).max(DVec3::ZERO).length_squared() <= reach * reach
        };
        let mut points = Points::default();
        let mut boxes: Vec<&fast::Source> = Vec::new();
        for tier in &self.tiers {
            for (_, s) in tier.near(&tier.points, lo, hi).filter(|(reach, s)| inside(s.p, *reach)) {
                points.push(s);
            }
            boxes.extend(tier.near(&tier.boxes, lo, hi).filter(|(reach, s)| inside(s.position, *reach)).map(|e| &e.1));
        }
        let support2 = (self.support * self.support) as f32;
        receivers
            .iter()
            .map(|&r| {
                let (p, n) = (bake.position_mm[r as usize], bake.normal[r as usize]);
                let (mut light, mut total) = points.sums(p, n, support2);
                for s in &boxes {
                    let offset = p - s.position;
                    if offset.length_squared() > support2 || n.dot(s.normal) < 0.0 {
                        continue;
                    }
                    let g = fast::texel_gaussian(kernel, self.k, s, offset) as f64;
                    for ch in 0..3 {
                        light[ch] += g * s.irradiance[ch] as f64;
                    }
                    total += g;
                }
                (r, [light[0], light[1], light[2], total])
            })
            .collect()
    }
}

/// Grid key `[z, y, x]` of a position.
fn key(p: DVec3, cell: f64) -> [i32; 3] {
    let f = |x: f64| (x / cell).floor() as i32;
    [f(p.z), f(p.y), f(p.x)]
}

/// [`super::scatter`]: scattered irradiance per texel.
pub(super) fn scatter(bake: &ReferenceBake, profile: &Profile) -> Vec<[f32; 3]> {
    let tree = Tree::new(bake);
    let kernel = fast::Kernel::new(profile);
    let receivers: Vec<u32> = (0..bake.covered.len() as u32)
        .filter(|&i| bake.covered[i as usize] && bake.position_mm[i as usize].is_finite())
        .collect();
    let (mut light, mut total) = (vec![[0.0f64; 3]; bake.covered.len()], vec![[0.0f64; 3]; bake.covered.len()]);
    for (k, weights) in WEIGHTS.iter().enumerate() {
        let sources = Sources::new(bake, &tree, &kernel, profile, k);
        let mut cells: Vec<([i32; 3], u32)> =
            receivers.iter().map(|&r| (key(bake.position_mm[r as usize].as_dvec3(), sources.cell), r)).collect();
        cells.sort_unstable();
        let runs: Vec<&[([i32; 3], u32)]> = cells.chunk_by(|a, b| a.0 == b.0).collect();
        let sums: Vec<Vec<(u32, [f64; 4])>> = runs
            .into_par_iter()
            .map(|run| {
                let members: Vec<u32> = run.iter().map(|e| e.1).collect();
                sources.receive(&kernel, bake, run[0].0, &members)
            })
            .collect();
        for (r, s) in sums.into_iter().flatten() {
            for c in 0..3 {
                light[r as usize][c] += weights[c] * s[c];
                total[r as usize][c] += weights[c] * s[3];
            }
        }
    }
    (0..bake.covered.len())
        .map(|i| {
            if !bake.covered[i] {
                return [0.0; 3];
            }
            let e = bake.irradiance[i];
            std::array::from_fn(|c| {
                let m = if total[i][c] > 0.0 { (light[i][c] / total[i][c]) as f32 } else { e[c] };
                if m.is_finite() { m } else { 0.0 }
            })
        })
        .collect()
}
