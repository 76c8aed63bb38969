//! Seam polishing: the finest level's texels chosen again, each among the sources its neighbours'
//! blocks continue, by the sum of the window distances it takes part in.
//!
//! A correction pass picks a texel's source by the one window centred on it. The suite's energy
//! counts every window: a texel sits in `N^2` of them, and each window's nearest exemplar window
//! is, inside a block, the one its centre's source names. Polishing minimises
//! `E = sum_c |W_c - X(coords(c))|^2` (the output window at `c` against the exemplar window at
//! `c`'s source) one texel at a time. Choosing source `s` for texel `t` changes two kinds of terms:
//! the windows around `t`'s neighbours `t + o`, whose source predicts `X(coords(t + o) - o)` at
//! `t`, and `t`'s own window against `X(s)`. Its cost is
//! `sum_{o != 0} |X(s) - X(coords(t + o) - o)|^2 + |out(t + o) - X(s + o)|^2`.

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::config::CORRECTION_STRIDE;
use crate::exemplar::{ExemplarLevel, better};
use crate::metrics::{self, CopyBlocks};

/// Runs `passes` polishing passes over a level with `n x n` windows, in the interleaved
/// sub-passes of the correction passes (so the result does not depend on the thread count).
/// With a copy cap, a texel may not join blocks whose sizes (at the start of the pass) add up to
/// more than `cap` texels.
pub(crate) fn polish(
    full: &ExemplarLevel,
    n: usize,
    cap: Option<usize>,
    out: &mut Grid<Vec3>,
    coords: &mut Grid<[u32; 2]>,
    passes: usize,
) {
    let (w, h) = out.size();
    let s = CORRECTION_STRIDE;
    let r = (n / 2) as isize;
    let offsets: Vec<[isize; 2]> =
        (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| [dx, dy])).filter(|&o| o != [0, 0]).collect();
    for _ in 0..passes {
        let blocks = cap.map(|cap| (cap, metrics::copy_blocks(coords, full.texels().size(), full.wraps())));
        let blocks = blocks.as_ref();
        for sub in 0..s * s {
            let (ox, oy) = (sub % s, sub / s);
            let rows: Vec<usize> = (oy..h).step_by(s).collect();
            let (read_out, read_coords) = (&*out, &*coords);
            let chosen: Vec<Vec<Option<usize>>> = rows
                .par_iter()
                .map_init(Vec::new, |scratch, &y| {
                    (ox..w)
                        .step_by(s)
                        .map(|x| choose(full, &offsets, blocks, x as isize, y as isize, read_out, read_coords, scratch))
                        .collect()
                })
                .collect();
            for (&y, row) in rows.iter().zip(&chosen) {
                for (x, best) in (ox..w).step_by(s).zip(row) {
                    if let Some(best) = *best {
                        *out.get_mut(x, y) = full.texel(best);
                        *coords.get_mut(x, y) = full.position(best);
                    }
                }
            }
        }
    }
}

/// The exemplar texel at `(x, y)`, wrapped when the exemplar wraps; `None` outside it otherwise.
fn texel_at(full: &ExemplarLevel, x: isize, y: isize) -> Option<Vec3> {
    let texels = full.texels();
    let (ew, eh) = texels.size();
    if full.wraps() {
        return Some(*texels.get_wrapped(x, y));
    }
    ((0..ew as isize).contains(&x) && (0..eh as isize).contains(&y)).then(|| *texels.get(x as usize, y as usize))
}

/// Whether texel `(x, y)` taking candidate `i` stays within the cap: itself and the blocks of the
/// 4-neighbours whose source it would continue.
fn within_cap(full: &ExemplarLevel, (cap, blocks): &(usize, CopyBlocks), coords: &Grid<[u32; 2]>, x: isize, y: isize, i: usize) -> bool {
    let w = coords.width() as isize;
    let mut labels = [u32::MAX; 4];
    let mut joined = 1;
    for (k, (dx, dy)) in [(1, 0), (-1, 0), (0, 1), (0, -1)].into_iter().enumerate() {
        let [nx, ny] = *coords.get_wrapped(x + dx, y + dy);
        if full.index_of(nx as isize - dx, ny as isize - dy) == Some(i) {
            let (px, py) = ((x + dx).rem_euclid(w), (y + dy).rem_euclid(coords.height() as isize));
            let label = blocks.labels[(py * w + px) as usize];
            if !labels.contains(&label) {
                labels[k] = label;
                joined += blocks.sizes[label as usize] as usize;
            }
        }
    }
    joined <= *cap
}

/// The source texel `(x, y)` takes, if it changes.
#[allow(clippy::too_many_arguments)]
fn choose(
    full: &ExemplarLevel,
    offsets: &[[isize; 2]],
    blocks: Option<&(usize, CopyBlocks)>,
    x: isize,
    y: isize,
    out: &Grid<Vec3>,
    coords: &Grid<[u32; 2]>,
    candidates: &mut Vec<usize>,
) -> Option<usize> {
    let [cx, cy] = *coords.get_wrapped(x, y);
    let own = full.index_of(cx as isize, cy as isize)?;
    candidates.clear();
    candidates.push(own);
    let mut predictions = [Vec3::ZERO; 48];
    let mut count = 0;
    for &[dx, dy] in offsets {
        let [nx, ny] = *coords.get_wrapped(x + dx, y + dy);
        let (px, py) = (nx as isize - dx, ny as isize - dy);
        if let Some(v) = texel_at(full, px, py).filter(|_| count < predictions.len()) {
            predictions[count] = v;
            count += 1;
        }
        candidates.extend(full.index_of(px, py));
    }
    candidates.sort_unstable();
    candidates.dedup();
    if let Some(blocks) = blocks {
        candidates.retain(|&i| i == own || within_cap(full, blocks, coords, x, y, i));
    }
    let predictions = &predictions[..count];
    let cost = |i: usize| {
        let [sx, sy] = full.position(i);
        let (sx, sy) = (sx as isize, sy as isize);
        let v = full.texel(i);
        let mut sum: f32 = predictions.iter().map(|p| (v - *p).length_squared()).sum();
        for &[dx, dy] in offsets {
            let e = texel_at(full, sx + dx, sy + dy).unwrap_or_else(|| *full.texels().get_clamped(sx + dx, sy + dy));
            sum += (*out.get_wrapped(x + dx, y + dy) - e).length_squared();
        }
        sum
    };
    let best = candidates.iter().map(|&i| (cost(i), i)).fold((f32::INFINITY, usize::MAX), better).1;
    (best != own).then_some(best)
}
