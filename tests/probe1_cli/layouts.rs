//! Rows 3.x and 4.x of the first probe: layouts asking for huge maps (refused from their
//! numbers and headers, in little memory) and exemplars with nothing valid to grow from.

use std::path::{Path, PathBuf};

use super::Scratch;
use super::inputs::{Rng, grey_png, rgb16_png};
use crate::support::s;

/// The bound on the peak memory of a refusal of a huge request (the probe's: they took
/// gigabytes before they were refused, or aborted).
const REFUSAL_MIB: u64 = 1024;

/// `in/layouts/<name>.toml`: a two-region layout of `size` (`512, 256`) grown from the cheek
/// and nose truth maps at exemplar scale `scale`, `extra` lines at its top.
pub fn layout(scratch: &Scratch, name: &str, size: &str, scale: &str, extra: &str) -> PathBuf {
    let region = |region: &str, u: f32| {
        let exemplar = scratch.input(&format!("molds/{region}/truth.png"));
        format!(
            "[[region]]\nname = \"{region}\"\nexemplar = \"{}\"\nexemplar_mm_per_texel = {scale}\npoints = [[{u}, 0.5]]\n",
            s(&exemplar)
        )
    };
    let path = scratch.folder("layouts").join(format!("{name}.toml"));
    let text =
        format!("size = [{size}]\nmm_per_texel = 0.05\n{extra}\n{}{}", region("cheek", 0.3), region("nose", 0.7));
    std::fs::write(&path, text).unwrap();
    path
}

/// `stitch --layout LAYOUT` fails naming `names` once, in little memory, writing nothing.
fn stitch_refuses(scratch: &Scratch, layout: &Path, names: &str, timeout: u64) {
    let args = ["stitch", "--layout", s(layout), "--out", "out/f.png"];
    let case = scratch.expect(&[1]).names(names).leaves_nothing_at(scratch.out("f.png"));
    case.within_mib(REFUSAL_MIB).timeout(timeout).run(&args);
}

/// 3.10, D6: a layout of 32768 x 32768 (the size limit) is refused from its numbers against the
/// memory limit, in under 1 GiB (it took 4.1 GB and 11 s).
#[test]
fn probe1_3_10_a_layout_at_the_size_limit_is_refused_in_little_memory() {
    let scratch = Scratch::new();
    let path = layout(&scratch, "huge", "32768, 32768", "0.02", "");
    stitch_refuses(&scratch, &path, s(&path), 120);
}

/// 3.14, D1: `exemplar_mm_per_texel = 1e9` is refused naming the region's field, in under
/// 1 GiB (it aborted).
#[test]
fn probe1_3_14_an_exemplar_scale_of_1e9_is_refused() {
    let scratch = Scratch::new();
    let path = layout(&scratch, "scale1e9", "512, 256", "1e9", "");
    stitch_refuses(&scratch, &path, s(&path), 60);
}

/// 3.15, D1: `exemplar_mm_per_texel = 3` (a 15360-texel exemplar after resampling) is refused
/// before resampling, in under 1 GiB (it took 2.7 GB first).
#[test]
fn probe1_3_15_an_exemplar_scale_of_3_is_refused_before_resampling() {
    let scratch = Scratch::new();
    let path = layout(&scratch, "scale3", "512, 256", "3.0", "");
    stitch_refuses(&scratch, &path, s(&path), 60);
}

/// 3.19, D6: a coverage PNG of 32768 x 32768 (a few MB of zeros) for a 512 x 256 map is refused
/// from its header, naming it, in under 1 GiB (it took 5.1 GB and 14 s).
#[test]
fn probe1_3_19_a_huge_coverage_png_is_refused_from_its_header() {
    let scratch = Scratch::new();
    let coverage = scratch.folder("layouts").join("coverage.png");
    grey_png(&coverage, 32768, 32768, 8, 0);
    let path = layout(&scratch, "coverage", "512, 256", "0.02", &format!("coverage = \"{}\"", s(&coverage)));
    stitch_refuses(&scratch, &path, s(&coverage), 60);
}

/// 4.6, D13: a random 16-bit RGB exemplar (some texels invalid) grows a map over 1 % invalid,
/// which fails saying `invalid` (issue 42, D6).
#[test]
fn probe1_4_6_a_random_exemplar_fails_on_its_invalid_share() {
    let scratch = Scratch::new();
    let exemplar = scratch.folder("exemplars").join("random.png");
    let mut rng = Rng(7);
    rgb16_png(&exemplar, 64, 64, |_, _| [rng.next() as u16, rng.next() as u16, rng.next() as u16]);
    let args = ["synth", s(&exemplar), "--size", "64x64", "--out", "out/s.png"];
    scratch.expect(&[1]).says(&["invalid"]).run(&args);
}

/// 4.9, D13: an exemplar whose every normal is invalid (all zeros) is refused within 5 s,
/// naming it and saying it has no valid normal.
#[test]
fn probe1_4_9_an_exemplar_with_no_valid_normal_is_refused_at_once() {
    let scratch = Scratch::new();
    let exemplar = scratch.folder("exemplars").join("invalid.png");
    rgb16_png(&exemplar, 64, 64, |_, _| [0, 0, 0]);
    let args = ["synth", s(&exemplar), "--size", "128x128", "--out", "out/s.png"];
    let case = scratch.expect(&[1]).names(s(&exemplar)).says(&["no valid normal"]);
    case.leaves_nothing_at(scratch.out("s.png")).within_seconds(5.0).run(&args);
}
