//! Digests of synthesis outputs, to check that a refactor keeps every bit (not run in CI).
//!
//! `cargo run --profile test -p skinkit-synth --example digest` prints one line per case: the
//! case, and an FNV-1a hash of the output texels' bits and coordinates. Compare the lines before
//! and after a change.

use glam::Vec3;
use skinkit_heightfield::SkinParams;
use skinkit_maps::Grid;
use skinkit_synth::{Search, Start, SynthConfig, synthesize, synthesize_normals};

/// A structured colour exemplar with no exactly repeated neighbourhoods (the tests' `pattern`).
fn pattern(w: usize, h: usize) -> Grid<Vec3> {
    Grid::from_fn(w, h, |x, y| {
        let hash = ((x as u32).wrapping_mul(73_856_093) ^ (y as u32).wrapping_mul(19_349_663)) % 1000;
        let r = hash as f32 / 1000.0;
        Vec3::new((x as f32 * 0.9).sin() + 0.3 * r, (y as f32 * 0.7).cos(), r)
    })
}

fn fnv(hash: &mut u64, bytes: &[u8]) {
    for &b in bytes {
        *hash ^= b as u64;
        *hash = hash.wrapping_mul(0x100_0000_01b3);
    }
}

fn digest(texels: &Grid<Vec3>, coords: &Grid<[u32; 2]>) -> u64 {
    let mut hash = 0xcbf2_9ce4_8422_2325;
    for v in texels.as_slice() {
        for c in v.to_array() {
            fnv(&mut hash, &c.to_bits().to_le_bytes());
        }
    }
    for [x, y] in coords.as_slice() {
        fnv(&mut hash, &x.to_le_bytes());
        fnv(&mut hash, &y.to_le_bytes());
    }
    hash
}

fn cases() -> Vec<(&'static str, bool, SynthConfig)> {
    let kc = |fallback| Search::KCoherence { k: 4, fallback, dims: 8, rerank: 8 };
    let d = |side| SynthConfig { seed: 3, ..SynthConfig::new(side, side) };
    let s = |side| SynthConfig { seed: 5, ..SynthConfig::scanline(side, side) };
    vec![
        ("default normals 128", true, d(128)),
        ("default normals 256", true, d(256)),
        ("default colour 96", false, d(96)),
        ("default no cap no finest fallback", true, SynthConfig { copy_cap: None, finest_fallback: None, ..d(128) }),
        ("default L2 coarse (tree fallback)", true, SynthConfig { robust_scale: 0.0, ..d(128) }),
        (
            "default overrides",
            true,
            SynthConfig {
                finest_penalty: Some(0.3),
                correction_penalty: Some(0.2),
                occurrence_penalty: 0.1,
                finest_coherence_bias: None,
                coarse_corrections: None,
                corrections: 2,
                polish: 2,
                jitter: 2,
                exemplar_wrap: true,
                ..d(160)
            },
        ),
        ("default k=4 no fallback", false, SynthConfig { search: kc(None), ..d(128) }),
        ("exact colour 96", false, SynthConfig { search: Search::Exact, ..d(96) }),
        ("exact normals 96 no cap", true, SynthConfig { search: Search::Exact, copy_cap: None, ..d(96) }),
        ("approximate normals 128", true, SynthConfig { search: Search::Approximate { dims: 8, rerank: 8 }, ..d(128) }),
        (
            "approximate colour no coherence",
            false,
            SynthConfig { search: Search::Approximate { dims: 6, rerank: 4 }, coherence: false, ..d(128) },
        ),
        (
            "approximate no corrections",
            true,
            SynthConfig {
                search: Search::Approximate { dims: 8, rerank: 8 },
                corrections: 0,
                coarse_corrections: Some(0),
                ..d(96)
            },
        ),
        ("scanline normals 128", true, s(128)),
        ("scanline colour 96", false, s(96)),
        ("scanline fallback 2", true, SynthConfig { search: kc(Some(2.0)), ..s(128) }),
        (
            "scanline fallback + cap + finest",
            true,
            SynthConfig {
                search: kc(Some(3.0)),
                copy_cap: Some(0.05),
                finest_fallback: Some(6.0),
                polish: 1,
                ..s(128)
            },
        ),
        ("scanline exact", false, SynthConfig { search: Search::Exact, ..s(96) }),
        ("scanline approximate", true, SynthConfig { search: Search::Approximate { dims: 8, rerank: 8 }, ..s(128) }),
        ("scanline no corrections", true, SynthConfig { corrections: 0, ..s(96) }),
        (
            "upsampled exact levels 1",
            false,
            SynthConfig { search: Search::Exact, levels: 1, start: Start::Upsampled, ..d(64) },
        ),
    ]
}

fn main() {
    let normals = SkinParams::forehead(64, 64, 1).generate().expect("the preset generates").normals;
    let colour = pattern(64, 64);
    for (name, is_normals, config) in cases() {
        let hash = if is_normals {
            let s = synthesize_normals(&normals, &config, &skinkit_maps::progress::NoProgress)
                .expect("valid configuration");
            digest(s.normals.grid(), &s.coords)
        } else {
            let s = synthesize(&colour, &config, &skinkit_maps::progress::NoProgress).expect("valid configuration");
            digest(&s.texels, &s.coords)
        };
        println!("{hash:016x} {name}");
    }
}
