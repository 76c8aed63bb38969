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

use std::ops::Range;

use glam::Vec3;
use skinkit_maps::Grid;

use crate::config::CORRECTION_STRIDE;
use crate::exemplar::{ExemplarLevel, better};
use crate::interleave::sub_pass;
use crate::metrics::{self, CopyBlocks};

/// Runs `passes` polishing passes over a level with `n x n` windows, in the interleaved
/// sub-passes of the correction passes (so the result does not depend on the thread count), in
/// the rows `active`.
/// With a copy cap, a texel may not join blocks whose sizes (at the start of the pass) add up to
/// more than `cap` texels.
pub(crate) fn polish(
    full: &ExemplarLevel,
    n: usize,
    cap: Option<usize>,
    (out, coords, active): (&mut Grid<Vec3>, &mut Grid<[u32; 2]>, &Range<usize>),
    passes: usize,
) {
    let r = (n / 2) as isize;
    let offsets: Vec<[isize; 2]> =
        (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| [dx, dy])).filter(|&o| o != [0, 0]).collect();
    for _ in 0..passes {
        let blocks = cap.map(|cap| (cap, metrics::copy_blocks(coords, full.texels().size(), full.wraps())));
        let blocks = blocks.as_ref();
        for sub in 0..CORRECTION_STRIDE * CORRECTION_STRIDE {
            sub_pass(full, out, coords, (sub, active), |x, y, read_out, read_coords, scratch| {
                choose(full, &offsets, blocks, x as isize, y as isize, read_out, read_coords, scratch)
            });
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
fn within_cap(
    full: &ExemplarLevel,
    (cap, blocks): &(usize, CopyBlocks),
    coords: &Grid<[u32; 2]>,
    x: isize,
    y: isize,
    i: usize,
) -> bool {
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

/// Per-thread buffers of a polishing pass.
#[derive(Default)]
pub(crate) struct Scratch {
    candidates: Vec<usize>,
    /// Per offset, the neighbour's source and its texel.
    sources: Vec<[u32; 2]>,
    values: Vec<Vec3>,
    predictions: Vec<Vec3>,
}

/// Reads the neighbours of `(x, y)` at `offsets` into `scratch` (direct indexing away from the
/// border, wrapped near it).
fn gather(
    offsets: &[[isize; 2]],
    x: isize,
    y: isize,
    out: &Grid<Vec3>,
    coords: &Grid<[u32; 2]>,
    scratch: &mut Scratch,
) {
    let (w, h) = (out.width() as isize, out.height() as isize);
    let r = offsets.iter().map(|o| o[0].abs().max(o[1].abs())).max().unwrap_or(0);
    scratch.sources.clear();
    scratch.values.clear();
    if x >= r && y >= r && x + r < w && y + r < h {
        let (c, o) = (coords.as_slice(), out.as_slice());
        for &[dx, dy] in offsets {
            let i = ((y + dy) * w + x + dx) as usize;
            scratch.sources.push(c[i]);
            scratch.values.push(o[i]);
        }
    } else {
        for &[dx, dy] in offsets {
            scratch.sources.push(*coords.get_wrapped(x + dx, y + dy));
            scratch.values.push(*out.get_wrapped(x + dx, y + dy));
        }
    }
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
    scratch: &mut Scratch,
) -> Option<usize> {
    let [cx, cy] = *coords.get_wrapped(x, y);
    let own = full.index_of(cx as isize, cy as isize)?;
    gather(offsets, x, y, out, coords, scratch);
    // Inside a block every window around the texel matches its source's: cost 0, nothing to gain.
    let continues = |[nx, ny]: [u32; 2], [dx, dy]: [isize; 2]| full.index_of(nx as isize - dx, ny as isize - dy);
    if scratch.sources.iter().zip(offsets).all(|(&n, &o)| continues(n, o) == Some(own)) {
        return None;
    }
    let Scratch { candidates, sources, values, predictions } = scratch;
    candidates.clear();
    candidates.push(own);
    predictions.clear();
    for (&[nx, ny], &[dx, dy]) in sources.iter().zip(offsets) {
        let (px, py) = (nx as isize - dx, ny as isize - dy);
        predictions.extend(texel_at(full, px, py));
        candidates.extend(full.index_of(px, py));
    }
    candidates.sort_unstable();
    candidates.dedup();
    if let Some(blocks) = blocks {
        candidates.retain(|&i| i == own || within_cap(full, blocks, coords, x, y, i));
    }
    // The candidate's exemplar window is the start of its full feature: the `n x n` texels in
    // row-major order, the centre (slot `offsets.len() / 2`) among them, as `offsets` are.
    let centre = offsets.len() / 2;
    debug_assert!(full.dim() >= 3 * (offsets.len() + 1));
    let cost = |i: usize| {
        let v = full.texel(i);
        let mut sum: f32 = predictions.iter().map(|p| (v - *p).length_squared()).sum();
        let window = full.feature(i);
        for (k, value) in values.iter().enumerate() {
            let slot = 3 * (k + usize::from(k >= centre));
            sum += (*value - Vec3::from_slice(&window[slot..slot + 3])).length_squared();
        }
        sum
    };
    let best = candidates.iter().map(|&i| (cost(i), i)).fold((f32::INFINITY, usize::MAX), better).1;
    (best != own).then_some(best)
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::neighbourhood::Neighbourhood;

    const N: usize = 5;

    /// A random 16x16 exemplar's candidates, and a 20x20 output of 4x4 patches copied from random
    /// places (seams between them, coherent inside).
    fn case(seed: u64) -> (ExemplarLevel, Grid<Vec3>, Grid<[u32; 2]>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let values: Vec<Vec3> = (0..256).map(|_| Vec3::new(rng.random(), rng.random(), rng.random())).collect();
        let texels = Grid::from_vec(16, 16, values).unwrap();
        let full = ExemplarLevel::new(texels, None, &Neighbourhood::full(N, 1, false), N, false);
        let starts: Vec<[u32; 2]> = (0..25).map(|_| [rng.random_range(2..10), rng.random_range(2..10)]).collect();
        let coords = Grid::from_fn(20, 20, |x, y| {
            let [sx, sy] = starts[(y / 4) * 5 + x / 4];
            [sx + (x % 4) as u32, sy + (y % 4) as u32]
        });
        let out = coords.map(|&[x, y]| *full.texels().get(x as usize, y as usize));
        (full, out, coords)
    }

    /// `sum_c |W_c - X(coords(c))|^2` over every output window (wrapped), in f64, by brute force.
    fn energy(full: &ExemplarLevel, out: &Grid<Vec3>, coords: &Grid<[u32; 2]>) -> f64 {
        let r = (N / 2) as isize;
        let (w, h) = out.size();
        let mut sum = 0.0;
        for (cy, cx) in (0..h as isize).flat_map(|y| (0..w as isize).map(move |x| (y, x))) {
            let [sx, sy] = *coords.get(cx as usize, cy as usize);
            for dy in -r..=r {
                for dx in -r..=r {
                    let e = full.texels().get((sx as isize + dx) as usize, (sy as isize + dy) as usize);
                    sum += (out.get_wrapped(cx + dx, cy + dy).as_dvec3() - e.as_dvec3()).length_squared();
                }
            }
        }
        sum
    }

    fn offsets() -> Vec<[isize; 2]> {
        let r = (N / 2) as isize;
        (-r..=r).flat_map(|dy| (-r..=r).map(move |dx| [dx, dy])).filter(|&o| o != [0, 0]).collect()
    }

    /// Each texel's choice is the candidate of least total energy, the whole map's energy
    /// recomputed for every candidate.
    #[test]
    fn a_texel_takes_the_candidate_of_least_total_energy() {
        let (full, out, coords) = case(3);
        let mut scratch = Scratch::default();
        let mut changed = 0;
        for (x, y) in (0..20).flat_map(|y| (0..20).map(move |x| (x, y))) {
            let own = full.index_of(coords.get(x, y)[0] as isize, coords.get(x, y)[1] as isize).unwrap();
            let pick = choose(&full, &offsets(), None, x as isize, y as isize, &out, &coords, &mut scratch);
            changed += usize::from(pick.is_some());
            let with = |i: usize| {
                let (mut o, mut c) = (out.clone(), coords.clone());
                *o.get_mut(x, y) = full.texel(i);
                *c.get_mut(x, y) = full.position(i);
                energy(&full, &o, &c)
            };
            let candidates = scratch.candidates.clone();
            let least = candidates.iter().map(|&i| with(i)).fold(f64::INFINITY, f64::min);
            let chosen = with(pick.unwrap_or(own));
            assert!(chosen <= least + 1e-4 * least.max(1.0), "({x}, {y}): energy {chosen} over the least {least}");
        }
        assert!(changed > 20, "only {changed} texels changed");
    }

    /// A pass lowers the energy; blocks stay within a cap; the result does not depend on threads.
    #[test]
    fn a_pass_lowers_the_energy_and_keeps_the_cap() {
        let (full, out, coords) = case(5);
        let before = energy(&full, &out, &coords);
        let run = |threads: usize, cap: Option<usize>| {
            let (mut o, mut c) = (out.clone(), coords.clone());
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| polish(&full, N, cap, (&mut o, &mut c, &(0..20)), 1));
            (o, c)
        };
        let (o, c) = run(1, None);
        let after = energy(&full, &o, &c);
        // Measured 2477 -> 2264 (-8.6 %) on this noise exemplar, whose seams cannot all be hidden.
        assert!(after < 0.95 * before, "energy {before} -> {after}");
        assert_eq!(run(2, None).1, c);
        let (o, c) = run(2, Some(24));
        let largest = metrics::copy_statistics(&c, (16, 16), false).largest_block;
        assert!(largest <= 24, "largest block {largest} over the cap 24");
        assert!(energy(&full, &o, &c) < before);
    }
}
