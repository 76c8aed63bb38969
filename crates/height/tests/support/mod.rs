//! Shared helpers of the height tests: test fields, the error measure and a brute-force solve.

use skinkit_heightfield::{HeightSample, Heightfield};
use skinkit_maps::NormalMap;

/// A field of whole sine waves across a `w x h` map at `mm` per texel (wrapping when `periodic`,
/// else a third of a wave more), 0.02 mm deep.
pub fn wave_field(w: usize, h: usize, mm: f64, periodic: bool) -> Heightfield {
    let extra = if periodic { 0.0 } else { 0.33 };
    let (lx, ly) = (w as f64 * mm, h as f64 * mm);
    let waves = [(3.0 + extra, 1.0, 0.01, 0.3), (5.0, 4.0 + extra, 0.006, 1.1), (11.0, 7.0, 0.004, 2.0)];
    Heightfield::from_fn(w, h, mm, move |x, y| {
        let mut s = HeightSample::default();
        for (kx, ky, a, phase) in waves {
            let (fx, fy) = (2.0 * std::f64::consts::PI * kx / lx, 2.0 * std::f64::consts::PI * ky / ly);
            let arg = fx * x + fy * y + phase;
            s.height += a * arg.sin();
            s.gradient.x += a * fx * arg.cos();
            s.gradient.y += a * fy * arg.cos();
        }
        s
    })
    .unwrap()
}

/// The least-squares heights of the edge equations, by Gauss-Seidel on the normal equations in
/// f64 (written out from the problem's definition, independent of the crate's code): each edge
/// between texels `a` and `b` asks `h_b - h_a = (s_a + s_b) / 2`; with `masked`, an edge with an
/// invalid end asks for the valid texels' mean slope at `hole_weight`, otherwise invalid texels'
/// slopes count as 0.
pub fn brute_force(normals: &NormalMap, wraps: bool, masked: bool, hole_weight: f64) -> Vec<f64> {
    let (w, h) = normals.size();
    let ok = |i: usize| {
        let n = normals.as_slice()[i];
        n.is_finite() && n.z > 0.0
    };
    let slope = |i: usize| {
        let n = normals.as_slice()[i];
        if ok(i) { (-(n.x / n.z) as f64, (n.y / n.z) as f64) } else { (0.0, 0.0) }
    };
    let valid: Vec<usize> = (0..w * h).filter(|&i| ok(i)).collect();
    let mean = |axis: usize| valid.iter().map(|&i| [slope(i).0, slope(i).1][axis]).sum::<f64>() / valid.len() as f64;
    let (mean_x, mean_y) = (mean(0), mean(1));
    let mut edges = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let a = y * w + x;
            let right = (x + 1 < w).then(|| a + 1).or((wraps && w > 1).then(|| y * w));
            let down = (y + 1 < h).then(|| a + w).or((wraps && h > 1).then_some(x));
            for (b, horizontal) in [(right, true), (down, false)] {
                let Some(b) = b else { continue };
                let (sa, sb) = (slope(a), slope(b));
                let step = if horizontal { (sa.0 + sb.0) / 2.0 } else { (sa.1 + sb.1) / 2.0 };
                let both = ok(a) && ok(b);
                let fill = if horizontal { mean_x } else { mean_y };
                let (weight, target) = if masked && !both { (hole_weight, fill) } else { (1.0, step) };
                edges.push((a, b, weight, target));
            }
        }
    }
    let mut hv = vec![0f64; w * h];
    let mut incident: Vec<Vec<(usize, f64, f64)>> = vec![Vec::new(); w * h];
    for &(a, b, weight, target) in &edges {
        incident[a].push((b, weight, -target));
        incident[b].push((a, weight, target));
    }
    for _ in 0..200_000 {
        let mut change = 0f64;
        for i in 0..w * h {
            let (num, den) = incident[i].iter().fold((0.0, 0.0), |(n, d), &(j, wt, t)| (n + wt * (hv[j] + t), d + wt));
            let next = num / den;
            change = change.max((next - hv[i]).abs());
            hv[i] = next;
        }
        if change < 1e-12 {
            break;
        }
    }
    hv
}
