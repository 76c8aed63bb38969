//! The error type of the `heightfield` crate, grouped by who is at fault.

/// Errors from building skin parameters, generating fields and rendering them.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter the caller got wrong; `field` names it as the caller spelled it.
    #[error("{field}: {reason}")]
    InvalidParameter { field: String, reason: String },
    /// A request larger than the crate's allocation limits.
    #[error("{what}: {requested} exceeds the limit of {limit}")]
    TooLarge { what: String, requested: u64, limit: u64 },
    /// A map or photo could not be built.
    #[error(transparent)]
    Maps(#[from] skinkit_maps::Error),
}

/// Result alias for the `heightfield` crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub(crate) fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Error::InvalidParameter { field: field.into(), reason: reason.into() }
    }
}
