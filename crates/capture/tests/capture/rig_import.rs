//! DiLiGenT and UW/Seitz light files: good inputs and errors that name file and line.

use glam::Vec3;
use skinkit_capture::Error;
use skinkit_capture::import::{diligent, parse_diligent, parse_uw_lights, uw_lights};

const DIRS: &str = "-0.06059872 -0.44839055 0.89179861\n0.1 0.2 0.97\n\n0.3 -0.1 0.9\n";
const INTS: &str = "2.05 1.99 1.97\n1.0 1.0 1.0\n0.5 0.6 0.7\n";

fn location(err: Error) -> (String, String) {
    match err {
        Error::BadFile { location, reason } => (location, reason),
        other => panic!("expected BadFile, got {other:?}"),
    }
}

#[test]
fn diligent_good_input() {
    let rig =
        parse_diligent(DIRS.as_bytes(), "light_directions.txt", INTS.as_bytes(), "light_intensities.txt").unwrap();
    assert_eq!(rig.lights().len(), 3);
    let d = Vec3::new(-0.06059872, -0.44839055, 0.891_798_6);
    assert!((rig.lights()[0].direction() - d.normalize()).length() < 1e-6);
    assert!((rig.lights()[1].direction() - Vec3::new(0.1, 0.2, 0.97).normalize()).length() < 1e-6);
    assert_eq!(rig.lights()[0].intensity(), Vec3::new(2.05, 1.99, 1.97));
    assert_eq!(rig.lights()[2].intensity(), Vec3::new(0.5, 0.6, 0.7));
    assert!(rig.conditioning().rank == 3);
}

#[test]
fn diligent_malformed_number_names_file_and_line() {
    let dirs = "0.1 0.2 0.97\n0.3 0.1 0.9\n0.1 O.5 0.8\n";
    let (loc, reason) = location(
        parse_diligent(dirs.as_bytes(), "light_directions.txt", INTS.as_bytes(), "light_intensities.txt").unwrap_err(),
    );
    assert_eq!(loc, "light_directions.txt: line 3");
    assert!(reason.contains("`O.5`"), "{reason}");
    let ints = "1 1 1\n1 1\n1 1 1\n";
    let (loc, reason) =
        location(parse_diligent(DIRS.as_bytes(), "d.txt", ints.as_bytes(), "light_intensities.txt").unwrap_err());
    assert_eq!(loc, "light_intensities.txt: line 2");
    assert!(reason.contains("expected 3 numbers"), "{reason}");
}

#[test]
fn diligent_count_mismatch() {
    let ints = "1 1 1\n1 1 1\n";
    let err =
        parse_diligent(DIRS.as_bytes(), "light_directions.txt", ints.as_bytes(), "light_intensities.txt").unwrap_err();
    assert_eq!(err.to_string(), "light_intensities.txt: 2 intensities but light_directions.txt has 3 directions");
}

#[test]
fn diligent_zero_direction_and_bad_intensity_name_their_line() {
    let dirs = "0.1 0.2 0.97\n0 0 0\n0.3 0.1 0.9\n";
    let err =
        parse_diligent(dirs.as_bytes(), "light_directions.txt", INTS.as_bytes(), "light_intensities.txt").unwrap_err();
    assert_eq!(err.to_string(), "light_directions.txt: line 2: direction has zero length");
    let ints = "1 1 1\n1 1 1\n1 0 1\n";
    let (loc, _) =
        location(parse_diligent(DIRS.as_bytes(), "d.txt", ints.as_bytes(), "light_intensities.txt").unwrap_err());
    assert_eq!(loc, "light_intensities.txt: line 3");
}

#[test]
fn diligent_reads_a_folder() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("light_directions.txt"), DIRS).unwrap();
    std::fs::write(dir.path().join("light_intensities.txt"), INTS).unwrap();
    assert_eq!(diligent(dir.path()).unwrap().lights().len(), 3);
    std::fs::remove_file(dir.path().join("light_intensities.txt")).unwrap();
    let err = diligent(dir.path()).unwrap_err();
    // Opened through the input gate (issue 42): its I/O error, as maps::Error::Input.
    let gate_io = matches!(err, Error::Maps(skinkit_maps::Error::Input(skinkit_maps::input::InputError::Io { .. })));
    assert!(gate_io && err.to_string().contains("light_intensities.txt"), "{err}");
}

const UW: &str = "4\n0.403259 0.480808 0.778592\n0.0982272 0.163712 0.981606\n-0.0654826 0.180077 0.98147\n-0.127999 0.431998 0.892745\n";

#[test]
fn uw_good_input() {
    let rig = parse_uw_lights(UW.as_bytes(), "lights.txt").unwrap();
    assert_eq!(rig.lights().len(), 4);
    assert!((rig.lights()[0].direction() - Vec3::new(0.403259, 0.480808, 0.778592).normalize()).length() < 1e-6);
    assert!(rig.lights().iter().all(|l| l.intensity() == Vec3::ONE));
    let mut flipped = rig.clone();
    flipped.flip_y();
    assert_eq!(flipped.lights()[0].direction().y, -rig.lights()[0].direction().y);
}

#[test]
fn uw_errors_name_file_and_line() {
    let bad_number = UW.replace("0.163712", "0.16x");
    let (loc, reason) = location(parse_uw_lights(bad_number.as_bytes(), "lights.txt").unwrap_err());
    assert_eq!(loc, "lights.txt: line 3");
    assert!(reason.contains("0.16x"));
    let bad_count = UW.replacen('4', "four", 1);
    let (loc, _) = location(parse_uw_lights(bad_count.as_bytes(), "lights.txt").unwrap_err());
    assert_eq!(loc, "lights.txt: line 1");
    let short = UW.replacen('4', "5", 1);
    let err = parse_uw_lights(short.as_bytes(), "lights.txt").unwrap_err();
    assert_eq!(err.to_string(), "lights.txt: declares 5 lights on line 1 but has 4 direction lines");
    let zero = UW.replace("-0.0654826 0.180077 0.98147", "0 0 0");
    assert_eq!(
        parse_uw_lights(zero.as_bytes(), "lights.txt").unwrap_err().to_string(),
        "lights.txt: line 4: direction has zero length"
    );
    assert!(parse_uw_lights(&b""[..], "lights.txt").is_err());
}

#[test]
fn uw_reads_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lights.txt");
    std::fs::write(&path, UW).unwrap();
    assert_eq!(uw_lights(&path).unwrap().lights().len(), 4);
}
