//! Maps written while they are computed (issue 43): a producer hands whole bands of rows to a
//! [`RowFeed`], and a writer thread encodes them with the ordinary row writers
//! ([`crate::io::write_png_rows`], the EXR scanline writer), which ask for rows in order. At most
//! [`QUEUED_BANDS`] bands wait, so a map of any height is written holding a few bands.
//!
//! The writers ask for rows in batches, in parallel within a batch, and never for a row far
//! behind the latest one asked for: a band is dropped once [`LAG_ROWS`] rows past its end were
//! asked for.

use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

use glam::Vec3;

use crate::encoding::NormalEncoding;
use crate::{Error, Result, io};

/// Bands that may wait for the writer before [`RowFeed::push`] blocks.
pub const QUEUED_BANDS: usize = 3;

/// Rows past a band's end the writer asks for before the band is dropped (more than the row
/// writers' batches: 64 rows for PNG, 128 for EXR).
pub const LAG_ROWS: usize = 256;

/// Rows handed from a producer to a writer thread, band by band, in order.
pub struct RowFeed<T> {
    width: usize,
    state: Mutex<Feed<T>>,
    changed: Condvar,
}

struct Feed<T> {
    /// `(first row, rows)` of the bands not yet dropped, in order.
    bands: VecDeque<(usize, Vec<T>)>,
    /// The producer is done (or gave up): rows not pushed by now never come.
    closed: bool,
    /// A row was asked for that never came (the file is then incomplete and must be discarded).
    missed: bool,
    /// The writer has ended (done, or failed): rows pushed now are dropped.
    ended: bool,
}

impl<T: Clone + Default> RowFeed<T> {
    /// A feed of rows `width` values long.
    pub fn new(width: usize) -> Self {
        let state = Feed { bands: VecDeque::new(), closed: false, missed: false, ended: false };
        RowFeed { width, state: Mutex::new(state), changed: Condvar::new() }
    }

    /// Hands over rows `first_row..` (`rows.len()` a multiple of the width), after the previous
    /// band's; waits while [`QUEUED_BANDS`] bands are waiting already. `false` when the writer
    /// has ended (a failed write): the rows are dropped, and the producer should stop.
    pub fn push(&self, first_row: usize, rows: Vec<T>) -> bool {
        let mut feed = self.state.lock().expect("a writer thread panicked");
        while feed.bands.len() >= QUEUED_BANDS && !feed.closed && !feed.ended {
            feed = self.changed.wait(feed).expect("a writer thread panicked");
        }
        if feed.ended {
            return false;
        }
        feed.bands.push_back((first_row, rows));
        self.changed.notify_all();
        true
    }

    /// The writer has ended: a producer waiting in [`Self::push`] goes on, and what it pushes is
    /// dropped.
    fn end(&self) {
        let mut feed = self.state.lock().expect("the producer panicked");
        feed.ended = true;
        feed.bands.clear();
        self.changed.notify_all();
    }

    /// No more rows come: the writer finishes (with default values where rows are missing, see
    /// [`Self::complete`]).
    pub fn close(&self) {
        self.state.lock().expect("a writer thread panicked").closed = true;
        self.changed.notify_all();
    }

    /// Whether every row the writer asked for came.
    pub fn complete(&self) -> bool {
        !self.state.lock().expect("a writer thread panicked").missed
    }

    /// Copies row `y` into `out` once it has come (default values if the feed closed without it),
    /// dropping the bands that ended [`LAG_ROWS`] rows before it.
    pub fn row(&self, y: usize, out: &mut [T]) {
        let w = self.width;
        let mut feed = self.state.lock().expect("the producer panicked");
        loop {
            let before = feed.bands.len();
            while feed.bands.front().is_some_and(|(first, rows)| first + rows.len() / w.max(1) + LAG_ROWS <= y) {
                feed.bands.pop_front();
            }
            if feed.bands.len() != before {
                self.changed.notify_all();
            }
            let band = feed.bands.iter().find(|(first, rows)| (*first..first + rows.len() / w.max(1)).contains(&y));
            if let Some((first, rows)) = band {
                out.clone_from_slice(&rows[(y - first) * w..(y - first + 1) * w]);
                return;
            }
            if feed.closed {
                feed.missed = true;
                out.iter_mut().for_each(|v| *v = T::default());
                return;
            }
            feed = self.changed.wait(feed).expect("the producer panicked");
        }
    }
}

/// Threads of a writer's own pool: its row requests wait for the producer, so they must not
/// hold the threads of the pool the producer computes on.
const WRITER_THREADS: usize = 2;

/// A file a thread writes from a [`RowFeed`] while its rows are computed. [`Self::finish`] says
/// whether it is whole; dropped unfinished (a failed or discarded run), the file is removed.
pub struct StreamedFile<T: Clone + Default + Send + Sync + 'static> {
    path: PathBuf,
    feed: Arc<RowFeed<T>>,
    writer: Option<JoinHandle<Result<()>>>,
}

impl<T: Clone + Default + Send + Sync + 'static> StreamedFile<T> {
    /// Starts writing `path` with `write`, which reads rows `width` values long from the feed.
    pub fn spawn(
        path: &Path,
        width: usize,
        write: impl FnOnce(&Path, &RowFeed<T>) -> Result<()> + Send + 'static,
    ) -> Self {
        let feed = Arc::new(RowFeed::new(width));
        let (reader, target) = (Arc::clone(&feed), path.to_owned());
        let writer = std::thread::spawn(move || {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(WRITER_THREADS).build();
            let written = match pool {
                Ok(pool) => pool.install(|| write(&target, &reader)),
                Err(e) => Err(Error::io(&target, std::io::Error::other(e))),
            };
            reader.end();
            written
        });
        StreamedFile { path: path.to_owned(), feed, writer: Some(writer) }
    }

    /// Hands over rows `first_row..` (see [`RowFeed::push`]); `false` when the writer has
    /// ended before the file was whole: [`Self::finish`] then gives its error.
    pub fn push(&self, first_row: usize, rows: Vec<T>) -> bool {
        self.feed.push(first_row, rows)
    }

    /// Waits for the writer and gives the file's path; an error when it failed or rows were
    /// missing (the file is then removed).
    ///
    /// # Errors
    /// The writer's, or an incomplete file's.
    pub fn finish(mut self) -> Result<PathBuf> {
        let written = self.join();
        let whole = self.feed.complete();
        match written {
            Ok(()) if whole => Ok(std::mem::take(&mut self.path)),
            Ok(()) => Err(Error::Encode { path: self.path.clone(), reason: "rows missing: the run stopped".into() }),
            Err(e) => Err(e),
        }
    }

    fn join(&mut self) -> Result<()> {
        self.feed.close();
        match self.writer.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(Error::Encode { path: self.path.clone(), reason: "the writer thread panicked".into() }),
            None => Ok(()),
        }
    }
}

impl<T: Clone + Default + Send + Sync + 'static> Drop for StreamedFile<T> {
    fn drop(&mut self) {
        if self.writer.is_some() {
            let _ = self.join();
        }
        if !self.path.as_os_str().is_empty() {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// A normal map written as its rows come ([`io::write_normal_rows`]).
pub fn normal_map(path: &Path, (w, h): (usize, usize), encoding: NormalEncoding, bits: u32) -> StreamedFile<Vec3> {
    StreamedFile::spawn(path, w, move |path, feed| {
        io::write_normal_rows(path, (w, h), encoding, bits, |y, row| feed.row(y, row))
    })
}

/// A colour map written as its rows come ([`io::write_color_rows`]).
pub fn color_map(path: &Path, (w, h): (usize, usize), bits: u32) -> StreamedFile<Vec3> {
    StreamedFile::spawn(path, w, move |path, feed| io::write_color_rows(path, (w, h), bits, |y, row| feed.row(y, row)))
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;

    /// A writer thread reads every row in order while the producer pushes bands of uneven
    /// heights; a feed closed early reports rows missing.
    #[test]
    fn rows_arrive_in_order_and_a_closed_feed_reports_what_is_missing() {
        let feed = Arc::new(RowFeed::<u32>::new(3));
        let reader = {
            let feed = Arc::clone(&feed);
            std::thread::spawn(move || {
                let mut row = [0u32; 3];
                (0..2000)
                    .map(|y| {
                        feed.row(y, &mut row);
                        row
                    })
                    .collect::<Vec<_>>()
            })
        };
        let mut first = 0;
        for rows in [700, 1, 600, 699] {
            feed.push(first, (first..first + rows).flat_map(|y| [y as u32, 1, 2]).collect());
            first += rows;
        }
        feed.close();
        let read = reader.join().unwrap();
        assert!(read.iter().enumerate().all(|(y, r)| *r == [y as u32, 1, 2]));
        assert!(feed.complete());
        let short = RowFeed::<u32>::new(2);
        short.push(0, vec![5; 4]);
        short.close();
        let mut row = [9u32; 2];
        short.row(1, &mut row);
        assert!(short.complete() && row == [5, 5]);
        short.row(2, &mut row);
        assert!(!short.complete() && row == [0, 0]);
    }

    /// A normal map streamed in bands is byte for byte the one written whole (PNG and EXR); one
    /// dropped before its last band leaves no file.
    #[test]
    fn a_streamed_map_is_the_map_written_whole() {
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (37, 700);
        let grid =
            crate::Grid::from_fn(w, h, |x, y| Vec3::new(x as f32 - 18.0, y as f32 * 0.01 - 3.0, 5.0).normalize());
        let map = crate::NormalMap::from_grid(grid);
        for name in ["n.png", "n.exr"] {
            let (whole, streamed) = (dir.path().join(format!("whole-{name}")), dir.path().join(name));
            io::write_normal_map(&whole, &map, NormalEncoding::default(), 16).unwrap();
            let file = normal_map(&streamed, (w, h), NormalEncoding::default(), 16);
            for rows in [0..300, 300..301, 301..700] {
                assert!(file.push(rows.start, map.as_slice()[rows.start * w..rows.end * w].to_vec()));
            }
            assert_eq!(file.finish().unwrap(), streamed);
            assert!(std::fs::read(&whole).unwrap() == std::fs::read(&streamed).unwrap(), "{name}");
        }
        let cut = dir.path().join("cut.png");
        let file = normal_map(&cut, (w, h), NormalEncoding::default(), 16);
        file.push(0, map.as_slice()[..300 * w].to_vec());
        drop(file);
        assert!(!cut.exists());
        let file = normal_map(&cut, (w, h), NormalEncoding::default(), 16);
        file.push(0, map.as_slice()[..300 * w].to_vec());
        assert!(file.finish().unwrap_err().to_string().contains("rows missing"));
        assert!(!cut.exists());
    }

    /// A writer that fails at once (its folder is missing) does not hold the producer: more
    /// bands than the queue takes are refused at once, and the file's error names it.
    #[test]
    fn a_failed_writer_refuses_rows_and_gives_its_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing").join("n.png");
        let (w, h) = (8, 64);
        let file = normal_map(&path, (w, h), NormalEncoding::default(), 16);
        let taken: Vec<bool> = (0..2 * QUEUED_BANDS + 2).map(|k| file.push(4 * k, vec![Vec3::Z; 4 * w])).collect();
        assert!(!taken.last().unwrap(), "{taken:?}");
        let error = file.finish().unwrap_err();
        assert!(error.to_string().contains("n.png"), "{error}");
        assert!(!path.exists());
    }
}
