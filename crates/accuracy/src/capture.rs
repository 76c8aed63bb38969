//! Capture: lights used (3 to 16) x sensor noise x solver, against the ground-truth normals of a
//! synthetic cheek mold (a [`skinkit_heightfield`] field with cast shadows and a faint specular
//! lobe, photographed under a ring of lights 45 degrees off the camera axis).
//!
//! Error: the mean angle between the solved normals and the truth over the valid pixels, no
//! detrend (the field is flat, so the truth needs none); the share of invalid pixels beside it.
//! Cost: the solve's wall-clock time (photos are made once per rig and noise level, not timed).
//!
//! Flat fields (issue 39): the same mold under 8 lights, each with an LED hotspot toward its side
//! of the field (the far corner an eighth of the hotspot), solved as photographed and after
//! dividing by each light's flat field (a white target under the same light), beside the
//! uniform-light case; the flats' cost is their fit and the correction, timed with the solve.
//!
//! Photos as the lab takes them (the `photos` module): exposure brackets against a single exposure, and
//! half-size DNG against the same photos as 16-bit TIFF.

mod photos;

use glam::Vec3;
use skinkit_capture::flat::{self, FlatField};
use skinkit_capture::solve::{self, Method, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Quantise, RenderConfig, RenderLight, SkinParams, Specular};
use skinkit_maps::{Channels, NormalMap, Photo, Samples};

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::timing::median_of;
use crate::{Config, Result};

/// Polar angle of the ring of lights from the camera axis, degrees.
pub(crate) const POLAR_DEG: f32 = 45.0;

/// The solvers, by their `--solver` name.
const SOLVERS: [(&str, Method); 3] =
    [("ls", Method::LeastSquares), ("threshold", Method::Threshold), ("robust", Method::Robust)];

/// Sizes and choices of one mode.
struct Plan {
    side: usize,
    lights: Vec<usize>,
    noise: Vec<f32>,
}

fn plan(config: &Config) -> Plan {
    if config.quick {
        Plan { side: 192, lights: vec![3, 4, 6, 8], noise: vec![0.005, 0.02] }
    } else {
        // The noise sweep of issue 39: 0 to 4 % of full scale, 3 to 16 lights.
        Plan { side: 512, lights: vec![3, 4, 5, 6, 8, 12, 16], noise: vec![0.0, 0.005, 0.01, 0.02, 0.04] }
    }
}

/// Measures every (lights, noise, solver) choice.
///
/// # Errors
/// When the mold cannot be generated or photographed, or a solve is refused.
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let plan = plan(config);
    let field = SkinParams::cheek(plan.side, plan.side, config.seed).generate()?;
    let setup = format!(
        "{0}x{0} synthetic cheek mold (seed {1}), cast shadows and a Blinn-Phong lobe (strength 0.05), \
         16-bit photos under a ring of lights {POLAR_DEG} degrees off axis, Gaussian sensor noise \
         (sigma as a share of full scale); error against the mold's exact normals, no detrend; \
         time of the solve alone",
        plan.side, config.seed
    );
    let mut report = StageReport::new(Stage::Capture, setup, "mean angular error (deg)", "seconds");
    let total = plan.lights.len() * plan.noise.len() * SOLVERS.len() + FLAT_CASES.len() + photos::CASES.len();
    let tally = crate::Tally::start(progress, Stage::Capture, total);
    for &noise in &plan.noise {
        for &k in &plan.lights {
            let (stack, rig) = photograph(&field, k, noise, config.seed)?;
            for (name, method) in SOLVERS {
                let choice = solve_choice(&stack, &rig, &field.normals, (name, method), k, noise, config.runs())?;
                report.choices.push(choice);
                tally.done(report.choices.len());
            }
        }
    }
    for case in FLAT_CASES {
        report.choices.push(flat_choice(&field, case, config)?);
        tally.done(report.choices.len());
    }
    for case in photos::CASES {
        report.choices.push(photos::choice(&field, case, config)?);
        tally.done(report.choices.len());
    }
    Ok(report)
}

/// The flat-field cases: uniform lights, a strong falloff as photographed, the falloff with flats.
const FLAT_CASES: [&str; 3] = ["uniform lights", "falloff, no flats", "falloff, flats"];

/// Light intensity of the flat-field cases: keeps the brightest hotspot reading under full scale.
const FLAT_INTENSITY: f32 = 0.3;

/// Light `i` of `k`'s falloff over a `side` x `side` field: an LED hotspot 0.8 of the way to the
/// edge toward the light, `(1 + d^2 / 1.5)^-1.5` in coordinates scaled to [-1, 1], mean 1.
fn falloff(i: usize, k: usize, side: usize) -> Vec<f32> {
    let a = std::f64::consts::TAU * i as f64 / k as f64;
    let (cx, cy) = (0.8 * a.cos(), -0.8 * a.sin());
    let at = |p: usize| {
        let u = 2.0 * (p % side) as f64 / (side - 1) as f64 - 1.0;
        let v = 2.0 * (p / side) as f64 / (side - 1) as f64 - 1.0;
        (1.0 + ((u - cx).powi(2) + (v - cy).powi(2)) / 1.5).powf(-1.5)
    };
    let mean = (0..side * side).map(at).sum::<f64>() / (side * side) as f64;
    (0..side * side).map(|p| (at(p) / mean) as f32).collect()
}

/// A 16-bit grey photo of `values` (full scale 1).
fn u16_photo(side: usize, values: impl Iterator<Item = f32>) -> Result<Photo> {
    let v = values.map(|x| (x.clamp(0.0, 1.0) * 65535.0).round() as u16).collect();
    Ok(Photo::new(side, side, Channels::Gray, Samples::U16(v))?)
}

/// One flat-field case at 8 lights and 0.5 % noise: its error and the time of flats and solve.
fn flat_choice(field: &skinkit_heightfield::Heightfield, case: &str, config: &Config) -> Result<Choice> {
    const K: usize = 8;
    let side = field.width();
    let (stack, rig) = photograph_with(field, K, 0.005, config.seed, Quantise::Float, FLAT_INTENSITY)?;
    let falloffs: Vec<Vec<f32>> = (0..K).map(|i| falloff(i, K, side)).collect();
    let mut lit = Vec::with_capacity(K);
    for (photo, f) in stack.photos().iter().zip(&falloffs) {
        let dim = if case == "uniform lights" { 1.0 } else { 0.0 };
        lit.push(u16_photo(side, (0..side * side).map(|p| photo.linear(p) * (dim + (1.0 - dim) * f[p])))?);
    }
    let solve_config = SolveConfig::default();
    let run = || -> Result<NormalMap> {
        let photos = if case == "falloff, flats" {
            let mut out = Vec::with_capacity(K);
            for (i, (photo, f)) in lit.iter().zip(&falloffs).enumerate() {
                let target = u16_photo(side, f.iter().map(|f| 0.5 * FLAT_INTENSITY * f))?;
                let field = FlatField::from_photo(&target, None, &format!("flat-{:02}.png", i + 1))?;
                out.push(flat::correct(
                    photo,
                    None,
                    Some(&field),
                    solve_config.saturation,
                    &format!("{:02}.png", i + 1),
                )?);
            }
            out
        } else {
            lit.clone()
        };
        let stack = PhotoStack::new(photos, (1..=K).map(|i| format!("{i:02}.png")).collect())?;
        Ok(solve::solve(&stack, &rig, &solve_config, &solve::NoProgress)?.normals)
    };
    let (normals, seconds) = median_of(config.runs(), run);
    let stats = normals?.angular_error(&field.normals, None)?;
    Ok(Choice::timed(
        &format!("flat fields: {case}"),
        case,
        knobs(&[("lights", K.to_string()), ("noise", "0.005".into()), ("flat fields", case.to_owned())]),
        metrics(&[("mean angular error (deg)", stats.mean as f64), ("p95 angular error (deg)", stats.p95 as f64)]),
        seconds,
        config.runs(),
    ))
}

/// Photos of `field` under a ring of `k` lights with `noise`, and the rig that took them.
fn photograph(field: &skinkit_heightfield::Heightfield, k: usize, noise: f32, seed: u64) -> Result<(PhotoStack, Rig)> {
    photograph_with(field, k, noise, seed, Quantise::U16, 1.0)
}

/// [`photograph`] stored as `format`, under lights of `intensity`.
fn photograph_with(
    field: &skinkit_heightfield::Heightfield,
    k: usize,
    noise: f32,
    seed: u64,
    format: Quantise,
    intensity: f32,
) -> Result<(PhotoStack, Rig)> {
    let lights = RenderLight::ring(k, POLAR_DEG, Vec3::splat(intensity));
    let render = RenderConfig {
        shadows: true,
        specular: Some(Specular { strength: 0.05, shininess: 40.0 }),
        noise_sigma: noise,
        format,
        seed,
        ..RenderConfig::default()
    };
    let photos = skinkit_heightfield::render(field, &lights, &render)?;
    let names = (1..=k).map(|i| format!("{i:02}.png")).collect();
    let stack = PhotoStack::new(photos, names)?;
    let rig_lights = lights
        .iter()
        .map(|l| Light::new(l.direction, l.intensity, None))
        .collect::<std::result::Result<Vec<_>, String>>()
        .map_err(|e| skinkit_capture::Error::InvalidInput(format!("ring of {k} lights: {e}")))?;
    Ok((stack, Rig::new(rig_lights, &format!("ring of {k}"))?))
}

/// One solve: its error against `truth` and its time.
fn solve_choice(
    stack: &PhotoStack,
    rig: &Rig,
    truth: &NormalMap,
    (name, method): (&str, Method),
    k: usize,
    noise: f32,
    runs: usize,
) -> Result<Choice> {
    let config = SolveConfig { method, ..SolveConfig::default() };
    let (solution, seconds) = median_of(runs, || solve::solve(stack, rig, &config, &solve::NoProgress));
    let solution = solution?;
    let stats = solution.normals.angular_error(truth, None)?;
    let pixels = (truth.width() * truth.height()).max(1) as f64;
    let invalid = 100.0 * (pixels - solution.normals.valid_count() as f64) / pixels;
    Ok(Choice::timed(
        &format!("{name}, noise {noise}"),
        &format!("{k}"),
        knobs(&[("lights", k.to_string()), ("noise", noise.to_string()), ("solver", name.to_owned())]),
        metrics(&[
            ("mean angular error (deg)", stats.mean as f64),
            ("p95 angular error (deg)", stats.p95 as f64),
            ("invalid pixels (%)", invalid),
        ]),
        seconds,
        runs,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The falloff case: flats cut the error at least 3x and land within 10 % of uniform lights.
    #[test]
    fn flats_remove_the_falloff() {
        let config = Config { quick: true, seed: 2, samples: std::path::PathBuf::new() };
        let field = SkinParams::cheek(96, 96, 2).generate().unwrap();
        let error = |case| flat_choice(&field, case, &config).unwrap().metric("mean angular error (deg)").unwrap();
        let (even, without, with) = (error(FLAT_CASES[0]), error(FLAT_CASES[1]), error(FLAT_CASES[2]));
        eprintln!("uniform {even:.3}, falloff {without:.3}, flats {with:.3}");
        assert!(3.0 * with <= without && with <= 1.1 * even, "uniform {even}, falloff {without}, flats {with}");
    }
}
