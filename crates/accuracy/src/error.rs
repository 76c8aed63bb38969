//! Errors of an accuracy run, grouped by the stage library that refused.

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A sample input is missing or unreadable.
    #[error("{0}")]
    Maps(#[from] skinkit_maps::Error),
    /// Synthetic molds could not be generated or photographed.
    #[error("{0}")]
    Heightfield(#[from] skinkit_heightfield::Error),
    /// The capture library refused a rig or a solve.
    #[error("{0}")]
    Capture(#[from] skinkit_capture::Error),
    /// The synthesis library refused a configuration.
    #[error("{0}")]
    Synth(#[from] skinkit_synth::Error),
    /// The stitching library refused a layout or its options.
    #[error("{0}")]
    Stitch(#[from] skinkit_stitch::Error),
    /// The height library refused a map.
    #[error("{0}")]
    Height(#[from] skinkit_height::Error),
    /// A scene could not be loaded or drawn (an adapter was found).
    #[error("rendering: {0}")]
    Render(String),
    /// A plot could not be drawn.
    #[error("plot of {stage}: {message}")]
    Plot { stage: String, message: String },
}

/// Result of this crate.
pub type Result<T> = std::result::Result<T, Error>;
