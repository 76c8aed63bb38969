//! The N-way multiresolution spline that joins per-region syntheses into one map (Haro et al. 2001,
//! section 4.2, after Burt and Adelson 1983, "A multiresolution spline with application to image
//! mosaics").
//!
//! Every region `r` comes as a [`Piece`]: its synthesis over a rectangle of the full map (its
//! bounding box grown by a margin). Per pyramid level `l` the output is
//! `O_l = sum_r M_{r,l} L_{r,l} / sum_r M_{r,l}`, where `L_{r,l}` is the Laplacian pyramid of the
//! piece and `M_{r,l}` the Gaussian pyramid of the region's mask (1 on its labels, 0 elsewhere);
//! the normalisation makes the weights add to one even where some texels belong to no region. The
//! output is the collapse of `O`. Regions are summed in index order at every texel, rows run in
//! parallel, so the bits do not depend on the thread count.
//!
//! # Levels, margins and alignment
//! `levels` counts pyramid levels including the finest (1 = hard labels, see
//! [`SplineConfig::no_blend`]). With the 5-tap kernel, the Gaussian level `l` of a texel reads
//! fine texels within `2^(l+1) - 2` of it and the Laplacian level `l` within `6 * 2^l - 2`, so a
//! region's weight is non-zero only within `2^(l+1) - 2` of the region and what it weighs reads
//! texels within [`margin_for_levels`]` = 2^(L+1) - 4` of the region. A piece covering the region's
//! bounding box grown by that margin (clamped to the map) therefore has, wherever it counts, the
//! same pyramid as the full map would: this is enblend's rule `2 (2^(L+1) - 4) <= overlap`
//! ([`levels_for_overlap`]) with the overlap shared by two sides (the "about `3 * 2^L`" of the
//! issue is this bound rounded up; `2^(L+1) - 4` is exact, and tested against a full-map oracle). For `reduce` of a piece to keep
//! the same texels as `reduce` of the full map, a piece's origin must be a multiple of `2^(L-1)`
//! ([`alignment_for_levels`]); [`piece_rect`] gives the smallest valid rectangle. Pieces that do not
//! fit are refused ([`SplineError::PieceTooSmall`], which names the largest level count they allow,
//! also given by [`max_levels_for_pieces`]): the spline never silently drops levels.
//!
//! # Locality
//! By the same count, a texel whose `(2R+1)^2` square (`R = 2^(L+1) - 4`) holds labels of one region
//! only is, in exact arithmetic, that region's piece texel. Such texels are copied from the piece
//! bit for bit rather than collapsed (which would only add float rounding), so the spline changes
//! nothing farther than `R` from a boundary (enblend's automatic levels do).
//!
//! # Cost
//! The finest Gaussian level of a region's mask is the mask itself, so the finest output level is
//! the own region's Laplacian: per region only levels `1..L` are accumulated into full-map
//! (quarter-size and smaller) sums, and the finest level is written texel by texel where the
//! output is not a copy. Memory: one full-size output, the level-1 and coarser sums (a third of
//! it), and one region's pyramids at a time; never regions x full map.
//!
//! # Normals
//! [`Blend::NormalVectors`] blends unnormalised vectors through the pyramid and normalises once at
//! the end; [`Blend::NormalSlopes`] blends slopes `(nx/nz, ny/nz)` (with `nz` clamped to at least
//! [`MIN_NZ`]) and turns them back into unit normals. Neither renormalises per level (averaging unit
//! vectors per level flattens the relief). An invalid (zero) normal of a region stays invalid in the
//! output. [`Blend::Colour`] is not normalised. Copied texels are taken verbatim (unit normals stay
//! bit for bit what they were); only blended texels are normalised. Texels whose label is not a
//! region index (`>=` the number of pieces) are zero in the output; non-finite piece texels are
//! refused ([`SplineError::NonFinite`]) rather than spread over a pyramid's support.
//!
//! # Length
//! Over 600 lines on purpose (about 650 without its tests): the level, margin and alignment rules,
//! the mask pyramids, the interior copy and the per-level sums are one algorithm whose bounds are
//! derived above from one count (`2^(L+1) - 4`); each part's correctness is that it agrees with the
//! others on that count, and the tests check them together against the full-map oracle.

use std::fmt;

use glam::Vec3;
use rayon::prelude::*;
use skinkit_maps::Grid;
use skinkit_maps::pyramid::{self, Border};

/// The most levels a spline may use (the margin `2^(L+1) - 4` must stay a sane size).
pub const MAX_LEVELS: usize = 20;

/// Smallest `nz` used when turning a normal into slopes: slopes are capped at 100 (89.4 degrees).
pub const MIN_NZ: f32 = 0.01;

/// A rectangle of the full map: `width x height` texels from `(x0, y0)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub struct Rect {
    pub x0: usize,
    pub y0: usize,
    pub width: usize,
    pub height: usize,
}

impl Rect {
    /// One past the last column (saturating, so absurd rectangles fail checks instead of panicking).
    pub fn x1(&self) -> usize {
        self.x0.saturating_add(self.width)
    }
    /// One past the last row (saturating).
    pub fn y1(&self) -> usize {
        self.y0.saturating_add(self.height)
    }
    /// Whether `other` lies inside `self` (an empty `other` always does).
    pub fn contains(&self, other: &Rect) -> bool {
        other.width == 0
            || other.height == 0
            || (other.x0 >= self.x0 && other.y0 >= self.y0 && other.x1() <= self.x1() && other.y1() <= self.y1())
    }
}

impl fmt::Display for Rect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}x{} at ({}, {})", self.width, self.height, self.x0, self.y0)
    }
}

/// One region's synthesis over a rectangle of the full map, whose top-left texel is `(x0, y0)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    pub x0: usize,
    pub y0: usize,
    pub texels: Grid<Vec3>,
}

impl Piece {
    /// A piece whose top-left texel sits at `(x0, y0)` of the full map.
    pub fn new(x0: usize, y0: usize, texels: Grid<Vec3>) -> Self {
        Piece { x0, y0, texels }
    }
    /// The rectangle of the full map the piece covers.
    pub fn rect(&self) -> Rect {
        Rect { x0: self.x0, y0: self.y0, width: self.texels.width(), height: self.texels.height() }
    }
}

/// What the texels are, which decides how they are blended and finished.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Blend {
    /// Colours (or any linear quantity): blended as they are, never normalised.
    Colour,
    /// Normals blended as unnormalised vectors, normalised once at the end.
    #[default]
    NormalVectors,
    /// Normals blended as slopes `(nx/nz, ny/nz)`, turned back into unit normals at the end.
    NormalSlopes,
}

/// Parameters of [`blend`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SplineConfig {
    /// Pyramid levels including the finest; 1 means hard labels.
    pub levels: usize,
    /// How texels are blended.
    pub blend: Blend,
}

impl SplineConfig {
    /// A spline with `levels` levels blending normals as vectors.
    pub fn new(levels: usize) -> Self {
        SplineConfig { levels, blend: Blend::default() }
    }
    /// Hard labels: each texel is its own region's piece texel (one level; `--no-blend`).
    pub fn no_blend(blend: Blend) -> Self {
        SplineConfig { levels: 1, blend }
    }
}

/// What [`blend`] refuses.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SplineError {
    /// The level count is 0 or above [`MAX_LEVELS`].
    #[error("spline levels must be in 1..={max}, got {levels}")]
    Levels { levels: usize, max: usize },
    /// More pieces than a `u16` label can name.
    #[error("{pieces} map pieces but labels are u16: at most 65535 regions")]
    TooManyRegions { pieces: usize },
    /// A piece reaches past the map's edge.
    #[error("region {region}: piece {piece} reaches outside the {width}x{height} map")]
    PieceOutsideMap { region: usize, piece: Rect, width: usize, height: usize },
    /// A piece does not cover its region plus the margin, or its origin is not aligned.
    #[error(
        "region {region}: piece {piece} does not cover {needed} (bounding box {bbox} grown by the \
         {margin}-texel margin of {levels} levels, origin a multiple of {align}); these pieces allow \
         at most {max_levels} levels",
        margin = margin_for_levels(*.levels),
        align = alignment_for_levels(*.levels)
    )]
    PieceTooSmall { region: usize, piece: Rect, needed: Rect, bbox: Rect, levels: usize, max_levels: usize },
    /// A piece holds a NaN or infinite texel.
    #[error("region {region}: texel ({x}, {y}) of the map (in its piece) is not finite")]
    NonFinite { region: usize, x: usize, y: usize },
}

/// Largest level count `L` with `2 (2^(L+1) - 4) <= overlap` (enblend's rule; at least 1, at most
/// [`MAX_LEVELS`]): `overlap` is the short side of the band two regions share.
pub fn levels_for_overlap(overlap: usize) -> usize {
    let mut levels = 1;
    while levels < MAX_LEVELS && 2 * margin_for_levels(levels + 1) <= overlap {
        levels += 1;
    }
    levels
}

/// How far past its region a piece must reach for `levels` levels: `2^(L+1) - 4` (0 for one level).
/// It is also the radius beyond which the spline leaves texels untouched.
pub fn margin_for_levels(levels: usize) -> usize {
    let levels = levels.clamp(1, MAX_LEVELS);
    (1usize << (levels + 1)) - 4
}

/// What a piece's origin must be a multiple of for `levels` levels: `2^(L-1)`.
pub fn alignment_for_levels(levels: usize) -> usize {
    1usize << (levels.clamp(1, MAX_LEVELS) - 1)
}

/// The smallest valid piece for a region whose labels lie in `bbox`: grown by
/// [`margin_for_levels`], clamped to the `width x height` map, origin rounded down to a multiple of
/// [`alignment_for_levels`].
pub fn piece_rect(bbox: Rect, levels: usize, width: usize, height: usize) -> Rect {
    let (margin, align) = (margin_for_levels(levels), alignment_for_levels(levels));
    let x0 = bbox.x0.saturating_sub(margin) / align * align;
    let y0 = bbox.y0.saturating_sub(margin) / align * align;
    let x1 = bbox.x1().saturating_add(margin).min(width).max(x0);
    let y1 = bbox.y1().saturating_add(margin).min(height).max(y0);
    Rect { x0, y0, width: x1 - x0, height: y1 - y0 }
}

/// Bounding box of each region `0..regions` in `labels`; `None` for a region with no texel.
pub fn region_bounds(labels: &Grid<u16>, regions: usize) -> Vec<Option<Rect>> {
    let width = labels.width().max(1);
    let found: Vec<Option<[usize; 4]>> = labels
        .as_slice()
        .par_chunks(width)
        .enumerate()
        .fold(|| vec![None; regions], |acc, (y, row)| row_bounds(acc, y, row))
        .reduce(|| vec![None; regions], |a, b| a.into_iter().zip(b).map(|(p, q)| union(p, q)).collect());
    found.into_iter().map(|b| b.map(|[x0, y0, x1, y1]| Rect { x0, y0, width: x1 - x0, height: y1 - y0 })).collect()
}

/// Grows per-region `[x0, y0, x1, y1)` boxes by the labels of row `y`.
fn row_bounds(mut acc: Vec<Option<[usize; 4]>>, y: usize, row: &[u16]) -> Vec<Option<[usize; 4]>> {
    for (x, &label) in row.iter().enumerate() {
        if let Some(slot) = acc.get_mut(label as usize) {
            *slot = union(*slot, Some([x, y, x + 1, y + 1]));
        }
    }
    acc
}

/// Union of two optional `[x0, y0, x1, y1)` boxes.
fn union(a: Option<[usize; 4]>, b: Option<[usize; 4]>) -> Option<[usize; 4]> {
    match (a, b) {
        (Some(p), Some(q)) => Some([p[0].min(q[0]), p[1].min(q[1]), p[2].max(q[2]), p[3].max(q[3])]),
        (p, None) => p,
        (None, q) => q,
    }
}

/// Whether `piece` is a valid piece for a region with bounding box `bbox` at `levels` levels.
fn fits(piece: Rect, bbox: Rect, levels: usize, width: usize, height: usize) -> bool {
    let align = alignment_for_levels(levels);
    piece.x0.is_multiple_of(align)
        && piece.y0.is_multiple_of(align)
        && piece.contains(&piece_rect(bbox, levels, width, height))
}

/// The largest level count (up to [`MAX_LEVELS`]) that every piece supports: 0 when some piece
/// does not even cover its region's bounding box. `pieces[r]` is region `r`'s rectangle.
pub fn max_levels_for_pieces(labels: &Grid<u16>, pieces: &[Rect]) -> usize {
    let bounds = region_bounds(labels, pieces.len());
    max_levels_for_bounds(labels.size(), &bounds, pieces)
}

fn max_levels_for_bounds((width, height): (usize, usize), bounds: &[Option<Rect>], pieces: &[Rect]) -> usize {
    let all_fit =
        |levels| bounds.iter().zip(pieces).all(|(b, &p)| b.is_none_or(|bbox| fits(p, bbox, levels, width, height)));
    (1..=MAX_LEVELS).take_while(|&l| all_fit(l)).last().unwrap_or(0)
}

/// The Gaussian pyramid (levels `0..levels`) of region `region`'s mask over `rect`: 1 where
/// `labels` is `region`, 0 elsewhere, reduced with clamped borders. `rect` must lie in the map.
pub fn region_mask_pyramid(labels: &Grid<u16>, region: u16, rect: Rect, levels: usize) -> Vec<Grid<f32>> {
    let mask =
        Grid::from_fn(
            rect.width,
            rect.height,
            |x, y| {
                if *labels.get(rect.x0 + x, rect.y0 + y) == region { 1.0 } else { 0.0 }
            },
        );
    reduce_chain(mask, levels)
}

/// Level 1 of [`region_mask_pyramid`] straight from the labels, bit for bit `pyramid::reduce` of
/// the 0/1 mask without the full-size mask: the 5-tap kernel at every other column, then row.
fn reduced_mask(labels: &Grid<u16>, region: u16, rect: Rect) -> Grid<f32> {
    let taps = |i: usize, n: usize| -> [usize; 5] {
        std::array::from_fn(|k| (2 * i + k).saturating_sub(2).min(n.saturating_sub(1)))
    };
    let mut across = Grid::filled(rect.width.div_ceil(2), rect.height, 0.0f32);
    across.par_rows_mut().for_each(|(y, row)| {
        let src = &labels.row(rect.y0 + y)[rect.x0..rect.x1()];
        for (o, out) in row.iter_mut().enumerate() {
            let t = taps(o, rect.width);
            *out =
                t.iter().zip(pyramid::KERNEL).fold(0.0, |acc, (&i, w)| acc + f32::from(u8::from(src[i] == region)) * w);
        }
    });
    let mut down = Grid::filled(across.width(), rect.height.div_ceil(2), 0.0f32);
    down.par_rows_mut().for_each(|(y, row)| {
        let rows: [&[f32]; 5] = taps(y, rect.height).map(|i| across.row(i));
        for (x, out) in row.iter_mut().enumerate() {
            *out = rows.iter().zip(pyramid::KERNEL).fold(0.0, |acc, (r, w)| acc + r[x] * w);
        }
    });
    down
}

/// `[g, reduce(g), reduce(reduce(g)), ...]`: exactly `levels` grids (at least one), even once they
/// are 1x1, so every piece has as many levels as the full map.
fn reduce_chain<T: pyramid::Texel>(g: Grid<T>, levels: usize) -> Vec<Grid<T>> {
    let mut chain = vec![g];
    while chain.len() < levels.max(1) {
        let next = pyramid::reduce(chain.last().expect("chain is not empty"), Border::Clamp);
        chain.push(next);
    }
    chain
}

/// Joins the regions' pieces along `labels` (region index per texel) with an N-way multiresolution
/// spline; `pieces[r]` belongs to region `r`. See the module documentation for the rules pieces
/// follow and what texels come out.
///
/// # Errors
/// [`SplineError`]: a level count outside `1..=MAX_LEVELS`, more than 65535 pieces, a piece outside
/// the map or too small for the levels, a non-finite texel in the piece of a region that has texels.
/// Pieces of regions without texels are ignored (they may be empty).
pub fn blend(labels: &Grid<u16>, pieces: &[Piece], config: &SplineConfig) -> Result<Grid<Vec3>, SplineError> {
    let levels = config.levels;
    if levels == 0 || levels > MAX_LEVELS {
        return Err(SplineError::Levels { levels, max: MAX_LEVELS });
    }
    if pieces.len() >= u16::MAX as usize {
        return Err(SplineError::TooManyRegions { pieces: pieces.len() });
    }
    let bounds = region_bounds(labels, pieces.len());
    check_pieces(labels.size(), &bounds, pieces, levels)?;
    check_finite(&bounds, pieces)?;
    let mut copied = interior_mask(labels, pieces.len(), margin_for_levels(levels));
    let mut out = zeros(labels.width(), labels.height());
    let mut sums = LevelSums::new(labels.size(), levels);
    for (r, piece) in pieces.iter().enumerate().filter(|(r, _)| bounds[*r].is_some()) {
        let source = blend_space(piece, config.blend);
        // One level (hard labels) copies every texel: no pyramid at all.
        let gauss = if levels > 1 { reduce_chain(pyramid::reduce(&source, Border::Clamp), levels - 1) } else { vec![] };
        let region = Region { index: r as u16, piece, source: &source, coarse: gauss.first() };
        write_finest(&mut out, &mut copied, labels, &region, config);
        if levels > 1 {
            let masks = reduce_chain(reduced_mask(labels, r as u16, piece.rect()), levels - 1);
            sums.add(&laplacians(gauss), &masks, piece.rect());
        }
    }
    if levels > 1 {
        finish(&mut out, labels, pieces.len(), &copied, &sums.collapse(), config.blend);
    }
    Ok(out)
}

/// Refuses pieces outside the map or too small for `levels`.
fn check_pieces(
    (width, height): (usize, usize),
    bounds: &[Option<Rect>],
    pieces: &[Piece],
    levels: usize,
) -> Result<(), SplineError> {
    for (region, (bbox, piece)) in bounds.iter().zip(pieces).enumerate() {
        let Some(bbox) = *bbox else { continue };
        let rect = piece.rect();
        if rect.x1() > width || rect.y1() > height {
            return Err(SplineError::PieceOutsideMap { region, piece: rect, width, height });
        }
        if !fits(rect, bbox, levels, width, height) {
            let rects: Vec<Rect> = pieces.iter().map(Piece::rect).collect();
            return Err(SplineError::PieceTooSmall {
                region,
                piece: rect,
                needed: piece_rect(bbox, levels, width, height),
                bbox,
                levels,
                max_levels: max_levels_for_bounds((width, height), bounds, &rects),
            });
        }
    }
    Ok(())
}

/// Refuses the first (in row order) non-finite texel of a piece whose region has texels.
fn check_finite(bounds: &[Option<Rect>], pieces: &[Piece]) -> Result<(), SplineError> {
    for (region, piece) in pieces.iter().enumerate().filter(|(r, _)| bounds[*r].is_some()) {
        let (texels, w) = (piece.texels.as_slice(), piece.texels.width().max(1));
        let bad = |v: &Vec3| !v.is_finite();
        if let Some(y) = texels.par_chunks(w).position_first(|row| row.iter().any(bad)) {
            let x = texels[y * w..].iter().position(bad).expect("the row holds a non-finite texel");
            return Err(SplineError::NonFinite { region, x: piece.x0 + x, y: piece.y0 + y });
        }
    }
    Ok(())
}

/// The piece in the space it is blended in: slopes for [`Blend::NormalSlopes`], else as is.
fn blend_space(piece: &Piece, blend: Blend) -> std::borrow::Cow<'_, Grid<Vec3>> {
    match blend {
        Blend::NormalSlopes => std::borrow::Cow::Owned(piece.texels.map(|&n| to_slope(n))),
        Blend::Colour | Blend::NormalVectors => std::borrow::Cow::Borrowed(&piece.texels),
    }
}

/// Slopes `(nx/nz, ny/nz, 0)` of a normal, `nz` clamped to at least [`MIN_NZ`]; zero for zero.
pub fn to_slope(n: Vec3) -> Vec3 {
    if n == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let nz = n.z.max(MIN_NZ);
    Vec3::new(n.x / nz, n.y / nz, 0.0)
}

/// The unit normal with slopes `(s.x, s.y)`: `(s.x, s.y, 1)` normalised.
pub fn from_slope(s: Vec3) -> Vec3 {
    Vec3::new(s.x, s.y, 1.0).normalize()
}

/// Texels whose `(2 radius + 1)^2` square, clamped to the map, holds one region's label only: the
/// spline copies them from their piece. Labels `>= regions` are never copied.
fn interior_mask(labels: &Grid<u16>, regions: usize, radius: usize) -> Grid<bool> {
    const NONE: u16 = u16::MAX;
    let (w, h) = labels.size();
    let mut row_uniform = Grid::filled(w, h, NONE);
    row_uniform.par_rows_mut().for_each(|(y, row)| {
        let src = labels.row(y);
        let changes = change_prefix(src.iter().copied());
        for (x, o) in row.iter_mut().enumerate() {
            let (lo, hi) = (x.saturating_sub(radius), (x + radius).min(w - 1));
            let valid = (src[x] as usize) < regions;
            *o = if valid && changes[hi] == changes[lo] { src[x] } else { NONE };
        }
    });
    // Columns in chunks, each swept down the rows on its own, so the vertical pass runs in parallel.
    let chunks: Vec<Vec<bool>> = (0..w.div_ceil(COLUMN_CHUNK))
        .into_par_iter()
        .map(|c| column_uniform(&row_uniform, c * COLUMN_CHUNK, ((c + 1) * COLUMN_CHUNK).min(w), radius))
        .collect();
    let mut copied = Grid::filled(w, h, false);
    copied.par_rows_mut().for_each(|(y, row)| {
        for (c, chunk) in chunks.iter().enumerate() {
            let x0 = c * COLUMN_CHUNK;
            let cw = (w - x0).min(COLUMN_CHUNK);
            row[x0..x0 + cw].copy_from_slice(&chunk[y * cw..(y + 1) * cw]);
        }
    });
    copied
}

/// Columns per parallel task of [`interior_mask`]'s vertical pass.
const COLUMN_CHUNK: usize = 128;

/// For columns `x0..x1` of `v` (row-uniform labels, `u16::MAX` for none), whether the column
/// window of `radius` rows around each texel is constant and not none; row-major, `x1 - x0` wide.
fn column_uniform(v: &Grid<u16>, x0: usize, x1: usize, radius: usize) -> Vec<bool> {
    let (cw, h) = (x1 - x0, v.height());
    // prefix[y][x]: changes between consecutive rows of column x up to row y.
    let mut prefix = vec![0u32; cw * h];
    for y in 1..h {
        let (done, rest) = prefix.split_at_mut(y * cw);
        let (above, here) = (&done[(y - 1) * cw..], &mut rest[..cw]);
        let (va, vh) = (&v.row(y - 1)[x0..x1], &v.row(y)[x0..x1]);
        for x in 0..cw {
            here[x] = above[x] + u32::from(va[x] != vh[x]);
        }
    }
    let mut out = Vec::with_capacity(cw * h);
    for y in 0..h {
        let (lo, hi) = (y.saturating_sub(radius), (y + radius).min(h - 1));
        let (plo, phi, vr) = (&prefix[lo * cw..(lo + 1) * cw], &prefix[hi * cw..(hi + 1) * cw], &v.row(y)[x0..x1]);
        out.extend((0..cw).map(|x| vr[x] != u16::MAX && plo[x] == phi[x]));
    }
    out
}

/// `p[i]` = number of `j in 1..=i` with `v[j] != v[j-1]`: `v[lo..=hi]` is constant iff `p[hi] == p[lo]`.
fn change_prefix(values: impl Iterator<Item = u16>) -> Vec<u32> {
    let mut prev = None;
    let mut count = 0u32;
    values
        .map(|v| {
            count += u32::from(prev.is_some_and(|p| p != v));
            prev = Some(v);
            count
        })
        .collect()
}

/// The Laplacian levels `1..L` from the Gaussian levels `1..L`: `G_l - expand(G_{l+1})`, the last
/// level the coarsest Gaussian.
fn laplacians(gauss: Vec<Grid<Vec3>>) -> Vec<Grid<Vec3>> {
    let count = gauss.len();
    let mut out = Vec::with_capacity(count);
    for l in 0..count {
        let mut band = gauss[l].clone();
        if l + 1 < count {
            let up = pyramid::expand(&gauss[l + 1], band.width(), band.height(), Border::Clamp);
            band.as_mut_slice().par_iter_mut().zip(up.as_slice().par_iter()).for_each(|(b, &u)| *b -= u);
        }
        out.push(band);
    }
    out
}

/// One region while it is written: its piece, the piece in blend space and that one's level 1.
struct Region<'a> {
    index: u16,
    piece: &'a Piece,
    source: &'a Grid<Vec3>,
    coarse: Option<&'a Grid<Vec3>>,
}

/// The finest level for the region's own texels: a copy of the piece where `copied` (or where the
/// piece holds an invalid zero normal, which then becomes a copy), else the finest Laplacian
/// `source - expand(G_1)`, to which [`finish`] adds the expanded blend of the coarser levels.
fn write_finest(
    out: &mut Grid<Vec3>,
    copied: &mut Grid<bool>,
    labels: &Grid<u16>,
    region: &Region,
    config: &SplineConfig,
) {
    let rect = region.piece.rect();
    let keep_zero = config.blend != Blend::Colour;
    out.par_rows_mut().zip(copied.par_rows_mut()).skip(rect.y0).take(rect.height).for_each(|((y, row), (_, done))| {
        let ly = y - rect.y0;
        let (piece, source, lab) = (region.piece.texels.row(ly), region.source.row(ly), labels.row(y));
        let coarse = region.coarse.map(|c| (c, expand_taps(ly, c.height())));
        for lx in 0..rect.width {
            let x = rect.x0 + lx;
            if lab[x] != region.index {
                continue;
            }
            match &coarse {
                Some((c, ty)) if !done[x] && (!keep_zero || piece[lx] != Vec3::ZERO) => {
                    row[x] = source[lx] - expand_at(c, lx, ty);
                }
                _ => {
                    row[x] = piece[lx];
                    done[x] = true;
                }
            }
        }
    });
}

/// Coarse indices and weights of the expand of fine index `i` from `n` coarse texels (clamped):
/// `[0.1, 0.8, 0.1]` at even `i`, `[0.5, 0.5]` at odd `i`, as in [`pyramid::expand`].
fn expand_taps(i: usize, n: usize) -> [(usize, f32); 3] {
    let c = i / 2;
    let at = |d: isize| (c as isize + d).clamp(0, n as isize - 1) as usize;
    if i.is_multiple_of(2) {
        [(at(-1), 0.1), (at(0), 0.8), (at(1), 0.1)]
    } else {
        [(at(0), 0.5), (at(1), 0.5), (at(0), 0.0)]
    }
}

/// One texel of [`pyramid::expand`] of `g` at fine column `x` for the row taps `ty` (rows first
/// summed across, then down, in the order `pyramid::expand` uses).
fn expand_at(g: &Grid<Vec3>, x: usize, ty: &[(usize, f32); 3]) -> Vec3 {
    let tx = expand_taps(x, g.width());
    ty.iter().fold(Vec3::ZERO, |acc, &(cy, wy)| {
        let row = g.row(cy);
        acc + tx.iter().fold(Vec3::ZERO, |a, &(cx, wx)| a + row[cx] * wx) * wy
    })
}

/// Adds the expanded blend of the coarser levels (`g1`, level 1 of the output) to every texel that
/// is not a copy, then turns blend space back into normals.
fn finish(
    out: &mut Grid<Vec3>,
    labels: &Grid<u16>,
    regions: usize,
    copied: &Grid<bool>,
    g1: &Grid<Vec3>,
    blend: Blend,
) {
    out.par_rows_mut().for_each(|(y, row)| {
        let (lab, done) = (labels.row(y), copied.row(y));
        let ty = expand_taps(y, g1.height());
        for (x, o) in row.iter_mut().enumerate() {
            if done[x] || lab[x] as usize >= regions {
                continue;
            }
            let v = *o + expand_at(g1, x, &ty);
            *o = match blend {
                Blend::Colour => v,
                Blend::NormalVectors => v.normalize_or_zero(),
                Blend::NormalSlopes => from_slope(v),
            };
        }
    });
}

/// A grid of zeros filled by rows in parallel (first touching a large allocation costs page faults,
/// which then run on every core).
fn zeros<T: Default + Copy + Send + Sync>(width: usize, height: usize) -> Grid<T> {
    Grid::from_fn(width, height, |_, _| T::default())
}

/// Per level `1..L` of the full map: the weighted sums `sum_r M_r L_r` and the weights `sum_r M_r`.
struct LevelSums {
    sums: Vec<Grid<Vec3>>,
    weights: Vec<Grid<f32>>,
}

impl LevelSums {
    fn new((width, height): (usize, usize), levels: usize) -> Self {
        let sizes: Vec<(usize, usize)> =
            (1..levels).map(|l| (width.div_ceil(1 << l).max(1), height.div_ceil(1 << l).max(1))).collect();
        LevelSums {
            sums: sizes.iter().map(|&(w, h)| zeros(w, h)).collect(),
            weights: sizes.iter().map(|&(w, h)| zeros(w, h)).collect(),
        }
    }

    /// Adds one region's Laplacian levels `1..L` weighted by its mask levels `1..L`; the piece sits
    /// at `rect` (origin aligned, so level `l` starts at `rect.x0 >> l`).
    fn add(&mut self, laps: &[Grid<Vec3>], masks: &[Grid<f32>], rect: Rect) {
        for (l, (sum, weight)) in self.sums.iter_mut().zip(&mut self.weights).enumerate().map(|(i, p)| (i + 1, p)) {
            let (lap, mask) = (&laps[l - 1], &masks[l - 1]);
            let (ox, oy) = (rect.x0 >> l, rect.y0 >> l);
            let rows = sum.par_rows_mut().zip(weight.par_rows_mut()).skip(oy).take(lap.height());
            rows.for_each(|((y, srow), (_, wrow))| {
                let (lrow, mrow) = (lap.row(y - oy), mask.row(y - oy));
                let (srow, wrow) = (&mut srow[ox..ox + lap.width()], &mut wrow[ox..ox + lap.width()]);
                for (((s, w), &v), &m) in srow.iter_mut().zip(wrow).zip(lrow).zip(mrow) {
                    if m != 0.0 {
                        *s += v * m;
                        *w += m;
                    }
                }
            });
        }
    }

    /// Normalises every level by its weights (zero where no region reaches) and collapses levels
    /// `1..L` into level 1 of the output.
    fn collapse(self) -> Grid<Vec3> {
        let bands: Vec<Grid<Vec3>> = self
            .sums
            .into_iter()
            .zip(self.weights)
            .map(|(mut sum, weight)| {
                let pairs = sum.as_mut_slice().par_iter_mut().zip(weight.as_slice().par_iter());
                pairs.for_each(|(s, &w)| *s = if w > 0.0 { *s / w } else { Vec3::ZERO });
                sum
            })
            .collect();
        pyramid::collapse(&bands, Border::Clamp)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enblend_rule_and_margins_agree() {
        // 2 (2^(L+1) - 4) <= overlap: L=2 needs 8, L=3 24, L=4 56, L=5 120.
        let table = [(0, 1), (7, 1), (8, 2), (23, 2), (24, 3), (56, 4), (119, 4), (120, 5)];
        for (overlap, levels) in table {
            assert_eq!(levels_for_overlap(overlap), levels, "overlap {overlap}");
            assert!(2 * margin_for_levels(levels) <= overlap);
        }
        assert_eq!(levels_for_overlap(usize::MAX), MAX_LEVELS);
        assert_eq!((margin_for_levels(1), margin_for_levels(4)), (0, 28));
        assert_eq!((alignment_for_levels(1), alignment_for_levels(4)), (1, 8));
    }

    #[test]
    fn piece_rect_grows_clamps_and_aligns() {
        let bbox = Rect { x0: 40, y0: 3, width: 10, height: 90 };
        let r = piece_rect(bbox, 3, 100, 95);
        // margin 12, alignment 4: x from 28 (a multiple of 4) to 62, y from 0 to 95 (clamped).
        assert_eq!(r, Rect { x0: 28, y0: 0, width: 34, height: 95 });
        assert!(fits(r, bbox, 3, 100, 95));
        assert!(!fits(Rect { x0: 29, ..r }, bbox, 3, 100, 95));
    }

    #[test]
    fn reduced_mask_is_the_reduce_of_the_mask_bit_for_bit() {
        let labels = Grid::from_fn(31, 22, |x, y| ((x * 7 + y * 3) % 11 > 4) as u16 + u16::from(x > 20));
        for rect in [Rect { x0: 4, y0: 2, width: 25, height: 19 }, Rect { x0: 0, y0: 0, width: 1, height: 1 }] {
            for region in 0..3 {
                let full = region_mask_pyramid(&labels, region, rect, 2);
                assert_eq!(reduced_mask(&labels, region, rect), full[1], "{rect} region {region}");
            }
        }
    }

    #[test]
    fn change_prefix_counts_changes() {
        assert_eq!(change_prefix([1u16, 1, 2, 2, 2, 1].into_iter()), vec![0, 0, 1, 1, 1, 2]);
    }

    #[test]
    fn expand_at_matches_pyramid_expand_bit_for_bit() {
        let g = Grid::from_fn(5, 4, |x, y| Vec3::new(x as f32 * 0.37, (y * x) as f32 * 0.11 - 1.0, 0.3));
        let e = pyramid::expand(&g, 9, 7, Border::Clamp);
        for y in 0..7 {
            let ty = expand_taps(y, 4);
            for x in 0..9 {
                assert_eq!(expand_at(&g, x, &ty), *e.get(x, y), "({x}, {y})");
            }
        }
    }

    #[test]
    fn interior_mask_matches_brute_force() {
        let labels = Grid::from_fn(23, 17, |x, y| {
            if x * 2 + y < 30 {
                0u16
            } else if x > 18 {
                5
            } else {
                1
            }
        });
        for radius in [0, 1, 3] {
            let mask = interior_mask(&labels, 2, radius);
            for y in 0..17 {
                for x in 0..23 {
                    let own = *labels.get(x, y);
                    let uniform = (y.saturating_sub(radius)..=(y + radius).min(16))
                        .all(|j| (x.saturating_sub(radius)..=(x + radius).min(22)).all(|i| *labels.get(i, j) == own));
                    assert_eq!(*mask.get(x, y), uniform && own < 2, "radius {radius} ({x}, {y})");
                }
            }
        }
    }
}
