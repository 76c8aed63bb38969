//! Banded levels (issue 43): a level taller than [`BAND_ROWS`] is grown in horizontal bands, top
//! to bottom, so that what a level holds while it is corrected grows with its width and the
//! band's height, not with its area, and the finest level's rows can be written as they finish.
//!
//! A band is a property of the algorithm, never of the memory limit or the thread count: the
//! same output size always gives the same bands, so the same bits. A level of at most
//! [`BAND_ROWS`] rows is one band, the whole toroidal level, exactly as before bands existed. A
//! taller level is cut into `ceil(h / BAND_ROWS)` bands of nearly equal height starting on even
//! rows; each is corrected in a window of its rows with [`BAND_HALO`] rows of context above and
//! below:
//!
//! * above: the previous band's last rows, final and frozen (the first band: the level's last
//!   rows, upsampled and corrected with the band, then dropped);
//! * below: the next rows, upsampled and corrected with the band, then dropped (the last band:
//!   the first band's first rows, final and frozen, so the output still wraps).
//!
//! A band's rows next to the band above are thus chosen seeing that band's final texels, as the
//! correction passes see any texel already corrected. What a band's window differs in from the
//! whole level is the halo's far edge: there the window wraps onto itself, which only the dropped
//! or frozen rows see. The coarsest level and the scanline start are never banded (the coarsest
//! is the smallest level; the causal pass is sequential over its whole level).
//!
//! The parent reads of a window stay aligned with the level's (texel row `y` reads coarser row
//! `y / 2`) because a window starts on an even level row. A level of odd height cannot wrap that
//! way across its last row: there the first band has no halo above and the last none below (each
//! window wraps onto itself), which only its first and last two rows see.

use std::ops::Range;

use glam::Vec3;
use skinkit_maps::Grid;

/// The most rows a band keeps; a level of at most this many rows is one band.
pub const BAND_ROWS: usize = 1024;

/// Rows of context a band's window holds above and below its own rows (even, so windows start on
/// even rows). The default's finest level runs 1 correction pass, 1 polishing pass and up to 4
/// repeated cuts, 54 sub-passes each reaching 2 rows: 32 rows keep what the window's far edge
/// differs in well away from the band's own rows in practice.
pub const BAND_HALO: usize = 32;

/// Where a grid being corrected lies in its level: the level row of its row 0, the level's
/// height, and the rows of the grid that may change (the others are context).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Window {
    pub(crate) row0: usize,
    pub(crate) level_height: usize,
    pub(crate) active: Range<usize>,
}

impl Window {
    /// A whole level of `height` rows, every row active.
    pub(crate) fn whole(height: usize) -> Self {
        Window { row0: 0, level_height: height, active: 0..height }
    }

    /// The level row of the grid's row `y`.
    pub(crate) fn level_row(&self, y: usize) -> usize {
        (self.row0 + y) % self.level_height.max(1)
    }
}

/// The rows each band of a level `height` rows tall keeps, top to bottom: all of them when the
/// level holds at most [`BAND_ROWS`], otherwise `ceil(height / BAND_ROWS)` bands of nearly equal
/// height, each starting on an even row.
pub fn bands(height: usize) -> Vec<Range<usize>> {
    if height <= BAND_ROWS {
        return std::iter::once(0..height).collect();
    }
    let n = height.div_ceil(BAND_ROWS);
    let start = |k: usize| if k == n { height } else { 2 * (k * height / (2 * n)) };
    (0..n).map(|k| start(k)..start(k + 1)).collect()
}

/// One band's window (see the module's docs).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct BandWindow {
    /// The window's place in the level; its active rows exclude the frozen ones.
    pub(crate) window: Window,
    /// Rows in the window.
    pub(crate) len: usize,
    /// Rows above the band's own (the band's rows are `top..top + band.len()` of the window).
    pub(crate) top: usize,
    /// Whether the rows above are the previous band's final rows.
    pub(crate) frozen_top: bool,
    /// How many rows at the window's end are the first band's final rows (the last band).
    pub(crate) frozen_bottom: usize,
}

/// The window of band `k` of `bands` (from [`bands`]) in a level `height` rows tall.
pub(crate) fn band_window(bands: &[Range<usize>], k: usize, height: usize) -> BandWindow {
    let (n, band) = (bands.len(), bands[k].clone());
    if n == 1 {
        let window = Window::whole(height);
        return BandWindow { window, len: height, top: 0, frozen_top: false, frozen_bottom: 0 };
    }
    let wraps = height.is_multiple_of(2);
    let top = if k > 0 || wraps { BAND_HALO } else { 0 };
    let bottom = if k + 1 < n || wraps { BAND_HALO } else { 0 };
    let frozen_bottom = if k + 1 == n { bottom } else { 0 };
    let len = top + band.len() + bottom;
    let active = if k > 0 { top } else { 0 }..len - frozen_bottom;
    let window = Window { row0: (band.start + height - top) % height, level_height: height, active };
    BandWindow { window, len, top, frozen_top: k > 0, frozen_bottom }
}

/// Rows `rows` of `grid`, as a grid of their own.
pub(crate) fn rows_of<T: Clone + Send + Sync>(grid: &Grid<T>, rows: Range<usize>) -> Grid<T> {
    let w = grid.width();
    let data = grid.as_slice()[rows.start * w..rows.end * w].to_vec();
    Grid::from_vec(w, rows.len(), data).expect("whole rows")
}

/// Copies the rows of `from` into `to` from row `at` on.
pub(crate) fn put_rows<T: Clone>(to: &mut Grid<T>, at: usize, from: &Grid<T>) {
    let w = to.width();
    to.as_mut_slice()[at * w..(at + from.height()) * w].clone_from_slice(from.as_slice());
}

/// The coarser level's rows a window reads: window row `y` reads coarser row `y / 2`, which is
/// level row `(row0 + y) / 2` (`row0` even), wrapped.
pub(crate) fn coarser_rows(coarser: &Grid<Vec3>, window: &Window, len: usize) -> Grid<Vec3> {
    let (cw, ch) = coarser.size();
    let first = window.row0 / 2;
    Grid::from_fn(cw, len.div_ceil(2), |x, y| *coarser.get(x, (first + y) % ch))
}

/// Collects a level's bands, top to bottom, into whole grids.
pub(crate) struct Collect {
    width: usize,
    height: usize,
    texels: Vec<Vec3>,
    coords: Vec<[u32; 2]>,
}

impl Collect {
    /// Room for a `width x height` level.
    pub(crate) fn new(width: usize, height: usize) -> Self {
        Collect { width, height, texels: Vec::new(), coords: Vec::new() }
    }

    /// Appends a band's rows (the bands come in order); a band that is the whole level is kept
    /// as it is, not copied.
    pub(crate) fn push(&mut self, texels: Grid<Vec3>, coords: Grid<[u32; 2]>) {
        if self.texels.is_empty() && texels.height() == self.height {
            (self.texels, self.coords) = (texels.into_vec(), coords.into_vec());
            return;
        }
        let texels_left = self.width * self.height - self.texels.len();
        self.texels.reserve_exact(texels_left);
        self.coords.reserve_exact(texels_left);
        self.texels.extend_from_slice(texels.as_slice());
        self.coords.extend_from_slice(coords.as_slice());
    }

    /// The whole level.
    pub(crate) fn finish(self) -> (Grid<Vec3>, Grid<[u32; 2]>) {
        let h = self.texels.len() / self.width.max(1);
        let texels = Grid::from_vec(self.width, h, self.texels).expect("whole rows");
        (texels, Grid::from_vec(self.width, h, self.coords).expect("whole rows"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bands cover the level once, in order, start on even rows and keep at most `BAND_ROWS`
    /// (plus one for an odd remainder); windows start on even rows and freeze what they should.
    #[test]
    fn bands_tile_the_level_and_windows_start_on_even_rows() {
        assert_eq!(bands(1024), std::iter::once(0..1024).collect::<Vec<_>>());
        assert_eq!(bands(1), std::iter::once(0..1).collect::<Vec<_>>());
        for h in [1025, 2048, 2049, 3000, 8191, 16384] {
            let b = bands(h);
            assert_eq!(b.len(), h.div_ceil(BAND_ROWS), "{h}");
            assert_eq!((b[0].start, b[b.len() - 1].end), (0, h));
            for (k, band) in b.iter().enumerate() {
                assert!(band.start % 2 == 0 && band.len() <= BAND_ROWS + 1 && band.len() > BAND_HALO, "{h}: {band:?}");
                if k > 0 {
                    assert_eq!(b[k - 1].end, band.start);
                }
                let w = band_window(&b, k, h);
                assert_eq!(w.window.row0 % 2, 0, "{h} band {k}");
                assert_eq!(w.window.level_row(w.top), band.start);
                assert_eq!(w.len, w.top + band.len() + if k + 1 < b.len() || h % 2 == 0 { BAND_HALO } else { 0 });
                assert_eq!(w.frozen_top, k > 0);
                assert!(w.window.active.contains(&w.top) && w.window.active.contains(&(w.top + band.len() - 1)));
            }
            let last = band_window(&b, b.len() - 1, h);
            // The last band's frozen rows below are the level's first rows.
            if h % 2 == 0 {
                assert_eq!(last.window.level_row(last.len - last.frozen_bottom), 0);
                assert_eq!(last.window.active.end, last.len - BAND_HALO);
            }
        }
    }
}
