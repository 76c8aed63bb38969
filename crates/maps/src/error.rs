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
    /// An output file whose folder could not be made ready: `path` is the output, `source`
    /// what failed there (which names the folder).
    #[error("{path}")]
    Output {
        path: PathBuf,
        #[source]
        source: Box<Error>,
    },
    /// Reading or writing a file failed.
    #[error("{path}")]
    Io {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },
}

/// Result alias for the `maps` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), error: source }
    }
    /// `self`, met while making the folder of the output `path` ready.
    pub(crate) fn for_output(self, path: impl Into<PathBuf>) -> Self {
        Error::Output { path: path.into(), source: Box::new(self) }
    }
    pub(crate) fn decode(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        Error::Decode { path: path.into(), reason: reason.to_string() }
    }

    /// An `image` crate refusal in the book's words (issue 42, D16): what the decoder cannot
    /// handle becomes the list of layouts skinkit reads, and the decoder's own memory limit is
    /// told apart from `--memory-limit`, never a Debug dump of the decoder's types.
    pub(crate) fn image(path: &std::path::Path, error: image::ImageError) -> Self {
        use image::ImageError as E;
        match error {
            E::Unsupported(_) => Error::Unsupported { path: path.to_owned(), reason: LAYOUTS_READ.to_owned() },
            E::Limits(_) => Error::decode(
                path,
                "the image decoder's own limit refuses it (a metadata chunk or a strip too large to \
                 read; --memory-limit does not change it): re-export the image without it",
            ),
            E::IoError(e) => Error::io(path, e),
            other => Error::decode(path, other),
        }
    }
}

/// The pixel layouts image files may have, as the book's formats table gives them.
pub(crate) const LAYOUTS_READ: &str = "its pixel layout is not one skinkit reads: PNG or TIFF of 8 or 16 bits \
     a sample, grey or RGB (alpha ignored), or float EXR with R, G and B channels";

/// The error and its causes on one line (issue 15, D10; issue 38): each error's `Display` says
/// only its own part (what was being done, the file, the field) and its cause is its
/// `source()`, so walking the chain and joining the parts with `: ` says each cause once.
///
/// ```
/// use skinkit_maps::error::one_line;
/// let io = std::io::Error::other("disk full");
/// let e = skinkit_maps::Error::Io { path: "a.png".into(), error: io };
/// assert_eq!(one_line(&e), "a.png: disk full");
/// ```
pub fn one_line(error: &(dyn std::error::Error + 'static)) -> String {
    let mut line = error.to_string();
    let mut cause = error.source();
    while let Some(e) = cause {
        line.push_str(": ");
        line.push_str(&e.to_string());
        cause = e.source();
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::error::{LimitError, LimitErrorKind};

    /// Issue 42, D16: the decoder's own memory limit (a PNG with a 256 MiB text chunk) is told
    /// apart from `--memory-limit`, not shown as a bare "Memory limit exceeded".
    #[test]
    fn probe2_d16_the_decoders_own_limit_is_not_mistaken_for_the_memory_limit() {
        let limit = image::ImageError::Limits(LimitError::from_kind(LimitErrorKind::InsufficientMemory));
        let e = Error::image(std::path::Path::new("03.png"), limit).to_string();
        assert!(e.starts_with("03.png: not a readable image: the image decoder's own limit"), "{e}");
        assert!(e.contains("--memory-limit does not change it"), "{e}");
    }

    /// A cause at each level: an error naming what was being done, a `maps` error naming the
    /// file, and the OS error. Each part is said once, in order, joined with `: `.
    #[test]
    fn one_line_joins_a_three_level_chain_in_order() {
        #[derive(Debug, thiserror::Error)]
        #[error("photo 3")]
        struct Reading(#[source] Error);
        let os = std::io::Error::new(std::io::ErrorKind::PermissionDenied, "permission denied");
        let e = Reading(Error::io("cheek/03.png", os));
        assert_eq!(one_line(&e), "photo 3: cheek/03.png: permission denied");
        // A transparent wrapper adds no part of its own.
        let os = std::io::Error::new(std::io::ErrorKind::NotFound, "gone");
        let wrapped = Error::Input(crate::input::InputError::Io { path: "rig.toml".into(), error: os });
        assert_eq!(one_line(&wrapped), "rig.toml: gone");
    }
}
