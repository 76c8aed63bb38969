//! The capture side of the resource policy (issue 15): rigs are refused by one check that
//! `capture` and `rig check` share (D7), and a photo stack over the memory limit is refused from
//! the headers before any photo is decoded (D9). Heap use is measured by a counting allocator
//! (installed in main.rs) that counts only the measured call's threads; each measuring test holds a lock.

use std::path::{Path, PathBuf};

use glam::Vec3;
use skinkit_capture::session::{self, CaptureOptions, Session};
use skinkit_capture::solve::SolveConfig;
use skinkit_capture::{Light, Rig};
use skinkit_heightfield::dng::dng_of_rgb;
use skinkit_testkit::alloc::{alone, peak_during};
use skinkit_testkit::header_only_png;

const MIB: usize = 1 << 20;

fn mold(region: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds").join(region)
}

/// A session of 8 photos claiming `side x side` pixels each, under the paper's turntable rig.
fn bomb_session(dir: &Path, side: u32) -> Session {
    let rig = dir.join("rig.toml");
    Rig::turntable(8, 45.0, 1.0).unwrap().save(&rig).unwrap();
    let photos = (1..=8)
        .map(|i| {
            let p = dir.join(format!("{i:02}.png"));
            header_only_png(&p, side, side);
            p
        })
        .collect();
    Session { rig, photos, mask: None, ambient: None, truth: None, skipped: Vec::new() }
}

#[test]
fn d9_a_photo_stack_over_the_memory_limit_is_refused_before_decoding() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let files = bomb_session(dir.path(), 16384);
    let options = CaptureOptions { memory_limit: 4 << 30, ..CaptureOptions::default() };
    // By hand: 8 photos of 2^28 one-byte samples (2 GiB), the solution's normals, grey albedo and
    // confidence at 20 bytes a pixel (5 GiB), and the larger of the photos and the detrended copy
    // (12 bytes a pixel, 3 GiB): 8 GiB.
    let px = 16384u64 * 16384;
    let by_hand = 20 * px + (8 * px).max(12 * px);
    assert_eq!(session::memory_estimate(&files, None, &options).unwrap(), by_hand);
    let (result, peak) = peak_during(|| session::capture(&files, &options, &skinkit_maps::progress::NoProgress));
    let e = result.map_err(|e| skinkit_maps::error::one_line(&e)).unwrap_err();
    assert!(e.contains("needs an estimated 8192 MiB") && e.contains("memory limit of 4096 MiB"), "{e}");
    assert!(e.contains(&dir.path().display().to_string()), "names the photos' folder: {e}");
    assert!(peak < 8 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d9_the_estimate_bounds_what_a_capture_holds() {
    let _alone = alone();
    let files = Session::from_dir(&mold("cheek")).unwrap();
    let options = CaptureOptions::default();
    let estimate = session::memory_estimate(&files, None, &options).unwrap() as usize;
    // The solution (20 bytes a pixel), the truth map (12), and the larger of the 8 photos of
    // 256x256 16-bit grey (16 bytes a pixel) and the detrended copy (12).
    let px = 256 * 256;
    assert_eq!(estimate, 20 * px + 12 * px + (16 * px).max(12 * px));
    let (captured, peak) =
        peak_during(|| session::capture(&files, &options, &skinkit_maps::progress::NoProgress).unwrap());
    drop(captured);
    eprintln!(
        "cheek 256x256: estimate {estimate} bytes, heap peak {peak} bytes ({:.2})",
        peak as f64 / estimate as f64
    );
    // Decoder buffers, thread-local scratch and the report ride on top of the large arrays.
    assert!(peak <= estimate + estimate / 4, "peak {peak} above the estimate {estimate}");
    assert!(peak >= estimate / 2, "peak {peak}: the estimate {estimate} is not about this capture");
}

/// The cheek mold's photos as 16-bit grey values in 0..1.
fn cheek_photos() -> Vec<Vec<f32>> {
    (1..=8)
        .map(|i| {
            let img = image::open(mold("cheek").join(format!("{i:02}.png"))).unwrap().into_luma16();
            img.pixels().map(|p| f32::from(p.0[0]) / 65535.0).collect()
        })
        .collect()
}

fn write_grey(path: &Path, side: u32, values: impl Iterator<Item = f32>) {
    let samples: Vec<u16> = values.map(|v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16).collect();
    image::ImageBuffer::<image::Luma<u16>, _>::from_raw(side, side, samples).unwrap().save(path).unwrap();
}

/// The cheek mold's rig with `extra(i)` added to light `i`'s table (from 1).
fn cheek_rig(dir: &Path, extra: &dyn Fn(usize) -> String) {
    let text = std::fs::read_to_string(mold("cheek").join("rig.toml")).unwrap();
    let mut light = 0;
    let lines = text.lines().map(|line| {
        if line.starts_with("intensity") {
            light += 1;
            format!("{line}\n{}\n", extra(light))
        } else {
            format!("{line}\n")
        }
    });
    std::fs::write(dir.join("rig.toml"), lines.collect::<String>()).unwrap();
}

/// Writes a session's files into a folder.
type MakeSession<'a> = dyn Fn(&Path) + 'a;

/// The cheek session three ways the estimate models stage by stage (issue 39): as half-size
/// DNGs (the RAW decode's file copies and sensor samples), three exposure brackets a light (the
/// merged readings) and a flat frame a light (the corrected copies and the flats' fits).
#[test]
fn the_estimate_bounds_raw_bracketed_and_flat_fielded_captures() {
    let _alone = alone();
    let side = 256u32;
    let photos = cheek_photos();
    let kinds: [(&str, &MakeSession); 3] = [
        ("RAW (half-size DNG)", &|dir: &Path| {
            std::fs::copy(mold("cheek").join("rig.toml"), dir.join("rig.toml")).unwrap();
            for (i, p) in photos.iter().enumerate() {
                let rgb: Vec<[f32; 3]> = p.iter().map(|&v| [v, v, v]).collect();
                let dng = dng_of_rgb(&rgb, side as usize, side as usize, [0, 1, 1, 2], 512, 16383);
                std::fs::write(dir.join(format!("{:02}.dng", i + 1)), dng).unwrap();
            }
        }),
        ("3 brackets a light", &|dir: &Path| {
            cheek_rig(dir, &|_| "exposures = [0.5, 1.0, 2.0]".to_owned());
            for (i, p) in photos.iter().enumerate() {
                for (j, t) in [0.5f32, 1.0, 2.0].into_iter().enumerate() {
                    write_grey(&dir.join(format!("{:02}-{j}.png", i + 1)), side, p.iter().map(|v| v * t));
                }
            }
        }),
        ("a flat frame a light", &|dir: &Path| {
            std::fs::create_dir(dir.join("flats")).unwrap();
            cheek_rig(dir, &|i| format!("flat = \"flats/{i:02}.png\""));
            for (i, p) in photos.iter().enumerate() {
                let gain = |k: usize| 0.6 + 0.3 * (k % side as usize) as f32 / side as f32;
                write_grey(&dir.join(format!("flats/{:02}.png", i + 1)), side, (0..p.len()).map(gain));
                let lit = p.iter().enumerate().map(|(k, v)| v * gain(k));
                write_grey(&dir.join(format!("{:02}.png", i + 1)), side, lit);
            }
        }),
    ];
    for (name, make) in kinds {
        let dir = tempfile::tempdir().unwrap();
        make(dir.path());
        let files = Session::from_dir(dir.path()).unwrap();
        let options = CaptureOptions::default();
        let estimate = session::memory_estimate(&files, None, &options).unwrap() as usize;
        let (captured, peak) =
            peak_during(|| session::capture(&files, &options, &skinkit_maps::progress::NoProgress).unwrap());
        assert_eq!(captured.report.width, side as usize, "{name}");
        drop(captured);
        let ratio = peak as f64 / estimate as f64;
        eprintln!("{name}: estimate {} KiB, heap peak {} KiB ({ratio:.2})", estimate >> 10, peak >> 10);
        assert!(peak <= estimate + estimate / 4, "{name}: peak {peak} above the estimate {estimate}");
        assert!(peak >= estimate / 2, "{name}: peak {peak}: the estimate {estimate} is not about this capture");
    }
}

/// An 8-light rig close to the plane y = 0 (directions `(cos a, +-eps, sin a)`): poorly
/// conditioned, with a condition number that grows as `eps` shrinks.
fn flat_rig(eps: f32) -> Rig {
    let lights = (0..8)
        .map(|i| {
            let a = (25.0 + 130.0 * i as f32 / 7.0).to_radians();
            let y = if i % 2 == 0 { eps } else { -eps };
            Light::new(Vec3::new(a.cos(), y, a.sin()), Vec3::ONE, None).unwrap()
        })
        .collect();
    Rig::new(lights, "flat").unwrap()
}

#[test]
fn d7_rig_check_refuses_exactly_what_capture_refuses() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let photos = Session::from_dir(&mold("nose")).unwrap().photos;
    for eps in [0.3, 0.02, 0.008] {
        let rig = flat_rig(eps);
        let path = dir.path().join(format!("rig-{eps}.toml"));
        rig.save(&path).unwrap();
        let c = rig.conditioning().condition_number;
        for max_condition in [c * 0.999, c * 1.001, 50.0] {
            let solve = SolveConfig { max_condition, ..SolveConfig::default() };
            let checked = session::check_rig(&path, &rig, None, &solve);
            let options = CaptureOptions { solve, detrend_block: 0, ..CaptureOptions::default() };
            let files = Session {
                rig: path.clone(),
                photos: photos.clone(),
                mask: None,
                ambient: None,
                truth: None,
                skipped: Vec::new(),
            };
            let captured = session::capture(&files, &options, &skinkit_maps::progress::NoProgress);
            assert_eq!(checked.is_ok(), captured.is_ok(), "condition {c}, limit {max_condition}");
            assert_eq!(checked.is_ok(), c <= max_condition, "condition {c}, limit {max_condition}");
            if let Err(e) = checked {
                let e = skinkit_maps::error::one_line(&e);
                assert!(e.contains(&path.display().to_string()) && e.contains("--max-condition"), "{e}");
            }
        }
    }
}

#[test]
fn d7_too_many_lights_and_a_missing_ambient_are_rig_errors() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig.toml");
    let many = Rig::turntable(200, 45.0, 1.0).unwrap();
    let e = session::check_rig(&path, &many, None, &SolveConfig::default())
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("200 lights") && e.contains("at most 128") && e.contains("rig.toml"), "{e}");
    // Refused before any photo is read: these 200 photos are headers without pixels.
    many.save(&path).unwrap();
    let photos: Vec<PathBuf> = (0..200)
        .map(|i| {
            let p = dir.path().join(format!("p{i:03}.png"));
            header_only_png(&p, 64, 64);
            p
        })
        .collect();
    let files = Session { rig: path.clone(), photos, mask: None, ambient: None, truth: None, skipped: Vec::new() };
    let e = session::capture(&files, &CaptureOptions::default(), &skinkit_maps::progress::NoProgress)
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("at most 128"), "{e}");

    let with_ambient = Rig::turntable(8, 45.0, 1.0).unwrap().with_ambient(Some(dir.path().join("nope.png")));
    let e = session::check_rig(&path, &with_ambient, None, &SolveConfig::default())
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("ambient") && e.contains("nope.png") && e.contains("rig.toml"), "{e}");
    let given = dir.path().join("gone.png");
    let e = session::check_rig(&path, &with_ambient, Some(&given), &SolveConfig::default())
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("ambient frame") && e.contains("gone.png"), "the flag's file overrides the rig's: {e}");
}

/// Issue 42, D13: the ambient frame is read by its header, as `capture` reads it: a rig whose
/// `ambient` is not an image (the rig file itself) is refused by the check `rig check` runs.
#[test]
fn d13_an_ambient_that_is_not_an_image_is_refused_by_the_rig_check() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rig.toml");
    let rig = Rig::turntable(8, 45.0, 1.0).unwrap().with_ambient(Some(path.clone()));
    rig.save(&path).unwrap();
    let e = session::check_rig(&path, &rig, None, &SolveConfig::default())
        .map_err(|e| skinkit_maps::error::one_line(&e))
        .unwrap_err();
    assert!(e.contains("field `ambient` (the ambient frame)") && e.contains("not a readable image"), "{e}");
}
