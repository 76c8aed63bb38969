//! The error type of the `synth` crate: every message names the offending values.

/// Errors from synthesis and coordinate replay.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The exemplar cannot hold a single full neighbourhood.
    #[error("exemplar {width}x{height} is smaller than the {n}x{n} neighbourhood")]
    ExemplarTooSmall { width: usize, height: usize, n: usize },
    /// A normal-map exemplar in which every texel is the invalid marker: nothing to copy.
    #[error(
        "the {width}x{height} exemplar has no valid normal (every texel is zero or non-finite): there is nothing to synthesise from"
    )]
    NoValidNormals { width: usize, height: usize },
    /// A [`crate::SynthConfig`] field out of range.
    #[error("synthesis option {field} = {value}: {reason}")]
    InvalidConfig { field: &'static str, value: String, reason: String },
    /// A run whose estimated working memory exceeds [`crate::SynthConfig::memory_limit`].
    #[error("synthesising {width}x{height} needs an estimated {estimate_mib} MiB, over the limit of {limit_mib} MiB")]
    TooLarge { width: usize, height: usize, estimate_mib: u64, limit_mib: u64 },
    /// A coordinate map that points outside the map it is replayed on.
    #[error(
        "coordinate map entry ({x}, {y}) at output texel ({col}, {row}) lies outside the {width}x{height} map being replayed"
    )]
    CoordsOutside { x: u32, y: u32, col: usize, row: usize, width: usize, height: usize },
    /// A streamed output that could not be written ([`crate::deliver`]); `source` names the
    /// file (the target, never the attempt's file beside it).
    #[error("cannot write {output}")]
    Write {
        output: Output,
        #[source]
        source: skinkit_maps::Error,
    },
    /// An error from the `maps` crate.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
}

/// Which of a growth's files a [`Error::Write`] ([`crate::deliver`]) is about; shown as the output's role.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    NormalMap,
    ColourImage,
    CoordinateMap,
}

impl std::fmt::Display for Output {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Output::NormalMap => "the normal map",
            Output::ColourImage => "the colour image",
            Output::CoordinateMap => "the coordinate map",
        })
    }
}

/// Result alias for the `synth` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn config(field: &'static str, value: impl ToString, reason: impl ToString) -> Self {
        Error::InvalidConfig { field, value: value.to_string(), reason: reason.to_string() }
    }
}
