//! The height crate's errors, grouped by who is at fault.

use thiserror::Error;

/// What can go wrong integrating a normal map or writing its deliverables.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum Error {
    /// Every texel's normal is invalid (zero, NaN or facing away): there is nothing to integrate.
    #[error("no texel of the {texels} has a usable normal (all zero, NaN or facing away): no height to integrate")]
    NoValidTexel { texels: usize },
    /// A parameter is out of its range.
    #[error("{0}")]
    Parameter(String),
    /// Reading or writing a map failed.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, Error>;

/// A height error as the `maps` crate's, which output sets carry: its own `maps` error where it
/// has one, else its message.
impl From<Error> for skinkit_maps::Error {
    fn from(e: Error) -> Self {
        match e {
            Error::Maps(e) => e,
            other => skinkit_maps::Error::InvalidParameter(other.to_string()),
        }
    }
}
