//! Interrupts (issue 15, D4): SIGINT, SIGTERM and SIGHUP stop the run, remove the unfinished
//! outputs, let `batch` write the report of what finished, and exit with 130.
//!
//! Why a handler that cleans up and exits rather than a cancel flag checked by the work: the long
//! loops live in the libraries (a synthesis level, a solve, a render can each run for minutes) and
//! have no cancellation points; a flag would stop a run only at the next check, and every library
//! loop would have to carry it. Cleaning up from the handler is robust without that, because every
//! output is staged in an [`OutputSet`](skinkit_maps::OutputSet) and nothing unfinished is visible
//! outside a staging folder:
//!
//! 1. a dedicated thread receives the signal (signal-hook's self-pipe: the real handler only
//!    writes a byte, so nothing runs in signal context);
//! 2. [`skinkit_maps::output_set::abandon_all`] waits for a commit in progress (a few renames),
//!    removes every live staging folder and keeps further commits from starting;
//! 3. the hooks registered with [`on_interrupt`] run (batch writes `batch-report.json` of the
//!    sessions that finished, each a complete folder);
//! 4. one line on stderr, then `_exit(130)`, which skips atexit handlers: the GPU driver's must
//!    not run while a worker thread may still be inside it.
//!
//! Work still running on other threads during steps 2-3 can only write into staging folders that
//! are being or have been removed, and cannot commit, so it adds nothing visible. Exit 130 is the
//! shell's code for SIGINT; SIGTERM and SIGHUP exit with it too, so scripts test one code.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

#[cfg(unix)]
use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};

/// What runs after the outputs were abandoned, before the exit.
type Hook = Box<dyn Fn() + Send>;

static HOOKS: Mutex<Vec<(u64, Hook)>> = Mutex::new(Vec::new());

/// Set first when a signal arrives: work that fails after it failed because its staging folder
/// was removed, not because of its input.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Whether a signal is stopping the run.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::SeqCst)
}

/// Starts the thread that handles the signals. A signal that arrived ignored stays ignored (a
/// script's background job ignores SIGINT so that Ctrl-C stops only the script's foreground).
/// Without the thread (an error registering) the signals keep their default action, and a re-run
/// still removes what was left.
#[cfg(unix)]
pub fn install() {
    let wanted: Vec<i32> = [SIGINT, SIGTERM, SIGHUP].into_iter().filter(|&s| !ignored(s)).collect();
    let Ok(mut signals) = signal_hook::iterator::Signals::new(wanted) else {
        return;
    };
    let spawned = std::thread::Builder::new().name("signals".into()).spawn(move || {
        if let Some(signal) = signals.forever().next() {
            stop(signal);
        }
    });
    drop(spawned);
}

/// Elsewhere signals keep their default action; a re-run removes what an interrupted run left.
#[cfg(not(unix))]
pub fn install() {}

/// Whether `signal`'s disposition is "ignore" (inherited from the parent).
#[cfg(unix)]
fn ignored(signal: i32) -> bool {
    // SAFETY: sigaction with a null new action only reads the current one into `old`, a plain C
    // struct for which all-zero bytes are a valid value.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(signal, std::ptr::null(), &mut old) == 0 && old.sa_sigaction == libc::SIG_IGN
    }
}

#[cfg(unix)]
fn stop(signal: i32) -> ! {
    REQUESTED.store(true, Ordering::SeqCst);
    let removed = skinkit_maps::output_set::abandon_all();
    let hooks = HOOKS.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    for (_, hook) in hooks.iter() {
        hook();
    }
    let name = match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "SIGHUP",
    };
    eprintln!("interrupted by {name}: {removed} unfinished output set(s) removed, finished ones are complete");
    signal_hook::low_level::exit(130);
}

/// Runs `hook` if the run is interrupted while the returned guard lives.
pub fn on_interrupt(hook: impl Fn() + Send + 'static) -> HookGuard {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let id = NEXT.fetch_add(1, Ordering::Relaxed);
    HOOKS.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).push((id, Box::new(hook)));
    HookGuard(id)
}

/// Unregisters its hook when dropped.
pub struct HookGuard(u64);

impl Drop for HookGuard {
    fn drop(&mut self) {
        HOOKS.lock().unwrap_or_else(|poisoned| poisoned.into_inner()).retain(|(id, _)| *id != self.0);
    }
}
