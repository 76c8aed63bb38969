//! [`Photo`]: a decoded photograph in its native sample type.
//!
//! Photometric stereo reads every sample of several large photos once, so photos stay as `u8` or
//! `u16` (half or a quarter of the memory of `f32`) and are turned into linear values inside the
//! solver, where the conversion folds into the per-light scale.

use crate::{Error, Result};

/// Grey or RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channels {
    Gray,
    Rgb,
}

impl Channels {
    pub fn count(self) -> usize {
        match self {
            Channels::Gray => 1,
            Channels::Rgb => 3,
        }
    }
}

/// How stored sample values relate to linear radiance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Transfer {
    /// Values are proportional to radiance (raw, 16-bit scientific captures, float).
    #[default]
    Linear,
    /// Values carry the sRGB curve (most 8-bit camera JPEG/PNG output).
    Srgb,
}

/// Interleaved samples in their native type.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    U8(Vec<u8>),
    U16(Vec<u16>),
    F32(Vec<f32>),
}

impl Samples {
    pub fn len(&self) -> usize {
        match self {
            Samples::U8(v) => v.len(),
            Samples::U16(v) => v.len(),
            Samples::F32(v) => v.len(),
        }
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Bits per stored sample (8, 16 or 32).
    pub fn bit_depth(&self) -> u32 {
        match self {
            Samples::U8(_) => 8,
            Samples::U16(_) => 16,
            Samples::F32(_) => 32,
        }
    }
    /// The stored value that means full scale: 255, 65535, or 1.0 for float.
    pub fn full_scale(&self) -> f32 {
        match self {
            Samples::U8(_) => 255.0,
            Samples::U16(_) => 65535.0,
            Samples::F32(_) => 1.0,
        }
    }
    /// Sample `i` as a float in stored units (not divided by full scale).
    #[inline]
    pub fn get(&self, i: usize) -> f32 {
        match self {
            Samples::U8(v) => v[i] as f32,
            Samples::U16(v) => v[i] as f32,
            Samples::F32(v) => v[i],
        }
    }
}

/// A decoded photo: `width x height` pixels of `channels`, row-major, interleaved.
#[derive(Clone, Debug, PartialEq)]
pub struct Photo {
    width: usize,
    height: usize,
    channels: Channels,
    samples: Samples,
    transfer: Transfer,
}

impl Photo {
    /// Wraps interleaved samples.
    ///
    /// # Errors
    /// When the sample count does not match `width * height * channels`.
    pub fn new(width: usize, height: usize, channels: Channels, samples: Samples) -> Result<Self> {
        let want = width * height * channels.count();
        if samples.len() != want {
            return Err(Error::InvalidParameter(format!(
                "photo of {width}x{height} {channels:?} needs {want} samples, got {}",
                samples.len()
            )));
        }
        Ok(Photo { width, height, channels, samples, transfer: Transfer::Linear })
    }

    /// The same photo with its transfer curve declared.
    pub fn with_transfer(mut self, transfer: Transfer) -> Self {
        self.transfer = transfer;
        self
    }

    pub fn width(&self) -> usize {
        self.width
    }
    pub fn height(&self) -> usize {
        self.height
    }
    pub fn channels(&self) -> Channels {
        self.channels
    }
    pub fn samples(&self) -> &Samples {
        &self.samples
    }
    pub fn transfer(&self) -> Transfer {
        self.transfer
    }
    pub fn bit_depth(&self) -> u32 {
        self.samples.bit_depth()
    }
    pub fn pixel_count(&self) -> usize {
        self.width * self.height
    }

    /// Linear value of sample `i` scaled so full scale is 1.
    #[inline]
    pub fn linear(&self, i: usize) -> f32 {
        let v = self.samples.get(i) / self.samples.full_scale();
        match self.transfer {
            Transfer::Linear => v,
            Transfer::Srgb => crate::encoding::srgb_to_linear(v),
        }
    }

    /// The photo as linear luminance in `[0, 1]` (Rec. 709 weights for RGB), row-major.
    pub fn luminance(&self) -> Vec<f32> {
        match self.channels {
            Channels::Gray => (0..self.pixel_count()).map(|i| self.linear(i)).collect(),
            Channels::Rgb => (0..self.pixel_count())
                .map(|i| {
                    0.2126 * self.linear(3 * i) + 0.7152 * self.linear(3 * i + 1) + 0.0722 * self.linear(3 * i + 2)
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_sample_count() {
        assert!(Photo::new(2, 2, Channels::Rgb, Samples::U8(vec![0; 11])).is_err());
        let p = Photo::new(2, 1, Channels::Gray, Samples::U16(vec![0, 65535])).unwrap();
        assert_eq!(p.linear(1), 1.0);
        assert_eq!(p.bit_depth(), 16);
    }

    #[test]
    fn srgb_photo_linearises() {
        let p = Photo::new(1, 1, Channels::Gray, Samples::U8(vec![188])).unwrap().with_transfer(Transfer::Srgb);
        assert!((p.linear(0) - 0.5029).abs() < 1e-3);
    }
}
