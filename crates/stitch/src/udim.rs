//! UDIM tiles (issue 41): a mesh whose UVs span several unit squares gets one map per tile, tile
//! `1001 + col + 10 * row` for the square `u in [col, col + 1)`, `v in [row, row + 1)` with v up
//! (Blender's and Mari's numbering). In skinkit's convention (v = 0 at the top of tile 1001, the
//! loaders flip OBJ's v), tile row `row` spans `v in (-row, 1 - row]`.
//!
//! The tiles a mesh touches are laid side by side into one atlas (tile rows with higher v above),
//! which is partitioned, grown and blended as one map, so the texels on both sides of a tile
//! boundary come from one continuous synthesis; [`Atlas::split`] cuts it into the tiles.

use skinkit_maps::Grid;

use crate::{Error, Result};

/// Columns of a UDIM row.
pub const COLUMNS: i64 = 10;
/// Rows accepted (tiles 1001 to 1100 x 10; beyond is not UDIM).
pub const MAX_ROWS: i64 = 100;

/// The tiles a mesh's UVs touch, laid out as one atlas of `cols x rows` tiles.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// Leftmost tile column.
    pub col0: i64,
    /// Topmost tile row (the highest v).
    pub row_top: i64,
    pub cols: usize,
    pub rows: usize,
    /// One tile's size in texels.
    pub tile_width: usize,
    pub tile_height: usize,
    /// The tiles holding a triangle's UV centroid, ascending.
    pub tiles: Vec<u32>,
}

/// The tile (column, row) of a UV in skinkit's convention.
pub fn tile_of(uv: [f64; 2]) -> (i64, i64) {
    (uv[0].floor() as i64, (1.0 - uv[1]).floor() as i64)
}

/// The UDIM number of tile (column, row).
pub fn tile_number(col: i64, row: i64) -> u32 {
    (1001 + col + COLUMNS * row) as u32
}

impl Atlas {
    /// The atlas of the tiles the triangles' UV `centroids` fall in, each tile `width x height`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `origin` for a centroid outside tiles 1001 to 1999.
    pub fn new(origin: &str, centroids: &[[f64; 2]], width: usize, height: usize) -> Result<Atlas> {
        let mut tiles = Vec::with_capacity(centroids.len());
        for &c in centroids {
            let (col, row) = tile_of(c);
            if !(0..COLUMNS).contains(&col) || !(0..MAX_ROWS).contains(&row) {
                let message = format!(
                    "{origin}: a triangle's UV ({:.3}, {:.3}) lies outside the UDIM tiles 1001 to 1999 (u in 0..10, v in 0..100 with v up)",
                    c[0],
                    1.0 - c[1]
                );
                return Err(Error::InvalidParameter(message));
            }
            tiles.push((col, row));
        }
        let col0 = tiles.iter().map(|t| t.0).min().unwrap_or(0);
        let col1 = tiles.iter().map(|t| t.0).max().unwrap_or(0);
        let row0 = tiles.iter().map(|t| t.1).min().unwrap_or(0);
        let row_top = tiles.iter().map(|t| t.1).max().unwrap_or(0);
        let mut numbers: Vec<u32> = tiles.iter().map(|&(c, r)| tile_number(c, r)).collect();
        numbers.sort_unstable();
        numbers.dedup();
        let (cols, rows) = ((col1 - col0 + 1) as usize, (row_top - row0 + 1) as usize);
        Ok(Atlas { col0, row_top, cols, rows, tile_width: width, tile_height: height, tiles: numbers })
    }

    /// True for the plain case: the one tile 1001, written without a tile number.
    pub fn is_single_1001(&self) -> bool {
        self.tiles == [1001] && self.cols == 1 && self.rows == 1
    }

    /// The atlas's size in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.cols * self.tile_width, self.rows * self.tile_height)
    }

    /// A UV (skinkit's convention, any tile) in the atlas's 0..1 coordinates.
    pub fn to_atlas(&self, uv: [f64; 2]) -> [f64; 2] {
        [(uv[0] - self.col0 as f64) / self.cols as f64, (uv[1] + self.row_top as f64) / self.rows as f64]
    }

    /// The texel rectangle `(x0, y0)` of tile `number` in the atlas.
    pub fn tile_origin(&self, number: u32) -> (usize, usize) {
        let n = i64::from(number) - 1001;
        let (col, row) = (n % COLUMNS, n / COLUMNS);
        (((col - self.col0) as usize) * self.tile_width, ((self.row_top - row) as usize) * self.tile_height)
    }

    /// The atlas-sized `grid` cut into its occupied tiles, `(number, tile)` in ascending order.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `grid` is not the atlas's size.
    pub fn split<T: Clone>(&self, grid: &Grid<T>) -> Result<Vec<(u32, Grid<T>)>> {
        if grid.size() != self.size() {
            let message = format!("a {:?} grid is not the {:?} atlas", grid.size(), self.size());
            return Err(Error::InvalidParameter(message));
        }
        self.tiles
            .iter()
            .map(|&t| {
                let (x0, y0) = self.tile_origin(t);
                Ok((t, grid.crop(x0, y0, self.tile_width, self.tile_height)?))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_numbered_with_v_up_and_laid_out_with_higher_v_on_top() {
        // Skinkit v = 0.5 is tile row 0; v = -0.5 (Blender v = 1.5) is row 1.
        assert_eq!(tile_of([0.5, 0.5]), (0, 0));
        assert_eq!(tile_of([1.5, -0.5]), (1, 1));
        let a = Atlas::new("m", &[[0.5, 0.5], [1.5, -0.5]], 8, 4).unwrap();
        assert_eq!(a.tiles, vec![1001, 1012]);
        assert_eq!(a.size(), (16, 8));
        assert_eq!(a.tile_origin(1012), (8, 0));
        assert_eq!(a.tile_origin(1001), (0, 4));
        assert_eq!(a.to_atlas([0.0, 1.0]), [0.0, 1.0]);
        assert_eq!(a.to_atlas([2.0, -1.0]), [1.0, 0.0]);
        assert!(Atlas::new("m", &[[11.0, 0.5]], 8, 4).unwrap_err().to_string().contains("1001 to 1999"));
    }
}
