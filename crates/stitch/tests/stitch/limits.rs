//! The stitch side of the resource policy (issue 15): a resampled exemplar's size and its
//! synthesis estimate are checked before it is resampled (D1), the coverage mask from its header
//! before it is decoded, and a map at the size limit from its numbers before anything of its size
//! is allocated (D6). Heap use is measured by a counting allocator (installed in main.rs) that counts
//! only the measured call's threads; each measuring test holds a lock.

use std::path::Path;

use skinkit_maps::NormalMap;
use skinkit_stitch::compose::{MAP_BYTES_PER_TEXEL, check_memory};
use skinkit_stitch::curve::CurveParams;
use skinkit_stitch::layout::Layout;
use skinkit_stitch::{ComposeOptions, compose};
use skinkit_synth::SynthConfig;
use skinkit_testkit::alloc::{alone, peak_during};
use skinkit_testkit::header_only_png;

const MIB: usize = 1 << 20;

/// Two regions on a `w x h` map at 0.05 mm per texel; region `b`'s exemplar is `scale` mm per
/// texel; `extra` goes on top of the file.
fn layout(dir: &Path, w: usize, h: usize, scale: f64, extra: &str) -> Layout {
    let text = format!(
        r#"{extra}
size = [{w}, {h}]
mm_per_texel = 0.05
[[region]]
name = "a"
exemplar = "a.png"
exemplar_mm_per_texel = 0.05
points = [[0.25, 0.5]]
[[region]]
name = "b"
exemplar = "b.png"
exemplar_mm_per_texel = {scale}
points = [[0.75, 0.5]]
"#
    );
    Layout::parse(&text, &dir.join("layout.toml")).unwrap()
}

fn options() -> ComposeOptions {
    ComposeOptions {
        curve: CurveParams::straight(),
        synth: SynthConfig { memory_limit: 8 << 30, ..SynthConfig::default() },
        ..ComposeOptions::default()
    }
}

fn exemplars() -> Vec<NormalMap> {
    vec![NormalMap::flat(64, 64), NormalMap::flat(256, 256)]
}

#[test]
fn d1_huge_exemplar_scale_is_refused_before_allocating() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 512, 256, 1e9, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &skinkit_maps::progress::NoProgress));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("layout.toml: region `b`: exemplar_mm_per_texel"), "{e}");
    assert!(e.contains("over the limit of 268435456 texels"), "{e}");
    assert!(peak < 16 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d1_an_exemplar_whose_synthesis_cannot_fit_is_refused_before_resampling() {
    let _alone = alone();
    // 3 mm against 0.05: the 256x256 exemplar would become 15360x15360 (2.7 GB of normals, which
    // the probe saw allocated) before the synthesis estimate refused it.
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 512, 256, 3.0, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &skinkit_maps::progress::NoProgress));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("region `b`") && e.contains("15360x15360") && e.contains("needs an estimated"), "{e}");
    assert!(peak < 64 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d6_a_coverage_bomb_is_refused_from_its_header() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    // A real 32768x32768 8-bit PNG of zeros would be about 1 MB; its header is all it takes.
    header_only_png(&dir.path().join("bomb.png"), 32768, 32768);
    let l = layout(dir.path(), 512, 256, 0.05, "coverage = \"bomb.png\"");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &skinkit_maps::progress::NoProgress));
    let e = result.unwrap_err().to_string();
    assert!(e.contains("coverage") && e.contains("bomb.png is 32768x32768 but the map is 512x256"), "{e}");
    assert!(peak < 4 * MIB, "{} MiB held before refusing", peak / MIB);
}

#[test]
fn d6_a_map_at_the_size_limit_is_refused_before_anything_is_allocated() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 32768, 32768, 0.05, "");
    let (result, peak) = peak_during(|| compose(&l, &exemplars(), &options(), &skinkit_maps::progress::NoProgress));
    let e = result.unwrap_err().to_string();
    // 2^30 texels at 28 bytes: 28 GiB.
    assert!(e.contains("layout.toml: size: a 32768x32768 face map needs an estimated 28672 MiB"), "{e}");
    assert!(e.contains("memory limit of 8192 MiB"), "{e}");
    assert!(peak < MIB, "{} bytes held before refusing", peak);
    assert!(check_memory(&l, &options()).is_err(), "callers can check before reading exemplars");
}

#[test]
fn d6_the_map_floor_is_below_what_a_compose_holds() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    let l = layout(dir.path(), 128, 64, 0.05, "");
    let (composed, peak) =
        peak_during(|| compose(&l, &exemplars(), &options(), &skinkit_maps::progress::NoProgress).unwrap());
    let floor = 128 * 64 * MAP_BYTES_PER_TEXEL as usize;
    eprintln!("128x64 map: floor {floor} bytes, heap peak {peak} bytes ({:.1}x)", peak as f64 / floor as f64);
    assert!(peak >= floor, "the floor {floor} is above the measured peak {peak}");
    drop(composed);
}

#[test]
fn regions_that_fit_the_limit_only_one_at_a_time_grow_one_at_a_time_to_the_same_map() {
    let _alone = alone();
    let dir = tempfile::tempdir().unwrap();
    // Two mirror-image regions from equal exemplars: equal estimates E, so the smallest doubling
    // of the limit that admits one (below 2E) cannot admit both beside the map.
    let l = layout(dir.path(), 256, 128, 0.05, "");
    let same = vec![NormalMap::flat(64, 64), NormalMap::flat(64, 64)];
    let roomy = compose(&l, &same, &options(), &skinkit_maps::progress::NoProgress).unwrap();
    assert_eq!(roomy.regions_at_once, 2);
    let mut limit = 1u64 << 20;
    let tight = loop {
        let tight_options =
            ComposeOptions { synth: SynthConfig { memory_limit: limit, ..options().synth }, ..options() };
        match compose(&l, &same, &tight_options, &skinkit_maps::progress::NoProgress) {
            Ok(composed) => break composed,
            Err(e) => assert!(e.to_string().contains("needs an estimated"), "{e}"),
        }
        limit *= 2;
        assert!(limit < 8 << 30, "never fitted");
    };
    assert_eq!(tight.regions_at_once, 1, "at {} MiB", limit >> 20);
    let bits = |c: &skinkit_stitch::Composed| {
        c.normals.grid().as_slice().iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>()
    };
    assert!(bits(&tight) == bits(&roomy), "one at a time gives the same bits");
}
