//! The suite's results, its markdown tables, the speed runs, the peer-score cache and the contact
//! sheet.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use glam::Vec3;
use skinkit_heightfield::SkinParams;
use texture_synthesis::image::{Rgb, RgbImage};

use crate::exemplars::{SIDE, Texels};
use crate::{OUT, Scores, parse_config, peer};

/// Both synthesisers' scores on one exemplar, per seed, and the seed-1 outputs.
#[derive(Default)]
pub struct ExemplarResult {
    pub name: String,
    pub peer: Vec<Scores>,
    pub ours: Vec<Scores>,
    pub exemplar: Option<Texels>,
    pub peer_output: Option<Texels>,
    pub output: Option<Texels>,
}

/// The mean, largest and smallest of a score over seeds.
fn mean(v: &[Scores], f: fn(&Scores) -> f64) -> f64 {
    v.iter().map(f).sum::<f64>() / v.len().max(1) as f64
}
fn max(v: &[Scores], f: fn(&Scores) -> f64) -> f64 {
    v.iter().map(f).fold(f64::NEG_INFINITY, f64::max)
}
fn min(v: &[Scores], f: fn(&Scores) -> f64) -> f64 {
    v.iter().map(f).fold(f64::INFINITY, f64::min)
}

/// Peer scores from earlier runs, keyed by `exemplar \t seed \t side`.
pub struct PeerCache {
    path: PathBuf,
    entries: BTreeMap<String, Scores>,
}

impl PeerCache {
    pub fn load(path: PathBuf) -> Self {
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let entries = text
            .lines()
            .filter_map(|line| {
                let fields: Vec<&str> = line.split('\t').collect();
                let v: Vec<f64> = fields.get(3..8)?.iter().map(|s| s.parse().ok()).collect::<Option<_>>()?;
                let scores = Scores { energy: v[0], copy: v[1], distribution: v[2], spectrum: v[3], variation: v[4] };
                Some((fields[..3].join("\t"), scores))
            })
            .collect();
        PeerCache { path, entries }
    }
    pub fn get(&self, key: &str) -> Option<Scores> {
        self.entries.get(key).copied()
    }
    pub fn put(&mut self, key: &str, s: Scores) {
        self.entries.insert(key.to_owned(), s);
    }
    pub fn save(&self) {
        let text: String = self
            .entries
            .iter()
            .map(|(k, s)| {
                format!("{k}\t{}\t{}\t{}\t{}\t{}\n", s.energy, s.copy, s.distribution, s.spectrum, s.variation)
            })
            .collect();
        if let Err(e) = std::fs::write(&self.path, text) {
            eprintln!("could not write {}: {e}", self.path.display());
        }
    }
}

/// The 1-minute load average, when the system has one (the machine is shared).
pub fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "unknown".to_owned())
}

/// The process's peak resident memory so far, bytes (`VmHWM`), when the system reports it.
fn peak_resident() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 { v[m] } else { 0.5 * (v[m - 1] + v[m]) }
}

fn timed(runs: usize, mut f: impl FnMut()) -> f64 {
    median(
        (0..runs)
            .map(|_| {
                let start = Instant::now();
                f();
                start.elapsed().as_secs_f64()
            })
            .collect(),
    )
}

/// The speed runs: `(peer, skinkit)` seconds at 512x512, then skinkit's `(width, height, seconds,
/// estimated bytes, peak resident bytes)` per size.
pub struct Speed {
    pub peer_512: f64,
    pub ours_512: f64,
    pub sizes: Vec<(usize, usize, f64, u64, Option<u64>)>,
}

pub fn speed(spec: &str) -> Speed {
    let ex = SkinParams::forehead(SIDE, SIDE, 1).generate().expect("preset generates").normals;
    let texels = Texels::Normal(ex.clone());
    eprintln!("speed: peer 512x512, 2 runs...");
    let peer_512 = timed(2, || drop(peer::run(&texels, 512, 512, 1)));
    let config = parse_config(spec, 512, 512, 1);
    eprintln!("speed: skinkit 512x512, 3 runs...");
    let ours_512 = timed(3, || {
        drop(skinkit_synth::synthesize_normals(&ex, &config, &skinkit_maps::progress::NoProgress).expect("valid"))
    });
    let mut sizes = vec![(1024, 1024), (2048, 2048), (4096, 2048)];
    if std::env::var("SYNTH_SUITE_LARGE").is_ok_and(|v| v == "1") {
        sizes.push((8192, 8192));
    }
    let mut rows = vec![(512, 512, ours_512, config.memory_estimate(SIDE, SIDE), peak_resident())];
    for (w, h) in sizes {
        eprintln!("speed: skinkit {w}x{h}...");
        let config = parse_config(spec, w, h, 1);
        let seconds = timed(1, || {
            drop(skinkit_synth::synthesize_normals(&ex, &config, &skinkit_maps::progress::NoProgress).expect("valid"))
        });
        rows.push((w, h, seconds, config.memory_estimate(SIDE, SIDE), peak_resident()));
    }
    Speed { peer_512, ours_512, sizes: rows }
}

const MIB: f64 = 1024.0 * 1024.0;

/// The report: the quality table, the speed tables, and what they mean.
pub fn markdown(results: &[ExemplarResult], speed: Option<&Speed>, spec: &str, seeds: u64, load: &str) -> String {
    let mut s = format!(
        "256x256 from 128x128, seeds 1-{seeds}, means over seeds (copy and variation: worst seed); \
         peer / skinkit in each cell. Configuration: {}.\n\n\
         | exemplar | energy | largest copy (% of exemplar) | distribution | spectrum | variation |\n\
         | --- | --- | --- | --- | --- | --- |\n",
        if spec.is_empty() { "the defaults".to_owned() } else { format!("defaults with `{spec}`") }
    );
    for r in results {
        let (p, o) = (&r.peer, &r.ours);
        s += &format!(
            "| {} | {:.3} / {:.3} | {:.1} / {:.1} | {:.4} / {:.4} | {:.3} / {:.3} | {:.2} / {:.2} |\n",
            r.name,
            mean(p, |q| q.energy),
            mean(o, |q| q.energy),
            100.0 * max(p, |q| q.copy),
            100.0 * max(o, |q| q.copy),
            mean(p, |q| q.distribution),
            mean(o, |q| q.distribution),
            mean(p, |q| q.spectrum),
            mean(o, |q| q.spectrum),
            min(p, |q| q.variation),
            min(o, |q| q.variation),
        );
    }
    if let Some(speed) = speed {
        s += &format!(
            "\n512x512 from the 128x128 heightfield forehead: peer {:.2} s (median of 2), skinkit {:.3} s \
             (median of 3), {:.1}x faster.\n\n\
             | output | seconds | seconds per megatexel | memory estimate (MiB) | peak resident so far (MiB) |\n\
             | --- | ---: | ---: | ---: | ---: |\n",
            speed.peer_512,
            speed.ours_512,
            speed.peer_512 / speed.ours_512
        );
        for &(w, h, seconds, estimate, peak) in &speed.sizes {
            let mtex = (w * h) as f64 / 1e6;
            let peak = peak.map_or("-".to_owned(), |p| format!("{:.0}", p as f64 / MIB));
            s += &format!(
                "| {w}x{h} | {seconds:.2} | {:.3} | {:.0} | {peak} |\n",
                seconds / mtex,
                estimate as f64 / MIB
            );
        }
    }
    s += &format!(
        "\nEnergy: mean squared distance of every other output texel's 5x5 window to the nearest exemplar \
         window, over the exemplar's own figure (each exemplar window to its nearest non-overlapping \
         one). Largest copy: the biggest block copied with one offset. Distribution: Wasserstein-1 of \
         slope (normals) or channel (colour) histograms; spectrum: radial spectra. Variation: the \
         output's slope or channel deviation over the exemplar's (below 0.5 is a collapse). 1-minute \
         load average {load} (start / end).\n"
    );
    s
}

/// Markers of the suite's block in the book's "Growing a map" chapter.
const START: &str = "<!-- synth-suite:start -->";
const END: &str = "<!-- synth-suite:end -->";

/// Replaces the block between the suite markers in `docs/book/src/synthesis.md` with `markdown`.
pub fn splice_doc(markdown: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/book/src/synthesis.md");
    let text = std::fs::read_to_string(&path).expect("the chapter reads");
    let (Some(a), Some(b)) = (text.find(START), text.find(END)) else {
        eprintln!("{} has no {START} ... {END} block; not changed", path.display());
        return;
    };
    let spliced = format!("{}{START}\n{markdown}{}", &text[..a], &text[b..]);
    std::fs::write(&path, spliced).expect("the chapter writes");
    eprintln!("{}: table replaced", path.display());
}

/// An 8-bit view of a map: colour as is, normals shaded by a light from the upper left.
fn view(t: &Texels) -> impl Fn(usize, usize) -> [u8; 3] + '_ {
    let light = Vec3::new(-0.5, 0.5, 0.7).normalize();
    move |x, y| {
        let v = *t.grid().get(x, y);
        let c = match t {
            Texels::Normal(_) => Vec3::splat(0.1 + 0.9 * v.dot(light).max(0.0)),
            Texels::Color(_) => v,
        };
        (c * 255.0).round().clamp(Vec3::ZERO, Vec3::splat(255.0)).to_array().map(|c| c as u8)
    }
}

/// One row per exemplar: exemplar (top left of its cell) | peer | skinkit, seed 1.
pub fn contact_sheet(results: &[ExemplarResult]) -> RgbImage {
    let gap = 4;
    let cell = OUT + gap;
    let mut sheet = RgbImage::from_pixel((3 * cell) as u32, (results.len() * cell).max(1) as u32, Rgb([255; 3]));
    for (row, r) in results.iter().enumerate() {
        let maps = [&r.exemplar, &r.peer_output, &r.output];
        for (col, map) in maps.iter().enumerate() {
            let Some(map) = map else { continue };
            let (w, h) = map.grid().size();
            let texel = view(map);
            for y in 0..h.min(OUT) {
                for x in 0..w.min(OUT) {
                    sheet.put_pixel((col * cell + x) as u32, (row * cell + y) as u32, Rgb(texel(x, y)));
                }
            }
        }
    }
    sheet
}
