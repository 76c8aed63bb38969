//! The input gate: every file skinkit reads is opened here (issue 42, D9 and D10).
//!
//! [`open`] refuses what is not a regular file (a FIFO, a device, a folder, a socket) and a
//! file longer than its [`Kind`]'s limit, from the file's metadata, before a byte is read. The
//! metadata is looked at twice: by path before opening, so a device or a FIFO is never opened
//! at all, and on the opened file itself, so a file swapped in between the two cannot slip
//! through. The file is opened without blocking (`O_NONBLOCK`), so a FIFO swapped in after the
//! first look is refused by the second rather than hanging in `open`. Callers read from the
//! [`File`] they are given and never open the path again; [`read`] and [`read_to_string`] also
//! stop at the limit, so a file that grows after the check is refused, not read without end.
//!
//! Files that describe the machine rather than the job (`/proc/meminfo`, `/proc/self/status`,
//! the CPU's name) are not inputs and are read directly.
//!
//! | kind | limit |
//! | --- | --- |
//! | [`Kind::Image`]: photo, mask, ambient, truth, exemplar, normal or coordinate map | [`MAX_IMAGE_BYTES`] |
//! | [`Kind::RawPhoto`]: camera RAW photo | [`MAX_RAW_BYTES`] |
//! | [`Kind::Mesh`]: OBJ, glTF or GLB file | [`MAX_MESH_BYTES`] |
//! | [`Kind::GltfBuffer`]: a glTF file's external buffer | [`MAX_MESH_BYTES`] |
//! | [`Kind::Toml`]: rig, scene, layout | [`MAX_TEXT_BYTES`] |
//! | [`Kind::LightFile`]: a light file `rig import` reads | [`MAX_TEXT_BYTES`] |
//! | [`Kind::Listing`]: a session's `filenames.txt` | [`MAX_TEXT_BYTES`] |
//! | [`Kind::Report`]: a report read back (batch shards, resume records) | [`MAX_REPORT_BYTES`] |
//! | [`Kind::SkinTable`]: a skin table (`lut` output) | [`MAX_SKIN_TABLE_BYTES`] |

use std::fs::{File, Metadata};
use std::io::Read;
use std::path::{Path, PathBuf};

use crate::limits::MAX_IMAGE_PIXELS;

/// Longest image file: four float channels at the pixel limit
/// ([`crate::limits::MAX_IMAGE_PIXELS`], 4 GiB) and 64 MiB for metadata and padding.
pub const MAX_IMAGE_BYTES: u64 = MAX_IMAGE_PIXELS * 16 + (64 << 20);
/// Longest camera RAW file: four bytes a sensor pixel at the pixel limit and 256 MiB for previews
/// and metadata ([`crate::raw`] also checks the configured pixel limit).
pub const MAX_RAW_BYTES: u64 = MAX_IMAGE_PIXELS * 4 + (256 << 20);
/// Longest mesh file or glTF buffer: 1 GiB (an OBJ of some ten million triangles).
pub const MAX_MESH_BYTES: u64 = 1 << 30;
/// Longest text input (rig, scene, layout, light file, photo listing): 16 MiB. A rig of the
/// 128-light limit takes some 20 KB; the TOML parser needs several times a file's length.
pub const MAX_TEXT_BYTES: u64 = 16 << 20;
/// Longest report read back: 256 MiB (a batch report of a hundred thousand sessions).
pub const MAX_REPORT_BYTES: u64 = 256 << 20;
/// Longest skin table: 512 MiB (four float channels of the largest table, 4096 x 4096).
pub const MAX_SKIN_TABLE_BYTES: u64 = 512 << 20;

/// What a file is read as; each kind has its own byte limit ([`Kind::limit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Kind {
    /// A PNG, TIFF or EXR image: photo, mask, ambient or truth frame, exemplar, normal or
    /// coordinate map.
    Image,
    /// A camera RAW photo.
    RawPhoto,
    /// An OBJ, glTF or GLB mesh.
    Mesh,
    /// An external buffer of a glTF file.
    GltfBuffer,
    /// A TOML file: rig, scene or layout.
    Toml,
    /// A light file that `rig import` reads (DiLiGenT, UW).
    LightFile,
    /// A session's photo listing, `filenames.txt`.
    Listing,
    /// A JSON report read back (batch shards, what a session's outputs were made from).
    Report,
    /// A skin table written by `skinkit lut`.
    SkinTable,
}

impl Kind {
    /// The longest file of this kind, in bytes.
    pub const fn limit(self) -> u64 {
        match self {
            Kind::Image => MAX_IMAGE_BYTES,
            Kind::RawPhoto => MAX_RAW_BYTES,
            Kind::Mesh | Kind::GltfBuffer => MAX_MESH_BYTES,
            Kind::Toml | Kind::LightFile | Kind::Listing => MAX_TEXT_BYTES,
            Kind::Report => MAX_REPORT_BYTES,
            Kind::SkinTable => MAX_SKIN_TABLE_BYTES,
        }
    }

    /// The kind as messages name it (`an image`, `a TOML file`).
    pub const fn name(self) -> &'static str {
        match self {
            Kind::Image => "an image",
            Kind::RawPhoto => "a camera RAW photo",
            Kind::Mesh => "a mesh",
            Kind::GltfBuffer => "a glTF buffer",
            Kind::Toml => "a TOML file",
            Kind::LightFile => "a light file",
            Kind::Listing => "a photo listing",
            Kind::Report => "a report",
            Kind::SkinTable => "a skin table",
        }
    }
}

/// Why the gate refused a file; every message names the file, and the limit where one applies.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InputError {
    /// A FIFO, device, folder or socket where a regular file is read.
    #[error("{path}: {what}, not a regular file ({} is read only from a regular file)", kind.name())]
    NotAFile { path: PathBuf, kind: Kind, what: &'static str },
    /// A file longer than its kind's limit.
    #[error(
        "{path}: {len} bytes is over the limit for {} of {} MiB",
        kind.name(),
        crate::limits::mib(kind.limit())
    )]
    TooLarge { path: PathBuf, kind: Kind, len: u64 },
    /// The file cannot be looked at, opened or read.
    #[error("{path}")]
    Io {
        path: PathBuf,
        #[source]
        error: std::io::Error,
    },
}

impl InputError {
    /// The file the error names.
    pub fn path(&self) -> &Path {
        match self {
            InputError::NotAFile { path, .. } | InputError::TooLarge { path, .. } | InputError::Io { path, .. } => path,
        }
    }
}

/// Opens `path` to be read as `kind`, after checking that it is a regular file of at most
/// [`Kind::limit`] bytes (see the module docs for how a swap is caught).
///
/// # Errors
/// [`InputError::NotAFile`], [`InputError::TooLarge`], or [`InputError::Io`] when the file is
/// missing or cannot be opened.
pub fn open(path: &Path, kind: Kind) -> Result<File, InputError> {
    let io = |error| InputError::Io { path: path.to_owned(), error };
    let before = std::fs::metadata(path).map_err(io)?;
    check(path, kind, &before)?;
    let file = open_nonblocking(path).map_err(io)?;
    let after = file.metadata().map_err(io)?;
    check(path, kind, &after)?;
    if !same_file(&before, &after) {
        let error = std::io::Error::other("the file was replaced while it was opened");
        return Err(InputError::Io { path: path.to_owned(), error });
    }
    Ok(file)
}

/// The metadata of `path` when it is a regular file within `kind`'s limit, looked at without
/// opening it: for listings that decide which entries of a folder to take (a FIFO among the
/// photos is named and skipped rather than opened).
///
/// # Errors
/// As [`open`].
pub fn look(path: &Path, kind: Kind) -> Result<Metadata, InputError> {
    let meta = std::fs::metadata(path).map_err(|error| InputError::Io { path: path.to_owned(), error })?;
    check(path, kind, &meta)?;
    Ok(meta)
}

/// The whole file, read through [`open`] and never past the kind's limit.
///
/// # Errors
/// As [`open`], and [`InputError::TooLarge`] when the file grew past the limit while read.
pub fn read(path: &Path, kind: Kind) -> Result<Vec<u8>, InputError> {
    let file = open(path, kind)?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut bytes = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    file.take(kind.limit() + 1)
        .read_to_end(&mut bytes)
        .map_err(|error| InputError::Io { path: path.to_owned(), error })?;
    if bytes.len() as u64 > kind.limit() {
        return Err(InputError::TooLarge { path: path.to_owned(), kind, len: bytes.len() as u64 });
    }
    Ok(bytes)
}

/// The whole file as UTF-8 text, read as [`read`] does.
///
/// # Errors
/// As [`read`], and [`InputError::Io`] (`InvalidData`, the words of `std::fs::read_to_string`)
/// when the text is not UTF-8.
pub fn read_to_string(path: &Path, kind: Kind) -> Result<String, InputError> {
    String::from_utf8(read(path, kind)?).map_err(|_| InputError::Io {
        path: path.to_owned(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidData, "stream did not contain valid UTF-8"),
    })
}

/// Refuses what is not a regular file, or is longer than the kind's limit.
fn check(path: &Path, kind: Kind, meta: &Metadata) -> Result<(), InputError> {
    if !meta.is_file() {
        return Err(InputError::NotAFile { path: path.to_owned(), kind, what: describe(meta) });
    }
    if meta.len() > kind.limit() {
        return Err(InputError::TooLarge { path: path.to_owned(), kind, len: meta.len() });
    }
    Ok(())
}

/// What a file that is not regular is, in a user's words.
fn describe(meta: &Metadata) -> &'static str {
    let kind = meta.file_type();
    if kind.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO (named pipe)";
        } else if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        } else if kind.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// Opens for reading without blocking on a FIFO (`O_NONBLOCK`; no effect on a regular file's reads).
fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    options.open(path)
}

/// Whether two metadata describe one file (device and inode on Unix).
fn same_file(a: &Metadata, b: &Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        a.dev() == b.dev() && a.ino() == b.ino()
    }
    #[cfg(not(unix))]
    {
        a.len() == b.len()
    }
}

#[cfg(test)]
mod tests;
