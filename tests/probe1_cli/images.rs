//! Rows 1.x of the first probe: photos that are not what capture needs, and flags out of range.

use super::Scratch;
use super::inputs::{grey_png, jpeg};
use crate::support::s;

/// A capture of `photos` with the cheek's rig into `out/c`.
fn capture<'a>(rig: &'a str, photos: &'a [String]) -> Vec<&'a str> {
    let mut args = vec!["capture", "--rig", rig, "--out", "out/c"];
    args.extend(photos.iter().map(String::as_str));
    args
}

/// 1.10, D9: eight 16384 x 16384 8-bit photos, at the per-photo cap (2.3 MB of PNGs, 2 GiB
/// decoded), are captured or refused within the memory budget, never aborted; the inputs stay
/// as they were.
#[test]
#[ignore = "slow: decodes 2 GiB of photos (minutes in a debug build)"]
fn probe1_1_10_eight_photos_at_the_size_cap_are_captured_or_refused() {
    let scratch = Scratch::new();
    let (_, rig, _) = scratch.cheek();
    let folder = scratch.folder("capped");
    grey_png(&folder.join("001.png"), 16384, 16384, 8, 100);
    for i in 2..=8 {
        std::fs::copy(folder.join("001.png"), folder.join(format!("{i:03}.png"))).unwrap();
    }
    std::fs::copy(rig, folder.join("rig.toml")).unwrap();
    let rig = folder.join("rig.toml");
    let args = ["capture", "--rig", s(&rig), "--photos-from", s(&folder), "--out", "out/capped"];
    let run = scratch.expect(&[0, 1]).names(s(&folder)).leaves_nothing_at(scratch.out("capped"));
    run.timeout(150).address_space(12_000_000).run(&args);
}

/// 1.12, D13: eight photos of JPEG data named `.png` are refused as JPEG (lossy, sRGB: photos
/// must be linear), naming the first of them once and writing nothing.
#[test]
fn probe1_1_12_jpeg_data_named_png_is_refused() {
    let scratch = Scratch::new();
    let (_, rig, _) = scratch.cheek();
    let folder = scratch.folder("jpeg");
    for i in 1..=8 {
        jpeg(&folder.join(format!("0{i}.png")), 256, 256, i);
    }
    std::fs::copy(rig, folder.join("rig.toml")).unwrap();
    let rig = folder.join("rig.toml");
    let first = format!("{}/0", s(&folder));
    scratch.expect(&[1]).names(first).says(&["JPEG", "linear"]).leaves_nothing_at(scratch.out("jpeg")).run(&[
        "capture",
        "--rig",
        s(&rig),
        "--photos-from",
        s(&folder),
        "--out",
        "out/jpeg",
    ]);
}

/// 1.22a, D10: photo 3 a folder is refused as photo 3, by its path, at once.
#[test]
fn probe1_1_22a_a_folder_as_photo_3_is_refused() {
    let scratch = Scratch::new();
    let (_, rig, mut photos) = scratch.cheek();
    let folder = scratch.folder("folder-photo/03.png");
    photos[2] = s(&folder).to_owned();
    scratch
        .expect(&[1])
        .names(s(&folder))
        .says(&["photo 3"])
        .leaves_nothing_at(scratch.out("c"))
        .run(&capture(s(&rig), &photos));
}

/// 1.22b, D10: `/dev/zero` as photo 3 is refused as photo 3 without being read (within 20 s).
#[test]
fn probe1_1_22b_dev_zero_as_photo_3_is_refused() {
    let scratch = Scratch::new();
    let (_, rig, mut photos) = scratch.cheek();
    photos[2] = "/dev/zero".to_owned();
    let case = scratch.expect(&[1]).names("/dev/zero").says(&["photo 3"]).leaves_nothing_at(scratch.out("c"));
    case.timeout(20).run(&capture(s(&rig), &photos));
}

/// 1.23, exit: `--saturation 0` is a usage error naming the flag, and nothing is written.
#[test]
fn probe1_1_23_a_saturation_of_0_is_a_usage_error() {
    let scratch = Scratch::new();
    let (folder, rig, _) = scratch.cheek();
    let args = ["capture", "--rig", s(&rig), "--photos-from", s(&folder), "--out", "out/c", "--saturation", "0"];
    scratch.expect(&[2]).names("--saturation").leaves_nothing_at(scratch.out("c")).run(&args);
}

/// 1.24, D8: `--threads 10000` on a capture of a few milliseconds either runs or is a usage
/// error naming the flag, within 30 s (it once ran past a minute starting threads).
#[test]
fn probe1_1_24_ten_thousand_threads_are_refused_or_harmless() {
    let scratch = Scratch::new();
    let (folder, rig, _) = scratch.cheek();
    let args = ["--threads", "10000", "capture", "--rig", s(&rig), "--photos-from", s(&folder), "--out", "out/c"];
    scratch.expect(&[0, 2]).names("--threads").timeout(30).run(&args);
}
