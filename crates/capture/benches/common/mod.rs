//! Inputs shared by the solve benchmarks: a ring rig and synthetic 16-bit photos of a bumpy
//! surface.

use glam::Vec3;
use skinkit_capture::solve::PhotoStack;
use skinkit_capture::{Light, Rig};
use skinkit_maps::{Channels, Photo, Samples};

/// `k` unit-intensity lights evenly on a ring at `theta` degrees from the camera axis.
pub fn ring(k: usize, theta: f32) -> Rig {
    let t = theta.to_radians();
    let lights = (0..k)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / k as f32;
            Light::new(Vec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos()), Vec3::ONE, None)
                .expect("a ring light is valid")
        })
        .collect();
    Rig::new(lights, "ring").expect("a ring of 3 or more lights is a valid rig")
}

/// A bumpy surface lit by `rig`; with `shadows`, about 6% of readings are zeroed in patches.
pub fn photos(size: usize, rig: &Rig, shadows: bool) -> PhotoStack {
    photos_with(size, rig, shadows, false)
}

/// [`photos`], and with `highlights` about 6% of readings (in other patches, at most one per
/// pixel: half the pixels have one) brightened by 0.2 of full scale, as a specular highlight
/// would: outliers least squares cannot explain, which the robust solve fits pixel by pixel.
#[allow(dead_code)] // `solve_kernel` includes this module too and uses only `photos`.
pub fn photos_with(size: usize, rig: &Rig, shadows: bool, highlights: bool) -> PhotoStack {
    let normal = |x: usize, y: usize| {
        let (u, v) = (x as f32 * 0.05, y as f32 * 0.043);
        Vec3::new(0.3 * u.sin(), 0.25 * v.cos(), 1.0).normalize()
    };
    let normals: Vec<Vec3> = (0..size * size).map(|p| normal(p % size, p / size)).collect();
    let photos = rig
        .lights()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let samples = (0..size * size)
                .map(|p| {
                    let (x, y) = (p % size, p / size);
                    let occluded = shadows && ((x / 16 + 3 * (y / 16) + 5 * i) % 16 == 0);
                    let lobe = highlights && ((x / 16 + 5 * (y / 16) + 3 * i) % 16 == 0);
                    let v = if occluded { 0.0 } else { 0.7 * normals[p].dot(l.direction()).max(0.0) };
                    let v = if lobe { v + 0.2 } else { v };
                    (v * 65535.0) as u16
                })
                .collect();
            Photo::new(size, size, Channels::Gray, Samples::U16(samples)).unwrap()
        })
        .collect();
    PhotoStack::new(photos, (0..rig.lights().len()).map(|i| format!("{i}.png")).collect()).unwrap()
}
