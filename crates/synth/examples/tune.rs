//! Scores synthesis configurations the way the peer benchmark does (256x256 from the 128x128
//! forehead heightfield, seed 1): `cargo run --release -p skinkit-synth --example tune -- k=4,n=5,c=1,l=4 ...`.
//! Keys: k (k-coherence k), n (causal side), c (correction passes), l (occurrence penalty),
//! L (levels), s (output side), h (output height, default s), up (upsampled start), j (jitter),
//! w (exemplar wrap), fl / cp (finest-level and correction penalties), cc (coarse corrections), seed.

use std::time::Instant;

use skinkit_heightfield::SkinParams;
use skinkit_synth::energy::window_energy;
use skinkit_synth::metrics::{self, DEFAULT_SPECTRUM_BINS};
use skinkit_synth::{Search, SynthConfig, synthesize_normals};

fn main() {
    let ex = SkinParams::forehead(128, 128, 1).generate().expect("preset").normals;
    for spec in std::env::args().skip(1) {
        let mut side = 256;
        let mut height = None;
        let mut config = SynthConfig { seed: 1, ..SynthConfig::new(side, side) };
        for kv in spec.split(',') {
            let (k, v) = kv.split_once('=').expect("key=value");
            let f: f64 = v.parse().expect("number");
            match k {
                "k" => config.search = Search::KCoherence { k: f as usize, fallback: None, dims: 8, rerank: 8 },
                "n" => config.neighbourhood = f as usize,
                "c" => config.corrections = f as usize,
                "l" => config.occurrence_penalty = f as f32,
                "L" => config.levels = f as usize,
                "fl" => config.finest_penalty = Some(f as f32),
                "up" => {
                    config.start =
                        if f > 0.0 { skinkit_synth::Start::Upsampled } else { skinkit_synth::Start::Scanline }
                }
                "j" => config.jitter = f as usize,
                "w" => config.exemplar_wrap = f > 0.0,
                "cp" => config.correction_penalty = Some(f as f32),
                "cc" => config.coarse_corrections = Some(f as usize),
                "s" => side = f as usize,
                "h" => height = Some(f as usize),
                "seed" => config.seed = f as u64,
                other => panic!("unknown key {other}"),
            }
        }
        config.width = side;
        config.height = height.unwrap_or(side);
        let t = Instant::now();
        let out = synthesize_normals(&ex, &config, &|_, _| {}).expect("synthesis");
        let secs = t.elapsed().as_secs_f64();
        let stride = (side / 128).max(1);
        let energy = window_energy(out.normals.grid(), ex.grid(), 5, stride);
        let slope = metrics::slope_distance(&out.normals, &ex);
        let spectrum = metrics::normal_spectrum_distance(&out.normals, &ex, DEFAULT_SPECTRUM_BINS);
        let copies = metrics::copy_statistics(&out.coords, ex.size(), false);
        println!(
            "{spec:<28} {secs:>7.3} s  energy {energy:.5}  slope {slope:.4}  spectrum {spectrum:.4}  largest {}",
            copies.largest_block
        );
    }
}
