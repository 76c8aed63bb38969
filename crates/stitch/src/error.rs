//! The error type of the `stitch` crate: every message names the file, field or values at fault.

/// Errors from layouts, partitions and blending.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An error from the `maps` crate.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
    /// An error from the `synth` crate.
    #[error(transparent)]
    Synth(#[from] skinkit_synth::Error),
}

/// Result alias for the `stitch` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
