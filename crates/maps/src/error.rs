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

/// The error and its causes on one line, each cause once (issue 15, D10). Two rules:
/// - a cause whose text the line already holds is skipped (a library error that embeds its
///   source's text, as every skinkit error does, repeats nothing);
/// - a cause that opens with what the line ends with drops that opening, so a context naming a
///   file (`cannot write a.png`) and a library error naming it again (`a.png: Is a directory`)
///   read `cannot write a.png: Is a directory`.
pub fn one_line(error: &(dyn std::error::Error + 'static)) -> String {
    let mut line = String::new();
    let mut cause = Some(error);
    while let Some(e) = cause {
        join_cause(&mut line, &e.to_string());
        cause = e.source();
    }
    line
}

/// Appends `cause` to `line` under the rules of [`one_line`].
fn join_cause(line: &mut String, cause: &str) {
    if cause.is_empty() || line.contains(cause) {
        return;
    }
    let rest = match cause.split_once(": ") {
        Some((head, rest)) if ends_with_word(line, head) => rest,
        _ => cause,
    };
    if line.contains(rest) {
        return;
    }
    if !line.is_empty() {
        line.push_str(": ");
    }
    line.push_str(rest);
}

/// `line` ends with `word` as a whole word (after a space, a quote or bracket, or as all of it).
fn ends_with_word(line: &str, word: &str) -> bool {
    match line.strip_suffix(word) {
        Some(before) => !line.is_empty() && before.chars().last().is_none_or(|c| " ([`'\"".contains(c)),
        None => false,
    }
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
}
