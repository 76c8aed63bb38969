//! How long camera RAW decoding takes beside the capture it feeds (issue 39): one synthetic DNG
//! of an 8192x8192 Bayer sensor (16-bit samples, RGGB, black 512, white 16383; 128 MiB), decoded
//! from memory at half size (4096x4096 RGB, the size of `scripts/bench-capture-vs-numpy.sh`'s
//! photos) and at full size, the median of `RUNS` decodes each. The file is decoded from memory,
//! so reading it from disk is not counted: this is the decoder's and the binning's own cost.
//!
//!     cargo run --release -p skinkit-capture --example raw_decode_timing [SENSOR_SIDE] [RUNS]

use std::path::Path;
use std::time::Instant;

use skinkit_heightfield::dng::{Dng, dng_bytes};
use skinkit_maps::Limits;
use skinkit_maps::raw::{self, RawMode};

fn main() {
    let mut args = std::env::args().skip(1);
    let side: usize = args.next().map_or(8192, |a| a.parse().expect("SENSOR_SIDE is a number"));
    let runs: usize = args.next().map_or(3, |a| a.parse().expect("RUNS is a number"));
    // A smooth gradient with a fine texture: values across the whole 512..16383 range.
    let samples: Vec<u16> = (0..side * side)
        .map(|i| (512 + ((i % side) * 7 + (i / side) * 5 + (i * 2_654_435_761) % 97) % 15800) as u16)
        .collect();
    let dng =
        Dng { width: side as u32, height: side as u32, samples: &samples, cfa: [0, 1, 1, 2], black: 512, white: 16383 };
    let bytes = dng_bytes(&dng);
    drop(samples);
    println!("DNG of a {side}x{side} sensor: {:.0} MiB", bytes.len() as f64 / (1 << 20) as f64);
    for mode in [RawMode::Half, RawMode::Full] {
        let mut seconds = Vec::with_capacity(runs);
        let mut size = (0, 0);
        for _ in 0..runs.max(1) {
            let t = Instant::now();
            let photo = raw::decode(Path::new("timing.dng"), &bytes, &Limits::default(), mode).expect("decodes");
            seconds.push(t.elapsed().as_secs_f64());
            size = (photo.width(), photo.height());
        }
        seconds.sort_by(f64::total_cmp);
        let median = seconds[seconds.len() / 2];
        println!(
            "{} size ({}x{} RGB float): median {median:.3} s a photo (runs {seconds:.3?}); 8 photos {:.2} s",
            mode.name(),
            size.0,
            size.1,
            8.0 * median
        );
    }
}
