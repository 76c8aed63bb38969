//! UDIM tiles (issue 41): a mesh whose UVs span several unit squares has one map per tile, tile
//! `1001 + col + 10 * row` for the square `u in [col, col + 1)`, `v in [row, row + 1)` with v up
//! (Blender's and Mari's numbering). In skinkit's convention (v = 0 at the top of tile 1001, the
//! loaders flip OBJ's v), tile row `row` spans `v in (-row, 1 - row]`.
//!
//! The tiles a mesh touches are laid side by side into one atlas (tile rows with higher v above),
//! which is partitioned, grown and blended as one map, so the texels on both sides of a tile
//! boundary come from one continuous synthesis; [`Atlas::split`] cuts it into the tiles and
//! [`Atlas::join`] puts tiles read back (a renderer's, an exporter's) into one atlas again, whose
//! UVs are [`Atlas::to_atlas`]: an affine map, so the texels on either side of a tile boundary are
//! neighbours in the atlas and a bilinear fetch across the boundary has no step.
//!
//! On disk a set of tiles is named by a pattern with [`TOKEN`] in its file name
//! (`normal.<UDIM>.png`, as Blender, Mari and Substance write it); [`find_tiles`] lists the files
//! the pattern matches.

use std::path::{Path, PathBuf};

use crate::{Error, Grid, Result};

/// The placeholder a file name carries for its tile number (`normal.<UDIM>.png`).
pub const TOKEN: &str = "<UDIM>";

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

/// True when `path`'s file name holds [`TOKEN`].
pub fn is_pattern(path: &Path) -> bool {
    path.file_name().is_some_and(|n| n.to_string_lossy().contains(TOKEN))
}

/// `pattern` with [`TOKEN`] replaced by `tile`.
pub fn tile_path(pattern: &Path, tile: u32) -> PathBuf {
    let name = pattern.file_name().map_or(String::new(), |n| n.to_string_lossy().replace(TOKEN, &tile.to_string()));
    pattern.with_file_name(name)
}

/// The tiles on disk that `pattern` names, `(number, path)` ascending: files in the pattern's
/// folder whose names are the pattern's with a number from 1001 to 1999 for [`TOKEN`].
///
/// # Errors
/// [`Error::Io`] when the folder cannot be listed.
pub fn find_tiles(pattern: &Path) -> Result<Vec<(u32, PathBuf)>> {
    let name = pattern.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let Some((prefix, suffix)) = name.split_once(TOKEN) else { return Ok(Vec::new()) };
    let dir = match pattern.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_owned(),
        _ => PathBuf::from("."),
    };
    let entries = std::fs::read_dir(&dir).map_err(|error| Error::Io { path: dir.clone(), error })?;
    let mut tiles = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|error| Error::Io { path: dir.clone(), error })?;
        let file = entry.file_name().to_string_lossy().into_owned();
        let number = file.strip_prefix(prefix).and_then(|rest| rest.strip_suffix(suffix));
        let number = number.filter(|n| n.len() == 4).and_then(|n| n.parse::<u32>().ok());
        if let Some(n) = number.filter(|n| (1001..=1999).contains(n)) {
            tiles.push((n, dir.join(&file)));
        }
    }
    tiles.sort();
    Ok(tiles)
}

/// The files a map path stands for: the path itself, or each tile on disk when it is a pattern
/// (none when its folder cannot be listed).
pub fn files(path: &Path) -> Vec<PathBuf> {
    match is_pattern(path) {
        true => find_tiles(path).unwrap_or_default().into_iter().map(|(_, p)| p).collect(),
        false => vec![path.to_owned()],
    }
}

impl Atlas {
    /// The atlas of the tiles `numbers` (each from 1001 to 1999), each `width x height`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a number outside 1001 to 1999 or no numbers.
    pub fn of_tiles(numbers: &[u32], width: usize, height: usize) -> Result<Atlas> {
        let bad = numbers.iter().find(|&&n| !(1001..=1999).contains(&n) || (n - 1001) % 10 >= COLUMNS as u32);
        if numbers.is_empty() || bad.is_some() {
            return Err(Error::InvalidParameter(format!("UDIM tiles {numbers:?}: each must be 1001 to 1999")));
        }
        let places: Vec<(i64, i64)> =
            numbers.iter().map(|&n| (i64::from(n - 1001) % COLUMNS, i64::from(n - 1001) / COLUMNS)).collect();
        Ok(Atlas::of_places(&places, width, height))
    }

    /// The atlas of tiles at (column, row) `places` (not empty).
    fn of_places(places: &[(i64, i64)], width: usize, height: usize) -> Atlas {
        let col0 = places.iter().map(|t| t.0).min().unwrap_or(0);
        let col1 = places.iter().map(|t| t.0).max().unwrap_or(0);
        let row0 = places.iter().map(|t| t.1).min().unwrap_or(0);
        let row_top = places.iter().map(|t| t.1).max().unwrap_or(0);
        let mut tiles: Vec<u32> = places.iter().map(|&(c, r)| tile_number(c, r)).collect();
        tiles.sort_unstable();
        tiles.dedup();
        let (cols, rows) = ((col1 - col0 + 1) as usize, (row_top - row0 + 1) as usize);
        Atlas { col0, row_top, cols, rows, tile_width: width, tile_height: height, tiles }
    }

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
        Ok(Atlas::of_places(&tiles, width, height))
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

    /// The inverse of [`Atlas::split`]: `tiles` (each the atlas's tile size, numbers in the
    /// atlas) placed into one atlas-sized grid, `fill` where the atlas has no tile.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a tile of another size or not in the atlas.
    pub fn join<T: Clone>(&self, tiles: &[(u32, Grid<T>)], fill: T) -> Result<Grid<T>> {
        let (w, h) = self.size();
        let mut atlas = Grid::filled(w, h, fill);
        for (number, tile) in tiles {
            if tile.size() != (self.tile_width, self.tile_height) || !self.tiles.contains(number) {
                let message = format!(
                    "UDIM tile {number} ({:?} texels) does not fit an atlas of {:?} tiles of {:?}",
                    tile.size(),
                    self.tiles,
                    (self.tile_width, self.tile_height)
                );
                return Err(Error::InvalidParameter(message));
            }
            let (x0, y0) = self.tile_origin(*number);
            for y in 0..self.tile_height {
                atlas.row_mut(y0 + y)[x0..x0 + self.tile_width].clone_from_slice(tile.row(y));
            }
        }
        Ok(atlas)
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
        assert_eq!(Atlas::of_tiles(&[1012, 1001], 8, 4).unwrap(), a);
        assert!(Atlas::of_tiles(&[1000], 8, 4).is_err() && Atlas::of_tiles(&[], 8, 4).is_err());
    }

    #[test]
    fn join_puts_back_what_split_cut() {
        let a = Atlas::of_tiles(&[1001, 1002, 1012], 3, 2).unwrap();
        let (w, h) = a.size();
        let grid = Grid::from_fn(w, h, |x, y| (x + 10 * y) as u32);
        let tiles = a.split(&grid).unwrap();
        let back = a.join(&tiles, u32::MAX).unwrap();
        // Tile 1011 (top left) is not in the atlas: filled; the rest is the grid.
        for y in 0..h {
            for x in 0..w {
                let want = if x < 3 && y < 2 { u32::MAX } else { *grid.get(x, y) };
                assert_eq!(*back.get(x, y), want, "({x}, {y})");
            }
        }
        assert!(a.join(&[(1003, Grid::filled(3, 2, 0))], 0).is_err());
        assert!(a.join(&[(1001, Grid::filled(2, 2, 0))], 0).is_err());
    }

    #[test]
    fn tile_files_are_found_by_their_pattern() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["n.1001.png", "n.1012.png", "n.1000.png", "n.10011.png", "m.1001.png", "n.1002.exr"] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let pattern = dir.path().join("n.<UDIM>.png");
        assert!(is_pattern(&pattern) && !is_pattern(&dir.path().join("n.1001.png")));
        assert_eq!(tile_path(&pattern, 1012), dir.path().join("n.1012.png"));
        let found: Vec<u32> = find_tiles(&pattern).unwrap().into_iter().map(|t| t.0).collect();
        assert_eq!(found, [1001, 1012]);
        assert_eq!(files(&pattern), [dir.path().join("n.1001.png"), dir.path().join("n.1012.png")]);
        assert_eq!(files(&dir.path().join("x.png")), [dir.path().join("x.png")]);
    }
}
