//! Stitching of per-region syntheses into one face map (Haro et al. 2001, section 4.2).
//!
//! A face layout ([`layout`]) names regions, their exemplars and a few seed points; texels go to
//! the nearest seed ([`partition`]), every straight boundary of that partition is replaced by a
//! seeded random curve ([`curve`]), each region is synthesised over its area plus a margin, and
//! the regions are joined by an N-way Burt-Adelson multiresolution spline ([`spline`]). [`seam`]
//! measures what is left of the boundaries.

pub mod compose;
pub mod curve;
pub mod error;
pub mod face;
pub mod layout;
pub mod partition;
pub mod seam;
pub mod spline;
pub mod surface;
pub use skinkit_maps::udim;

pub use compose::{ComposeOptions, Composed, compose};
pub use error::{Error, Result};
pub use face::{Face, FaceOptions, FaceReport};
