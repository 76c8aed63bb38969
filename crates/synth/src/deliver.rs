//! A growth written to its files as its bands finish (issue 43): the map and its coordinate map
//! are streamed ([`skinkit_maps::stream`]), so a job holds its coarser levels and a band or two
//! of the finest, never the whole output.
//!
//! The quality figures are measured as the rows pass where that is cheap (the guards, the
//! wrap-around seam, invalid texels) and otherwise on a crop: the whole output up to
//! [`QUALITY_SIDE`] texels a side, else its central `QUALITY_SIDE x QUALITY_SIDE` texels (the
//! spectra, histograms and copied blocks of a larger output are those of its centre).
//!
//! Each growth (a guard may grow the output twice) writes files of its own beside the targets
//! (`.attempt<n>.<name>`); the kept growth's are renamed onto the targets, the other's removed.

use std::path::{Path, PathBuf};

use skinkit_maps::progress::Progress;
use skinkit_maps::stream::{self, StreamedFile};
use skinkit_maps::{Grid, NormalEncoding, NormalMap, Vec3};

use crate::map::Map;
use crate::metrics::SeamMeter;
use crate::report::QualityReport;
use crate::{BandSink, Delivery, Guards, Result, Streamed, SynthConfig};

/// The largest side of the crop the quality figures are measured on.
pub const QUALITY_SIDE: usize = 2048;

/// Where a streamed growth writes: the map (PNG at 16 bits or EXR float, as [`Map::write`]) and,
/// if asked, the coordinate map ([`crate::coords`]).
#[derive(Clone, Debug)]
pub struct Files {
    pub map: PathBuf,
    /// How normals are stored (colour maps ignore it).
    pub encoding: NormalEncoding,
    pub coords: Option<PathBuf>,
}

pub use crate::error::Output;

/// What a streamed growth gives besides its files.
#[derive(Clone, Debug)]
pub struct Delivered {
    pub warnings: Vec<String>,
    /// Wall-clock seconds per level, `[0]` the finest.
    pub level_seconds: Vec<f64>,
    pub guards: Guards,
    /// The quality figures (see the module's docs for which are measured on a crop).
    pub quality: QualityReport,
    /// Invalid (zero) normals in the output; 0 for colour maps.
    pub invalid_texels: usize,
}

/// Grows `exemplar` under `config` into `files`, telling `progress` as [`crate::synthesize`] does.
///
/// # Errors
/// As [`crate::synthesize`] and [`crate::synthesize_normals`], and when a file cannot be written
/// (nothing is left at its target then).
pub fn grow_into_files(
    exemplar: &Map,
    config: &SynthConfig,
    progress: &dyn Progress,
    files: &Files,
) -> Result<Delivered> {
    let config = &SynthConfig { delivery: Delivery::Streamed { coords: files.coords.is_some() }, ..config.clone() };
    let mut attempts = 0;
    let mut open = || {
        attempts += 1;
        Ok(FileSink::new(exemplar, config, files, attempts))
    };
    let s: Streamed<FileSink> = match exemplar {
        Map::Normal(n) => crate::synthesize_normals_streamed(n, config, progress, &mut open)?,
        Map::Color(c) => crate::synthesize_streamed(c, config, progress, &mut open)?,
    };
    let Streamed { sink, warnings, level_seconds, guards } = s;
    let (crop, crop_coords, seam, invalid_texels) = sink.finish()?;
    let mut quality = QualityReport::new(exemplar, &crop, &crop_coords, config.exemplar_wrap, guards)
        .expect("the crop has the exemplar's kind");
    quality.seam_energy_ratio = seam;
    Ok(Delivered { warnings, level_seconds, guards, quality, invalid_texels })
}

/// `target`'s file for growth `n`, beside it.
fn attempt_path(target: &Path, n: usize) -> PathBuf {
    let name = target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    target.with_file_name(format!(".attempt{n}.{name}"))
}

/// `error`, from writing `output`'s attempt file or moving it onto `target`, as a
/// [`crate::Error::Write`] naming `target`: the attempt's file is an internal name.
fn write_error(output: Output, target: &Path, error: skinkit_maps::Error) -> crate::Error {
    use skinkit_maps::Error as E;
    let source = match error {
        E::Io { error, .. } => E::Io { path: target.to_owned(), error },
        E::Encode { reason, .. } => E::Encode { path: target.to_owned(), reason },
        E::Output { source, .. } => E::Output { path: target.to_owned(), source },
        other => other,
    };
    crate::Error::Write { output, source }
}

/// One of a growth's files: what it is, where it goes, and its writer (taken when it ends).
struct Target<T: Clone + Default + Send + Sync + 'static> {
    output: Output,
    path: PathBuf,
    file: Option<StreamedFile<T>>,
}

impl<T: Clone + Default + Send + Sync + 'static> Target<T> {
    /// Hands rows to the writer; its error, naming the target, when it has failed.
    fn push(&mut self, first_row: usize, rows: Vec<T>) -> Result<()> {
        let file = self.file.as_ref().expect("a target ends once");
        if file.push(first_row, rows) {
            return Ok(());
        }
        match self.finish() {
            Err(e) => Err(e),
            Ok(_) => unreachable!("a writer that took every row refused one more"),
        }
    }

    /// Waits for the writer, and gives its file's path, or its error naming the target.
    fn finish(&mut self) -> Result<PathBuf> {
        let file = self.file.take().expect("a target ends once");
        file.finish().map_err(|e| write_error(self.output, &self.path, e))
    }

    /// Moves the finished file `from` onto the target.
    fn place(&self, from: &Path) -> Result<()> {
        let failed = |error| write_error(self.output, &self.path, skinkit_maps::Error::Io { path: from.into(), error });
        std::fs::rename(from, &self.path).map_err(failed)
    }
}

/// One growth's files and measures.
struct FileSink {
    normals: bool,
    size: (usize, usize),
    map: Target<Vec3>,
    coords: Option<Target<[u32; 2]>>,
    /// The crop's columns and rows, and its texels and coordinates so far.
    crop: ((usize, usize), (usize, usize)),
    crop_texels: Vec<Vec3>,
    crop_coords: Vec<[u32; 2]>,
    seam: SeamMeter<fn(Vec3) -> bool>,
    invalid: usize,
}

impl FileSink {
    fn new(exemplar: &Map, config: &SynthConfig, files: &Files, n: usize) -> Self {
        let (normals, size) = (matches!(exemplar, Map::Normal(_)), (config.width, config.height));
        let path = attempt_path(&files.map, n);
        let (output, file) = if normals {
            (Output::NormalMap, stream::normal_map(&path, size, files.encoding, 16))
        } else {
            (Output::ColourImage, stream::color_map(&path, size, 16))
        };
        let map = Target { output, path: files.map.clone(), file: Some(file) };
        let coords = files.coords.as_ref().map(|c| Target {
            output: Output::CoordinateMap,
            path: c.clone(),
            file: Some(crate::coords::stream(&attempt_path(c, n), size)),
        });
        let side = |s: usize| (s.saturating_sub(QUALITY_SIDE) / 2, s.min(QUALITY_SIDE));
        let valid: fn(Vec3) -> bool = if normals { |v| v != Vec3::ZERO } else { |_| true };
        let crop = (side(size.0), side(size.1));
        // Reserved whole: a crop grown by doubling would hold up to three times its size.
        let crop_texels = crop.0.1 * crop.1.1;
        FileSink {
            normals,
            size,
            map,
            coords,
            crop,
            crop_texels: Vec::with_capacity(crop_texels),
            crop_coords: Vec::with_capacity(crop_texels),
            seam: SeamMeter::new(size, valid),
            invalid: 0,
        }
    }

    /// Waits for the files, moves them onto their targets, and gives the crop as a map, its
    /// coordinates, the seam energy ratio and the invalid texels.
    fn finish(mut self) -> Result<(Map, Grid<[u32; 2]>, f64, usize)> {
        let written = self.map.finish()?;
        let placed = self.coords.as_mut().map(Target::finish).transpose().and_then(|coords_written| {
            self.map.place(&written)?;
            match (coords_written, &self.coords) {
                (Some(from), Some(target)) => target.place(&from).inspect_err(|_| drop(std::fs::remove_file(&from))),
                _ => Ok(()),
            }
        });
        // A finished file is no longer removed by its writer: a failure after it removes it here.
        placed.inspect_err(|_| drop(std::fs::remove_file(&written)))?;
        let ((_, cw), (_, ch)) = self.crop;
        let texels = Grid::from_vec(cw, ch, self.crop_texels)?;
        let crop = if self.normals { Map::Normal(NormalMap::from_unit_grid(texels)?) } else { Map::Color(texels) };
        let coords = Grid::from_vec(cw, ch, self.crop_coords)?;
        Ok((crop, coords, self.seam.finish().ratio, self.invalid))
    }
}

impl BandSink for FileSink {
    fn band(&mut self, first_row: usize, texels: Grid<Vec3>, coords: Grid<[u32; 2]>) -> Result<()> {
        debug_assert!(texels.width() == self.size.0 && first_row + texels.height() <= self.size.1);
        self.seam.add(texels.as_slice());
        if self.normals {
            self.invalid += texels.as_slice().iter().filter(|v| **v == Vec3::ZERO).count();
        }
        let ((x0, cw), (y0, ch)) = self.crop;
        for y in (first_row..first_row + texels.height()).filter(|y| (y0..y0 + ch).contains(y)) {
            let row = y - first_row;
            self.crop_texels.extend_from_slice(&texels.row(row)[x0..x0 + cw]);
            self.crop_coords.extend_from_slice(&coords.row(row)[x0..x0 + cw]);
        }
        self.map.push(first_row, texels.into_vec())?;
        if let Some(target) = &mut self.coords {
            target.push(first_row, coords.into_vec())?;
        }
        Ok(())
    }
}
