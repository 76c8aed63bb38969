//! Errors of an accuracy run, grouped by the stage library that refused.

/// What went wrong.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A sample input is missing or unreadable.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
    /// Synthetic molds could not be generated or photographed.
    #[error(transparent)]
    Heightfield(#[from] skinkit_heightfield::Error),
    /// The capture library refused a rig or a solve.
    #[error(transparent)]
    Capture(#[from] skinkit_capture::Error),
    /// The synthesis library refused a configuration.
    #[error(transparent)]
    Synth(#[from] skinkit_synth::Error),
    /// The stitching library refused a layout or its options.
    #[error(transparent)]
    Stitch(#[from] skinkit_stitch::Error),
    /// The height library refused a map.
    #[error(transparent)]
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
