//! Near point lights: a lamp 60 mm from a 5 mm field biases a directional solve by degrees; the
//! near-light solve, told where the lamps are, removes the bias.

use glam::Vec3;
use skinkit_capture::solve::{self, Method, PhotoStack, SolveConfig};
use skinkit_capture::{Light, Rig, near};
use skinkit_heightfield::{self as hf, SkinParams};

const DISTANCE_MM: f32 = 60.0;

fn near_rig(mm_per_pixel: f32) -> Rig {
    let lights = (0..8)
        .map(|i| {
            let azimuth = std::f32::consts::TAU * i as f32 / 8.0;
            let dir = Vec3::new(azimuth.cos(), azimuth.sin(), 1.0).normalize();
            Light::new(dir, Vec3::ONE, Some(dir * DISTANCE_MM)).unwrap()
        })
        .collect();
    Rig::new(lights, "test rig").unwrap().with_mm_per_pixel(Some(mm_per_pixel), "test rig").unwrap()
}

#[test]
fn near_solve_removes_the_bias_of_a_close_lamp() {
    let field = hf::generate(&SkinParams::cheek(256, 256, 7)).unwrap();
    let rig = near_rig(field.mm_per_texel as f32);
    let lights: Vec<hf::RenderLight> =
        rig.lights().iter().map(|l| hf::RenderLight::point(l.position().unwrap(), l.intensity())).collect();
    let photos = hf::render(&field, &lights, &hf::RenderConfig::default()).unwrap();
    let names = (1..=8).map(|i| format!("{i:02}.png")).collect();
    let stack = PhotoStack::new(photos, names).unwrap();
    assert!(near::applies(&rig));

    for method in [Method::LeastSquares, Method::Robust] {
        let config = SolveConfig { method, ..SolveConfig::default() };
        let near = near::solve(&stack, &rig, &config).unwrap();
        let directional = solve::solve(&stack, &rig, &config, &solve::NoProgress).unwrap();
        let near_err = near.normals.angular_error(&field.normals, None).unwrap();
        let dir_err = directional.normals.angular_error(&field.normals, None).unwrap();
        println!("{method:?}: near-light mean {:.4} deg, directional mean {:.3} deg", near_err.mean, dir_err.mean);
        // What is left is the parallax of the heights (up to ~0.05 mm at 60 mm: ~0.05 deg).
        assert!(near_err.mean < 0.03 && near_err.p95 < 0.01, "{near_err:?}");
        if method == Method::Robust {
            // Least squares keeps the clamped readings of self-shadowed pore walls; robust drops them.
            assert!(near_err.max < 0.2, "{near_err:?}");
        }
        assert!(dir_err.mean > 1.0, "{dir_err:?}");
        assert_eq!(near.stats.invalid_count, 0);
        let albedo = near.albedo.get(128, 128);
        assert!((albedo.x - 0.7).abs() < 1e-3, "albedo {albedo}");
    }
}

#[test]
fn near_solve_needs_positions_and_pixel_size() {
    let field = hf::generate(&SkinParams::flat(8, 8, 0.05, 1)).unwrap();
    let mut rig = near_rig(0.05);
    let lights: Vec<hf::RenderLight> =
        rig.lights().iter().map(|l| hf::RenderLight::point(l.position().unwrap(), l.intensity())).collect();
    let photos = hf::render(&field, &lights, &hf::RenderConfig::default()).unwrap();
    let stack = PhotoStack::new(photos, (0..8).map(|i| i.to_string()).collect()).unwrap();
    rig = rig.with_mm_per_pixel(None, "test rig").unwrap();
    assert!(!near::applies(&rig));
    let e = near::solve(&stack, &rig, &SolveConfig::default()).unwrap_err().to_string();
    assert!(e.contains("mm_per_pixel"), "{e}");
}

/// LED beams (issue 39): a flat plane under 8 LEDs 20 mm away, each aimed off the field's centre
/// with a `cos^3` beam, photographed by the formula computed here (Lambert, inverse square, the
/// beam); the near solve told the beams gives the plane's normal, told none it is biased.
#[test]
fn near_solve_with_led_beams_removes_their_falloff() {
    const SIDE: usize = 64;
    const MM: f64 = 0.1;
    let (mu, albedo) = (3.0f64, 0.6f64);
    let leds: Vec<(glam::DVec3, glam::DVec3)> = (0..8)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / 8.0;
            let p = glam::DVec3::new(a.cos(), a.sin(), 1.2).normalize() * 20.0;
            // Aimed 1.5 mm past the centre, so the beam sweeps the field.
            let target = glam::DVec3::new(-1.5 * a.cos(), -1.5 * a.sin(), 0.0);
            (p, (target - p).normalize())
        })
        .collect();
    let photos: Vec<skinkit_maps::Photo> = leds
        .iter()
        .map(|&(p, axis)| {
            let centre_cos = (-p.normalize()).dot(axis);
            let v = (0..SIDE * SIDE)
                .map(|i| {
                    let x = glam::DVec3::new(
                        ((i % SIDE) as f64 - (SIDE as f64 - 1.0) / 2.0) * MM,
                        ((SIDE as f64 - 1.0) / 2.0 - (i / SIDE) as f64) * MM,
                        0.0,
                    );
                    let d = p - x;
                    let l = d.normalize();
                    let beam = ((-l).dot(axis) / centre_cos).powf(mu);
                    (albedo * 0.5 * beam * p.length_squared() / d.length_squared() * l.z) as f32
                })
                .collect();
            skinkit_maps::Photo::new(SIDE, SIDE, skinkit_maps::Channels::Gray, skinkit_maps::Samples::F32(v)).unwrap()
        })
        .collect();
    let stack = PhotoStack::new(photos, (1..=8).map(|i| format!("{i:02}.exr")).collect()).unwrap();
    let rig = |beams: bool| {
        let lights = leds
            .iter()
            .map(|&(p, axis)| {
                let light = Light::new(p.as_vec3(), Vec3::splat(0.5), Some(p.as_vec3())).unwrap();
                if beams { light.with_beam(axis.as_vec3(), mu as f32).unwrap() } else { light }
            })
            .collect();
        Rig::new(lights, "leds").unwrap().with_mm_per_pixel(Some(MM as f32), "leds").unwrap()
    };
    let flat = skinkit_maps::NormalMap::flat(SIDE, SIDE);
    let config = SolveConfig { method: Method::LeastSquares, ..SolveConfig::default() };
    let error = |rig: &Rig| near::solve(&stack, rig, &config).unwrap().normals.angular_error(&flat, None).unwrap();
    let (with, without) = (error(&rig(true)), error(&rig(false)));
    eprintln!(
        "LED beams cos^{mu}: mean error {:.5} deg told the beams, {:.3} deg without (max {:.3})",
        with.mean, without.mean, without.max
    );
    assert!(with.max < 0.01, "told the beams: {with:?}");
    assert!(without.mean > 20.0 * with.mean.max(1e-3), "without the beams {without:?}");
    let text = rig(true).to_toml_string();
    assert_eq!(Rig::parse(&text, "again").unwrap(), rig(true), "beams round-trip:\n{text}");
}
