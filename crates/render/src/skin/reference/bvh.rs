//! The bounding-volume hierarchy of the reference's exact shadow rays (median splits, any-hit
//! queries).

use glam::Vec3;

/// A bounding-volume hierarchy over triangles for shadow rays (any-hit queries).
pub struct Bvh {
    triangles: Vec<[Vec3; 3]>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
    nodes: Vec<Node>,
}

#[derive(Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Leaf: first entry in `order`; inner: index of the left child (the right one follows its
    /// subtree, stored in `right`).
    start: u32,
    count: u32,
    right: u32,
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// A hierarchy over `triangles` (non-finite triangles are left out).
    pub fn new(triangles: Vec<[Vec3; 3]>) -> Self {
        let mut order: Vec<u32> =
            (0..triangles.len() as u32).filter(|&t| triangles[t as usize].iter().all(|p| p.is_finite())).collect();
        let mut bvh = Self { triangles, order: Vec::new(), nodes: Vec::new() };
        let len = order.len();
        if len > 0 {
            bvh.build(&mut order, 0, len);
        }
        bvh.order = order;
        bvh
    }

    /// The diagonal of the bounding box (0 when empty).
    pub fn diagonal(&self) -> f32 {
        self.nodes.first().map_or(0.0, |n| (n.max - n.min).length())
    }

    fn bounds(&self, order: &[u32]) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for &t in order {
            for p in self.triangles[t as usize] {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    }

    fn centroid(&self, t: u32) -> Vec3 {
        let [a, b, c] = self.triangles[t as usize];
        (a + b + c) / 3.0
    }

    /// Builds the node for `order[start..end]` and returns its index.
    fn build(&mut self, order: &mut [u32], start: usize, end: usize) -> u32 {
        let (min, max) = self.bounds(&order[start..end]);
        let index = self.nodes.len() as u32;
        self.nodes.push(Node { min, max, start: start as u32, count: (end - start) as u32, right: 0 });
        if end - start <= LEAF_SIZE {
            return index;
        }
        let axis = (max - min).max_position();
        let mid = (start + end) / 2;
        order[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
            self.centroid(a)[axis].total_cmp(&self.centroid(b)[axis]).then(a.cmp(&b))
        });
        self.build(order, start, mid);
        let right = self.build(order, mid, end);
        let node = &mut self.nodes[index as usize];
        node.count = 0;
        node.right = right;
        index
    }

    /// Whether any triangle other than `skip` crosses the ray `origin + t direction`,
    /// `0 < t < t_max`.
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_max: f32, skip: u32) -> bool {
        if self.nodes.is_empty() {
            return false;
        }
        let inv = direction.recip();
        let mut stack = vec![0u32];
        while let Some(n) = stack.pop() {
            let node = self.nodes[n as usize];
            if !slab_hit(node.min, node.max, origin, inv, t_max) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.right);
                stack.push(n + 1);
                continue;
            }
            let leaf = &self.order[node.start as usize..(node.start + node.count) as usize];
            if leaf.iter().any(|&t| t != skip && ray_triangle(origin, direction, self.triangles[t as usize], t_max)) {
                return true;
            }
        }
        false
    }
}

/// Ray-box test (slabs); `inv` is the componentwise reciprocal of the direction.
fn slab_hit(min: Vec3, max: Vec3, origin: Vec3, inv: Vec3, t_max: f32) -> bool {
    let t0 = (min - origin) * inv;
    let t1 = (max - origin) * inv;
    // NaN (0 * inf on a slab plane) is ignored by min/max, which keeps the test conservative.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max);
    near <= far
}

/// Möller-Trumbore: whether the ray hits the triangle at `0 < t < t_max` (both sides).
fn ray_triangle(origin: Vec3, direction: Vec3, [a, b, c]: [Vec3; 3], t_max: f32) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return false;
    }
    let inv = 1.0 / det;
    let s = origin - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = e2.dot(q) * inv;
    t > 0.0 && t < t_max
}
