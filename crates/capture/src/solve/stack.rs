//! [`PhotoStack`]: the photos of one solve, checked to share one size and one format.

use skinkit_maps::{Channels, Grid, Photo, Transfer};

use crate::{Error, Result};

/// Photos taken in rig order, validated to share one size and one sample format.
#[derive(Clone, Debug)]
pub struct PhotoStack {
    pub(super) photos: Vec<Photo>,
    pub(super) names: Vec<String>,
    pub(super) ambient: Option<Photo>,
    pub(super) mask: Option<Grid<bool>>,
}

impl PhotoStack {
    /// Wraps `photos` (in rig order) with display `names` (usually file names) used in messages.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when there are no photos, the name count differs, the photos are
    /// empty, or a photo differs from the first in size, channels, bit depth or transfer curve.
    pub fn new(photos: Vec<Photo>, names: Vec<String>) -> Result<Self> {
        if photos.is_empty() {
            return Err(Error::InvalidInput("no photos were given".into()));
        }
        if names.len() != photos.len() {
            return Err(Error::InvalidInput(format!("{} photos but {} names were given", photos.len(), names.len())));
        }
        if photos[0].pixel_count() == 0 {
            return Err(Error::InvalidInput(format!("photo 1 ({}) has no pixels", names[0])));
        }
        for (i, photo) in photos.iter().enumerate().skip(1) {
            check_same(photo, &format!("photo {} ({})", i + 1, names[i]), &photos[0], &names[0])?;
        }
        Ok(PhotoStack { photos, names, ambient: None, mask: None })
    }

    /// Adds an ambient frame (all rig lights off), subtracted from every photo.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when it differs from the photos in size or format.
    pub fn with_ambient(mut self, ambient: Photo, name: &str) -> Result<Self> {
        check_same(&ambient, &format!("ambient photo ({name})"), &self.photos[0], &self.names[0])?;
        self.ambient = Some(ambient);
        Ok(self)
    }

    /// Restricts the solve to texels where `mask` is true; the others come out invalid.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the mask's size differs from the photos'.
    pub fn with_mask(mut self, mask: Grid<bool>) -> Result<Self> {
        if mask.size() != self.size() {
            return Err(Error::InvalidInput(format!(
                "mask is {}x{} but photo 1 ({}) is {}x{}",
                mask.width(),
                mask.height(),
                self.names[0],
                self.width(),
                self.height()
            )));
        }
        self.mask = Some(mask);
        Ok(self)
    }

    pub fn len(&self) -> usize {
        self.photos.len()
    }
    pub fn is_empty(&self) -> bool {
        self.photos.is_empty()
    }
    pub fn width(&self) -> usize {
        self.photos[0].width()
    }
    pub fn height(&self) -> usize {
        self.photos[0].height()
    }
    /// `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.width(), self.height())
    }
    pub fn channels(&self) -> Channels {
        self.photos[0].channels()
    }
    pub fn photos(&self) -> &[Photo] {
        &self.photos
    }
    pub fn names(&self) -> &[String] {
        &self.names
    }
    pub fn ambient(&self) -> Option<&Photo> {
        self.ambient.as_ref()
    }
    pub fn mask(&self) -> Option<&Grid<bool>> {
        self.mask.as_ref()
    }
}

/// `8-bit rgb srgb`-style description of a photo's format.
pub(super) fn format_of(p: &Photo) -> String {
    let channels = match p.channels() {
        Channels::Gray => "grey",
        Channels::Rgb => "rgb",
    };
    let transfer = match p.transfer() {
        Transfer::Linear => "linear",
        Transfer::Srgb => "srgb",
    };
    format!("{}-bit {channels} {transfer}", p.bit_depth())
}

/// Checks that `photo` (described by `what`) matches the first photo in size and format.
pub(super) fn check_same(photo: &Photo, what: &str, first: &Photo, first_name: &str) -> Result<()> {
    if (photo.width(), photo.height()) != (first.width(), first.height()) {
        return Err(Error::InvalidInput(format!(
            "{what} is {}x{} but photo 1 ({first_name}) is {}x{}",
            photo.width(),
            photo.height(),
            first.width(),
            first.height()
        )));
    }
    let (a, b) = (format_of(photo), format_of(first));
    if a != b {
        return Err(Error::InvalidInput(format!(
            "{what} is {a} but photo 1 ({first_name}) is {b}; convert the photos to one format"
        )));
    }
    Ok(())
}
