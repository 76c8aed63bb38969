//! `skinkit capture`: photos of a mold under a known rig -> normal, albedo and confidence maps.

use std::path::{Path, PathBuf};

use anyhow::Result;
use skinkit_capture::session::{self, Session};

use crate::output::Output;
use crate::solve_flags::SolveArgs;
use skinkit_maps::progress::Progress;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Light rig file (TOML) whose lights are in the same order as the photos.
    #[arg(long, value_name = "RIG")]
    pub rig: PathBuf,
    /// Output folder: normal.exr, normal.png, albedo.png, confidence.png, report.json.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Photos in rig order (PNG or TIFF, 8 or 16-bit, grey or RGB; float EXR; or camera RAW).
    #[arg(value_name = "PHOTO", required_unless_present = "photos_from", conflicts_with = "photos_from")]
    pub photos: Vec<PathBuf>,
    /// Take the photos from a folder instead: in the order of its filenames.txt if it has one
    /// (DiLiGenT), else sorted by file name (files named mask.*, ambient.* and truth.* are not
    /// photos).
    #[arg(long, value_name = "DIR")]
    pub photos_from: Option<PathBuf>,
    /// Object mask (PNG): only nonzero pixels are solved.
    #[arg(long, value_name = "PNG")]
    pub mask: Option<PathBuf>,
    /// Ambient frame (all lights off) subtracted from every photo; overrides the rig's.
    #[arg(long, value_name = "PHOTO")]
    pub ambient: Option<PathBuf>,
    /// Ground-truth normal map: adds the angular error to the report.
    #[arg(long, value_name = "MAP")]
    pub truth: Option<PathBuf>,
    #[command(flatten)]
    pub solve: SolveArgs,
}

/// Refuses, before any work, an `--out` that is a file, the folder holding the photos (the maps
/// would be taken for photos by the next run from that folder: refusing is clearer than a photo
/// discovery that guesses which files are skinkit's, and keeps a session folder a session), or
/// whose files would replace an input. A sub-folder of the photo folder is fine: photos are files.
pub fn check_out(out: &Path, photos_from: Option<&Path>, files: &Session) -> Result<()> {
    skinkit_maps::gate::out_folder("--out", out)?;
    let photo_folders = files.photos.iter().map(|p| p.parent().filter(|d| !d.as_os_str().is_empty()));
    let folders = photos_from.into_iter().chain(photo_folders.map(|d| d.unwrap_or(Path::new("."))));
    for folder in folders {
        if skinkit_maps::gate::resolve(folder) == skinkit_maps::gate::resolve(out) {
            return Err(crate::output::usage(format!(
                "--out {} is the folder of the photos: the maps would be taken for photos by the next run; choose another folder",
                out.display()
            )));
        }
    }
    let mut inputs = vec![("the rig".to_owned(), files.rig.clone())];
    inputs.extend(files.photos.iter().enumerate().map(|(i, p)| (format!("photo {}", i + 1), p.clone())));
    for (what, path) in
        [("the mask", &files.mask), ("the ambient frame", &files.ambient), ("the truth map", &files.truth)]
    {
        inputs.extend(path.iter().map(|p| (what.to_owned(), p.clone())));
    }
    let outputs: Vec<PathBuf> = skinkit_capture::outputs::FILES.iter().map(|f| out.join(f)).collect();
    let flags: Vec<(&str, &Path)> = outputs.iter().map(|p| ("--out", p.as_path())).collect();
    Ok(skinkit_maps::gate::not_an_input(&flags, &inputs)?)
}

pub fn run(args: Args, out: &Output) -> Result<i32> {
    let options = args.solve.options(out)?;
    let folder = match &args.photos_from {
        Some(dir) => session::photos_in(dir)?,
        None => session::PhotoFolder { photos: args.photos.clone(), skipped: Vec::new() },
    };
    for skipped in &folder.skipped {
        out.note(format!("note: skipped {skipped}"));
    }
    let (photos, skipped) = (folder.photos, folder.skipped);
    let files = Session { rig: args.rig, photos, mask: args.mask, ambient: args.ambient, truth: args.truth, skipped };
    check_out(&args.out, args.photos_from.as_deref(), &files)?;
    let set = skinkit_capture::outputs::output_set(&args.out)?;
    let bar = out.progress(0, "capture");
    let mut captured = session::capture(&files, &options, &bar)?;
    bar.start("write", 0);
    let swept = skinkit_capture::outputs::write(set, &mut captured, &options)?;
    bar.clear();
    out.swept(&swept);
    for w in &captured.report.warnings {
        out.warn(w);
    }
    let r = &captured.report;
    out.result(r, || {
        let mut s = format!(
            "{}: {}x{}, {} lights (condition {:.2}), {} invalid pixels, normals tilt {:.2} deg rms, {:.2} s",
            args.out.display(),
            r.width,
            r.height,
            r.light_count,
            r.condition_number,
            r.invalid_pixels,
            r.tilt_degrees.rms,
            r.timings_s.total
        );
        if let Some(e) = &r.error_vs_truth_degrees {
            s += &format!("\nerror vs truth: mean {:.3} deg, rms {:.3}, p95 {:.3}", e.mean, e.rms, e.p95);
        }
        s
    });
    Ok(0)
}

#[cfg(test)]
mod tests {
    use clap::{Args, FromArgMatches};

    use super::SolveArgs;
    use crate::output::{GlobalArgs, Output};

    /// The options `SolveArgs` resolves to from `argv` (the flags alone).
    fn resolved(argv: &[&str]) -> Option<String> {
        let command = SolveArgs::augment_args(clap::Command::new("t"));
        let matches = command.try_get_matches_from([&["t"], argv].concat()).ok()?;
        let args = SolveArgs::from_arg_matches(&matches).ok()?;
        let globals = GlobalArgs { quiet: true, json: false, threads: None, memory_limit: Some(1 << 30) };
        let options = args.options(&Output::new(&globals)).ok()?;
        Some(format!("{options:?}"))
    }

    /// Issue 42, D4: a batch knows a session is up to date from the resolved `CaptureOptions`
    /// it was made with, so every solver flag must change them. Each flag (found by walking the
    /// flags, so a new one is checked without being listed) is given a value other than its
    /// default; one that changes nothing would let a batch keep maps made with another value.
    #[test]
    fn probe2_d4_every_solver_flag_reaches_the_options_a_batch_compares() {
        let base = resolved(&[]).expect("the defaults resolve");
        let command = SolveArgs::augment_args(clap::Command::new("t"));
        let flags: Vec<_> = command.get_arguments().filter(|a| a.get_action().takes_values()).collect();
        assert!(flags.len() >= 8, "{} flags", flags.len());
        for arg in flags {
            let long = format!("--{}", arg.get_long().expect("solver flags are long flags"));
            let defaults: Vec<String> =
                arg.get_default_values().iter().map(|v| v.to_string_lossy().into_owned()).collect();
            let named: Vec<String> = arg.get_possible_values().iter().map(|v| v.get_name().to_owned()).collect();
            let tries: Vec<String> = if named.is_empty() {
                ["0.3", "7", "0.05", "100", "0"].iter().map(|v| (*v).to_owned()).collect()
            } else {
                named
            };
            let changed = tries
                .iter()
                .filter(|v| !defaults.contains(v))
                .filter_map(|v| resolved(&[&long, v]))
                .any(|options| options != base);
            assert!(changed, "{long}: no value changes the resolved CaptureOptions");
        }
    }
}
