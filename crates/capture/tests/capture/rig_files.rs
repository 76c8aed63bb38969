//! Rig files: parsing, validation messages, save/load round trips and the shipped turntable rig.

use std::path::{Path, PathBuf};

use glam::Vec3;
use skinkit_capture::{Error, Light, Rig};

fn calibration(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../calibration").join(name)
}

fn three_lights(extra: &str) -> String {
    format!(
        "[[light]]\ndirection = [1.0, 0.0, 1.0]\n[[light]]\ndirection = [0.0, 1.0, 1.0]\n[[light]]\ndirection = [-1.0, -1.0, 1.0]\n{extra}"
    )
}

fn parse_err(text: &str) -> String {
    match Rig::parse(text, "rig.toml") {
        Err(e @ Error::BadFile { .. }) => e.to_string(),
        other => panic!("expected a BadFile error, got {other:?}"),
    }
}

#[test]
fn shipped_turntable_matches_generator() {
    let file = Rig::load(&calibration("turntable-8.toml")).unwrap();
    let generated = Rig::turntable(8, 45.0, 1.0).unwrap();
    assert_eq!(file.name(), Some("turntable-8"));
    assert_eq!(file.lights().len(), 8);
    for (i, (a, b)) in file.lights().iter().zip(generated.lights()).enumerate() {
        assert!(
            (a.direction() - b.direction()).abs().max_element() < 1e-6,
            "light {i}: {} vs {}",
            a.direction(),
            b.direction()
        );
        assert!((a.intensity() - b.intensity()).abs().max_element() < 1e-6);
        assert_eq!(a.position(), None);
    }
    assert!(file.conditioning().warning().is_none());
}

#[test]
fn turntable_geometry() {
    let rig = Rig::turntable(4, 30.0, 2.0).unwrap();
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    // azimuth 0 is +x; counter-clockwise seen from the camera puts azimuth 90 at +y (up).
    let want = [Vec3::new(c, 0.0, s), Vec3::new(0.0, c, s), Vec3::new(-c, 0.0, s), Vec3::new(0.0, -c, s)];
    for (l, w) in rig.lights().iter().zip(want) {
        assert!((l.direction() - w).length() < 1e-6, "{} vs {w}", l.direction());
        assert_eq!(l.intensity(), Vec3::splat(2.0));
    }
    // At 90 degrees every light is on the camera axis: rank 1, refused.
    assert!(matches!(Rig::turntable(8, 90.0, 1.0), Err(Error::BadRig(_))));
}

#[test]
fn zero_direction_names_file_and_light() {
    let text = three_lights("[[light]]\ndirection = [0.0, 0.0, 0.0]\n");
    assert_eq!(parse_err(&text), "rig.toml: light 4: direction has zero length");
}

#[test]
fn light_below_the_mold_plane_is_refused() {
    let text = three_lights("[[light]]\ndirection = [1.0, 0.0, -0.1]\n");
    let msg = parse_err(&text);
    assert!(msg.starts_with("rig.toml: light 4: direction") && msg.contains("below the mold plane"), "{msg}");
    let flat = three_lights("[[light]]\ndirection = [1.0, 0.0, 0.0]\n");
    assert!(parse_err(&flat).contains("light 4"));
}

#[test]
fn bad_intensities_are_refused() {
    for (value, what) in [
        ("0.0", "must be finite and > 0"),
        ("[1.0, -1.0, 1.0]", "must be finite and > 0"),
        ("\"bright\"", "a number or [r, g, b]"),
        ("[1.0, 2.0]", "a number or [r, g, b]"),
    ] {
        let text = format!("[[light]]\ndirection = [0.0, 0.0, 1.0]\nintensity = {value}\n{}", three_lights(""));
        let msg = parse_err(&text);
        assert!(msg.starts_with("rig.toml: light 1: intensity") && msg.contains(what), "{value}: {msg}");
    }
}

#[test]
fn non_finite_values_are_refused() {
    let text = three_lights("[[light]]\ndirection = [nan, 0.0, 1.0]\n");
    assert!(parse_err(&text).contains("light 4: direction [NaN"), "{}", parse_err(&text));
    let pos = three_lights("[[light]]\ndirection = [0.0, 0.0, 1.0]\nposition = [inf, 0.0, 1.0]\n");
    assert!(parse_err(&pos).contains("light 4: position"), "{}", parse_err(&pos));
    let mm = format!("mm_per_pixel = -0.5\n{}", three_lights(""));
    assert!(parse_err(&mm).contains("mm_per_pixel -0.5"), "{}", parse_err(&mm));
}

#[test]
fn unknown_and_missing_keys_name_the_key_and_line() {
    let unknown = three_lights("[[light]]\ndirection = [0.0, 0.0, 1.0]\ncolour = 3\n");
    let msg = parse_err(&unknown);
    assert!(msg.starts_with("rig.toml: ") && msg.contains("colour") && msg.contains("line"), "{msg}");
    let top = format!("lights = 3\n{}", three_lights(""));
    assert!(parse_err(&top).contains("lights"));
    let missing = three_lights("[[light]]\nintensity = 1.0\n");
    let msg = parse_err(&missing);
    assert!(msg.contains("direction") && msg.contains("line"), "{msg}");
}

#[test]
fn fewer_than_three_lights_is_an_error() {
    let msg = parse_err("[[light]]\ndirection = [0.0, 0.0, 1.0]\n[[light]]\ndirection = [1.0, 0.0, 1.0]\n");
    assert_eq!(msg, "rig.toml: rig has 2 lights; photometric stereo needs at least 3");
    assert!(parse_err("name = \"empty\"").contains("0 lights"));
}

#[test]
fn save_and_load_round_trip_with_relative_ambient() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig.toml");
    let text = format!("name = \"bench\"\nambient = \"dark.png\"\nmm_per_pixel = 0.0125\n{}", three_lights(""));
    std::fs::write(&path, text).unwrap();
    let mut rig = Rig::load(&path).unwrap();
    assert_eq!(rig.ambient(), Some(dir.path().join("dark.png").as_path()));
    let mut lights = rig.lights().to_vec();
    lights[1] = Light::new(lights[1].direction(), Vec3::new(0.9, 1.1, 1.3), None).unwrap();
    lights[2] = Light::new(lights[2].direction(), Vec3::ONE, Some(Vec3::new(-100.0, 20.5, 800.0))).unwrap();
    rig = Rig::new(lights, "edited")
        .unwrap()
        .with_name("bench")
        .with_description("with \"quotes\" and\nnewline")
        .with_ambient(rig.ambient().map(Into::into))
        .with_mm_per_pixel(rig.mm_per_pixel(), "edited")
        .unwrap();

    let out = dir.path().join("saved.toml");
    rig.save(&out).unwrap();
    let written = std::fs::read_to_string(&out).unwrap();
    assert!(written.contains("ambient = \"dark.png\""), "{written}");
    assert_eq!(Rig::load(&out).unwrap(), rig);
    // and through text alone (the ambient path is kept as given)
    assert_eq!(Rig::parse(&rig.to_toml_string(), "text").unwrap(), rig);
}

#[test]
fn load_of_a_missing_file_names_it() {
    let err = Rig::load(Path::new("/nonexistent/rig.toml")).unwrap_err();
    // Read through the input gate (issue 42): its I/O error, as maps::Error::Input.
    assert!(matches!(err, Error::Maps(skinkit_maps::Error::Input(skinkit_maps::input::InputError::Io { .. }))));
    assert!(err.to_string().contains("/nonexistent/rig.toml"));
}

/// Exposure brackets (issue 39): parsed, counted in the photos a session needs, round-tripped,
/// and a time that is not positive is refused naming the light and the time.
#[test]
fn exposure_brackets_parse_count_and_round_trip() {
    let text = "[[light]]\ndirection = [1, 0, 1]\nexposures = [0.5, 1, 2]\n\
                [[light]]\ndirection = [0, 1, 1]\n[[light]]\ndirection = [-1, -1, 1]\n";
    let rig = Rig::parse(text, "rig.toml").unwrap();
    assert_eq!(rig.lights()[0].exposures(), &[0.5, 1.0, 2.0]);
    assert_eq!(rig.lights()[1].photo_count(), 1);
    rig.expect_photos(5).unwrap();
    let e = rig.expect_photos(3).unwrap_err().to_string();
    assert!(e.contains("rig has 3 lights (5 photos with their brackets) but 3 photos were given"), "{e}");
    assert_eq!(Rig::parse(&rig.to_toml_string(), "text").unwrap(), rig);
    let e = parse_err(&text.replace("[0.5, 1, 2]", "[0.5, 0, 2]"));
    assert!(e.contains("rig.toml: light 1") && e.contains("exposure time 2 is 0"), "{e}");
}
