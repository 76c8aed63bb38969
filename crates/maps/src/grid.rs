//! [`Grid`]: a row-major 2-D array, the storage under every skinkit map.

use glam::Vec3;
use rayon::prelude::*;

use crate::{Error, Result};

/// A row-major `width x height` array; texel `(x, y)` is at `data[y * width + x]`, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid<T> {
    width: usize,
    height: usize,
    data: Vec<T>,
}

/// A single-channel float map (confidence, height, masks, ...).
pub type ScalarMap = Grid<f32>;
/// A linear RGB map (albedo, ...).
pub type ColorMap = Grid<Vec3>;

impl<T: Clone> Grid<T> {
    /// A grid filled with `value`.
    pub fn filled(width: usize, height: usize, value: T) -> Self {
        Grid { width, height, data: vec![value; width * height] }
    }
}

impl<T> Grid<T> {
    /// Wraps row-major `data`.
    ///
    /// # Errors
    /// When `data.len() != width * height`.
    pub fn from_vec(width: usize, height: usize, data: Vec<T>) -> Result<Self> {
        if width.checked_mul(height) != Some(data.len()) {
            return Err(Error::InvalidParameter(format!(
                "grid of {width}x{height} needs {} texels, got {}",
                width.saturating_mul(height),
                data.len()
            )));
        }
        Ok(Grid { width, height, data })
    }

    /// Builds a grid by evaluating `f(x, y)` for every texel, rows in parallel.
    pub fn from_fn(width: usize, height: usize, f: impl Fn(usize, usize) -> T + Sync) -> Self
    where
        T: Send,
    {
        let mut data = Vec::with_capacity(width * height);
        (0..width * height).into_par_iter().map(|i| f(i % width.max(1), i / width.max(1))).collect_into_vec(&mut data);
        Grid { width, height, data }
    }

    pub fn width(&self) -> usize {
        self.width
    }
    pub fn height(&self) -> usize {
        self.height
    }
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
    pub fn len(&self) -> usize {
        self.data.len()
    }
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data
    }
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }
    /// The texel at `(x, y)`; panics when out of range.
    pub fn get(&self, x: usize, y: usize) -> &T {
        assert!(x < self.width && y < self.height, "texel ({x}, {y}) outside {}x{}", self.width, self.height);
        &self.data[y * self.width + x]
    }
    pub fn get_mut(&mut self, x: usize, y: usize) -> &mut T {
        assert!(x < self.width && y < self.height, "texel ({x}, {y}) outside {}x{}", self.width, self.height);
        &mut self.data[y * self.width + x]
    }
    /// The texel at `(x, y)` with coordinates wrapped (toroidal addressing, used by synthesis).
    pub fn get_wrapped(&self, x: isize, y: isize) -> &T {
        // Most reads are inside the grid: skip the two integer divisions there (synthesis reads
        // texels this way in its inner loops).
        let wrap = |v: isize, n: usize| {
            if (0..n as isize).contains(&v) { v as usize } else { v.rem_euclid(n as isize) as usize }
        };
        &self.data[wrap(y, self.height) * self.width + wrap(x, self.width)]
    }
    /// The texel at `(x, y)` with coordinates clamped to the border.
    pub fn get_clamped(&self, x: isize, y: isize) -> &T {
        let xc = x.clamp(0, self.width as isize - 1) as usize;
        let yc = y.clamp(0, self.height as isize - 1) as usize;
        &self.data[yc * self.width + xc]
    }
    /// Row `y` as a slice.
    pub fn row(&self, y: usize) -> &[T] {
        &self.data[y * self.width..(y + 1) * self.width]
    }
    /// Row `y` as a mutable slice.
    pub fn row_mut(&mut self, y: usize) -> &mut [T] {
        &mut self.data[y * self.width..(y + 1) * self.width]
    }
    /// Iterator over rows.
    pub fn rows(&self) -> std::slice::ChunksExact<'_, T> {
        self.data.chunks_exact(self.width.max(1))
    }
    /// Parallel iterator over mutable rows with their index.
    pub fn par_rows_mut(&mut self) -> impl IndexedParallelIterator<Item = (usize, &mut [T])>
    where
        T: Send,
    {
        self.data.par_chunks_mut(self.width.max(1)).enumerate()
    }
    /// Applies `f` to every texel, producing a grid of the same size.
    pub fn map<U: Send>(&self, f: impl Fn(&T) -> U + Sync + Send) -> Grid<U>
    where
        T: Sync,
    {
        let mut data = Vec::with_capacity(self.data.len());
        self.data.par_iter().map(f).collect_into_vec(&mut data);
        Grid { width: self.width, height: self.height, data }
    }
    /// A copy of the `w x h` window whose top-left texel is `(x0, y0)`.
    ///
    /// # Errors
    /// When the window does not fit inside the grid.
    pub fn crop(&self, x0: usize, y0: usize, w: usize, h: usize) -> Result<Self>
    where
        T: Clone,
    {
        if x0 + w > self.width || y0 + h > self.height {
            return Err(Error::InvalidParameter(format!(
                "crop {w}x{h} at ({x0}, {y0}) does not fit in {}x{}",
                self.width, self.height
            )));
        }
        let mut data = Vec::with_capacity(w * h);
        for y in y0..y0 + h {
            data.extend_from_slice(&self.row(y)[x0..x0 + w]);
        }
        Ok(Grid { width: w, height: h, data })
    }
}

impl<T> std::ops::Index<(usize, usize)> for Grid<T> {
    type Output = T;
    fn index(&self, (x, y): (usize, usize)) -> &T {
        self.get(x, y)
    }
}

impl<T> std::ops::IndexMut<(usize, usize)> for Grid<T> {
    fn index_mut(&mut self, (x, y): (usize, usize)) -> &mut T {
        self.get_mut(x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn from_vec_checks_length() {
        assert!(Grid::from_vec(3, 2, vec![0.0f32; 5]).is_err());
        let g = Grid::from_vec(3, 2, (0..6).collect::<Vec<i32>>()).unwrap();
        assert_eq!(*g.get(2, 1), 5);
        assert_eq!(g.row(1), &[3, 4, 5]);
    }

    #[test]
    fn wrapped_and_clamped_addressing() {
        let g = Grid::from_fn(4, 3, |x, y| (x + 10 * y) as i32);
        assert_eq!(*g.get_wrapped(-1, -1), 23);
        assert_eq!(*g.get_wrapped(4, 3), 0);
        assert_eq!(*g.get_clamped(-5, 7), 20);
    }

    #[test]
    fn crop_copies_window() {
        let g = Grid::from_fn(5, 4, |x, y| (x + 10 * y) as i32);
        let c = g.crop(1, 2, 3, 2).unwrap();
        assert_eq!(c.as_slice(), &[21, 22, 23, 31, 32, 33]);
        assert!(g.crop(3, 0, 3, 1).is_err());
    }
}
