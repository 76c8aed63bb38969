//! The error type of the `capture` crate, grouped by who is at fault.

use std::path::PathBuf;

/// Errors from rigs, calibration and solving.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A rig or light file that cannot be parsed or has an invalid field. `location` names the
    /// file and, where known, the light or line (`rig.toml: light 5`).
    #[error("{location}: {reason}")]
    BadFile { location: String, reason: String },
    /// A rig whose lights cannot determine a normal (coplanar, rank-deficient, too few).
    #[error("{0}")]
    BadRig(String),
    /// Inputs that do not fit together (photo count, sizes) or a parameter out of range.
    #[error("{0}")]
    InvalidInput(String),
    /// A calibration that could not find what it looks for (no sphere, no highlight).
    #[error("{0}")]
    Calibration(String),
    /// Image IO, from the `maps` crate.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
    /// What was being done or read (`photo 3`, `rig a.toml`) when `cause` happened; the cause
    /// is its `source()`, so a printed chain reads `context: cause`.
    #[error("{context}")]
    Context {
        context: String,
        #[source]
        cause: Box<Error>,
    },
    /// Reading or writing a file failed.
    #[error("{path}")]
    Io {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },
}

/// Result alias for the `capture` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
