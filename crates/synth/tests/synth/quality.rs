//! Quality of synthesised maps against the exemplar's own variation (issue 3, "What it must show").
//!
//! The yardstick is how much two disjoint halves of one larger ground-truth field differ: a
//! `256 x 128` field (a heightfield preset, or a sample mold's captured `256 x 256` map) is cut into
//! two `128 x 128` halves, A (the exemplar) and B (unseen). Synthesis grows A into `256 x 256`
//! (default [`SynthConfig`]: three levels, 5x5 + 3x3, k-coherence) and the output O is compared with
//! A and with B by the crate's metrics; every bound is a factor of the A-vs-B distance, measured
//! first and then set with a margin (the measured values are in the comments, test profile,
//! seed 1 unless said).
//!
//! Synthesis runs once per case and is shared by the tests that read it (`OnceLock`).

use std::path::PathBuf;
use std::sync::OnceLock;

use glam::Vec3;
use skinkit_capture::solve::{self, PhotoStack, SolveConfig};
use skinkit_capture::{Rig, detrend};
use skinkit_heightfield::SkinParams;
use skinkit_maps::io::{self, Limits};
use skinkit_maps::{ColorMap, Grid, NormalMap, Transfer};
use skinkit_synth::metrics::{self, CopyStats, DEFAULT_SPECTRUM_BINS as BINS};
use skinkit_synth::{NormalSynthesis, SynthConfig, Synthesis, synthesize, synthesize_normals};

/// Side of the exemplar halves.
const HALF: usize = 128;
/// Side of the outputs.
const OUT: usize = 256;
/// Detrend block of the captured maps (as `skinkit demo`, the paper's 50 x 50).
const DETREND_BLOCK: usize = 50;

fn config(seed: u64) -> SynthConfig {
    SynthConfig { seed, ..SynthConfig::new(OUT, OUT) }
}

// ---------------------------------------------------------------------------------------------
// Cases
// ---------------------------------------------------------------------------------------------

/// Exemplar A, unseen half B, and the synthesis grown from A.
struct NormalCase {
    name: &'static str,
    a: NormalMap,
    b: NormalMap,
    out: NormalSynthesis,
}

/// Left and right `HALF x HALF` halves of the top rows of `n`.
fn halves(n: &NormalMap) -> (NormalMap, NormalMap) {
    let half = |x0| NormalMap::from_unit_grid(n.grid().crop(x0, 0, HALF, HALF).unwrap()).unwrap();
    (half(0), half(HALF))
}

fn grow(name: &'static str, field: &NormalMap) -> NormalCase {
    let (a, b) = halves(field);
    let out = synthesize_normals(&a, &config(1), &skinkit_maps::progress::NoProgress).unwrap();
    NormalCase { name, a, b, out }
}

const PRESETS: [&str; 4] = ["forehead", "nose", "cheek", "forehead_edge"];

fn preset(name: &str, width: usize, height: usize, seed: u64) -> SkinParams {
    match name {
        "forehead" => SkinParams::forehead(width, height, seed),
        "nose" => SkinParams::nose(width, height, seed),
        "cheek" => SkinParams::cheek(width, height, seed),
        "forehead_edge" => SkinParams::forehead_edge(width, height, seed),
        _ => unreachable!("unknown preset {name}"),
    }
}

/// The heightfield case of `PRESETS[i]`: a `256 x 128` field, seed 7.
fn heightfield_case(i: usize) -> &'static NormalCase {
    static CASES: [OnceLock<NormalCase>; 4] = [const { OnceLock::new() }; 4];
    CASES[i].get_or_init(|| {
        let field = preset(PRESETS[i], 2 * HALF, HALF, 7).generate().unwrap().normals;
        grow(PRESETS[i], &field)
    })
}

const MOLDS: [&str; 4] = ["forehead", "nose", "cheek", "forehead-edge"];

fn mold_dir(region: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../samples/molds").join(region)
}

/// The photos `01.png .. 08.png` of a sample mold, linear, in rig order.
fn mold_photos(region: &str) -> (Vec<skinkit_maps::Photo>, Vec<String>) {
    let names: Vec<String> = (1..=8).map(|i| format!("{i:02}.png")).collect();
    let photos = names
        .iter()
        .map(|n| io::read_photo(&mold_dir(region).join(n), &Limits::default()).unwrap().with_transfer(Transfer::Linear))
        .collect();
    (photos, names)
}

/// A sample mold's captured normals as `skinkit capture` makes them: distant-light solve with the
/// rig, then the paper's 50 x 50 detrend.
fn captured(region: &str) -> NormalMap {
    let rig = Rig::load(&mold_dir(region).join("rig.toml")).unwrap();
    let (photos, names) = mold_photos(region);
    let stack = PhotoStack::new(photos, names).unwrap();
    let mut solution = solve::solve(&stack, &rig, &SolveConfig::default(), &solve::NoProgress).unwrap();
    detrend::detrend(&mut solution.normals, DETREND_BLOCK);
    solution.normals
}

/// The captured case of `MOLDS[i]` (the map is `256 x 256`; its top half is cut in two).
fn mold_case(i: usize) -> &'static NormalCase {
    static CASES: [OnceLock<NormalCase>; 4] = [const { OnceLock::new() }; 4];
    CASES[i].get_or_init(|| grow(MOLDS[i], &captured(MOLDS[i])))
}

// ---------------------------------------------------------------------------------------------
// Checks
// ---------------------------------------------------------------------------------------------

/// Bounds of one family of cases, as factors of the A-vs-B distance.
struct Bounds {
    slope: f64,
    spectrum: f64,
}

/// Slope-histogram and spectrum distances of the output within `bounds` of the halves' own
/// variation, against the exemplar A and against the unseen half B.
fn assert_statistics(c: &NormalCase, bounds: &Bounds) {
    let o = &c.out.normals;
    let slope =
        [metrics::slope_distance(&c.a, &c.b), metrics::slope_distance(o, &c.a), metrics::slope_distance(o, &c.b)];
    let spectrum = [
        metrics::normal_spectrum_distance(&c.a, &c.b, BINS),
        metrics::normal_spectrum_distance(o, &c.a, BINS),
        metrics::normal_spectrum_distance(o, &c.b, BINS),
    ];
    println!("{}: slope AB {:.4} OA {:.4} OB {:.4}", c.name, slope[0], slope[1], slope[2]);
    println!("{}: spectrum AB {:.4} OA {:.4} OB {:.4}", c.name, spectrum[0], spectrum[1], spectrum[2]);
    assert!(slope[0] > 0.0 && spectrum[0] > 0.0, "{}: the halves must differ", c.name);
    for (what, d, bound) in [("slope", slope, bounds.slope), ("spectrum", spectrum, bounds.spectrum)] {
        assert!(d[1] <= bound * d[0], "{}: {what} distance output-A {:.4} > {bound} x A-B {:.4}", c.name, d[1], d[0]);
        assert!(d[2] <= bound * d[0], "{}: {what} distance output-B {:.4} > {bound} x A-B {:.4}", c.name, d[2], d[0]);
    }
}

/// Root mean square of the slopes of a normal map (both axes).
fn rms_slope(n: &NormalMap) -> f64 {
    let (sx, sy) = metrics::slopes(n);
    let sum: f64 = sx.iter().chain(&sy).map(|&s| (s as f64).powi(2)).sum();
    (sum / (sx.len() + sy.len()).max(1) as f64).sqrt()
}

/// The output keeps at least `min` of the exemplar's rms slope (it does not come out flat).
fn assert_not_flat(c: &NormalCase, min: f64) {
    let ratio = rms_slope(&c.out.normals) / rms_slope(&c.a);
    println!("{}: rms slope output / exemplar {ratio:.3}", c.name);
    assert!(ratio >= min && ratio <= 1.5, "{}: rms slope ratio {ratio:.3} outside [{min}, 1.5]", c.name);
}

/// Distinct exemplar texels an output copies.
fn distinct_sources(coords: &Grid<[u32; 2]>) -> usize {
    let mut seen = vec![false; HALF * HALF];
    for &[x, y] in coords.as_slice() {
        seen[y as usize * HALF + x as usize] = true;
    }
    seen.iter().filter(|&&s| s).count()
}

/// Not a tiled copy: no large verbatim block, small blocks on average, and many exemplar texels and
/// offsets in use.
fn assert_not_tiled(name: &str, coords: &Grid<[u32; 2]>) {
    let stats = metrics::copy_statistics(coords, (HALF, HALF), false);
    let sources = distinct_sources(coords);
    println!(
        "{name}: largest block {} mean block {:.2} offsets {} sources {sources}",
        stats.largest_block, stats.mean_block, stats.distinct_offsets
    );
    assert_copy_bounds(name, &stats, sources);
}

/// Largest block at most an eighth of the exemplar (2048 texels; the default's copy cap keeps it
/// under 9 %, 1474), mean block at most 32 texels (the default copies coherent patches, which is
/// what keeps its energy low, and seam polishing merges their small fragments: measured 9.7 to
/// 20.7; the scanline start 2.2 to 4.9), at least a quarter of the exemplar's texels used as
/// sources (4096; measured 7745 to 12614 of the 124 x 124 = 15376 candidates) and a sixteenth as
/// many distinct offsets (1024; the default gives 2079 to 4965, the scanline start 9963 to 21829;
/// a tiled copy has one).
fn assert_copy_bounds(name: &str, stats: &CopyStats, sources: usize) {
    let area = HALF * HALF;
    assert!(stats.largest_block <= area / 8, "{name}: largest copied block {} > {}", stats.largest_block, area / 8);
    assert!(stats.mean_block <= 32.0, "{name}: mean copied block {:.2} > 32", stats.mean_block);
    assert!(sources >= area / 4, "{name}: only {sources} distinct exemplar texels used");
    assert!(stats.distinct_offsets >= area / 16, "{name}: only {} distinct offsets", stats.distinct_offsets);
}

/// Mean squared difference across each row boundary `y | y + 1` (`rows[y]`, the last one wrapping
/// to row 0) and each column boundary (`cols[x]`), computed directly.
fn line_energies(map: &Grid<Vec3>) -> (Vec<f64>, Vec<f64>) {
    let (w, h) = map.size();
    let d2 = |a: &Vec3, b: &Vec3| (a.as_dvec3() - b.as_dvec3()).length_squared();
    let rows = (0..h).map(|y| (0..w).map(|x| d2(map.get(x, y), map.get(x, (y + 1) % h))).sum::<f64>() / w as f64);
    let cols = (0..w).map(|x| (0..h).map(|y| d2(map.get(x, y), map.get((x + 1) % w, y))).sum::<f64>() / h as f64);
    (rows.collect(), cols.collect())
}

/// The seam line (the last of `lines`) over the median of the interior lines.
fn seam_over_median(lines: &[f64]) -> f64 {
    let (seam, interior) = lines.split_last().unwrap();
    let mut sorted = interior.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    if median > 0.0 {
        seam / median
    } else if *seam > 0.0 {
        f64::INFINITY
    } else {
        1.0
    }
}

/// Tileability bounds.
struct Tiling {
    /// Bound on `metrics::seam_energy(..).ratio` (both seams against the mean interior pair).
    ratio: f64,
    /// Bound on each seam line (the column boundary `w - 1 | 0` and the row boundary `h - 1 | 0`)
    /// over the median interior line of its orientation.
    line: f64,
}

/// Tileability: `metrics::seam_energy` agrees with the per-line energies computed here, and its
/// ratio and each seam line stay within `bounds`.
fn assert_tiles(name: &str, map: &Grid<Vec3>, bounds: &Tiling) {
    let seam = metrics::seam_energy(map);
    let (rows, cols) = line_energies(map);
    let (w, h) = (map.width() as f64, map.height() as f64);
    // Oracle: the seam pairs are the last row and column boundary; the interior pairs the rest.
    let across = (rows[rows.len() - 1] * w + cols[cols.len() - 1] * h) / (w + h);
    let interior_sum: f64 =
        rows[..rows.len() - 1].iter().sum::<f64>() * w + cols[..cols.len() - 1].iter().sum::<f64>() * h;
    let interior = interior_sum / (w * (h - 1.0) + h * (w - 1.0));
    assert!((seam.across_seam - across).abs() <= 1e-9 * across.max(1e-30), "{name}: {seam:?} vs {across}");
    assert!((seam.interior - interior).abs() <= 1e-9 * interior, "{name}: {seam:?} vs {interior}");
    let (row_line, col_line) = (seam_over_median(&rows), seam_over_median(&cols));
    println!("{name}: seam ratio {:.3}; seam / median line: rows {row_line:.2}, columns {col_line:.2}", seam.ratio);
    assert!(seam.ratio <= bounds.ratio, "{name}: seam ratio {:.3} > {}", seam.ratio, bounds.ratio);
    assert!(row_line <= bounds.line, "{name}: row seam {row_line:.2} x the median row boundary > {}", bounds.line);
    assert!(
        col_line <= bounds.line,
        "{name}: column seam {col_line:.2} x the median column boundary > {}",
        bounds.line
    );
}

// ---------------------------------------------------------------------------------------------
// Heightfield exemplars
// ---------------------------------------------------------------------------------------------

/// Least output / exemplar rms slope. Measured with the occurrence penalty (default 4): heightfield
/// forehead 0.785, nose 0.719, cheek 0.639, forehead_edge 0.907; captured forehead 0.780, nose
/// 0.724, cheek 0.624, forehead-edge 0.925 (without it: 0.48, 0.65, 0.35, 1.07; 0.56, 0.63, 0.36,
/// 0.99: flat outputs, see [`heightfield_slope_distance_within_one_and_a_half_times_own_variation`]).
const MIN_RMS_SLOPE_RATIO: f64 = 0.55;

/// Tileability bounds of every normal output but forehead edge. Measured seam ratio 0.98 to 1.71,
/// seam line over the median line at most 3.33 (captured cheek, rows). The cheek's figure was 2.55
/// with the capture's earlier shadow rule; the one rule of issue 12 (shadowed below 0.1 of the
/// pixel's 90th percentile) changed its captured exemplar, and with 0.05 it measured under 3.0 again
/// but cat's error with 8 lights rose from 6.34 to 6.99 deg, so the capture keeps 0.1.
const NORMAL_TILING: Tiling = Tiling { ratio: 3.0, line: 3.5 };
/// Colour: seam ratio 0.81 to 1.39, line at most 3.16 (photo forehead, rows; the row seam grew
/// with the occurrence penalty, whose counts are highest when the last rows are chosen).
const COLOUR_TILING: Tiling = Tiling { ratio: 3.0, line: 4.0 };

/// Forehead edge (strong horizontal wrinkles). The vertical seam it showed (column boundary
/// `255 | 0` 8.9 times the median column boundary, heightfield, 7.2 captured, when the first
/// columns matched their wrapped left neighbours while those were still noise) is gone: 1.98 and
/// 1.47 now (see [`forehead_edge_column_seam_within_the_other_textures_bound`]). The captured
/// map's row seam is 6.11 times the median row boundary (seam ratio 3.68; heightfield 1.00 and
/// 0.98): the last rows are chosen under the highest occurrence counts. Not solved yet.
const FOREHEAD_EDGE_TILING: Tiling = Tiling { ratio: 4.5, line: 8.0 };

fn normal_tiling(name: &str) -> &'static Tiling {
    if name.starts_with("forehead") && name.ends_with("edge") { &FOREHEAD_EDGE_TILING } else { &NORMAL_TILING }
}

/// Heightfield bounds. Measured OA / AB (OB / AB) slope: forehead 2.98 (3.91), nose 0.48 (1.33),
/// cheek 2.25 (3.25), forehead_edge 1.66 (2.03) (without the occurrence penalty 8.1 (9.0), 1.0
/// (1.7), 4.5 (5.5), 3.1 (4.0)); spectrum: forehead 1.11 (1.13), nose 0.67 (1.46), cheek 0.55
/// (1.43), forehead_edge 0.33 (1.24).
const HEIGHTFIELD: Bounds = Bounds { slope: 4.5, spectrum: 3.0 };

fn check_heightfield(i: usize) {
    let c = heightfield_case(i);
    assert_statistics(c, &HEIGHTFIELD);
    assert_not_flat(c, MIN_RMS_SLOPE_RATIO);
    assert_not_tiled(c.name, &c.out.coords);
    assert_tiles(c.name, c.out.normals.grid(), normal_tiling(c.name));
}

#[test]
fn heightfield_forehead() {
    check_heightfield(0);
}

#[test]
fn heightfield_nose() {
    check_heightfield(1);
}

#[test]
fn heightfield_cheek() {
    check_heightfield(2);
}

#[test]
fn heightfield_forehead_edge() {
    check_heightfield(3);
}

// ---------------------------------------------------------------------------------------------
// Sample molds, captured
// ---------------------------------------------------------------------------------------------

/// Captured bounds. Measured OA / AB (OB / AB) slope: forehead 5.3 (5.3), nose 2.7 (3.6), cheek
/// 4.0 (4.9), forehead-edge 0.90 (1.74) (without the occurrence penalty 12.5 (12.5), 4.2 (5.0), 8.0
/// (8.9), 1.9 (2.7)); spectrum: forehead 1.80 (1.77), nose 1.57 (1.34), cheek 1.80 (2.39),
/// forehead-edge 0.60 (0.52).
const CAPTURED: Bounds = Bounds { slope: 6.5, spectrum: 3.0 };

fn check_mold(i: usize) {
    let c = mold_case(i);
    assert_statistics(c, &CAPTURED);
    assert_not_flat(c, MIN_RMS_SLOPE_RATIO);
    assert_not_tiled(c.name, &c.out.coords);
    assert_tiles(c.name, c.out.normals.grid(), normal_tiling(c.name));
}

#[test]
fn captured_forehead() {
    check_mold(0);
}

#[test]
fn captured_nose() {
    check_mold(1);
}

#[test]
fn captured_cheek() {
    check_mold(2);
}

#[test]
fn captured_forehead_edge() {
    check_mold(3);
}

// ---------------------------------------------------------------------------------------------
// Colour
// ---------------------------------------------------------------------------------------------

/// An albedo-like map of a heightfield preset (`256 x 128`): a skin tint lighter on ridges and
/// darker in pores and furrows (height in standard deviations), times soft shading of the normals.
fn albedo(name: &str) -> ColorMap {
    let hf = preset(name, 2 * HALF, HALF, 7).generate().unwrap();
    let h = &hf.heights;
    let n = h.len() as f64;
    let mean = h.as_slice().iter().map(|&v| v as f64).sum::<f64>() / n;
    let sd = (h.as_slice().iter().map(|&v| (v as f64 - mean).powi(2)).sum::<f64>() / n).sqrt().max(1e-12);
    let light = Vec3::new(0.3, 0.3, 0.9).normalize();
    Grid::from_fn(h.width(), h.height(), |x, y| {
        let t = (0.5 + 0.15 * ((*h.get(x, y) as f64 - mean) / sd) as f32).clamp(0.0, 1.0);
        let shade = hf.normals.get(x, y).dot(light).max(0.0);
        Vec3::new(0.55 + 0.2 * t, 0.35 + 0.2 * t, 0.3 + 0.15 * t) * (0.7 + 0.3 * shade)
    })
}

/// A sample mold's first photo as a tinted linear colour map (`256 x 256`).
fn photo_colour(region: &str) -> ColorMap {
    let (photos, _) = mold_photos(region);
    let lum = photos[0].luminance();
    Grid::from_fn(photos[0].width(), photos[0].height(), |x, y| {
        let v = lum[y * photos[0].width() + x];
        Vec3::new(v, 0.8 * v, 0.7 * v)
    })
}

/// Grows the left half of `map` and checks channel and spectrum distances against the halves'
/// own variation (factors `channel` and `spectrum`), copies and tileability.
fn check_colour(name: &str, map: &ColorMap, channel: f64, spectrum: f64) {
    let a = map.crop(0, 0, HALF, HALF).unwrap();
    let b = map.crop(HALF, 0, HALF, HALF).unwrap();
    let s: Synthesis = synthesize(&a, &config(1), &skinkit_maps::progress::NoProgress).unwrap();
    let o = &s.texels;
    let ch = [metrics::channel_distance(&a, &b), metrics::channel_distance(o, &a), metrics::channel_distance(o, &b)];
    let sp = [
        metrics::color_spectrum_distance(&a, &b, BINS),
        metrics::color_spectrum_distance(o, &a, BINS),
        metrics::color_spectrum_distance(o, &b, BINS),
    ];
    println!("{name}: channel AB {:.5} OA {:.5} OB {:.5}", ch[0], ch[1], ch[2]);
    println!("{name}: spectrum AB {:.4} OA {:.4} OB {:.4}", sp[0], sp[1], sp[2]);
    for (what, d, bound) in [("channel", ch, channel), ("spectrum", sp, spectrum)] {
        assert!(d[0] > 0.0, "{name}: the halves must differ");
        assert!(d[1] <= bound * d[0], "{name}: {what} output-A {:.5} > {bound} x A-B {:.5}", d[1], d[0]);
        assert!(d[2] <= bound * d[0], "{name}: {what} output-B {:.5} > {bound} x A-B {:.5}", d[2], d[0]);
    }
    assert_not_tiled(name, &s.coords);
    assert_tiles(name, o, &COLOUR_TILING);
}

/// Measured OA / AB (OB / AB): channel 2.5 (3.5), spectrum 1.84 (1.80).
#[test]
fn colour_albedo_forehead() {
    check_colour("albedo forehead", &albedo("forehead"), 8.0, 3.0);
}

/// Measured OA / AB (OB / AB): channel 1.8 (2.8), spectrum 1.59 (1.94).
#[test]
fn colour_albedo_cheek() {
    check_colour("albedo cheek", &albedo("cheek"), 8.0, 3.0);
}

/// A photo is shading under one light, so it shows the flattening of the normal outputs again.
/// Measured OA / AB (OB / AB): channel 4.5 (4.2), spectrum 1.64 (1.75) (10.7 (10.4), 2.72 (2.75)
/// without the occurrence penalty).
#[test]
fn colour_photo_forehead() {
    check_colour("photo forehead", &photo_colour("forehead"), 16.0, 4.0);
}

// ---------------------------------------------------------------------------------------------
// The checks themselves catch what they are meant to catch
// ---------------------------------------------------------------------------------------------

/// A 2 x 2 tiling of the exemplar fails the copy bounds: one block covers the whole output.
#[test]
fn a_tiled_copy_fails_the_copy_bounds() {
    let coords = Grid::from_fn(OUT, OUT, |x, y| [(x % HALF) as u32, (y % HALF) as u32]);
    let wrapped = metrics::copy_statistics(&coords, (HALF, HALF), true);
    assert_eq!(wrapped.largest_block, OUT * OUT);
    // Without wrap every tile is its own verbatim block of the whole exemplar.
    let plain = metrics::copy_statistics(&coords, (HALF, HALF), false);
    assert_eq!(plain.largest_block, HALF * HALF);
    assert_eq!(distinct_sources(&coords), HALF * HALF);
    let result = std::panic::catch_unwind(|| assert_copy_bounds("tiled", &plain, distinct_sources(&coords)));
    assert!(result.is_err(), "a tiled copy passed the copy bounds");
}

/// A map with a step at its wrap-around boundary (a ramp) fails the tileability check.
#[test]
fn a_visible_seam_fails_the_tileability_check() {
    let texture = albedo("cheek");
    let ramp =
        Grid::from_fn(64, 64, |x, y| Vec3::new(x as f32 / 64.0, y as f32 / 64.0, 0.0) + *texture.get(x, y) * 0.1);
    let result = std::panic::catch_unwind(|| assert_tiles("ramp", &ramp, &NORMAL_TILING));
    assert!(result.is_err(), "a ramp passed the tileability check");
}

/// Slope distance within 1.5 times the halves' own variation (issue 14's bound), met on the
/// heightfield presets since the layout penalty (`SynthConfig::layout_penalty`; measured OA / AB:
/// forehead 1.00, nose 0.31, cheek 0.56, forehead_edge 1.32; without it 1.60, 0.35, 0.63, 1.65;
/// before the occurrence penalty 8.1, 1.0, 4.5, 3.1).
#[test]
fn heightfield_slope_distance_within_one_and_a_half_times_own_variation() {
    for i in 0..4 {
        assert_slope_within(heightfield_case(i), 1.5);
    }
}

fn assert_slope_within(c: &NormalCase, factor: f64) {
    let (ab, oa) = (metrics::slope_distance(&c.a, &c.b), metrics::slope_distance(&c.out.normals, &c.a));
    assert!(oa <= factor * ab, "{}: slope distance output-A {oa:.4} > {factor} x A-B {ab:.4}", c.name);
}

/// The same bound on the captured maps, met since the layout penalty: measured OA / AB forehead
/// 1.09, nose 0.59, cheek 0.75, forehead-edge 1.10 (seeds 2 and 3: forehead 1.11 and 1.12); without
/// it 2.12, 0.57, 0.92, 1.09 (seeds 2 and 3: forehead 2.09 and 1.94); the scanline start: 5.3,
/// 4.0, 2.7, 0.90.
#[test]
fn captured_slope_distance_within_one_and_a_half_times_own_variation() {
    for i in 0..4 {
        assert_slope_within(mold_case(i), 1.5);
    }
}

/// The forehead edge's vertical seam within the bound of the other textures (see
/// [`FOREHEAD_EDGE_TILING`]): column seam line 1.98 (heightfield) and 1.47 (captured) times the
/// median column boundary.
#[test]
fn forehead_edge_column_seam_within_the_other_textures_bound() {
    for c in [heightfield_case(3), mold_case(3)] {
        let (_, cols) = line_energies(c.out.normals.grid());
        let line = seam_over_median(&cols);
        assert!(line <= NORMAL_TILING.line, "{}: column seam {line:.2} x the median > {}", c.name, NORMAL_TILING.line);
    }
}
