//! What `skinkit synth` costs from 512x512 to 16384x16384 (issue 43): seconds, seconds per
//! megatexel, the memory estimate and the peak resident memory the run's report gives, for three
//! exemplar kinds made here from a synthetic forehead (pores and two furrow families, 128x128 at
//! 0.02 mm a texel, seed 7; none is in the synthesis suite):
//!
//! - `normal`: its unit normals, a 16-bit normal map;
//! - `colour`: an 8-bit sRGB colour image (shading, height and slope in the three channels);
//! - `height`: its heights, a 16-bit grey image grown as linear colour.
//!
//! Each run is one process of the release binary with the defaults, so each peak is its own.
//! The exemplars are kept in `target/synth-memory/`. `MEMORY_BENCH_MAX` (default 16384) is the largest side run; `MEMORY_BENCH_KINDS` a comma list
//! of kinds. The table goes to stderr and `target/synth-memory.md`; with `MEMORY_BENCH_DOCS=1` it
//! also replaces the block between the `synth-memory` markers in the README.
//!
//! `cargo bench -p skinkit-cli --bench memory` (about an hour on a 2-core machine at 16384).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use glam::Vec3;
use skinkit_heightfield::{Heightfield, SkinParams};
use skinkit_maps::io;
use skinkit_maps::{Grid, NormalEncoding};

/// Exemplar side.
const SIDE: usize = 128;

/// Output sizes, smallest first.
const SIZES: [(usize, usize); 6] = [(512, 512), (1024, 1024), (2048, 2048), (4096, 2048), (8192, 8192), (16384, 16384)];

/// One run's figures.
struct Row {
    kind: &'static str,
    size: (usize, usize),
    seconds: f64,
    estimate_mib: f64,
    peak_mib: f64,
}

fn main() {
    let max: usize = std::env::var("MEMORY_BENCH_MAX").ok().and_then(|v| v.parse().ok()).unwrap_or(16384);
    let kinds = std::env::var("MEMORY_BENCH_KINDS").unwrap_or_else(|_| "normal,colour,height".to_owned());
    let dir = tempfile::tempdir().expect("a temporary folder");
    // The exemplars are kept, to rerun a row by hand.
    let exemplars = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/synth-memory");
    std::fs::create_dir_all(&exemplars).expect("the exemplars' folder");
    let field = SkinParams::forehead(SIDE, SIDE, 7).generate().expect("the preset generates");
    let load_before = load_average();
    let mut rows = Vec::new();
    for kind in kinds.split(',').map(str::trim) {
        let (exemplar, flags) = exemplar(&exemplars, kind, &field);
        for &(w, h) in SIZES.iter().filter(|(w, h)| *w.max(h) <= max) {
            eprintln!("memory: {kind} {w}x{h}...");
            rows.push(run(kind_name(kind), &exemplar, &flags, (w, h), dir.path()));
        }
    }
    let table = markdown(&rows, &load_before);
    eprintln!("{table}");
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/synth-memory.md");
    std::fs::write(&target, &table).expect("the report writes");
    if std::env::var("MEMORY_BENCH_DOCS").is_ok_and(|v| v == "1") {
        splice_readme(&table);
    }
}

fn kind_name(kind: &str) -> &'static str {
    match kind {
        "normal" => "normal",
        "colour" => "colour",
        "height" => "height",
        other => panic!("MEMORY_BENCH_KINDS: unknown kind {other} (normal, colour, height)"),
    }
}

/// Writes the exemplar of `kind` and gives its path and the flags that read it.
fn exemplar(dir: &Path, kind: &str, field: &Heightfield) -> (PathBuf, Vec<&'static str>) {
    let path = dir.join(format!("{kind}.png"));
    match kind {
        "normal" => {
            io::write_normal_map(&path, &field.normals, NormalEncoding::default(), 16).expect("writes");
            (path, vec![])
        }
        "height" => {
            let (lo, hi) = range(field.heights.as_slice());
            let unit = field.heights.map(|h| (h - lo) / (hi - lo).max(f32::MIN_POSITIVE));
            io::write_scalar_png(&path, &unit, 16).expect("writes");
            (path, vec!["--kind", "color", "--transfer", "linear"])
        }
        _ => {
            let (lo, hi) = range(field.heights.as_slice());
            let light = Vec3::new(-0.4, 0.5, 0.77).normalize();
            let colour = Grid::from_fn(SIDE, SIDE, |x, y| {
                let n = field.normals.grid().get(x, y);
                let h = (*field.heights.get(x, y) - lo) / (hi - lo).max(f32::MIN_POSITIVE);
                Vec3::new(0.2 + 0.7 * n.dot(light).max(0.0), h, 1.0 - n.z.clamp(0.0, 1.0) * 0.8)
            });
            io::write_color_map(&path, &colour, 8).expect("writes");
            (path, vec!["--kind", "color"])
        }
    }
}

fn range(values: &[f32]) -> (f32, f32) {
    values.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
}

/// One `skinkit synth` of `exemplar` to `w x h`, its report read back.
fn run(kind: &'static str, exemplar: &Path, flags: &[&str], (w, h): (usize, usize), dir: &Path) -> Row {
    let (out, report) = (dir.join("out.png"), dir.join("report.json"));
    let size = format!("{w}x{h}");
    let start = Instant::now();
    let status = Command::new(env!("CARGO_BIN_EXE_skinkit"))
        .args(["synth", &exemplar.display().to_string(), "--size", &size, "--quiet"])
        .args(["--out", &out.display().to_string(), "--report", &report.display().to_string()])
        .args(flags)
        .status()
        .expect("the binary runs");
    assert!(status.success(), "skinkit synth {kind} {size} failed");
    let seconds = start.elapsed().as_secs_f64();
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).expect("the report reads")).expect("the report is JSON");
    let estimate_mib = r["memory_estimate_mib"].as_f64().expect("the report has the estimate");
    let peak_mib = r["peak_memory_mib"].as_f64().unwrap_or(f64::NAN);
    Row { kind, size: (w, h), seconds, estimate_mib, peak_mib }
}

/// The table, and what produced it.
fn markdown(rows: &[Row], load_before: &str) -> String {
    let mut s = format!(
        "`skinkit synth` with the defaults, one process a run, from a {SIDE}x{SIDE} synthetic forehead \
         (pores and furrows, seed 7; made by `crates/cli/benches/memory.rs`) as a 16-bit normal map, an 8-bit \
         colour image and a 16-bit height image; seconds wall clock (load average {load_before} before, {} after).\n\n\
         | exemplar | output | seconds | s / megatexel | estimate (MiB) | peak resident (MiB) | estimate / peak |\n\
         | --- | --- | ---: | ---: | ---: | ---: | ---: |\n",
        load_average()
    );
    for r in rows {
        let megatexels = (r.size.0 * r.size.1) as f64 / 1e6;
        s += &format!(
            "| {} | {}x{} | {:.1} | {:.2} | {:.0} | {:.0} | {:.2} |\n",
            r.kind,
            r.size.0,
            r.size.1,
            r.seconds,
            r.seconds / megatexels,
            r.estimate_mib,
            r.peak_mib,
            r.estimate_mib / r.peak_mib
        );
    }
    s
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_owned))
        .unwrap_or_else(|| "unknown".to_owned())
}

const START: &str = "<!-- synth-memory:start -->";
const END: &str = "<!-- synth-memory:end -->";

/// Replaces the block between the markers in the README with `table`.
fn splice_readme(table: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    let text = std::fs::read_to_string(&path).expect("the README reads");
    let (Some(a), Some(b)) = (text.find(START), text.find(END)) else {
        eprintln!("{} has no {START} ... {END} block; not changed", path.display());
        return;
    };
    std::fs::write(&path, format!("{}{START}\n{table}{}", &text[..a], &text[b..])).expect("the README writes");
    eprintln!("{}: table replaced", path.display());
}
