//! The image formats skinkit meets, recognised from a file name in one place.
//!
//! Every stage that reads or writes an image by name (photos, maps, heights, tables, renders, a
//! face folder) asks [`ImageFormat::of`] what the name says rather than comparing extension
//! strings; what the bytes hold is checked against it when the file is read (`signature`).

use std::path::Path;

/// File extensions read as camera RAW.
pub const RAW_EXTENSIONS: &[&str] = &[
    "dng", "cr2", "nef", "nrw", "arw", "srf", "sr2", "orf", "rw2", "pef", "srw", "erf", "kdc", "dcr", "mef", "mrw",
    "3fr",
];

/// An image format, as a file's extension names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageFormat {
    /// `.png`: 8- or 16-bit integer samples.
    Png,
    /// `.exr`: OpenEXR, float samples.
    Exr,
    /// `.tif` or `.tiff`.
    Tiff,
    /// `.jpg` or `.jpeg`: recognised so it can be refused (lossy, sRGB-encoded).
    Jpeg,
    /// Camera RAW ([`RAW_EXTENSIONS`]).
    Raw,
}

impl ImageFormat {
    /// The format `path`'s extension names (any case), if it names one.
    pub fn of(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFormat::Png),
            "exr" => Some(ImageFormat::Exr),
            "tif" | "tiff" => Some(ImageFormat::Tiff),
            "jpg" | "jpeg" => Some(ImageFormat::Jpeg),
            raw if RAW_EXTENSIONS.contains(&raw) => Some(ImageFormat::Raw),
            _ => None,
        }
    }

    /// Whether `path`'s extension names one of `formats`.
    pub fn is_one_of(path: &Path, formats: &[ImageFormat]) -> bool {
        ImageFormat::of(path).is_some_and(|f| formats.contains(&f))
    }

    /// The extension skinkit writes for this format (without the dot; `dng` for RAW, which
    /// skinkit reads only).
    pub fn extension(self) -> &'static str {
        match self {
            ImageFormat::Png => "png",
            ImageFormat::Exr => "exr",
            ImageFormat::Tiff => "tif",
            ImageFormat::Jpeg => "jpg",
            ImageFormat::Raw => "dng",
        }
    }

    /// The format's name in messages: `PNG`, `EXR`, `TIFF`, `JPEG`, `camera RAW`.
    pub fn name(self) -> &'static str {
        match self {
            ImageFormat::Png => "PNG",
            ImageFormat::Exr => "EXR",
            ImageFormat::Tiff => "TIFF",
            ImageFormat::Jpeg => "JPEG",
            ImageFormat::Raw => "camera RAW",
        }
    }

    /// Whether a capture session reads files of this format as photos (linear PNG, TIFF, EXR or
    /// RAW; JPEG is refused when read, not skipped).
    pub fn is_photo(self) -> bool {
        !matches!(self, ImageFormat::Jpeg)
    }

    /// `formats` as a message lists their extensions: `.png or .exr`.
    pub fn extensions(formats: &[ImageFormat]) -> String {
        let names: Vec<String> = formats.iter().map(|f| format!(".{}", f.extension())).collect();
        names.join(" or ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_case_of_every_extension_names_its_format() {
        let cases = [
            ("a.png", Some(ImageFormat::Png)),
            ("a.PNG", Some(ImageFormat::Png)),
            ("b.exr", Some(ImageFormat::Exr)),
            ("c.tif", Some(ImageFormat::Tiff)),
            ("c.TIFF", Some(ImageFormat::Tiff)),
            ("d.JPEG", Some(ImageFormat::Jpeg)),
            ("e.Cr2", Some(ImageFormat::Raw)),
            ("f.txt", None),
            ("no-extension", None),
            ("dir.png/file", None),
        ];
        for (name, want) in cases {
            assert_eq!(ImageFormat::of(Path::new(name)), want, "{name}");
        }
        for ext in RAW_EXTENSIONS {
            assert_eq!(ImageFormat::of(Path::new(&format!("x.{}", ext.to_uppercase()))), Some(ImageFormat::Raw));
        }
    }

    #[test]
    fn the_written_extension_reads_back_as_its_format() {
        for f in [ImageFormat::Png, ImageFormat::Exr, ImageFormat::Tiff, ImageFormat::Jpeg, ImageFormat::Raw] {
            assert_eq!(ImageFormat::of(Path::new(&format!("x.{}", f.extension()))), Some(f));
        }
        assert_eq!(ImageFormat::extensions(&[ImageFormat::Png, ImageFormat::Exr]), ".png or .exr");
        assert!(ImageFormat::is_one_of(Path::new("m.EXR"), &[ImageFormat::Png, ImageFormat::Exr]));
        assert!(!ImageFormat::is_one_of(Path::new("m.tif"), &[ImageFormat::Png, ImageFormat::Exr]));
    }
}
