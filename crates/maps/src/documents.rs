//! Text documents beside the maps (reports, records, pages), written atomically like them: a
//! reader sees the old file or the whole new one, never a part.

use std::io::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::io::write_atomic;
use crate::{Error, Result};

/// Writes `value` as pretty-printed JSON (UTF-8) at `path`.
pub fn write_json<T: Serialize + ?Sized>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Encode { path: path.to_owned(), reason: format!("cannot encode as JSON: {e}") })?;
    write_text(path, &text)
}

/// Writes `text` (UTF-8) at `path`.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| w.write_all(text.as_bytes()).map_err(|error| Error::Io { path: path.to_owned(), error }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_document_is_written_whole_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("report.json");
        write_json(&path, &serde_json::json!({"a": 1, "b": [1.5, 2.0]})).unwrap();
        let back: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        assert_eq!(back["b"][0], 1.5);
        write_text(&path, "replaced").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "replaced");
        let e = write_text(&dir.path().join("missing/x.txt"), "x").unwrap_err().to_string();
        assert!(e.contains("missing"), "{e}");
    }
}
