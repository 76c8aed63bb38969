//! Re-running a batch (`skinkit batch` again on the same output folder): a session whose outputs
//! are complete and up to date is not captured again (`--force` redoes it).
//!
//! Complete: the session's `report.json` exists (its output set writes it last, so a folder with
//! it holds every output). Up to date: the report is newer than every input (photos, rig, mask,
//! ambient frame, truth, `filenames.txt`), lists the same photos, and was made with the same
//! solver, detrend block and transfer curve. Anything else, including a report that does not
//! parse, runs the session again.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use skinkit_capture::session::{CaptureOptions, Session};

/// What a skipped session's report says.
pub struct Done {
    pub invalid_pixels: usize,
    /// Pixels of the map (width x height).
    pub pixels: usize,
    pub condition_number: Option<f64>,
    pub seconds: f64,
}

/// The session's previous result in `out_dir`, when it is complete and up to date.
pub fn up_to_date(
    dir: &Path,
    files: &Session,
    ambient: Option<&Path>,
    out_dir: &Path,
    options: &CaptureOptions,
) -> Option<Done> {
    let report_path = out_dir.join("report.json");
    let made = modified(&report_path)?;
    let listing = dir.join("filenames.txt");
    let inputs = files
        .photos
        .iter()
        .map(PathBuf::as_path)
        .chain([files.rig.as_path()])
        .chain(files.mask.as_deref())
        .chain(ambient)
        .chain(files.truth.as_deref())
        .chain(Some(listing.as_path()).filter(|p| p.is_file()));
    for input in inputs {
        if modified(input)? >= made {
            return None;
        }
    }
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report_path).ok()?).ok()?;
    let photos: Vec<String> = files.photos.iter().map(|p| p.display().to_string()).collect();
    let listed: Vec<&str> = report["photos"].as_array()?.iter().filter_map(|p| p.as_str()).collect();
    let method = format!("{:?}", options.solve.method).to_lowercase();
    let same = listed == photos
        && report["solver"].as_str()?.split(' ').next()? == method
        && report["detrend_block"].as_u64()? == options.detrend_block as u64
        && report["transfer"].as_str()? == skinkit_capture::session::transfer_name(options.transfer);
    same.then_some(Done {
        invalid_pixels: report["invalid_pixels"].as_u64()? as usize,
        pixels: (report["width"].as_u64()? * report["height"].as_u64()?) as usize,
        condition_number: report["condition_number"].as_f64(),
        seconds: report["timings_s"]["total"].as_f64()?,
    })
}

fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).ok()?.modified().ok()
}
