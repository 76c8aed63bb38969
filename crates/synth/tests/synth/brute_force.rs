//! Exact search against independent references: a plain single-level Wei-Levoy loop and plain
//! correction passes over every exemplar texel, written here from the paper's description, must
//! choose the same texels as the library's exact search (tiny exemplars: both are
//! O(output x exemplar)).

use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_synth::config::{CORRECTION_STRIDE, SCANLINE_OCCURRENCE_PENALTY};
use skinkit_synth::neighbourhood::Neighbourhood;
use skinkit_synth::synthesis::random_copies;
use skinkit_synth::{Search, SynthConfig, synthesize};

use crate::support::pattern;

/// The occurrence factor of `SynthConfig::occurrence_penalty` (Kopf et al. 2007): candidates
/// copied more often than `expected` have their squared distance scaled up.
fn occurrence_factor(lambda: f32, count: u32, expected: f32) -> f32 {
    1.0 + lambda * (count as f32 - expected).max(0.0)
}

/// Independent single-level Wei-Levoy: a plain loop over every interior exemplar texel. The
/// output starts as `random_copies` of interior texels; texels are chosen in scanline order by the
/// squared distance over the 5x5 window around them (centre excluded, toroidal) restricted to the
/// texels synthesised already (earlier in scanline order) and, this being the coarsest level, to
/// the rows above the first (which read the initial copies), times the occurrence factor of the
/// candidate's count so far (first strict minimum in scanline order). Returns the output and its
/// coordinates.
fn brute_force_single_level(
    ex: &Grid<Vec3>,
    w: usize,
    h: usize,
    seed: u64,
    lambda: f32,
) -> (Grid<Vec3>, Grid<[u32; 2]>) {
    let (mut out, mut coords) = random_copies(ex, 2, w, h, seed, 0);
    let (cols, rows) = (ex.width() - 4, ex.height() - 4);
    let expected = (w * h) as f32 / (cols * rows) as f32;
    let mut counts = vec![0u32; cols * rows];
    let synthesised = |x: isize, y: isize, px: isize, py: isize| {
        let (wx, wy) = (x.rem_euclid(w as isize), y.rem_euclid(h as isize));
        wy < py || (wy == py && wx < px)
    };
    for y in 0..h as isize {
        for x in 0..w as isize {
            let mut best = (f32::INFINITY, [0u32; 2], 0);
            for ey in 2..ex.height() as isize - 2 {
                for ex_x in 2..ex.width() as isize - 2 {
                    let mut d = 0.0f32;
                    for dy in -2..=2isize {
                        for dx in -2..=2isize {
                            let active = synthesised(x + dx, y + dy, x, y) || (dy < 0 && y + dy < 0);
                            if (dx, dy) == (0, 0) || !active {
                                continue;
                            }
                            let a = *out.get_wrapped(x + dx, y + dy);
                            let b = *ex.get((ex_x + dx) as usize, (ey + dy) as usize);
                            for c in 0..3 {
                                d += (a[c] - b[c]) * (a[c] - b[c]);
                            }
                        }
                    }
                    let i = (ey - 2) as usize * cols + (ex_x - 2) as usize;
                    let d = d * occurrence_factor(lambda, counts[i], expected);
                    if d < best.0 {
                        best = (d, [ex_x as u32, ey as u32], i);
                    }
                }
            }
            let [bx, by] = best.1;
            *out.get_mut(x as usize, y as usize) = *ex.get(bx as usize, by as usize);
            *coords.get_mut(x as usize, y as usize) = best.1;
            counts[best.2] += 1;
        }
    }
    (out, coords)
}

/// Independent correction passes of a single level (no coarser level, no exemplar wrap): in each
/// pass, for every residue `(ox, oy)` of `(x, y)` modulo `stride` in row-major order, the texels
/// with that residue are chosen from a snapshot of the output by their full 5x5 window (centre
/// included) over every interior exemplar texel (first strict minimum in scanline order), the
/// squared distance times the occurrence factor of the candidate's count in the snapshot (not
/// counting the texel itself), then written.
fn brute_force_corrections(
    ex: &Grid<Vec3>,
    out: &mut Grid<Vec3>,
    coords: &mut Grid<[u32; 2]>,
    passes: usize,
    stride: usize,
    lambda: f32,
) {
    let (w, h) = out.size();
    let (cols, rows) = (ex.width() - 4, ex.height() - 4);
    let expected = (w * h) as f32 / (cols * rows) as f32;
    for _ in 0..passes {
        for oy in 0..stride {
            for ox in 0..stride {
                let snapshot = out.clone();
                let mut counts = vec![0u32; cols * rows];
                for &[sx, sy] in coords.as_slice() {
                    counts[(sy as usize - 2) * cols + sx as usize - 2] += 1;
                }
                for y in (oy..h).step_by(stride) {
                    for x in (ox..w).step_by(stride) {
                        let own = *coords.get(x, y);
                        let mut best = (f32::INFINITY, [0u32; 2]);
                        for ey in 2..ex.height() as isize - 2 {
                            for ex_x in 2..ex.width() as isize - 2 {
                                let mut d = 0.0f32;
                                for dy in -2..=2isize {
                                    for dx in -2..=2isize {
                                        let a = *snapshot.get_wrapped(x as isize + dx, y as isize + dy);
                                        let b = *ex.get((ex_x + dx) as usize, (ey + dy) as usize);
                                        for c in 0..3 {
                                            d += (a[c] - b[c]) * (a[c] - b[c]);
                                        }
                                    }
                                }
                                let i = (ey - 2) as usize * cols + (ex_x - 2) as usize;
                                let count = counts[i] - u32::from(own == [ex_x as u32, ey as u32]);
                                let d = d * occurrence_factor(lambda, count, expected);
                                if d < best.0 {
                                    best = (d, [ex_x as u32, ey as u32]);
                                }
                            }
                        }
                        let [bx, by] = best.1;
                        *out.get_mut(x, y) = *ex.get(bx as usize, by as usize);
                        *coords.get_mut(x, y) = best.1;
                    }
                }
            }
        }
    }
}

#[test]
fn exact_search_equals_a_brute_force_scan() {
    let ex = pattern(13, 11);
    // 0: plain Wei-Levoy; the default penalty; a strong one (changes the choices more often).
    for lambda in [0.0, SCANLINE_OCCURRENCE_PENALTY, 50.0] {
        let c = SynthConfig {
            levels: 1,
            search: Search::Exact,
            seed: 7,
            corrections: 0,
            occurrence_penalty: lambda,
            ..SynthConfig::scanline(9, 10)
        };
        let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(s.coords, brute_force_single_level(&ex, 9, 10, 7, lambda).1, "lambda {lambda}");
    }
    let plain = brute_force_single_level(&ex, 9, 10, 7, 0.0).1;
    assert_ne!(plain, brute_force_single_level(&ex, 9, 10, 7, 50.0).1, "the penalty changes something");
    assert_eq!(Neighbourhood::new(5, 3, false).dim(), 36);
}

#[test]
fn exact_search_with_corrections_equals_a_brute_force_scan() {
    let ex = pattern(13, 11);
    for lambda in [0.0, SCANLINE_OCCURRENCE_PENALTY] {
        // 10 x 8 is not a multiple of the stride, so sub-passes differ in size and wrap unevenly.
        let (mut out, mut coords) = brute_force_single_level(&ex, 10, 8, 5, lambda);
        let causal = coords.clone();
        brute_force_corrections(&ex, &mut out, &mut coords, 2, CORRECTION_STRIDE, lambda);
        assert_ne!(coords, causal, "the corrections change something, so the comparison means something");
        let c = SynthConfig {
            levels: 1,
            search: Search::Exact,
            seed: 5,
            corrections: 2,
            occurrence_penalty: lambda,
            ..SynthConfig::scanline(10, 8)
        };
        let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(s.coords, coords, "lambda {lambda}");
        assert_eq!(s.texels, out, "lambda {lambda}");
    }
}
