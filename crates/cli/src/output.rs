//! Where results and messages go: results to stdout (text or `--json`), progress and messages
//! to stderr, nothing but errors with `--quiet`.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde::Serialize;
use skinkit_maps::limits;
use skinkit_maps::progress::Progress;

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

    /// A progress bar on stderr over `len` steps, hidden with `--quiet`/`--json` or off a terminal;
    /// each stage a library starts takes it over (its name and length).
    pub fn progress(&self, len: u64, message: &str) -> Bar {
        let visible = !self.quiet && !self.json;
        Bar {
            current: Mutex::new(BarState { bar: new_bar(visible, len, message), started: true }),
            visible,
            keep: false,
        }
    }

    /// A progress bar per stage a library starts, each left on stderr, done, when the next starts
    /// (synthesis shows every pyramid level so).
    pub fn stage_bars(&self) -> Bar {
        let visible = !self.quiet && !self.json;
        Bar { current: Mutex::new(BarState { bar: ProgressBar::hidden(), started: false }), visible, keep: true }
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

    /// With `--json`, one compact line `{"record": KIND, ...}` on stdout, for a command that
    /// streams one record per item as each ends (a script reads them line by line); otherwise
    /// nothing.
    pub fn record<T: Serialize>(&self, kind: &str, value: &T) {
        if self.json {
            println!("{}", tagged(kind, value));
        }
    }

    /// The last line of such a stream: the command's result as a record of `kind` with `--json`,
    /// else the text `human` gives.
    pub fn result_record<T: Serialize>(&self, kind: &str, value: &T, human: impl FnOnce() -> String) {
        if self.json {
            println!("{}", tagged(kind, value));
        } else if !self.quiet {
            println!("{}", human());
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

/// The one [`Progress`] of the command line, over indicatif: what a library reports and what the
/// CLI's own loops count (`advance`) both move it.
pub struct Bar {
    current: Mutex<BarState>,
    visible: bool,
    /// A new bar per stage, the finished ones left on screen ([`Output::stage_bars`]).
    keep: bool,
}

struct BarState {
    bar: ProgressBar,
    /// Whether `bar` is a stage's (else a placeholder before the first stage).
    started: bool,
}

impl Bar {
    fn bar(&self) -> ProgressBar {
        self.current.lock().expect("progress bar lock").bar.clone()
    }

    /// Removes the bar from the terminal (the job is done).
    pub fn clear(&self) {
        self.bar().finish_and_clear();
    }

    /// Runs `f` with the bar hidden, so that lines `f` prints are not drawn over.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        self.bar().suspend(f)
    }
}

impl Progress for Bar {
    fn start(&self, name: &str, len: u64) {
        let mut state = self.current.lock().expect("progress bar lock");
        if self.keep {
            if state.started {
                state.bar.finish();
            }
            *state = BarState { bar: new_bar(self.visible, len, name), started: true };
        } else {
            state.bar.set_message(name.to_owned());
            state.bar.set_length(len);
            state.bar.set_position(0);
        }
    }

    fn advance(&self, steps: u64) {
        self.bar().inc(steps);
    }

    fn finish(&self) {
        let bar = self.bar();
        if self.keep {
            bar.finish();
        } else if let Some(len) = bar.length() {
            bar.set_position(len);
        }
    }
}

/// A bar over `len` steps labelled `message`, drawn on stderr when `visible` (and a terminal).
fn new_bar(visible: bool, len: u64, message: &str) -> ProgressBar {
    let bar = if visible {
        ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr())
    } else {
        ProgressBar::hidden()
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

/// `value` as one line of JSON with a `record` field naming its kind.
fn tagged<T: Serialize>(kind: &str, value: &T) -> String {
    let mut json = serde_json::to_value(value).expect("serialisable record");
    if let serde_json::Value::Object(map) = &mut json {
        map.insert("record".into(), kind.into());
    }
    json.to_string()
}

/// The error and its causes on one line, joined with `: ` ([`skinkit_maps::error::one_line`]).
pub(crate) fn one_line(error: &anyhow::Error) -> String {
    skinkit_maps::error::one_line(error.as_ref())
}

/// A command line that asks for something impossible (an `--out` that is an input, a folder where
/// a file goes): refused before any work, exit 2 like clap's own usage errors. The output gate's
/// refusals are these.
pub use skinkit_maps::gate::Refused as UsageError;

/// A [`UsageError`] as an `anyhow::Error`.
pub fn usage(message: String) -> anyhow::Error {
    anyhow::Error::new(UsageError(message))
}

/// The exit code of a failed run: 2 for a [`UsageError`] anywhere in the chain, else 1.
pub fn exit_code(error: &anyhow::Error) -> i32 {
    if error.chain().any(|cause| cause.is::<UsageError>()) { 2 } else { 1 }
}

#[cfg(test)]
mod tests {
    use super::one_line;
    use anyhow::Context;

    fn io_error(kind: std::io::ErrorKind) -> std::io::Error {
        std::io::Error::from(kind)
    }

    /// Issue 15, D10 and issue 38: each cause once, because each error says only its own part
    /// (a context what was being done, a library error the file) and its cause is `source()`.
    #[test]
    fn d10_error_chains_say_each_cause_once() {
        let os = std::io::Error::from_raw_os_error(2);
        let text = os.to_string();
        // A context saying what was being done over a library error naming the file.
        let e = anyhow::Error::new(skinkit_maps::Error::Io { path: "a.png".into(), error: os }).context("photo 3");
        assert_eq!(one_line(&e), format!("photo 3: a.png: {text}"));
        // A context naming the file over an `io::Error`, which names none.
        let inner = anyhow::Error::new(io_error(std::io::ErrorKind::IsADirectory));
        let kind_text = inner.to_string();
        let e = inner.context("cannot create out");
        assert_eq!(one_line(&e), format!("cannot create out: {kind_text}"));
        // Unrelated causes are all kept, in order.
        let e = anyhow::anyhow!("bad value").context("field b").context("scene.toml");
        assert_eq!(one_line(&e), "scene.toml: field b: bad value");
    }

    /// The printer matches no text: a part that overlaps the one before is kept whole (a context
    /// must not repeat what its cause says; the printer does not hide it when one does).
    #[test]
    fn a_cause_is_not_dropped_for_a_partial_overlap() {
        let e = anyhow::anyhow!("photo 12: too dark").context("photo 1");
        assert_eq!(one_line(&e), "photo 1: photo 12: too dark");
        let e = anyhow::anyhow!("2: too dark").context("light 12");
        assert_eq!(one_line(&e), "light 12: 2: too dark");
        let r: Result<(), _> = Err(anyhow::anyhow!("a.png: gone")).context("mask a.png");
        assert_eq!(one_line(&r.unwrap_err()), "mask a.png: a.png: gone");
    }
}
