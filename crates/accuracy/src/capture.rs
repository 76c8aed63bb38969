//! Capture: lights used (3 to 16) x sensor noise x solver, against the ground-truth normals of a
//! synthetic cheek mold (a [`skinkit_heightfield`] field with cast shadows and a faint specular
//! lobe, photographed under a ring of lights 45 degrees off the camera axis).
//!
//! Error: the mean angle between the solved normals and the truth over the valid pixels, no
//! detrend (the field is flat, so the truth needs none); the share of invalid pixels beside it.
//! Cost: the solve's wall-clock time (photos are made once per rig and noise level, not timed).

use glam::Vec3;
use skinkit_capture::solve::{self, Method, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Quantise, RenderConfig, RenderLight, SkinParams, Specular};
use skinkit_maps::NormalMap;

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::timing::median_of;
use crate::{Config, Result};

/// Polar angle of the ring of lights from the camera axis, degrees.
const POLAR_DEG: f32 = 45.0;

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
pub fn measure(config: &Config, progress: &dyn Fn(usize, usize)) -> Result<StageReport> {
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
    let total = plan.lights.len() * plan.noise.len() * SOLVERS.len();
    progress(0, total);
    for &noise in &plan.noise {
        for &k in &plan.lights {
            let (stack, rig) = photograph(&field, k, noise, config.seed)?;
            for (name, method) in SOLVERS {
                let choice = solve_choice(&stack, &rig, &field.normals, (name, method), k, noise, config.runs())?;
                report.choices.push(choice);
                progress(report.choices.len(), total);
            }
        }
    }
    Ok(report)
}

/// Photos of `field` under a ring of `k` lights with `noise`, and the rig that took them.
fn photograph(field: &skinkit_heightfield::Heightfield, k: usize, noise: f32, seed: u64) -> Result<(PhotoStack, Rig)> {
    let lights = RenderLight::ring(k, POLAR_DEG, Vec3::ONE);
    let render = RenderConfig {
        shadows: true,
        specular: Some(Specular { strength: 0.05, shininess: 40.0 }),
        noise_sigma: noise,
        format: Quantise::U16,
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
    let (solution, seconds) = median_of(runs, || solve::solve(stack, rig, &config, &solve::no_progress));
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
