//! Height: every integrator against the exact heights of synthetic fields, against its time, on
//! the cases each is meant for and the ones it is not:
//!
//! * `wraps`: whole waves across the map (a grown map tiles); error after removing the mean;
//! * `rectangle`: a tilted skin patch with pores and furrows that does not wrap; error after
//!   removing the best plane (what a capture's detrend leaves undetermined);
//! * `holes`: the same patch with a disc and a band of invalid normals; error over the valid
//!   texels after the best plane;
//! * `16-bit`: the rectangle's normals quantised as a 16-bit PNG stores them.
//!
//! The default is what [`Integrator::choose`] takes for the case; the error is the RMS height
//! error as a share of the exact heights' RMS (%).

use skinkit_height::compare::error_share;
use skinkit_height::{HeightOptions, Integrator, Scale, integrate};
use skinkit_heightfield::{Heightfield, SkinParams, periodic};
use skinkit_maps::{NormalMap, Vec3};

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::timing::median_of;
use crate::{Config, Result};

/// The error metric's name.
const ERROR: &str = "height error (% of RMS)";

/// One test case: its name, normals, exact heights, valid texels and whether it wraps.
struct Case {
    name: &'static str,
    normals: NormalMap,
    field: Heightfield,
    valid: Option<Vec<bool>>,
    wraps: bool,
}

fn side(config: &Config) -> usize {
    if config.quick { 256 } else { 1024 }
}

/// Measures every integrator on every case.
///
/// # Errors
/// When a field cannot be generated or a map cannot be integrated.
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let n = side(config);
    let cases = cases(n, config.seed)?;
    let setup = format!(
        "{n}x{n} synthetic fields (seed {}): whole waves that wrap (error after the mean), a tilted \
         skin patch at 0.005 mm a texel that does not (after the best plane), the patch with a disc \
         and a band of invalid normals (over the valid texels), and its normals quantised to 16 bits; \
         the default is what `skinkit height` chooses for the case",
        config.seed
    );
    let mut report = StageReport::new(Stage::Height, setup, ERROR, "seconds");
    let integrators = [Integrator::Periodic, Integrator::Neumann, Integrator::Masked];
    let total = cases.len() * integrators.len();
    let tally = crate::Tally::start(progress, Stage::Height, total);
    for case in &cases {
        let default = Integrator::choose(case.wraps, case.normals.valid_count().abs_diff(n * n));
        for integrator in integrators {
            report.choices.push(measure_one(config, case, integrator, integrator == default)?);
            tally.done(report.choices.len());
        }
    }
    Ok(report)
}

fn measure_one(config: &Config, case: &Case, integrator: Integrator, default: bool) -> Result<Choice> {
    let mm = case.field.mm_per_texel;
    let options = HeightOptions { integrator: Some(integrator), scale: Scale::MmPerTexel(mm), ..Default::default() };
    let (height, seconds) = median_of(config.runs(), || integrate(&case.normals, &options));
    let height = height?;
    let error = 100.0 * error_share(&height.map, &case.field.heights, case.valid.as_deref(), !case.wraps);
    let label = format!("{}{}", integrator.name(), if default { " (default)" } else { "" });
    Ok(Choice::timed(
        case.name,
        &label,
        knobs(&[("integrator", integrator.name().to_owned()), ("case", case.name.to_owned())]),
        metrics(&[
            (ERROR, error),
            ("residual (% of RMS slope)", 100.0 * height.report.residual_relative),
            ("iterations", height.report.iterations.unwrap_or(0) as f64),
        ]),
        seconds,
        config.runs(),
    ))
}

fn cases(n: usize, seed: u64) -> Result<Vec<Case>> {
    let waves = periodic(n, n, 0.02, seed)?;
    let mut params = SkinParams::forehead(n, n, seed);
    params.tilt = [0.05, -0.03];
    params.mm_per_texel = 0.005;
    let patch = params.generate()?;
    let (holes, valid) = with_holes(&patch.normals);
    let quantised = NormalMap::from_grid(patch.normals.grid().map(|v| v.to_array().map(quantise16).into()));
    Ok(vec![
        Case { name: "wraps", normals: waves.normals.clone(), field: waves, valid: None, wraps: true },
        Case { name: "rectangle", normals: patch.normals.clone(), field: patch.clone(), valid: None, wraps: false },
        Case { name: "holes", normals: holes, field: patch.clone(), valid: Some(valid), wraps: false },
        Case { name: "16-bit", normals: quantised, field: patch, valid: None, wraps: false },
    ])
}

/// The map with a disc (radius an eighth of the side) and a vertical band (a twentieth wide, from
/// 15 % to 85 % of the height, so the valid texels stay connected) invalid.
fn with_holes(normals: &NormalMap) -> (NormalMap, Vec<bool>) {
    let (w, h) = normals.size();
    let mut out = normals.clone();
    let mut valid = vec![true; w * h];
    let r = w as f64 / 8.0;
    for y in 0..h {
        for x in 0..w {
            let disc = (x as f64 - w as f64 * 0.3).powi(2) + (y as f64 - h as f64 * 0.5).powi(2) < r * r;
            let band = x >= w * 7 / 10 && x < w * 7 / 10 + (w / 20).max(1) && y >= h * 15 / 100 && y < h * 85 / 100;
            if disc || band {
                out.set(x, y, Vec3::ZERO);
                valid[y * w + x] = false;
            }
        }
    }
    (out, valid)
}

/// A component as a 16-bit PNG stores it: `(c + 1) / 2` in 65535 steps.
fn quantise16(c: f32) -> f32 {
    ((c * 0.5 + 0.5) * 65535.0).round() / 65535.0 * 2.0 - 1.0
}
