//! How a long library call says how far it has got: one small trait every library takes, so the
//! command line draws every progress bar the same way (issue 38) and no library depends on a
//! terminal crate.
//!
//! A job is a run of stages. [`Progress::start`] begins a stage with its name and its length in
//! steps (0 when the length is not known), which ends the stage before it; [`Progress::advance`]
//! counts steps of the current stage done, from any thread; [`Progress::finish`] ends the
//! current stage. A library never prints: what a user sees is the caller's choice.
//!
//! [`NoProgress`] ignores everything. A closure of one [`Step`] is a `Progress` too, which keeps
//! a test that watches the steps short:
//!
//! ```
//! use skinkit_maps::progress::{Progress, Step};
//! use std::sync::Mutex;
//! let steps = Mutex::new(0);
//! let watch = |step: Step<'_>| {
//!     if let Step::Advance(n) = step {
//!         *steps.lock().unwrap() += n;
//!     }
//! };
//! watch.start("rows", 2);
//! watch.advance(2);
//! watch.finish();
//! assert_eq!(*steps.lock().unwrap(), 2);
//! ```

/// Receives a job's stages and steps; called from worker threads, so it is `Sync`.
pub trait Progress: Sync {
    /// A stage named `name` of `len` steps (0 when unknown) begins; the one before it ends.
    fn start(&self, name: &str, len: u64);
    /// `steps` more steps of the current stage are done.
    fn advance(&self, steps: u64);
    /// The current stage is done.
    fn finish(&self);
}

/// One report to a closure used as [`Progress`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step<'a> {
    /// [`Progress::start`].
    Start {
        /// The stage's name.
        name: &'a str,
        /// Its length in steps, 0 when unknown.
        len: u64,
    },
    /// [`Progress::advance`].
    Advance(u64),
    /// [`Progress::finish`].
    Finish,
}

impl<F: Fn(Step<'_>) + Sync> Progress for F {
    fn start(&self, name: &str, len: u64) {
        self(Step::Start { name, len })
    }
    fn advance(&self, steps: u64) {
        self(Step::Advance(steps))
    }
    fn finish(&self) {
        self(Step::Finish)
    }
}

/// A [`Progress`] that ignores every report.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _name: &str, _len: u64) {}
    fn advance(&self, _steps: u64) {}
    fn finish(&self) {}
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    /// A closure sees each call as one step, in order, and a stage's advances add up.
    #[test]
    fn a_closure_sees_every_step_in_order() {
        let seen = Mutex::new(Vec::new());
        let record = |step: Step<'_>| seen.lock().unwrap().push(format!("{step:?}"));
        let progress: &dyn Progress = &record;
        progress.start("solve", 4);
        progress.advance(3);
        progress.advance(1);
        progress.finish();
        let seen = seen.into_inner().unwrap();
        assert_eq!(seen, ["Start { name: \"solve\", len: 4 }", "Advance(3)", "Advance(1)", "Finish"]);
        NoProgress.start("ignored", 1);
    }
}
