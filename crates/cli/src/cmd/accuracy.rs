//! `skinkit accuracy`: what accuracy costs in time, stage by stage, on the bundled samples. The
//! measuring is `skinkit_accuracy`'s; this module parses the flags, draws one progress bar per
//! stage, prints the results and writes `accuracy.md`, `accuracy.json` and one plot per stage
//! as one output set (all or nothing, the JSON last).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use skinkit_accuracy::{Config, Report, Stage, StageReport, markdown, plot};
use skinkit_maps::OutputSet;
use skinkit_maps::io::write_atomic;

use crate::output::Output;
use crate::pipeline::write_json_in;

/// The file whose presence marks a complete accuracy folder (written last).
pub const MARKER: &str = "accuracy.json";

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Folder to write accuracy.md, accuracy.json and the plots (`accuracy-<stage>.png`) into.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Small sizes, a couple of choices per knob, one timed run per choice (a few minutes);
    /// without it, the sizes and choices of the book's tables, medians of 3 runs.
    #[arg(long)]
    pub quick: bool,
    /// Seed of every random choice (molds, sensor noise, synthesis, curves).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only these stages (comma-separated: capture, detrend, height, synthesis, stitching, rendering).
    #[arg(long, value_name = "STAGES", value_delimiter = ',', value_parser = parse_stage)]
    pub only: Vec<Stage>,
    /// The samples folder (sample molds, face layout, scenes) [default: the repository's samples].
    #[arg(long, value_name = "DIR")]
    pub samples: Option<PathBuf>,
}

fn parse_stage(text: &str) -> std::result::Result<Stage, String> {
    Stage::ALL.into_iter().find(|s| s.name() == text).ok_or_else(|| {
        let names: Vec<&str> = Stage::ALL.iter().map(|s| s.name()).collect();
        format!("`{text}` is not a stage ({})", names.join(", "))
    })
}

fn default_samples() -> PathBuf {
    let here = PathBuf::from("samples");
    if here.join("molds").is_dir() { here } else { Path::new(env!("CARGO_MANIFEST_DIR")).join("../../samples") }
}

/// Runs `skinkit accuracy`.
///
/// # Errors
/// When a stage cannot read its samples or a file cannot be written.
pub fn run(args: Args, out: &Output) -> Result<i32> {
    let config =
        Config { quick: args.quick, seed: args.seed, samples: args.samples.clone().unwrap_or_else(default_samples) };
    let stages: Vec<Stage> = if args.only.is_empty() {
        Stage::ALL.to_vec()
    } else {
        Stage::ALL.into_iter().filter(|s| args.only.contains(s)).collect()
    };
    let report = to_dir(&config, &stages, &args.out, out)?;
    out.result(&report, || summary(&report, &args.out));
    Ok(0)
}

/// Measures `stages` (a progress bar each) and writes `accuracy.md`, the plots and
/// `accuracy.json` into `dir` (`skinkit accuracy`, and the demo's quick run).
///
/// # Errors
/// When a stage cannot read its samples or a file cannot be written.
pub fn to_dir(config: &Config, stages: &[Stage], dir: &Path, out: &Output) -> Result<Report> {
    let start = Instant::now();
    let set = OutputSet::folder(dir, MARKER).context("cannot write the accuracy folder")?;
    let mut reports = Vec::new();
    for &stage in stages {
        reports.push(measure_stage(stage, config, out)?);
    }
    let report = Report {
        quick: config.quick,
        seed: config.seed,
        threads: rayon::current_num_threads(),
        runs: config.runs(),
        stages: reports,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    write_all(set, &report)?;
    Ok(report)
}

/// One stage under its progress bar; a skipped stage is noted.
fn measure_stage(stage: Stage, config: &Config, out: &Output) -> Result<StageReport> {
    let bar = out.progress(0, stage.name());
    let report = skinkit_accuracy::measure(stage, config, &bar).with_context(|| format!("stage {stage}"))?;
    bar.clear();
    if let Some(reason) = &report.skipped {
        out.warn(format!("{stage}: skipped: {reason}"));
    } else {
        out.note(format!("{stage}: {} choices in {:.1} s", report.choices.len(), report.wall_seconds));
    }
    Ok(report)
}

/// Writes the markdown, the plots and the JSON (last) into the set's folder, all or nothing.
fn write_all(set: OutputSet, report: &Report) -> Result<()> {
    let bytes = |name: &str, role: &str, data: &[u8]| -> Result<()> {
        set.write(name, |p| {
            write_atomic(p, |w| {
                use std::io::Write;
                w.write_all(data).map_err(|e| skinkit_maps::Error::Io { path: p.to_owned(), error: e })
            })
        })
        .with_context(|| format!("cannot write {role}"))
    };
    bytes("accuracy.md", "the accuracy summary", markdown::render(report).as_bytes())?;
    for stage in &report.stages {
        let png = plot::png(stage)?;
        bytes(&markdown::plot_name(stage), &format!("the {} plot", stage.stage.name()), &png)?;
    }
    write_json_in(&set, MARKER, "the accuracy report", report)?;
    set.commit().context("cannot finish writing the accuracy results")?;
    Ok(())
}

/// The results table printed on stdout: per stage, each choice's error and time.
fn summary(report: &Report, dir: &Path) -> String {
    let mut s = String::new();
    for stage in &report.stages {
        s.push_str(&format!("{}:", stage.stage));
        match &stage.skipped {
            Some(reason) => s.push_str(&format!(" skipped ({reason})\n")),
            None => {
                s.push_str(&format!(" {} against {}\n", stage.error_metric, stage.cost_axis));
                for c in &stage.choices {
                    s.push_str(&format!(
                        "  {:<36} {:>10.4} {:>10.4}\n",
                        format!("{}: {}", c.series, c.label),
                        c.error(),
                        c.cost
                    ));
                }
            }
        }
    }
    s.push_str(&format!("wrote {} ({:.1} s)", dir.join("accuracy.md").display(), report.wall_seconds));
    s
}
