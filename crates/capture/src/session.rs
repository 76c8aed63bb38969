//! A capture session as one library call: the files of a session ([`Session`], or
//! [`Session::from_dir`] for the folder layout `skinkit batch` reads), and [`capture`], which
//! reads and checks every input, picks near or distant lights from the rig, solves, detrends and
//! measures the result ([`CaptureReport`]). Writing the maps is left to the caller.
//!
//! # Session folders
//! A session folder holds `rig.toml`, the photos, and optionally `mask.png` (nonzero pixels are
//! the object), `ambient.png` (all lights off) and `truth.png` (a ground-truth normal map). The
//! photos are the files `filenames.txt` lists, one per line, when the folder has one (the DiLiGenT
//! layout), else every `.png`, `.tif`, `.tiff`, `.exr` and camera RAW (`.dng`, `.cr2`, `.nef`,
//! `.arw`, ...) file sorted by name except those whose stem is `mask`, `ambient` or `truth` ([`photos_in`]).
//! An entry with such a name that is not a regular file (a FIFO, a looping symlink) is skipped
//! and named ([`Session::skipped`], the report's `skipped`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::limits;
use skinkit_maps::normal::AngularStats;
use skinkit_maps::progress::Progress;
use skinkit_maps::raw::RawMode;
use skinkit_maps::{Grid, NormalEncoding, NormalMap, Photo, Transfer, Vec3};

use skinkit_height::{Height, HeightOptions, HeightReport, Scale};

use crate::solve::{self, PhotoStack, SolveConfig};
use crate::{Error, Result, Rig, detrend, near};

mod folder;
mod memory;
mod prepare;
pub use folder::{PhotoFolder, RESERVED_STEMS, Session, Skipped, photos_in};
pub use memory::memory_estimate;
pub use prepare::corrections;
use prepare::{flatten, merge_brackets, raw_reading, unscale_albedo};

/// Everything that shapes a capture besides its files.
#[derive(Clone, Debug)]
pub struct CaptureOptions {
    pub solve: SolveConfig,
    /// Side of the detrend block in pixels; 0 turns detrending off.
    pub detrend_block: usize,
    /// How 8- and 16-bit photo values relate to light (float photos are always linear).
    pub transfer: Transfer,
    /// How camera RAW photos become RGB: 2x2 Bayer binning (half size) or demosaiced.
    pub raw: RawMode,
    /// Green convention of the truth map.
    pub encoding: NormalEncoding,
    pub limits: Limits,
    /// Bytes a capture may hold at its peak ([`memory_estimate`], from the headers); a larger
    /// session is refused before anything is decoded.
    pub memory_limit: u64,
}

/// The name of a transfer curve in reports: `linear` or `srgb`.
pub fn transfer_name(transfer: Transfer) -> &'static str {
    match transfer {
        Transfer::Linear => "linear",
        Transfer::Srgb => "srgb",
    }
}

impl Default for CaptureOptions {
    /// The robust solve, the paper's 50-pixel detrend, linear photos, green-up truth.
    fn default() -> Self {
        CaptureOptions {
            solve: SolveConfig::default(),
            detrend_block: 50,
            transfer: Transfer::Linear,
            raw: RawMode::Half,
            encoding: NormalEncoding::default(),
            limits: Limits::default(),
            memory_limit: limits::default_memory_limit(),
        }
    }
}

/// The stage [`capture`] is starting, for progress displays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    Decode,
    Solve,
    Detrend,
    Statistics,
    Height,
}

impl Stage {
    /// Lowercase name: `decode`, `solve`, `detrend`, `statistics`, `height`.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Decode => "decode",
            Stage::Solve => "solve",
            Stage::Detrend => "detrend",
            Stage::Statistics => "statistics",
            Stage::Height => "height",
        }
    }
}

/// Seconds spent in each stage.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    pub decode: f64,
    pub solve: f64,
    pub detrend: f64,
    /// Report statistics (normal tilt, error against the truth).
    pub stats: f64,
    /// Integrating the normals into the height map.
    pub height: f64,
    /// Writing the outputs: 0 from [`capture`], filled in by whoever writes them.
    pub write: f64,
    /// Seconds per output file (written concurrently, so these overlap); empty from [`capture`].
    pub write_files: std::collections::BTreeMap<String, f64>,
    pub total: f64,
}

/// What a capture found: its inputs, the rig's conditioning, the solve's counts, the normals'
/// statistics and the stage timings (serialised as the CLI's `report.json`).
#[derive(Clone, Debug, Serialize)]
pub struct CaptureReport {
    pub rig: String,
    pub photos: Vec<String>,
    pub width: usize,
    pub height: usize,
    pub light_count: usize,
    /// `leastsquares` or `robust`, with ` (near lights)` when the rig's lamps are near.
    pub solver: String,
    pub condition_number: f64,
    pub noise_amplification: f64,
    pub detrend_block: usize,
    /// How photo values were read: `linear` or `srgb` ([`transfer_name`]).
    pub transfer: String,
    pub valid_pixels: usize,
    pub invalid_pixels: usize,
    /// Angle of the output normals from +Z, in degrees (how rough the captured surface is).
    pub tilt_degrees: AngularStats,
    /// Angular error against the ground truth, when one was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error_vs_truth_degrees: Option<AngularStats>,
    pub warnings: Vec<String>,
    /// Entries of the session folder that looked like inputs but were not regular files, each
    /// named with the reason ([`Session::skipped`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub skipped: Vec<String>,
    /// The rig's photo pixel size on the mold, which makes the height millimetres.
    pub mm_per_pixel: Option<f64>,
    /// The height integrated from the normals: range, unit, integrator, residual (none when no
    /// pixel could be solved).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height_map: Option<HeightReport>,
    pub timings_s: Timings,
    /// Peak resident memory of the process, in MiB: `None` from [`capture`], filled in by a
    /// caller that measures it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub peak_memory_mib: Option<f64>,
    /// Corrections applied to the photos before solving, in order (`ambient subtraction`,
    /// `flat fields (3 of 8 lights)`).
    pub corrections: Vec<String>,
}

/// A finished capture in memory.
#[derive(Clone, Debug)]
pub struct Captured {
    /// Normals (detrended), albedo and confidence.
    pub solution: solve::Solution,
    /// The normals integrated into heights (mm when the rig gives `mm_per_pixel`); none when no
    /// pixel could be solved.
    pub height: Option<Height>,
    pub report: CaptureReport,
}

/// The decoded inputs of a session.
struct Inputs {
    photos: Vec<Photo>,
    ambient: Option<Photo>,
    mask: Option<Grid<bool>>,
    truth: Option<NormalMap>,
}

/// Reads every input of `session` and checks they fit together, solves (near point lights when
/// the rig gives every lamp's position and the pixel size, else distant lights), detrends, and
/// measures the result. Writes nothing. `progress` is told each [`Stage`] by name as it starts
/// (stages of unknown length, 0 steps) and the end of the last.
///
/// # Errors
/// When a file is unreadable or the inputs do not fit together (rig and photo count, sizes,
/// formats); the message names the file.
pub fn capture(session: &Session, options: &CaptureOptions, progress: &dyn Progress) -> Result<Captured> {
    let start = Instant::now();
    let mut timings = Timings::default();
    // Rig::load's errors name the rig file; later rig errors get it as context, once.
    let rig = Rig::load(&session.rig)?;
    let in_rig = |e: Error| context(session.rig.display().to_string(), e);
    // A photo count that does not fit the rig names the folder's skipped entries (issue 42, D17):
    // a FIFO among the photos is the likely missing one.
    rig.expect_photos(session.photos.len()).map_err(|e| {
        in_rig(Error::InvalidInput(folder::with_skipped(skinkit_maps::error::one_line(&e), &session.skipped)))
    })?;
    // Solver options first, so that every error of the solve below is the rig's.
    options.solve.validate()?;
    check_rig(&session.rig, &rig, session.ambient.as_deref(), &options.solve)?;
    let conditioning = rig.conditioning();
    let mut warnings: Vec<String> = conditioning.warning().into_iter().collect();
    let ambient = ambient_frame(session, &rig);
    check_memory(session, &rig, ambient.as_ref().map(|(p, _)| p.as_path()), options)?;

    progress.start(Stage::Decode.name(), 0);
    let Stacked { stack, names, corrections, scale, truth } =
        stacked(session, &rig, ambient.as_ref(), options, &mut timings)?;
    let (width, height) = (stack.width(), stack.height());

    progress.start(Stage::Solve.name(), 0);
    let t = Instant::now();
    let (mut solution, near_lights) = solved(stack, &rig, options, scale).map_err(in_rig)?;
    timings.solve = t.elapsed().as_secs_f64();

    progress.start(Stage::Detrend.name(), 0);
    let t = Instant::now();
    detrend::detrend(&mut solution.normals, options.detrend_block);
    timings.detrend = t.elapsed().as_secs_f64();

    progress.start(Stage::Statistics.name(), 0);
    let t = Instant::now();
    let tilt = tilt_stats(&solution.normals);
    let error_vs_truth =
        truth.map(|truth| compare_with_truth(&solution.normals, truth, options.detrend_block)).transpose()?;
    let invalid = solution.stats.invalid_count;
    warnings.extend(unsolved_warning(invalid, width * height));
    timings.stats = t.elapsed().as_secs_f64();

    progress.start(Stage::Height.name(), 0);
    let t = Instant::now();
    let mm_per_pixel = rig.mm_per_pixel().map(f64::from);
    let heights = integrate_height(&solution.normals, mm_per_pixel)?;
    timings.height = t.elapsed().as_secs_f64();
    progress.finish();
    timings.total = start.elapsed().as_secs_f64();
    let solver = format!("{:?}{}", options.solve.method, if near_lights { " (near lights)" } else { "" });
    let report = CaptureReport {
        rig: session.rig.display().to_string(),
        photos: names,
        width,
        height,
        light_count: rig.light_count(),
        solver: solver.to_lowercase(),
        condition_number: conditioning.condition_number,
        noise_amplification: conditioning.noise_amplification,
        detrend_block: options.detrend_block,
        transfer: transfer_name(options.transfer).to_owned(),
        valid_pixels: width * height - invalid,
        invalid_pixels: invalid,
        tilt_degrees: tilt,
        error_vs_truth_degrees: error_vs_truth,
        warnings,
        skipped: session.skipped.iter().map(ToString::to_string).collect(),
        mm_per_pixel,
        height_map: heights.as_ref().map(|h| h.report.clone()),
        timings_s: timings,
        peak_memory_mib: None,
        corrections,
    };
    Ok(Captured { solution, height: heights, report })
}

/// Solves the stack (near point lights when the rig gives every lamp's position and the pixel
/// size, else distant lights) and undoes the flat-field rescale of the albedo; `true` with near
/// lights.
fn solved(stack: PhotoStack, rig: &Rig, options: &CaptureOptions, scale: f32) -> Result<(solve::Solution, bool)> {
    let near_lights = near::applies(rig);
    let mut solution = if near_lights {
        near::solve(&stack, rig, &options.solve)?
    } else {
        solve::solve(&stack, rig, &options.solve, &solve::NoProgress)?
    };
    drop(stack);
    unscale_albedo(&mut solution.albedo, scale);
    Ok((solution, near_lights))
}

/// The photos of a capture stacked for the solve, with what the report needs of their reading.
struct Stacked {
    stack: PhotoStack,
    names: Vec<String>,
    corrections: Vec<String>,
    scale: f32,
    truth: Option<NormalMap>,
}

/// Decodes `session`'s files (timed into `timings.decode`), merges each light's brackets,
/// corrects the flat fields and stacks the photos with the ambient frame and mask.
fn stacked(
    session: &Session,
    rig: &Rig,
    ambient: Option<&(PathBuf, String)>,
    options: &CaptureOptions,
    timings: &mut Timings,
) -> Result<Stacked> {
    let t = Instant::now();
    let inputs = decode(session, ambient.map(|(p, role)| (p.as_path(), role.as_str())), options)?;
    timings.decode = t.elapsed().as_secs_f64();
    let names: Vec<String> = session.photos.iter().map(|p| p.display().to_string()).collect();
    let mut corrections = corrections(rig, inputs.ambient.is_some());
    if session.photos.iter().any(|p| skinkit_maps::raw::is_raw(p)) {
        corrections.insert(0, raw_reading(options.raw));
    }
    let saturation = options.solve.saturation;
    let (merged, readings) = merge_brackets(rig, inputs.photos, &names, inputs.ambient.is_some(), saturation)
        .map_err(|e| context(session.rig.display().to_string(), e))?;
    let (photos, ambient_frame, scale) = flatten(rig, merged, inputs.ambient, &readings, options)?;
    let mut stack = PhotoStack::new(photos, readings)?;
    if let (Some(frame), Some((path, _))) = (ambient_frame, ambient) {
        stack = stack.with_ambient(frame, &path.display().to_string())?;
    }
    if let Some(mask) = inputs.mask {
        stack = stack.with_mask(mask)?;
    }
    Ok(Stacked { stack, names, corrections, scale, truth: inputs.truth })
}

/// The warning of a capture that left more than a tenth of its `pixels` unsolved.
fn unsolved_warning(invalid: usize, pixels: usize) -> Option<String> {
    (invalid * 10 > pixels).then(|| {
        format!(
            "{invalid} of {pixels} pixels ({:.1}%) could not be solved (shadowed, saturated or too few usable lights)",
            100.0 * invalid as f64 / pixels as f64
        )
    })
}

/// Checks a rig against everything [`capture`] refuses of a rig before decoding a photo: at most
/// [`solve::MAX_LIGHTS`] lights; for distant lights, a condition number (as the solver computes
/// it) within `config.max_condition`; the ambient frame (`ambient`, which overrides the rig's
/// own) a readable image, by its header. `skinkit rig check` calls this same function, and
/// `skinkit rig import` before it writes, so both refuse exactly the rigs `capture` refuses.
///
/// # Errors
/// [`Error::Context`] naming the rig file around the light-count or conditioning refusal, or
/// naming the ambient frame around the reason its header cannot be read.
pub fn check_rig(rig_path: &Path, rig: &Rig, ambient: Option<&Path>, config: &SolveConfig) -> Result<()> {
    let in_rig = |e| context(rig_path.display().to_string(), e);
    if near::applies(rig) {
        // The near-light solve judges each pixel's lights itself: only the count is a rig rule.
        solve::check_light_count(rig.light_count()).map_err(in_rig)?;
    } else {
        solve::check_conditioning(rig, config).map_err(in_rig)?;
    }
    let (path, whose) = match (ambient, rig.ambient()) {
        (Some(p), _) => (p, "the ambient frame".to_owned()),
        (None, Some(p)) => (p, format!("{}: field `ambient` (the ambient frame)", rig_path.display())),
        (None, None) => return Ok(()),
    };
    // Read by header, as the capture reads it first (issue 42, D13): a file that is not an image
    // (the rig file itself, say) is refused here too, not only once photos are decoded.
    limits::image_header(path, limits::MAX_IMAGE_PIXELS).map_err(|e| context(whose, e.into()))?;
    Ok(())
}

/// Refuses a session whose [`memory_estimate`] exceeds `options.memory_limit`.
fn check_memory(session: &Session, rig: &Rig, ambient: Option<&Path>, options: &CaptureOptions) -> Result<()> {
    let estimate = memory::estimate(session, Some(rig), ambient, options)?;
    let folder = session.photos[0].parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let what = format!("capturing {} photos", session.photos.len());
    limits::check_memory(&folder.display().to_string(), &what, estimate, options.memory_limit)?;
    Ok(())
}

/// The ambient frame to subtract, if any (the session's overrides the rig's), with how messages
/// name it: a missing rig ambient reads as the rig file's field, not as a photo (issue 15, D11).
fn ambient_frame(session: &Session, rig: &Rig) -> Option<(PathBuf, String)> {
    match (&session.ambient, rig.ambient()) {
        (Some(path), _) => Some((path.clone(), "ambient frame".to_owned())),
        (None, Some(path)) => {
            Some((path.to_owned(), format!("{}: field `ambient` (the ambient frame)", session.rig.display())))
        }
        (None, None) => None,
    }
}

/// The capture's height: masked where pixels are invalid, Neumann otherwise (a capture does not
/// wrap); `None` when no pixel was solved (the report says so through its counts).
fn integrate_height(normals: &NormalMap, mm_per_pixel: Option<f64>) -> Result<Option<Height>> {
    let scale = Scale::from_mm(mm_per_pixel).map_err(|e| Error::InvalidInput(e.to_string()))?;
    match skinkit_height::integrate(normals, &HeightOptions { scale, ..HeightOptions::default() }) {
        Ok(height) => Ok(Some(height)),
        Err(skinkit_height::Error::NoValidTexel { .. }) => Ok(None),
        Err(e) => Err(Error::InvalidInput(skinkit_maps::error::one_line(&e))),
    }
}

/// `cause` with what was being done when it happened.
fn context(what: String, cause: Error) -> Error {
    Error::Context { context: what, cause: Box::new(cause) }
}

/// Decodes the photos, the ambient frame (its path and its role in messages), the mask and the
/// truth map, all in parallel.
fn decode(session: &Session, ambient: Option<(&Path, &str)>, options: &CaptureOptions) -> Result<Inputs> {
    let (photos, (ambient, (mask, truth))) = rayon::join(
        || {
            let photos = session.photos.par_iter().enumerate();
            photos.map(|(i, p)| read_photo(p, &format!("photo {}", i + 1), options)).collect::<Result<Vec<_>>>()
        },
        || {
            rayon::join(
                || ambient.map(|(p, role)| read_photo(p, role, options)).transpose(),
                || {
                    rayon::join(
                        || session.mask.as_deref().map(|p| read_mask(p, &options.limits)).transpose(),
                        || session.truth.as_deref().map(|p| read_truth(p, options)).transpose(),
                    )
                },
            )
        },
    );
    Ok(Inputs { photos: photos?, ambient: ambient?, mask: mask?, truth: truth? })
}

/// Reads a photo; `role` (`photo 3`, `ambient frame`) prefixes its errors, which name the file.
fn read_photo(path: &Path, role: &str, options: &CaptureOptions) -> Result<Photo> {
    let photo =
        io::read_photo_as(path, &options.limits, options.raw).map_err(|e| context(role.to_owned(), e.into()))?;
    // The transfer applies to integer photos only: float photos are linear by definition.
    Ok(if photo.bit_depth() == 32 { photo } else { photo.with_transfer(options.transfer) })
}

/// A mask image: nonzero pixels are the object.
fn read_mask(path: &Path, limits: &Limits) -> Result<Grid<bool>> {
    let map = io::read_scalar_map(path, limits).map_err(|e| context("mask".into(), e.into()))?;
    Ok(map.map(|&v| v > 0.0))
}

fn read_truth(path: &Path, options: &CaptureOptions) -> Result<NormalMap> {
    io::read_normal_map(path, options.encoding, &options.limits).map_err(|e| context("ground truth".into(), e.into()))
}

/// Angular error of `normals` against a ground-truth map, the truth detrended with the same
/// `block` as the capture so the two describe the same (fine-scale) surface.
///
/// # Errors
/// [`Error::InvalidInput`] when the sizes differ.
pub fn compare_with_truth(normals: &NormalMap, mut truth: NormalMap, block: usize) -> Result<AngularStats> {
    if truth.size() != normals.size() {
        return Err(Error::InvalidInput(format!(
            "ground truth is {}x{} but the photos are {}x{}",
            truth.width(),
            truth.height(),
            normals.width(),
            normals.height()
        )));
    }
    detrend::detrend(&mut truth, block);
    Ok(normals.angular_error(&truth, None)?)
}

/// Angles of the valid normals from +Z.
fn tilt_stats(normals: &NormalMap) -> AngularStats {
    AngularStats::from_slice(normals.as_slice(), |&n| (n != Vec3::ZERO).then(|| tilt_degrees(n)))
}

/// Angle of a unit vector from +Z in degrees (atan2 form: exact near zero, unlike acos).
fn tilt_degrees(n: Vec3) -> f32 {
    n.truncate().length().atan2(n.z).to_degrees()
}
