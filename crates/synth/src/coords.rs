//! The coordinate-map file: which exemplar texel every output texel copies, as a 16-bit RGB PNG
//! (R = exemplar x, G = exemplar y, B = 0, linear: no transfer curve), so that any map of the
//! exemplar's size can be laid out the same way later ([`crate::replay`]).

use std::path::Path;

use skinkit_maps::io::{self, Limits, PngColour, PngLayout};
use skinkit_maps::stream::StreamedFile;
use skinkit_maps::{Channels, Error, Grid, Result, Samples};

/// The largest exemplar side a coordinate map can address (16-bit samples).
pub const MAX_COORD_SIDE: usize = u16::MAX as usize;

/// Writes `coords` to `path`; every coordinate must be under [`MAX_COORD_SIDE`].
pub fn write(path: &Path, coords: &Grid<[u32; 2]>) -> Result<()> {
    let (w, h) = coords.size();
    if let Some(c) = coords.as_slice().iter().find(|c| c[0] as usize > MAX_COORD_SIDE || c[1] as usize > MAX_COORD_SIDE)
    {
        return Err(Error::Encode {
            path: path.to_owned(),
            reason: format!("exemplar texel ({}, {}) does not fit a 16-bit coordinate map", c[0], c[1]),
        });
    }
    io::write_png_rows(path, w, h, PngLayout::Rgb16, PngColour::Linear, |y, row| {
        for (px, c) in row.chunks_exact_mut(3).zip(coords.row(y)) {
            px.copy_from_slice(&[c[0] as u16, c[1] as u16, 0]);
        }
    })
}

/// A coordinate map of a `w x h` output written as its rows come ([`skinkit_maps::stream`]), as
/// [`write()`] writes it whole. The coordinates must be under [`MAX_COORD_SIDE`] (the exemplar's
/// sides, checked before a run starts).
pub fn stream(path: &Path, (w, h): (usize, usize)) -> StreamedFile<[u32; 2]> {
    StreamedFile::spawn(path, w, move |path, feed| {
        io::write_png_rows(path, w, h, PngLayout::Rgb16, PngColour::Linear, |y, row| {
            let mut coords = vec![[0u32; 2]; w];
            feed.row(y, &mut coords);
            for (px, c) in row.chunks_exact_mut(3).zip(&coords) {
                px.copy_from_slice(&[
                    c[0].min(MAX_COORD_SIDE as u32) as u16,
                    c[1].min(MAX_COORD_SIDE as u32) as u16,
                    0,
                ]);
            }
        })
    })
}

/// Reads a coordinate map written by [`write()`].
pub fn read(path: &Path) -> Result<Grid<[u32; 2]>> {
    let photo = io::read_photo(path, &Limits::default())?;
    let (Channels::Rgb, Samples::U16(samples)) = (photo.channels(), photo.samples()) else {
        return Err(Error::Unsupported {
            path: path.to_owned(),
            reason: format!(
                "not a coordinate map (expected a 16-bit RGB PNG from `skinkit synth --coords`, got {}-bit {:?})",
                photo.bit_depth(),
                photo.channels()
            ),
        });
    };
    let texels = samples.chunks_exact(3).map(|c| [c[0] as u32, c[1] as u32]).collect();
    Grid::from_vec(photo.width(), photo.height(), texels)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coordinate_map_reads_back_as_written_and_a_colour_image_is_refused() {
        let dir = std::env::temp_dir().join(format!("skinkit-coords-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let coords = Grid::from_fn(5, 3, |x, y| [(x * 7919 + y) as u32 % 65_536, (y * 31 + x) as u32]);
        let path = dir.join("coords.png");
        write(&path, &coords).unwrap();
        assert_eq!(read(&path).unwrap().as_slice(), coords.as_slice());
        let grey = dir.join("grey.png");
        io::write_scalar_png(&grey, &Grid::from_fn(4, 4, |x, _| x as f32 / 4.0), 16).unwrap();
        let e = read(&grey).unwrap_err().to_string();
        assert!(e.contains("grey.png") && e.contains("not a coordinate map"), "{e}");
        let too_far = Grid::from_fn(2, 2, |_, _| [70_000, 0]);
        assert!(write(&dir.join("far.png"), &too_far).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
