//! Rows 2.x of the first probe: rigs that cannot determine a normal or break a limit, refused by
//! `rig check` and by `capture` alike (the probe found `rig check` passing rigs capture refused).

use std::path::{Path, PathBuf};

use super::Scratch;
use super::inputs::{Rig, grey_png, noise, rig};
use crate::support::s;

/// The rig `kind` written as `in/rigs/<name>.toml`.
fn rig_file(scratch: &Scratch, name: &str, kind: Rig) -> PathBuf {
    let path = scratch.folder("rigs").join(format!("{name}.toml"));
    rig(&path, kind);
    path
}

/// `rig check` of `rig` fails, naming it once and saying `words`.
fn check_refuses(scratch: &Scratch, rig: &Path, words: &[&str]) {
    scratch.expect(&[1]).names(s(rig)).says(words).run(&["rig", "check", s(rig)]);
}

/// A capture of the cheek's photos with `rig` fails, naming it once and saying `words`, and
/// writes nothing.
fn capture_refuses(scratch: &Scratch, rig: &Path, words: &[&str]) {
    let (folder, _, _) = scratch.cheek();
    let args = ["capture", "--rig", s(rig), "--photos-from", s(&folder), "--out", "out/c"];
    scratch.expect(&[1]).names(s(rig)).says(words).leaves_nothing_at(scratch.out("c")).run(&args);
}

/// 2.6, D11: a rig of rank 2 (two directions, each four times) fails `rig check`, naming it.
#[test]
fn probe1_2_6_a_rank_2_rig_fails_rig_check() {
    let scratch = Scratch::new();
    check_refuses(&scratch, &rig_file(&scratch, "rank2", Rig::Rank2), &["coplanar"]);
}

/// 2.7a, 2.7b, D11: coplanar lights fail `rig check` and `capture`, which writes nothing.
#[test]
fn probe1_2_7_coplanar_lights_fail_rig_check_and_capture() {
    let scratch = Scratch::new();
    let rig = rig_file(&scratch, "coplanar", Rig::Coplanar);
    check_refuses(&scratch, &rig, &["coplanar"]);
    capture_refuses(&scratch, &rig, &["coplanar"]);
}

/// 2.8a, 2.8b, D7, D11: a condition number over capture's limit (nearly coplanar lights) fails
/// `rig check` as it fails `capture`, both saying `condition`.
#[test]
fn probe1_2_8_a_condition_number_over_the_limit_fails_both() {
    let scratch = Scratch::new();
    let rig = rig_file(&scratch, "near-coplanar", Rig::NearCoplanar);
    check_refuses(&scratch, &rig, &["condition"]);
    capture_refuses(&scratch, &rig, &["condition"]);
}

/// 2.10a, 2.10b, D7, D11: 200 lights, over the limit of 128, fail `rig check`, and `capture`
/// of 200 photos before decoding any, both giving the limit.
#[test]
fn probe1_2_10_two_hundred_lights_fail_both_with_the_limit() {
    let scratch = Scratch::new();
    check_refuses(&scratch, &rig_file(&scratch, "lights200", Rig::Lights200), &["128"]);
    let folder = scratch.folder("p200");
    grey_png(&folder.join("001.png"), 8, 8, 16, 30000);
    for i in 2..=200 {
        std::fs::copy(folder.join("001.png"), folder.join(format!("{i:03}.png"))).unwrap();
    }
    let rig_path = folder.join("rig.toml");
    rig(&rig_path, Rig::Lights200);
    let args = ["capture", "--rig", s(&rig_path), "--photos-from", s(&folder), "--out", "out/c"];
    scratch.expect(&[1]).names(s(&rig_path)).says(&["128"]).leaves_nothing_at(scratch.out("c")).run(&args);
}

/// 2.16, D10: 2000 random bytes as a rig are refused in one line naming the file.
#[test]
fn probe1_2_16_random_bytes_as_a_rig_are_refused() {
    let scratch = Scratch::new();
    let path = scratch.folder("rigs").join("noise.toml");
    noise(&path, 2000, 16);
    check_refuses(&scratch, &path, &[]);
}

/// 2.17a, 2.17b, D7, D11: a rig naming a missing ambient frame fails `rig check` as it fails
/// `capture`, both naming the field.
#[test]
fn probe1_2_17_a_missing_ambient_frame_fails_both() {
    let scratch = Scratch::new();
    let rig = rig_file(&scratch, "ambient", Rig::Ambient);
    check_refuses(&scratch, &rig, &["ambient"]);
    capture_refuses(&scratch, &rig, &["ambient"]);
}

/// 2.18a, 2.18b, D7, D11: lights positioned at (0, 0, 0), on the mold plane, fail `rig check`
/// as they fail `capture`, both naming the position.
#[test]
fn probe1_2_18_lights_on_the_mold_plane_fail_both() {
    let scratch = Scratch::new();
    let rig = rig_file(&scratch, "positions", Rig::Positions);
    check_refuses(&scratch, &rig, &["position"]);
    capture_refuses(&scratch, &rig, &["position"]);
}

/// 2.25, D10: a DiLiGenT folder without `light_intensities.txt` fails `rig import`, naming
/// that file, and writes no rig.
#[test]
fn probe1_2_25_a_diligent_folder_without_intensities_fails_rig_import() {
    let scratch = Scratch::new();
    let folder = scratch.folder("diligent");
    std::fs::write(folder.join("light_directions.txt"), "0 0 1\n0.5 0 0.8\n0 0.5 0.8\n").unwrap();
    let args = ["rig", "import", "--diligent", s(&folder), "--out", "out/r.toml"];
    let case = scratch.expect(&[1]).names("light_intensities.txt").leaves_nothing_at(scratch.out("r.toml"));
    case.run(&args);
}
