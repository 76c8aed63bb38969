//! Mean angular error of least squares, threshold and robust against sensor noise and light
//! count on the synthetic cheek mold of `skinkit accuracy`'s capture stage (cast shadows and a
//! faint specular lobe, a ring of lights 45 degrees off axis), with the robust solve's measured
//! noise floor and gate. Highlights and shadows can be turned off to see the Lambertian case.
//!
//! ```text
//! cargo run --release -p skinkit-capture --example noise_sweep -- [SIDE] [lambertian]
//! ```

use glam::Vec3;
use skinkit_capture::solve::{self, Method, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::{Quantise, RenderConfig, RenderLight, SkinParams, Specular};

type Failure = Box<dyn std::error::Error>;

fn main() -> Result<(), Failure> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let side: usize = args.first().map_or(Ok(384), |s| s.parse())?;
    let lambertian = args.iter().any(|a| a == "lambertian");
    let field = SkinParams::cheek(side, side, 1).generate()?;
    println!("{side}x{side} cheek, {}", if lambertian { "Lambertian, no shadows" } else { "shadows + specular" });
    println!("noise  lights      ls  thresh  robust  ratio  sigma    gate");
    for noise in [0.0f32, 0.005, 0.01, 0.02, 0.04] {
        for k in [4usize, 6, 8, 12, 16] {
            let lights = RenderLight::ring(k, 45.0, Vec3::ONE);
            let render = RenderConfig {
                shadows: !lambertian,
                specular: (!lambertian).then_some(Specular { strength: 0.05, shininess: 40.0 }),
                noise_sigma: noise,
                format: Quantise::U16,
                seed: 1,
                ..RenderConfig::default()
            };
            let photos = skinkit_heightfield::render(&field, &lights, &render)?;
            let stack = PhotoStack::new(photos, (1..=k).map(|i| format!("{i:02}.png")).collect())?;
            let rig_lights: Result<Vec<Light>, String> =
                lights.iter().map(|l| Light::new(l.direction, l.intensity, None)).collect();
            let rig = Rig::new(rig_lights?, "ring")?;
            let mut errors = Vec::new();
            let mut floor = None;
            for method in [Method::LeastSquares, Method::Threshold, Method::Robust] {
                let config = SolveConfig { method, ..SolveConfig::default() };
                let solution = solve::solve(&stack, &rig, &config, &solve::NoProgress)?;
                errors.push(solution.normals.angular_error(&field.normals, None)?.mean);
                floor = floor.or(solution.noise);
            }
            let (sigma, gate) = floor.map_or((0.0, 0.0), |f| (f.sigma, f.gate));
            println!(
                "{noise:5.3}  {k:6}  {:6.3}  {:6.3}  {:6.3}  {:5.3}  {sigma:.4}  {gate:.4}",
                errors[0],
                errors[1],
                errors[2],
                errors[2] / errors[0]
            );
        }
    }
    Ok(())
}
