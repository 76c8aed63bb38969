//! The resource policy: every size a file or a flag can ask for, with its limit, in one place.
//!
//! Each limit is checked from what is known before the work starts (an image's header, a
//! layout's numbers, a flag's value), with overflow-free arithmetic, before anything of that size
//! is allocated, and the refusal names the file or flag and the limit.
//!
//! | what | limit | where it is checked |
//! | --- | --- | --- |
//! | one image (photo, mask, exemplar, map) | [`MAX_IMAGE_PIXELS`] | [`image_header`], [`crate::io::Limits`] |
//! | a face map (`size`, `--size`) | [`MAX_MAP_TEXELS`] | `skinkit_stitch::layout` |
//! | an exemplar resampled to a face map's scale | [`MAX_EXEMPLAR_TEXELS`] | `skinkit_stitch::compose` |
//! | a mask or map compared with another size | its header, before decoding | [`image_header`] |
//! | lights in a rig | [`MAX_LIGHTS`] | `skinkit_capture::session::check_rig` |
//! | images per camera of `render --orbit --frames` | [`MAX_FRAMES`] | the CLI's flag parser |
//! | worker threads (`--threads`) | [`max_threads`] | the CLI's flag parser |
//! | the memory of one job (a photo stack and its maps, a synthesis, a face) | [`default_memory_limit`] or `--memory-limit` | estimates from headers |
//! | sessions a batch runs at once | their estimates must fit the memory limit together | [`MemoryGate`] |
//! | bytes of every file read, by kind (a regular file only) | [`crate::input::Kind::limit`] | [`crate::input::open`] |

use std::fs::File;
use std::io::BufReader;
use std::path::Path;
use std::sync::{Condvar, Mutex};

use crate::{Error, Result};

/// Largest image any reader decodes: 16384 x 16384 pixels (four times a 4096 x 4096 photo's side).
pub const MAX_IMAGE_PIXELS: u64 = 16384 * 16384;
/// Largest face map: 2^30 texels (32768 x 32768).
pub const MAX_MAP_TEXELS: u64 = 1 << 30;
/// Largest exemplar after resampling to a face map's scale (as large as any image read).
pub const MAX_EXEMPLAR_TEXELS: u64 = MAX_IMAGE_PIXELS;
/// Most lights in a rig: the solver keeps a pixel's usable lights as the bits of a `u128`.
pub const MAX_LIGHTS: usize = 128;
/// Most images per camera of a turntable render (`--frames`): ten per degree.
pub const MAX_FRAMES: usize = 3600;
/// Worker threads allowed per available core (`--threads`; see [`max_threads`]).
pub const THREADS_PER_CORE: usize = 4;
/// [`max_threads`] on a machine with few cores.
pub const MIN_MAX_THREADS: usize = 16;
/// The default memory limit as a fraction of the machine's memory (`MemTotal`).
pub const DEFAULT_MEMORY_FRACTION: f64 = 0.5;
/// The default memory limit where the machine's memory cannot be read (no `/proc/meminfo`).
pub const FALLBACK_MEMORY_LIMIT: u64 = 8 << 30;

/// Most worker threads `--threads` accepts: [`THREADS_PER_CORE`] per available core, at least
/// [`MIN_MAX_THREADS`]. More only adds start-up time and memory (10000 threads ran past a minute
/// for a 0.03 s capture).
pub fn max_threads() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    cores.saturating_mul(THREADS_PER_CORE).max(MIN_MAX_THREADS)
}

/// The machine's memory in bytes (`MemTotal` of `/proc/meminfo`), where it can be read.
pub fn machine_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    parse_meminfo(&text)
}

/// `MemTotal` of a `/proc/meminfo` text, in bytes.
fn parse_meminfo(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let mut words = line.split_whitespace().skip(1);
    let value: u64 = words.next()?.parse().ok()?;
    match words.next() {
        Some("kB") | None => value.checked_mul(1024),
        _ => None,
    }
}

/// The memory limit when none is given: [`DEFAULT_MEMORY_FRACTION`] of the machine's memory, or
/// [`FALLBACK_MEMORY_LIMIT`] where that cannot be read.
pub fn default_memory_limit() -> u64 {
    machine_memory().map_or(FALLBACK_MEMORY_LIMIT, |m| (m as f64 * DEFAULT_MEMORY_FRACTION) as u64)
}

/// Parses a memory size: bytes (`1000000`), binary units (`512K`, `800M`, `12G`, `1T`, also
/// written `MiB`/`GB`...; fractions such as `1.5G` allowed), or a percentage of the machine's
/// memory (`75%`). The result must be at least 1 MiB.
///
/// # Errors
/// A message (for the flag parser) when the text is not such a size.
pub fn parse_bytes(text: &str) -> std::result::Result<u64, String> {
    let bad = || {
        format!("`{text}` is not a memory size: give bytes, a size such as 800M or 12G, or a percentage such as 50%")
    };
    let t = text.trim();
    let bytes = if let Some(percent) = t.strip_suffix('%') {
        let p: f64 = percent.trim().parse().map_err(|_| bad())?;
        if !(p > 0.0 && p <= 100.0) {
            return Err(format!("`{text}`: a percentage of the machine's memory must be in (0, 100]"));
        }
        let total = machine_memory().ok_or_else(|| format!("`{text}`: the machine's memory is unknown here"))?;
        total as f64 * p / 100.0
    } else {
        let digits = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
        let (number, unit) = t.split_at(digits);
        let value: f64 = number.parse().map_err(|_| bad())?;
        let scale = match unit.trim().to_ascii_lowercase().as_str() {
            "" | "b" => 1u64,
            "k" | "kb" | "kib" => 1 << 10,
            "m" | "mb" | "mib" => 1 << 20,
            "g" | "gb" | "gib" => 1 << 30,
            "t" | "tb" | "tib" => 1 << 40,
            _ => return Err(bad()),
        };
        value * scale as f64
    };
    if !bytes.is_finite() || bytes >= u64::MAX as f64 {
        return Err(bad());
    }
    if bytes < (1u64 << 20) as f64 {
        return Err(format!("`{text}` is below the smallest memory limit, 1M"));
    }
    Ok(bytes as u64)
}

/// `bytes` in MiB, rounded up (for messages).
pub fn mib(bytes: u64) -> u64 {
    bytes.div_ceil(1 << 20)
}

/// Refuses an estimate over the memory limit: `subject` names the file (or flag) and `what`
/// the job.
///
/// # Errors
/// [`Error::OverBudget`] when `estimate > limit`.
pub fn check_memory(subject: &str, what: &str, estimate: u64, limit: u64) -> Result<()> {
    if estimate > limit {
        return Err(Error::OverBudget { subject: subject.into(), what: what.into(), estimate, limit });
    }
    Ok(())
}

/// `width * height` when both are positive and the product is at most `max`.
///
/// # Errors
/// [`Error::TooLarge`] naming `path` otherwise (an overflowing product is over any limit).
pub fn check_pixels(path: &Path, width: u64, height: u64, max: u64) -> Result<u64> {
    if width == 0 || height == 0 {
        return Err(Error::decode(path, format!("image has zero size ({width}x{height})")));
    }
    match width.checked_mul(height) {
        Some(n) if n <= max => Ok(n),
        _ => Err(Error::TooLarge { path: path.to_owned(), width, height, max_pixels: max }),
    }
}

/// What an image's header says, read without decoding its pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageHeader {
    pub width: u64,
    pub height: u64,
    /// Channels in the file, alpha included.
    pub channels: u8,
    /// Whether one of the channels is alpha (dropped on decoding).
    pub alpha: bool,
    /// Bytes per stored sample after decoding (1, 2 or 4).
    pub sample_bytes: u8,
}

impl ImageHeader {
    /// Pixels of the image.
    pub fn pixels(&self) -> u64 {
        self.width.saturating_mul(self.height)
    }

    /// Bytes the decoded photo holds ([`crate::Photo`]: native samples, alpha dropped) plus,
    /// for images with alpha, the decoder's buffer it is converted from.
    pub fn decoded_bytes(&self) -> u64 {
        let kept = u64::from(self.channels - u8::from(self.alpha)).max(1);
        let transient = if self.alpha { u64::from(self.channels) } else { 0 };
        self.pixels().saturating_mul((kept + transient) * u64::from(self.sample_bytes))
    }
}

/// Reads the header of a PNG, TIFF or EXR image and checks its size against `max_pixels`,
/// without decoding the pixels.
///
/// # Errors
/// When the file cannot be opened, is not a supported image, or is empty or over the limit
/// ([`Error::TooLarge`] naming the file).
pub fn image_header(path: &Path, max_pixels: u64) -> Result<ImageHeader> {
    image_header_as(path, max_pixels, crate::raw::RawMode::default())
}

/// As [`image_header`], with camera RAW files described as [`crate::io::read_photo_as`] reads
/// them in `raw` mode (the sensor's size is what is checked against `max_pixels`).
///
/// # Errors
/// As [`image_header`].
pub fn image_header_as(path: &Path, max_pixels: u64, raw: crate::raw::RawMode) -> Result<ImageHeader> {
    if crate::raw::is_raw(path) {
        return crate::raw::header(path, max_pixels, raw);
    }
    // The same signature rules as the decoders (JPEG refused with its reason, a name that says
    // another format), so a header read first gives the error the decode would have given.
    let mut file = crate::io::open_buffered(path)?;
    crate::signature::check_reader(path, &mut file)?;
    if let Some(found) = crate::tiff_grey::probe(path, &mut file)? {
        let header = found.header();
        check_pixels(path, header.width, header.height, max_pixels)?;
        return Ok(header);
    }
    let header = if crate::format::ImageFormat::of(path) == Some(crate::format::ImageFormat::Exr) {
        exr_header(path, file, max_pixels)?
    } else {
        raster_header(path, file)?
    };
    check_pixels(path, header.width, header.height, max_pixels)?;
    Ok(header)
}

fn raster_header(path: &Path, file: BufReader<File>) -> Result<ImageHeader> {
    use image::ImageDecoder;
    let reader = image::ImageReader::new(file).with_guessed_format().map_err(|e| Error::io(path, e))?;
    if reader.format().is_none() {
        return Err(Error::decode(path, "unrecognised file signature (expected PNG, TIFF or EXR)"));
    }
    let decoder = reader.into_decoder().map_err(|e| Error::image(path, e))?;
    let (width, height) = decoder.dimensions();
    let color = decoder.color_type();
    let channels = color.channel_count();
    Ok(ImageHeader {
        width: u64::from(width),
        height: u64::from(height),
        channels,
        alpha: color.has_alpha(),
        sample_bytes: color.bytes_per_pixel() / channels.max(1),
    })
}

fn exr_header(path: &Path, file: BufReader<File>, max_pixels: u64) -> Result<ImageHeader> {
    let (width, height) = exr_read_size(path, file, max_pixels, false)?;
    // The EXR reader keeps three f32 channels (missing ones are 0, alpha is dropped).
    Ok(ImageHeader { width: width as u64, height: height as u64, channels: 3, alpha: false, sample_bytes: 4 })
}

/// The size of the part of an EXR file the reader decodes (the first with R, G and B channels,
/// else the first), after checking every part against `max_pixels`: a multi-part file's decoder
/// may allocate for any part, so a small first part must not let a huge second one through.
///
/// # Errors
/// When the header cannot be read, the file has no part, or a part is empty or over the limit.
/// With `need_rgb`, a file without a part holding R, G and B is refused, naming its channels
/// (issue 42, D16: the decoder's own words were "no layer ... matched your requirements").
pub(crate) fn exr_read_size(
    path: &Path,
    file: impl std::io::Read,
    max_pixels: u64,
    need_rgb: bool,
) -> Result<(usize, usize)> {
    let meta = exr::meta::MetaData::read_from_buffered(file, false).map_err(|e| Error::decode(path, e))?;
    for header in &meta.headers {
        check_pixels(path, header.layer_size.width() as u64, header.layer_size.height() as u64, max_pixels)?;
    }
    let has = |header: &exr::meta::header::Header, name: &str| header.channels.list.iter().any(|c| c.name.eq(name));
    let rgb = meta.headers.iter().find(|h| has(h, "R") && has(h, "G") && has(h, "B"));
    if need_rgb && rgb.is_none() {
        let names: Vec<String> =
            meta.headers.iter().flat_map(|h| h.channels.list.iter().map(|c| c.name.to_string())).collect();
        let reason = format!("an EXR photo or map needs R, G and B channels; this one has {}", names.join(", "));
        return Err(Error::Unsupported { path: path.to_owned(), reason });
    }
    let read = rgb.or(meta.headers.first());
    let size = read.ok_or_else(|| Error::decode(path, "no layer"))?.layer_size;
    Ok((size.width(), size.height()))
}

/// Admits jobs whose memory estimates fit a budget together: [`MemoryGate::acquire`] waits
/// until the job's estimate fits beside those running, so a batch runs fewer jobs at once
/// rather than failing. A job larger than the whole budget is refused ([`MemoryGate::fits`])
/// rather than queued, since it could never start.
#[derive(Debug)]
pub struct MemoryGate {
    budget: u64,
    state: Mutex<GateState>,
    freed: Condvar,
}

#[derive(Debug, Default)]
struct GateState {
    in_use: u64,
    running: usize,
    peak_running: usize,
    peak_in_use: u64,
}

/// A job admitted by a [`MemoryGate`]; its estimate is returned to the gate when it is dropped.
#[derive(Debug)]
pub struct Admission<'g> {
    gate: &'g MemoryGate,
    bytes: u64,
}

impl MemoryGate {
    /// A gate admitting at most `budget` bytes of estimates at once.
    pub fn new(budget: u64) -> Self {
        MemoryGate { budget, state: Mutex::new(GateState::default()), freed: Condvar::new() }
    }

    /// The budget.
    pub fn budget(&self) -> u64 {
        self.budget
    }

    /// Whether a job of `bytes` can ever be admitted.
    pub fn fits(&self, bytes: u64) -> bool {
        bytes <= self.budget
    }

    /// Waits until `bytes` fit beside the jobs running, then admits the job.
    ///
    /// # Panics
    /// When `bytes` exceeds the whole budget (check [`MemoryGate::fits`] first: such a job would
    /// wait forever).
    pub fn acquire(&self, bytes: u64) -> Admission<'_> {
        assert!(self.fits(bytes), "a job of {bytes} bytes can never fit a budget of {}", self.budget);
        let mut state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        while state.in_use + bytes > self.budget {
            state = self.freed.wait(state).unwrap_or_else(|e| e.into_inner());
        }
        state.in_use += bytes;
        state.running += 1;
        state.peak_running = state.peak_running.max(state.running);
        state.peak_in_use = state.peak_in_use.max(state.in_use);
        Admission { gate: self, bytes }
    }

    /// The most jobs that ran at once, and the largest sum of their estimates.
    pub fn peaks(&self) -> (usize, u64) {
        let state = self.state.lock().unwrap_or_else(|e| e.into_inner());
        (state.peak_running, state.peak_in_use)
    }
}

/// Runs `job` on every item from `workers` threads of its own (outside the rayon pool, so a job
/// waiting at a [`MemoryGate`] blocks its own thread, never a pool worker the running jobs need),
/// items taken in order; the results come back in item order.
pub fn run_queued<T: Sync, R: Send>(items: &[T], workers: usize, job: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let next = std::sync::atomic::AtomicUsize::new(0);
    let results: Vec<Mutex<Option<R>>> = items.iter().map(|_| Mutex::new(None)).collect();
    std::thread::scope(|scope| {
        for _ in 0..workers.clamp(1, items.len().max(1)) {
            scope.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(item) = items.get(i) else { break };
                    let result = job(item);
                    *results[i].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
                }
            });
        }
    });
    results
        .into_iter()
        .map(|r| r.into_inner().unwrap_or_else(|e| e.into_inner()).expect("every item was taken by a worker"))
        .collect()
}

impl Drop for Admission<'_> {
    fn drop(&mut self) {
        let mut state = self.gate.state.lock().unwrap_or_else(|e| e.into_inner());
        state.in_use -= self.bytes;
        state.running -= 1;
        drop(state);
        self.gate.freed.notify_all();
    }
}

/// The process's peak resident set (Linux's `VmHWM`) in MiB, where `/proc` exposes it: what
/// reports give as the memory a run took.
pub fn peak_resident_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

#[cfg(test)]
mod tests;
