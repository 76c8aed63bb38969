//! Sphere calibration on rendered photos of a mirror and a matte sphere under known lights.

use glam::{DVec3, Vec3};
use skinkit_capture::Error;
use skinkit_capture::sphere::{self, Circle, Locate};
use skinkit_maps::{Channels, Grid, Photo, Samples};

const W: usize = 96;
const H: usize = 90;
const CIRCLE: Circle = Circle { cx: 47.3, cy: 44.8, radius: 36.0 };

/// Known lights as (azimuth, elevation) in degrees, and their relative RGB intensities.
fn lights() -> Vec<(DVec3, Vec3)> {
    [
        (0.0, 45.0, [1.0, 1.0, 1.0]),
        (100.0, 60.0, [0.7, 0.8, 0.6]),
        (220.0, 35.0, [1.3, 1.2, 1.4]),
        (300.0, 70.0, [1.0, 0.9, 1.1]),
    ]
    .iter()
    .map(|&(az, el, e): &(f64, f64, [f32; 3])| {
        let (a, e_rad) = (f64::to_radians(az), f64::to_radians(el));
        (DVec3::new(e_rad.cos() * a.cos(), e_rad.cos() * a.sin(), e_rad.sin()), Vec3::from_array(e))
    })
    .collect()
}

fn gray(values: Vec<f32>) -> Photo {
    Photo::new(W, H, Channels::Gray, Samples::F32(values)).unwrap()
}

/// A chrome sphere reflecting a dim room (0.15, brighter toward the top) and a small Gaussian
/// highlight (sigma 1.2 px) centred where the mirror reflects `light` toward the camera.
fn mirror_photo(light: DVec3, circle: &Circle) -> Photo {
    let n = (light + DVec3::Z).normalize();
    let [hx, hy] = circle.pixel_of(n);
    gray(
        (0..W * H)
            .map(|i| {
                let (x, y) = ((i % W) as f64, (i / W) as f64);
                match circle.normal_at(x, y) {
                    None => 0.02,
                    Some(m) => {
                        let d2 = (x - hx).powi(2) + (y - hy).powi(2);
                        (0.15 + 0.03 * m.y + 0.8 * (-d2 / (2.0 * 1.2 * 1.2)).exp()) as f32
                    }
                }
            })
            .collect(),
    )
}

/// An exact Lambertian sphere (albedo 0.6) as a 16-bit RGB photo; black background.
fn matte_photo(light: DVec3, e: Vec3) -> Photo {
    let mut samples = Vec::with_capacity(W * H * 3);
    for i in 0..W * H {
        let cos = CIRCLE.normal_at((i % W) as f64, (i / W) as f64).map_or(0.0, |n| n.dot(light).max(0.0));
        for c in 0..3 {
            samples.push((0.6 * e[c] as f64 * cos * 65535.0).round() as u16);
        }
    }
    Photo::new(W, H, Channels::Rgb, Samples::U16(samples)).unwrap()
}

fn angle_deg(a: Vec3, b: DVec3) -> f64 {
    a.as_dvec3().angle_between(b).to_degrees()
}

fn mean_intensity(lights: &[(DVec3, Vec3)]) -> Vec3 {
    lights.iter().map(|(_, e)| *e).sum::<Vec3>() / lights.len() as f32
}

#[test]
fn mirror_sphere_with_known_circle_recovers_directions() {
    let lights = lights();
    let photos: Vec<Photo> = lights.iter().map(|(d, _)| mirror_photo(*d, &CIRCLE)).collect();
    let cal = sphere::mirror(&photos, &Locate::Circle(CIRCLE)).unwrap();
    assert_eq!(cal.rig.lights().len(), 4);
    for (i, ((want, _), got)) in lights.iter().zip(cal.rig.lights()).enumerate() {
        // A 0.05 px highlight error on a 36 px sphere moves the direction by about 0.16 deg.
        let err = angle_deg(got.direction(), *want);
        assert!(err < 0.2, "light {i}: {err} deg");
        assert_eq!(got.intensity(), Vec3::ONE);
        let [hx, hy] = cal.lights[i].highlight.unwrap();
        let [ex, ey] = CIRCLE.pixel_of((*want + DVec3::Z).normalize());
        assert!((hx - ex).abs() < 0.05 && (hy - ey).abs() < 0.05, "light {i}: ({hx}, {hy}) vs ({ex}, {ey})");
        assert!(cal.lights[i].highlight_spread.unwrap() < 2.0);
    }
    assert_eq!(cal.mirror_circle, Some(CIRCLE));
}

#[test]
fn mirror_sphere_found_automatically() {
    let lights = lights();
    let photos: Vec<Photo> = lights.iter().map(|(d, _)| mirror_photo(*d, &CIRCLE)).collect();
    let cal = sphere::mirror(&photos, &Locate::Auto).unwrap();
    let c = cal.mirror_circle.unwrap();
    // the circle from the blob's area and centroid: a fraction of a pixel off on a 36 px sphere
    assert!(
        (c.cx - CIRCLE.cx).abs() < 0.2 && (c.cy - CIRCLE.cy).abs() < 0.2 && (c.radius - CIRCLE.radius).abs() < 0.3,
        "{c:?}"
    );
    for ((want, _), got) in lights.iter().zip(cal.rig.lights()) {
        let err = angle_deg(got.direction(), *want);
        assert!(err < 0.6, "{err} deg");
    }
    // the same through a mask
    let mask = Grid::from_fn(W, H, |x, y| CIRCLE.normal_at(x as f64, y as f64).is_some());
    let from_mask = sphere::mirror(&photos, &Locate::Mask(mask)).unwrap();
    assert_eq!(from_mask.mirror_circle, cal.mirror_circle);
}

#[test]
fn matte_sphere_recovers_directions_and_intensities() {
    let lights = lights();
    let photos: Vec<Photo> = lights.iter().map(|(d, e)| matte_photo(*d, *e)).collect();
    let cal = sphere::matte(&photos, &Locate::Auto).unwrap();
    let mean = mean_intensity(&lights);
    for (i, ((d, e), got)) in lights.iter().zip(cal.rig.lights()).enumerate() {
        // exact Lambert at pixel centres; the error is the found circle's (about 0.1 deg)
        let err = angle_deg(got.direction(), *d);
        assert!(err < 0.2, "light {i}: {err} deg");
        let want = *e / mean;
        assert!(
            ((got.intensity() - want) / want).abs().max_element() < 0.01,
            "light {i}: {} vs {want}",
            got.intensity()
        );
        assert!(cal.lights[i].lambert_rms.unwrap() < 0.01);
        assert!(cal.lights[i].lit_pixels.unwrap() > 1000);
    }
    let c = cal.matte_circle.unwrap();
    assert!(
        (c.cx - CIRCLE.cx).abs() < 0.3 && (c.cy - CIRCLE.cy).abs() < 0.3 && (c.radius - CIRCLE.radius).abs() < 0.5,
        "{c:?}"
    );
}

#[test]
fn mirror_directions_with_matte_intensities() {
    let lights = lights();
    let mirror_circle = Circle { cx: 40.0, cy: 50.0, radius: 30.0 };
    let mirror: Vec<Photo> = lights.iter().map(|(d, _)| mirror_photo(*d, &mirror_circle)).collect();
    let matte: Vec<Photo> = lights.iter().map(|(d, e)| matte_photo(*d, *e)).collect();
    let cal = sphere::mirror_and_matte(&mirror, &Locate::Circle(mirror_circle), &matte, &Locate::Auto).unwrap();
    let mean = mean_intensity(&lights);
    for (i, ((d, e), got)) in lights.iter().zip(cal.rig.lights()).enumerate() {
        assert!(angle_deg(got.direction(), *d) < 0.25);
        let want = *e / mean;
        assert!(
            ((got.intensity() - want) / want).abs().max_element() < 0.02,
            "light {i}: {} vs {want}",
            got.intensity()
        );
        assert!(cal.lights[i].mirror_matte_angle_deg.unwrap() < 0.3);
    }
    assert!(sphere::mirror_and_matte(&mirror[..3], &Locate::Auto, &matte, &Locate::Auto).is_err());
}

#[test]
fn missing_highlight_names_the_photo() {
    let lights = lights();
    let mut photos: Vec<Photo> = lights.iter().map(|(d, _)| mirror_photo(*d, &CIRCLE)).collect();
    photos[2] = gray(
        (0..W * H)
            .map(|i| if CIRCLE.normal_at((i % W) as f64, (i / W) as f64).is_some() { 0.15 } else { 0.02 })
            .collect(),
    );
    let err = sphere::mirror(&photos, &Locate::Circle(CIRCLE)).unwrap_err();
    assert!(matches!(err, Error::Calibration(_)));
    assert!(err.to_string().starts_with("photo 3: no highlight found"), "{err}");
}

#[test]
fn no_sphere_and_unlit_sphere_are_reported() {
    let dark: Vec<Photo> = (0..3).map(|_| gray(vec![0.0; W * H])).collect();
    let err = sphere::mirror(&dark, &Locate::Auto).unwrap_err();
    assert!(err.to_string().starts_with("no mirror sphere found"), "{err}");

    let lights = lights();
    let mut photos: Vec<Photo> = lights.iter().map(|(d, e)| matte_photo(*d, *e)).collect();
    photos[1] = Photo::new(W, H, Channels::Rgb, Samples::U16(vec![0; W * H * 3])).unwrap();
    let err = sphere::matte(&photos, &Locate::Auto).unwrap_err();
    assert!(err.to_string().starts_with("photo 2: the matte sphere is not lit"), "{err}");

    let mut sizes: Vec<Photo> = lights.iter().map(|(d, _)| mirror_photo(*d, &CIRCLE)).collect();
    sizes[1] = Photo::new(4, 4, Channels::Gray, Samples::F32(vec![0.0; 16])).unwrap();
    let err = sphere::mirror(&sizes, &Locate::Auto).unwrap_err();
    assert!(err.to_string().contains("photo 2 is 4x4 but photo 1 is 96x90"), "{err}");
}

#[test]
fn matte_sphere_with_known_circle_is_exact() {
    let lights = lights();
    let photos: Vec<Photo> = lights.iter().map(|(d, e)| matte_photo(*d, *e)).collect();
    let cal = sphere::matte(&photos, &Locate::Circle(CIRCLE)).unwrap();
    let mean = mean_intensity(&lights);
    for ((d, e), got) in lights.iter().zip(cal.rig.lights()) {
        assert!(angle_deg(got.direction(), *d) < 0.01);
        assert!(((got.intensity() - *e / mean) / (*e / mean)).abs().max_element() < 1e-3);
    }
}
