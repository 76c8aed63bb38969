//! Interleaved sub-passes: a level's texels chosen again in `s x s` interleaved groups
//! (`s` = [`CORRECTION_STRIDE`]), each group in parallel from the state the previous groups left,
//! so the result does not depend on the thread count. The correction passes
//! ([`crate::correction`]) and seam polishing ([`crate::polish`]) both run their texels this way.

use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::Grid;

use crate::config::CORRECTION_STRIDE;
use crate::exemplar::ExemplarLevel;

/// One interleaved sub-pass (`sub` in row-major order of the residues `(x mod s, y mod s)`,
/// `s` = [`CORRECTION_STRIDE`]): `choose` picks a new candidate (or none) for each of its texels
/// in parallel from the state the previous sub-passes left, then all are written, so the result
/// does not depend on the thread count. Only the rows in `active` are chosen again (a band's
/// window, [`crate::band`], reads the rows around them). Shared by the correction passes and
/// seam polishing.
pub(crate) fn sub_pass<S: Default + Send>(
    full: &ExemplarLevel,
    out: &mut Grid<Vec3>,
    coords: &mut Grid<[u32; 2]>,
    (sub, active): (usize, &Range<usize>),
    choose: impl Fn(usize, usize, &Grid<Vec3>, &Grid<[u32; 2]>, &mut S) -> Option<usize> + Sync,
) {
    let (w, h) = out.size();
    let s = CORRECTION_STRIDE;
    let (ox, oy) = (sub % s, sub / s);
    let rows: Vec<usize> = (oy..h).step_by(s).filter(|y| active.contains(y)).collect();
    let (read_out, read_coords) = (&*out, &*coords);
    let chosen: Vec<Vec<Option<usize>>> = rows
        .par_iter()
        .map_init(S::default, |scratch, &y| {
            (ox..w).step_by(s).map(|x| choose(x, y, read_out, read_coords, scratch)).collect()
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
