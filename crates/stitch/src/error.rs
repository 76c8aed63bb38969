//! The error type of the `stitch` crate: every message names the file, field or values at fault.
//!
//! Grouped by who is at fault: a layout file that does not parse or does not make sense
//! ([`Error::Toml`], [`Error::Layout`], [`Error::CoincidentPoints`]), a layout naming a file that
//! is not there ([`Error::MissingExemplar`], [`Error::Io`]), a caller passing bad parameters
//! ([`Error::InvalidParameter`]), and errors passed through from `maps` and `synth`.

use std::path::PathBuf;

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
    /// Pieces the spline cannot blend.
    #[error(transparent)]
    Spline(#[from] crate::spline::SplineError),
    /// A seam measurement that cannot be made.
    #[error(transparent)]
    Seam(#[from] crate::seam::SeamError),
    /// A layout file that is not valid TOML or does not match the layout's keys.
    #[error("{}: {message}", origin.display())]
    Toml { origin: PathBuf, message: String },
    /// A layout whose values do not make sense: `field` names the key (with its region).
    #[error("{}: {field}: {message}", origin.display())]
    Layout { origin: PathBuf, field: String, message: String },
    /// Two seed points on the same texel: the nearest-point partition cannot separate them.
    #[error(
        "{}: region `{first}` point {first_point} and region `{second}` point {second_point} fall on the same texel ({x}, {y}) of the {width}x{height} map",
        origin.display()
    )]
    CoincidentPoints {
        origin: PathBuf,
        first: String,
        first_point: usize,
        second: String,
        second_point: usize,
        x: u32,
        y: u32,
        width: usize,
        height: usize,
    },
    /// A region's exemplar (normal map or capture session) is not where the layout says.
    #[error("{}: region `{region}`: {what} {} does not exist", origin.display(), path.display())]
    MissingExemplar { origin: PathBuf, region: String, what: &'static str, path: PathBuf },
    /// A region's exemplar could not be read, or its session could not be captured.
    #[error("{}: region `{region}`: {what}", origin.display())]
    Exemplar {
        origin: PathBuf,
        region: String,
        what: String,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// Integrating a face's height failed.
    #[error("cannot integrate the face's normals")]
    Height(#[source] skinkit_height::Error),
    /// Writing one of a face's files failed: `role` says which (`the label map`), in the
    /// user's words; `source` names the path.
    #[error("cannot write {role}")]
    Write {
        role: String,
        #[source]
        source: skinkit_maps::Error,
    },
    /// Reading a file failed.
    #[error("{}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },
    /// A parameter the caller got wrong (curve parameters, seed points, sizes, ...).
    #[error("{0}")]
    InvalidParameter(String),
}

/// Result alias for the `stitch` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
