//! Where results and messages go: results to stdout (text or `--json`), progress and messages
//! to stderr, nothing but errors with `--quiet`.

use std::path::PathBuf;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use skinkit_maps::limits;

/// Flags every subcommand takes.
#[derive(clap::Args, Debug, Clone)]
pub struct GlobalArgs {
    /// Print nothing but errors (and `--json` results).
    #[arg(long, short, global = true)]
    pub quiet: bool,
    /// Print results as one JSON document on stdout (for scripts).
    #[arg(long, global = true)]
    pub json: bool,
    /// Worker threads (default: all cores; at most 4 per core, at least 16 allowed). Results do
    /// not depend on it.
    #[arg(long, global = true, value_name = "N", value_parser = thread_count)]
    pub threads: Option<usize>,
    /// Memory one job may take, estimated from the inputs' headers before anything is allocated
    /// (bytes, 800M, 12G, or a percentage of the machine's memory such as 75%) [default: half of
    /// the machine's memory]. `batch` runs fewer sessions at once to stay within it.
    #[arg(long, global = true, value_name = "SIZE", value_parser = limits::parse_bytes)]
    pub memory_limit: Option<u64>,
}

/// A `--threads` value: 1 to [`limits::max_threads`].
fn thread_count(text: &str) -> Result<usize, String> {
    let max = limits::max_threads();
    match text.parse::<usize>() {
        Ok(n) if (1..=max).contains(&n) => Ok(n),
        _ => Err(format!("`{text}` is not a thread count from 1 to {max} (4 per core, at least 16)")),
    }
}

/// The terminal side of a command run, and the run's resource limits.
pub struct Output {
    quiet: bool,
    json: bool,
    memory_limit: u64,
}

impl Output {
    pub fn new(args: &GlobalArgs) -> Self {
        if let Some(n) = args.threads {
            // Ignore the error: the global pool can only be set once, and tests may set it first.
            let _ = rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build_global();
        }
        let memory_limit = args.memory_limit.unwrap_or_else(limits::default_memory_limit);
        Output { quiet: args.quiet, json: args.json, memory_limit }
    }

    /// The memory limit of one job, bytes (`--memory-limit`).
    pub fn memory_limit(&self) -> u64 {
        self.memory_limit
    }

    /// A progress bar on stderr over `len` steps, hidden with `--quiet`/`--json` or off a terminal.
    pub fn progress(&self, len: u64, message: &str) -> ProgressBar {
        let bar = if self.quiet || self.json {
            ProgressBar::hidden()
        } else {
            ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr())
        };
        bar.set_style(
            ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed}")
                .expect("static template")
                .progress_chars("=> "),
        );
        bar.set_message(message.to_owned());
        bar.enable_steady_tick(Duration::from_millis(200));
        bar
    }

    /// A message for people, on stderr, unless quiet or json.
    pub fn note(&self, message: impl std::fmt::Display) {
        if !self.quiet && !self.json {
            eprintln!("{message}");
        }
    }

    /// A warning on stderr (shown unless `--quiet`).
    pub fn warn(&self, message: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("warning: {message}");
        }
    }

    /// Prints an error and its causes on stderr.
    pub fn error(&self, error: &anyhow::Error) {
        eprintln!("error: {}", one_line(error));
    }

    /// One line on stderr when a run removed what an interrupted or killed run had left (not an
    /// error: the outputs it finds are replaced anyway).
    pub fn swept(&self, paths: &[PathBuf]) {
        if let Some(first) = paths.first() {
            let more = if paths.len() > 1 { format!(" and {} more", paths.len() - 1) } else { String::new() };
            self.note(format!("removed leftovers of an interrupted run: {}{more}", first.display()));
        }
    }

    /// Prints a result: as JSON with `--json`, else as the text `human` gives, on stdout.
    pub fn result<T: Serialize>(&self, value: &T, human: impl FnOnce() -> String) {
        if self.json {
            println!("{}", serde_json::to_string_pretty(value).expect("serialisable result"));
        } else if !self.quiet {
            println!("{}", human());
        }
    }
}

/// The error and its causes on one line, each cause once: a cause whose text the line already
/// holds (a library error that prints its own source) is not repeated.
fn one_line(error: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

/// A command line that asks for something impossible (an `--out` that is an input, a folder where
/// a file goes): refused before any work, exit 2 like clap's own usage errors.
#[derive(Debug)]
pub struct UsageError(pub String);

impl std::fmt::Display for UsageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for UsageError {}

/// The exit code of a failed run: 2 for a [`UsageError`] anywhere in the chain, else 1.
pub fn exit_code(error: &anyhow::Error) -> i32 {
    if error.chain().any(|cause| cause.is::<UsageError>()) { 2 } else { 1 }
}
