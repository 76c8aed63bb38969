//! The output gate for names that come from data (a layout's region, a session folder, a
//! subject): such a name becomes part of an output path only as one plain path component, so no
//! name can reach outside the output folder, onto another output, or onto an input.

use std::ffi::OsStr;

/// Why a name cannot be a file name.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    #[error("`{0}` is not valid UTF-8")]
    NotUtf8(String),
    #[error("a name must not be empty")]
    Empty,
    #[error("`{0}` holds a path separator (`/` or `\\`): a name is one plain file name")]
    Separator(String),
    #[error("`{0}` starts with `.` (`.`, `..` and hidden names are refused)")]
    LeadingDot(String),
    #[error("`{0}` holds a control character")]
    Control(String),
    #[error("`{0}` is longer than {MAX_NAME_BYTES} bytes")]
    TooLong(String),
}

/// Longest name accepted, in bytes (with room for an extension under the usual 255-byte limit).
pub const MAX_NAME_BYTES: usize = 200;

/// `name` as one plain path component: valid UTF-8, not empty, no `/` or `\`, not starting with
/// `.`, no control character (NUL included), at most [`MAX_NAME_BYTES`].
///
/// # Errors
/// Says which rule the name breaks, quoting it (lossily, with escapes, when it is not UTF-8).
pub fn file_component(name: &OsStr) -> Result<&str, NameError> {
    let Some(text) = name.to_str() else {
        return Err(NameError::NotUtf8(name.to_string_lossy().escape_debug().to_string()));
    };
    check(text)?;
    Ok(text)
}

/// The same checks on a name that is already text (a region's name in a layout).
///
/// # Errors
/// As [`file_component`].
pub fn check(name: &str) -> Result<(), NameError> {
    let quoted = || name.escape_debug().to_string();
    if name.is_empty() {
        Err(NameError::Empty)
    } else if name.contains(['/', '\\']) {
        Err(NameError::Separator(quoted()))
    } else if name.starts_with('.') {
        Err(NameError::LeadingDot(quoted()))
    } else if name.chars().any(char::is_control) {
        Err(NameError::Control(quoted()))
    } else if name.len() > MAX_NAME_BYTES {
        Err(NameError::TooLong(format!("{}...", name.chars().take(24).collect::<String>())))
    } else {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_pass_and_paths_do_not() {
        for ok in ["cheek", "Patient-Müller", "forehead left", "a.b", "x..y"] {
            assert_eq!(check(ok), Ok(()), "{ok}");
        }
        for (bad, why) in [
            ("", NameError::Empty),
            ("../cheek", NameError::Separator("../cheek".into())),
            ("a/b", NameError::Separator("a/b".into())),
            ("a\\b", NameError::Separator("a\\\\b".into())),
            ("..", NameError::LeadingDot("..".into())),
            (".hidden", NameError::LeadingDot(".hidden".into())),
            ("nul\0", NameError::Control("nul\\0".into())),
        ] {
            assert_eq!(check(bad), Err(why), "{bad:?}");
        }
        assert!(matches!(check(&"x".repeat(201)), Err(NameError::TooLong(_))));
    }

    #[cfg(unix)]
    #[test]
    fn names_that_are_not_utf8_are_refused_not_mangled() {
        use std::os::unix::ffi::OsStrExt;
        let latin1 = OsStr::from_bytes(b"Patient-M\xfcller");
        let err = file_component(latin1).unwrap_err();
        assert!(matches!(&err, NameError::NotUtf8(s) if s.contains("Patient-M")), "{err}");
        assert_eq!(file_component(OsStr::new("ann")), Ok("ann"));
    }
}
