//! Times one integration of a `SIDE x SIDE` normal map and measures its peak memory beyond the
//! input, for `scripts/bench-height-vs-scipy.sh`: prints one JSON line.
//!
//! `cargo run --release -p skinkit-height --example timing -- SIDE [neumann|periodic|masked] [RUNS]`

use std::time::Instant;

use skinkit_height::{HeightOptions, Integrator, Scale, integrate};
use skinkit_maps::{Grid, NormalMap, Vec3};

/// VmHWM or VmRSS of this process in MiB.
fn status_mib(field: &str) -> f64 {
    let text = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let line = text.lines().find(|l| l.starts_with(field)).unwrap_or("x 0 kB");
    line.split_whitespace().nth(1).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0) / 1024.0
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let side: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(4096);
    let integrator = match args.get(2).map(String::as_str) {
        Some("periodic") => Integrator::Periodic,
        Some("masked") => Integrator::Masked,
        _ => Integrator::Neumann,
    };
    let runs: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(3);
    let f = |x: usize, y: usize| {
        let (u, v) = (x as f32 * 0.013, y as f32 * 0.021);
        Vec3::new(0.3 * u.sin() * v.cos(), 0.2 * (u + v).cos(), 1.0).normalize()
    };
    let normals = NormalMap::from_grid(Grid::from_fn(side, side, f));
    let before = status_mib("VmRSS:");
    let options = HeightOptions { integrator: Some(integrator), scale: Scale::Texels, ..HeightOptions::default() };
    let mut seconds = Vec::new();
    for _ in 0..runs {
        let t = Instant::now();
        let h = integrate(&normals, &options).expect("a valid map");
        seconds.push(t.elapsed().as_secs_f64());
        std::hint::black_box(&h);
    }
    seconds.sort_by(f64::total_cmp);
    let beyond = status_mib("VmHWM:") - before;
    let floats = beyond * 1024.0 * 1024.0 / 4.0 / (side * side) as f64;
    println!(
        "{{\"side\": {side}, \"integrator\": \"{}\", \"median_s\": {:.3}, \"min_s\": {:.3}, \"peak_beyond_input_mib\": {beyond:.0}, \"floats_per_texel\": {floats:.2}, \"threads\": {}}}",
        integrator.name(),
        seconds[seconds.len() / 2],
        seconds[0],
        rayon::current_num_threads()
    );
}
