//! End-to-end checks of Wei-Levoy synthesis on tiny exemplars (exact search is
//! O(output x exemplar), so sizes stay small).

use glam::Vec3;
use skinkit_maps::Grid;
use skinkit_maps::progress::Step;
use skinkit_synth::config::SCANLINE_OCCURRENCE_PENALTY;
use skinkit_synth::energy::{self_energy, window_energy};
use skinkit_synth::exemplar::ExemplarLevel;
use skinkit_synth::neighbourhood::Neighbourhood;
use skinkit_synth::search::KCoherenceSets;
use skinkit_synth::synthesis::histogram_noise;
use skinkit_synth::{Error, Search, SynthConfig, replay, synthesize, synthesize_normals};

use crate::support::pattern;

fn config(w: usize, h: usize, search: Search) -> SynthConfig {
    SynthConfig { levels: 2, search, ..SynthConfig::scanline(w, h) }
}

const APPROX: Search = Search::Approximate { dims: 8, rerank: 4 };
const KCOH: Search = Search::KCoherence { k: 4, fallback: None, dims: 8, rerank: 4 };
const KCOH_FALLBACK: Search = Search::KCoherence { k: 4, fallback: Some(1.0), dims: 8, rerank: 4 };

fn on_threads<T: Send>(n: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(f)
}

#[test]
fn same_bits_on_one_and_two_threads() {
    let ex = pattern(16, 16);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let c = config(24, 24, search);
        let one = on_threads(1, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
        let two = on_threads(2, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
        assert_eq!(one.coords, two.coords, "{search:?}");
        let bits = |s: &skinkit_synth::Synthesis| {
            s.texels.as_slice().iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        assert_eq!(bits(&one), bits(&two), "{search:?}");
    }
}

#[test]
fn output_texels_are_copies_of_their_coords() {
    let ex = pattern(16, 16);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let s = synthesize(&ex, &config(24, 24, search), &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(s.texels.size(), (24, 24));
        for y in 0..24 {
            for x in 0..24 {
                let [sx, sy] = *s.coords.get(x, y);
                assert_eq!(s.texels.get(x, y), ex.get(sx as usize, sy as usize));
                // Without exemplar wrap only texels with a whole 5x5 window inside are copied.
                assert!((2..14).contains(&sx) && (2..14).contains(&sy), "({sx}, {sy})");
            }
        }
        assert_eq!(replay(&s.coords, &ex).unwrap(), s.texels);
        // Not a single copied texel: the output uses many exemplar positions.
        let mut used: Vec<[u32; 2]> = s.coords.as_slice().to_vec();
        used.sort();
        used.dedup();
        assert!(used.len() > 20, "{search:?}: {} positions", used.len());
    }
}

#[test]
fn corrections_give_the_same_bits_on_one_and_two_threads() {
    let ex = pattern(16, 16);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let c = SynthConfig { corrections: 2, ..config(23, 19, search) };
        let one = on_threads(1, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
        let two = on_threads(2, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
        assert_eq!(one.coords, two.coords, "{search:?}");
        let bits = |s: &skinkit_synth::Synthesis| {
            s.texels.as_slice().iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        assert_eq!(bits(&one), bits(&two), "{search:?}");
        // Every output texel is still a copy of the exemplar texel at its coordinate.
        assert_eq!(replay(&one.coords, &ex).unwrap(), one.texels, "{search:?}");
    }
}

#[test]
fn corrections_lower_the_window_energy() {
    let ex = pattern(24, 24);
    // Without the occurrence penalty, which trades window energy for texel variety on purpose.
    let energy = |search: Search, corrections: usize| {
        let c = SynthConfig { corrections, occurrence_penalty: 0.0, ..config(40, 40, search) };
        window_energy(&synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap().texels, &ex, 5, 1)
    };
    // Measured ratios of one pass to none: 0.878 (k-coherence), 0.944 (approximate).
    for (search, ratio) in [(KCOH, 0.92), (APPROX, 0.97)] {
        let e: Vec<f64> = (0..3).map(|c| energy(search, c)).collect();
        assert!(e[1] < ratio * e[0], "{search:?}: {e:?}");
        assert!(e[2] < 1.05 * e[1], "{search:?}: {e:?}");
    }
}

#[test]
fn constant_exemplar_gives_constant_output() {
    let v = Vec3::new(0.2, -0.4, 0.9);
    let ex = Grid::filled(12, 12, v);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let s = synthesize(&ex, &config(10, 7, search), &skinkit_maps::progress::NoProgress).unwrap();
        assert!(s.texels.as_slice().iter().all(|t| *t == v), "{search:?}");
    }
}

#[test]
fn exemplar_smaller_than_the_neighbourhood_is_refused() {
    let err =
        synthesize(&pattern(3, 4), &config(8, 8, Search::Exact), &skinkit_maps::progress::NoProgress).unwrap_err();
    assert!(matches!(err, Error::ExemplarTooSmall { width: 3, height: 4, n: 5 }));
    assert_eq!(err.to_string(), "exemplar 3x4 is smaller than the 5x5 neighbourhood");
}

#[test]
fn one_by_one_output_and_non_square_exemplar() {
    let ex = pattern(21, 9);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let s = synthesize(&ex, &config(1, 1, search), &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(s.texels.size(), (1, 1));
        assert!(s.texels.get(0, 0).is_finite());
        let s = synthesize(&ex, &config(17, 6, search), &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(s.coords.size(), (17, 6));
        assert!(s.coords.as_slice().iter().all(|&[x, y]| (2..19).contains(&x) && (2..7).contains(&y)));
    }
}

#[test]
fn too_many_levels_are_clamped_with_a_warning() {
    let ex = pattern(16, 16);
    let c = SynthConfig { levels: 6, search: APPROX, ..SynthConfig::scanline(8, 8) };
    let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
    // 16 -> 8 -> 4: only two levels keep a 5x5 window.
    assert_eq!(s.level_seconds.len(), 2);
    assert_eq!(s.warnings.len(), 1);
    assert!(s.warnings[0].contains("levels 6 clamped to 2"), "{}", s.warnings[0]);
}

#[test]
fn wrapped_exemplar_uses_every_texel_position() {
    let ex = pattern(8, 8);
    let c = SynthConfig { exemplar_wrap: true, ..config(16, 16, Search::Exact) };
    let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
    for (t, &[x, y]) in s.texels.as_slice().iter().zip(s.coords.as_slice()) {
        assert_eq!(t, ex.get(x as usize, y as usize));
    }
}

#[test]
fn progress_reaches_one_on_every_level() {
    for corrections in [0, 2] {
        // Each stage: its name, its length and the steps of each advance.
        let seen = std::sync::Mutex::new(Vec::<(String, u64, Vec<u64>)>::new());
        let report = |step: Step<'_>| {
            let mut seen = seen.lock().unwrap();
            match step {
                Step::Start { name, len } => seen.push((name.to_owned(), len, Vec::new())),
                Step::Advance(n) => seen.last_mut().expect("a stage was started").2.push(n),
                Step::Finish => {}
            }
        };
        let c = SynthConfig { corrections, ..config(6, 6, APPROX) };
        synthesize(&pattern(16, 16), &c, &report).unwrap();
        let seen = seen.into_inner().unwrap();
        let names: Vec<&str> = seen.iter().map(|(name, _, _)| name.as_str()).collect();
        assert_eq!(names, ["level 1", "level 0"], "coarsest first");
        // The coarser level has 3 rows, counted once by the causal pass and once per correction.
        assert_eq!(seen[0].1, 3 * (1 + corrections as u64));
        assert_eq!(seen[0].2.first(), Some(&1), "the first row is told at once");
        for (name, len, steps) in &seen {
            assert_eq!(steps.iter().sum::<u64>(), *len, "{name} reaches its length");
        }
    }
}

#[test]
fn replay_rejects_coordinates_outside_the_map() {
    let coords = Grid::filled(2, 2, [5u32, 1]);
    let err = replay(&coords, &Grid::filled(4, 4, 0.0f32)).unwrap_err();
    assert!(err.to_string().contains("(5, 1)") && err.to_string().contains("4x4"), "{err}");
}

#[test]
fn normal_maps_come_out_unit_length() {
    let field = skinkit_heightfield::SkinParams::forehead(16, 16, 3).generate().unwrap();
    let c = config(20, 12, APPROX);
    let s = synthesize_normals(&field.normals, &c, &skinkit_maps::progress::NoProgress).unwrap();
    assert_eq!(s.normals.size(), (20, 12));
    for n in s.normals.as_slice() {
        assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
    }
    assert_eq!(replay(&s.coords, field.normals.grid()).unwrap(), *s.normals.grid());
}

#[test]
fn approximate_search_reranking_every_candidate_equals_exact() {
    // 16x16 without wrap: 12 x 12 = 144 candidates per finest level, fewer at the coarser one.
    let ex = pattern(16, 16);
    let exact = synthesize(&ex, &config(12, 12, Search::Exact), &skinkit_maps::progress::NoProgress).unwrap();
    for coherence in [false, true] {
        let c = SynthConfig { coherence, ..config(12, 12, Search::Approximate { dims: 3, rerank: 144 }) };
        let approx = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
        assert_eq!(approx.coords, exact.coords, "coherence {coherence}");
    }
}

#[test]
fn outputs_over_the_memory_limit_are_refused_with_the_estimate() {
    let c = SynthConfig { memory_limit: 1 << 20, ..config(1024, 1024, Search::Exact) };
    let estimate = c.memory_estimate(16, 16);
    // 1024x1024 texels at 20 bytes each (texel and coordinates) on the finest level alone.
    assert!(estimate > 20 << 20, "{estimate}");
    let err = synthesize(&pattern(16, 16), &c, &skinkit_maps::progress::NoProgress).unwrap_err();
    assert!(matches!(err, Error::TooLarge { width: 1024, height: 1024, limit_mib: 1, .. }), "{err}");
    assert!(err.to_string().contains(&format!("{} MiB", estimate.div_ceil(1 << 20))), "{err}");
}

#[test]
fn non_finite_exemplar_texels_are_zeroed_with_a_warning() {
    let mut ex = pattern(12, 12);
    *ex.get_mut(5, 5) = Vec3::new(f32::NAN, 0.0, f32::INFINITY);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        let s = synthesize(&ex, &config(9, 9, search), &skinkit_maps::progress::NoProgress).unwrap();
        assert!(s.texels.as_slice().iter().all(|t| t.is_finite()), "{search:?}");
        assert!(s.warnings.iter().any(|w| w.contains("1 exemplar texels were not finite")), "{:?}", s.warnings);
    }
}

#[test]
fn k_coherence_with_a_zero_fallback_and_full_rerank_equals_exact() {
    // A zero ratio sends every texel whose best coherent candidate is not a perfect match to the
    // tree, which then returns every candidate within the bound: the exact answer.
    let ex = pattern(16, 16);
    let exact = synthesize(&ex, &config(12, 12, Search::Exact), &skinkit_maps::progress::NoProgress).unwrap();
    let c = config(12, 12, Search::KCoherence { k: 3, fallback: Some(0.0), dims: 3, rerank: 144 });
    assert_eq!(synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap().coords, exact.coords);
}

#[test]
fn k_coherence_sets_are_the_nearest_full_windows() {
    // 8x8 without wrap, 5x5 windows: 4 x 4 = 16 candidates, all within the sets' re-scored pool
    // (max(2 k, 16) = 18 for k = 9), so the sets are exact.
    let ex = pattern(8, 8);
    let k = 9;
    let full = ExemplarLevel::new(ex.clone(), None, &Neighbourhood::full(5, 3, false), 5, false);
    let causal = ExemplarLevel::new(ex.clone(), None, &Neighbourhood::new(5, 3, false), 5, false);
    let sets = KCoherenceSets::new(&full, &causal, k, 8);
    let window_distance = |(ax, ay): (usize, usize), (bx, by): (usize, usize)| {
        let mut d = 0.0f32;
        for dy in 0..5 {
            for dx in 0..5 {
                let diff = *ex.get(ax + dx - 2, ay + dy - 2) - *ex.get(bx + dx - 2, by + dy - 2);
                d += diff.length_squared();
            }
        }
        d
    };
    let cells: Vec<(usize, usize)> = (2..6).flat_map(|y| (2..6).map(move |x| (x, y))).collect();
    for (i, &a) in cells.iter().enumerate() {
        let mut others: Vec<(f32, usize)> =
            cells.iter().enumerate().filter(|&(j, _)| j != i).map(|(j, &b)| (window_distance(a, b), j)).collect();
        others.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.cmp(&q.1)));
        let expect: Vec<u32> =
            std::iter::once(i).chain(others[..k - 1].iter().map(|o| o.1)).map(|j| j as u32).collect();
        assert_eq!(sets.set(i), expect.as_slice(), "candidate {i} at {a:?}");
    }
    assert!(sets.typical() > 0.0);
}

#[test]
fn window_energy_matches_a_brute_force_scan() {
    let ex = pattern(9, 8);
    let out = histogram_noise(&ex, 6, 5, 3, 0);
    let brute = |stride: usize| {
        let mut sum = 0.0f64;
        let mut count = 0;
        for y in (0..5).step_by(stride) {
            for x in (0..6).step_by(stride) {
                let mut best = f32::INFINITY;
                for ey in 1..7isize {
                    for ex_x in 1..8isize {
                        let mut d = 0.0;
                        for dy in -1..=1isize {
                            for dx in -1..=1isize {
                                let a = *out.get_wrapped(x as isize + dx, y as isize + dy);
                                let b = *ex.get((ex_x + dx) as usize, (ey + dy) as usize);
                                d += (a - b).length_squared();
                            }
                        }
                        best = best.min(d);
                    }
                }
                sum += best as f64;
                count += 1;
            }
        }
        sum / count as f64
    };
    for stride in [1, 2] {
        let e = window_energy(&out, &ex, 3, stride);
        let b = brute(stride);
        assert!((e - b).abs() <= 1e-5 * b, "stride {stride}: {e} vs {b}");
    }
    // An output cut from the exemplar's interior matches it exactly away from its wrapped edges.
    let crop = Grid::from_fn(5, 4, |x, y| *ex.get(x + 2, y + 2));
    assert!(window_energy(&crop, &ex, 1, 1) == 0.0);
}

#[test]
fn k_coherence_beats_noise_on_window_energy() {
    let ex = pattern(24, 24);
    let c = SynthConfig { levels: 2, search: KCOH, ..SynthConfig::scanline(32, 32) };
    let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
    let synthesized = window_energy(&s.texels, &ex, 5, 1);
    let noise = window_energy(&histogram_noise(&ex, 32, 32, 0, 0), &ex, 5, 1);
    assert!(synthesized < 0.5 * noise, "{synthesized} vs noise {noise}");
}

/// The most copies of one exemplar texel in `coords`.
fn most_copies(coords: &Grid<[u32; 2]>) -> usize {
    let mut counts = std::collections::HashMap::new();
    for c in coords.as_slice() {
        *counts.entry(*c).or_insert(0usize) += 1;
    }
    counts.into_values().max().unwrap_or(0)
}

#[test]
fn the_occurrence_penalty_spreads_the_copies() {
    // A smooth exemplar with a few sharp spikes (pores): plain nearest-neighbour search keeps
    // copying the smooth texels; the penalty caps how often any one is reused.
    let ex = Grid::from_fn(24, 24, |x, y| {
        let spike = if (x * 7 + y * 3) % 23 == 0 { 1.0 } else { 0.0 };
        Vec3::new(0.05 * (x as f32 * 0.3).sin(), 0.05 * (y as f32 * 0.2).cos(), spike)
    });
    for search in [Search::Exact, KCOH] {
        let run = |lambda| {
            let c = SynthConfig { occurrence_penalty: lambda, ..config(40, 40, search) };
            synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap().coords
        };
        let (plain, penalised) = (most_copies(&run(0.0)), most_copies(&run(SCANLINE_OCCURRENCE_PENALTY)));
        println!("{search:?}: most copies of one texel {plain} without the penalty, {penalised} with");
        assert!(penalised < plain, "{search:?}: {penalised} vs {plain}");
    }
}

#[test]
fn a_negative_or_non_finite_penalty_is_refused() {
    for lambda in [-1.0, f32::NAN, f32::INFINITY] {
        let c = SynthConfig { occurrence_penalty: lambda, ..config(8, 8, KCOH) };
        let err = synthesize(&pattern(16, 16), &c, &skinkit_maps::progress::NoProgress).unwrap_err().to_string();
        assert!(err.contains("occurrence_penalty"), "{err}");
    }
}

fn upsampled(w: usize, h: usize, search: Search) -> SynthConfig {
    SynthConfig { levels: 3, search, ..SynthConfig::new(w, h) }
}

#[test]
fn upsampled_start_gives_the_same_bits_on_one_and_two_threads() {
    let ex = pattern(24, 24);
    for search in [Search::Exact, APPROX, KCOH, KCOH_FALLBACK] {
        for jitter in [0, 1] {
            let c = SynthConfig { jitter, ..upsampled(40, 33, search) };
            let one = on_threads(1, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
            let two = on_threads(2, || synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap());
            assert_eq!(one.coords, two.coords, "{search:?} jitter {jitter}");
            assert!(one.texels.as_slice().iter().zip(two.texels.as_slice()).all(|(a, b)| a.to_array() == b.to_array()));
            // Every texel is its coordinate's exemplar texel.
            let copied = replay(&one.coords, &ex).unwrap();
            assert_eq!(copied.as_slice(), one.texels.as_slice(), "{search:?}");
        }
    }
}

#[test]
fn upsampled_coordinates_copy_two_by_two_blocks_before_correction() {
    let ex = pattern(40, 40);
    // No correction pass: the finest level is its coarser level's coordinates upsampled, so each
    // 2x2 output block copies a 2x2 exemplar block (clamped into the candidates at the border).
    let c = SynthConfig { corrections: 0, levels: 2, ..SynthConfig::new(30, 22) };
    let s = synthesize(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
    let (mut aligned, mut blocks) = (0, 0);
    for by in 0..11 {
        for bx in 0..15 {
            let [x0, y0] = *s.coords.get(2 * bx, 2 * by);
            blocks += 1;
            let ok = (0..2)
                .all(|dy| (0..2).all(|dx| *s.coords.get(2 * bx + dx, 2 * by + dy) == [x0 + dx as u32, y0 + dy as u32]));
            aligned += usize::from(ok);
        }
    }
    // Only blocks whose source was clamped at the candidates' right or bottom edge differ.
    assert!(aligned * 10 >= blocks * 9, "{aligned} of {blocks} blocks are whole 2x2 copies");
    assert!(s.coords.as_slice().iter().all(|&[x, y]| (2..38).contains(&x) && (2..38).contains(&y)));
}

#[test]
fn upsampled_start_hard_cases() {
    let v = Vec3::new(0.2, -0.4, 0.9);
    let s = synthesize(&Grid::filled(12, 12, v), &upsampled(10, 7, KCOH), &skinkit_maps::progress::NoProgress).unwrap();
    assert!(s.texels.as_slice().iter().all(|t| *t == v));
    let ex = pattern(21, 9);
    let s = synthesize(&ex, &upsampled(1, 1, KCOH), &skinkit_maps::progress::NoProgress).unwrap();
    assert!(s.texels.get(0, 0).is_finite());
    // Five levels asked of a 21x9 exemplar: clamped, with a warning.
    let s = synthesize(&ex, &SynthConfig::new(17, 6), &skinkit_maps::progress::NoProgress).unwrap();
    assert!(!s.warnings.is_empty());
    assert!(s.coords.as_slice().iter().all(|&[x, y]| (2..19).contains(&x) && (2..7).contains(&y)));
}

#[test]
fn the_default_beats_the_scanline_start_on_a_skin_exemplar() {
    // 128x128 grown from a 64x64 forehead heightfield: the default's energy and slope distance
    // are both lower than the scanline start's.
    let ex = skinkit_heightfield::SkinParams::forehead(64, 64, 1).generate().unwrap().normals;
    let score = |c: SynthConfig| {
        let out = synthesize_normals(&ex, &SynthConfig { seed: 1, ..c }, &skinkit_maps::progress::NoProgress)
            .unwrap()
            .normals;
        (window_energy(out.grid(), ex.grid(), 5, 1), skinkit_synth::metrics::slope_distance(&out, &ex))
    };
    let (e_scan, s_scan) = score(SynthConfig::scanline(128, 128));
    let (e_up, s_up) = score(SynthConfig::new(128, 128));
    assert!(e_up < 0.8 * e_scan, "energy: default {e_up:.5} vs scanline {e_scan:.5}");
    assert!(s_up < s_scan, "slope distance: default {s_up:.5} vs scanline {s_scan:.5}");
}

/// Issue 15, D13: an exemplar without one valid normal is refused before any work, and one with
/// some invalid texels is synthesised with a warning that counts them.
#[test]
fn d13_an_exemplar_without_valid_normals_is_refused_early() {
    use skinkit_maps::NormalMap;
    let called = std::sync::atomic::AtomicBool::new(false);
    let progress = |_: Step<'_>| called.store(true, std::sync::atomic::Ordering::Relaxed);
    let empty = NormalMap::from_grid(Grid::filled(24, 20, Vec3::ZERO));
    let e = synthesize_normals(&empty, &config(16, 16, Search::Exact), &progress).unwrap_err();
    assert!(matches!(e, Error::NoValidNormals { width: 24, height: 20 }), "{e}");
    assert!(e.to_string().contains("no valid normal"), "{e}");
    assert!(!called.load(std::sync::atomic::Ordering::Relaxed), "refused after work had started");

    let mut some = NormalMap::from_grid(Grid::filled(24, 20, Vec3::Z));
    for x in 0..6 {
        some.set(x, 3, Vec3::ZERO);
    }
    let s = synthesize_normals(&some, &config(16, 16, Search::Exact), &skinkit_maps::progress::NoProgress).unwrap();
    assert!(s.warnings[0].contains("6 of 480 texels"), "{:?}", s.warnings);
}

/// The exemplar's own energy equals a brute-force scan over pairs of non-overlapping windows.
#[test]
fn self_energy_matches_a_brute_force_scan() {
    let ex = pattern(11, 9);
    let n = 3;
    let brute = |stride: usize| {
        let window = |x: usize, y: usize| -> Vec<Vec3> {
            (0..n)
                .flat_map(|dy| (0..n).map(move |dx| (dx, dy)))
                .map(|(dx, dy)| *ex.get(x + dx - 1, y + dy - 1))
                .collect()
        };
        let centres: Vec<(usize, usize)> = (1..8).flat_map(|y| (1..10).map(move |x| (x, y))).collect();
        let mut mins = Vec::new();
        for &(x, y) in centres.iter().filter(|c| c.0 % stride == 0 && c.1 % stride == 0) {
            let a = window(x, y);
            let best = centres
                .iter()
                .filter(|&&(u, v)| u.abs_diff(x) >= n || v.abs_diff(y) >= n)
                .map(|&(u, v)| a.iter().zip(window(u, v)).map(|(p, q)| (*p - q).length_squared()).sum::<f32>())
                .fold(f32::INFINITY, f32::min);
            mins.push(best as f64);
        }
        mins.iter().sum::<f64>() / mins.len() as f64
    };
    for stride in [1, 2] {
        let (e, b) = (self_energy(&ex, n, stride), brute(stride));
        assert!(b > 0.0 && (e - b).abs() <= 1e-5 * b, "stride {stride}: {e} vs {b}");
    }
    assert_eq!(self_energy(&Grid::filled(2, 2, Vec3::ONE), 3, 1), 0.0, "no whole window");
}

/// The copy cap: without it the default's patches come down the pyramid whole (a quarter of the
/// exemplar and more); with it no verbatim block is larger than the cap. Blocks that merge during
/// the last pass are cut again (before, a 6 % cap let through up to 10.8 % on the suite).
#[test]
fn the_copy_cap_bounds_the_largest_verbatim_block() {
    let ex = skinkit_heightfield::SkinParams::forehead(64, 64, 1).generate().unwrap().normals;
    let largest = |copy_cap: Option<f32>| {
        let c = SynthConfig { seed: 3, copy_cap, ..SynthConfig::new(128, 128) };
        let s = synthesize_normals(&ex, &c, &skinkit_maps::progress::NoProgress).unwrap();
        skinkit_synth::metrics::copy_statistics(&s.coords, (64, 64), false).largest_block
    };
    let area = 64 * 64;
    let free = largest(None);
    assert!(free > area / 8, "uncapped largest block {free}: nothing for the cap to do");
    for cap in [0.03, 0.06] {
        let capped = largest(Some(cap));
        assert!(capped as f64 <= f64::from(cap) * area as f64, "cap {cap}: largest block {capped} of {area}");
    }
}
