//! The error type of the `maps` crate, grouped by who is at fault.

use std::path::PathBuf;

/// Errors from map construction and image IO.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file exists but is not a valid image of a supported format.
    #[error("{path}: not a readable image: {reason}")]
    Decode { path: PathBuf, reason: String },
    /// A valid image in a layout skinkit does not handle.
    #[error("{path}: unsupported image: {reason}")]
    Unsupported { path: PathBuf, reason: String },
    /// A parameter or data layout the caller got wrong.
    #[error("{0}")]
    InvalidParameter(String),
    /// An image larger than the configured [`crate::Limits`].
    #[error("{path}: {width}x{height} exceeds the limit of {max_pixels} pixels")]
    TooLarge { path: PathBuf, width: u64, height: u64, max_pixels: u64 },
    /// A job whose estimated memory, worked out from headers and sizes before anything is
    /// allocated, exceeds the memory limit ([`crate::limits`]).
    #[error(
        "{subject}: {what} needs an estimated {} MiB, over the memory limit of {} MiB (--memory-limit)",
        crate::limits::mib(*estimate),
        limit >> 20
    )]
    OverBudget { subject: String, what: String, estimate: u64, limit: u64 },
    /// Encoding an image failed.
    #[error("{path}: cannot encode: {reason}")]
    Encode { path: PathBuf, reason: String },
    /// The input gate refused a file ([`crate::input`]).
    #[error(transparent)]
    Input(#[from] crate::input::InputError),
    /// Reading or writing a file failed.
    #[error("{path}: {error}")]
    Io { path: PathBuf, error: std::io::Error },
}

/// Result alias for the `maps` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), error: source }
    }
    pub(crate) fn decode(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Error::Decode { path: path.into(), reason: reason.to_string() }
    }
}
