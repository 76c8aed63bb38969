//! Synthetic skin-like heightfields with exact analytic normals, and a renderer that photographs
//! them under a light rig: the test and sample data of every other skinkit stage.
//!
//! * [`params`]: [`SkinParams`] with presets per face region after Haro, Guenter and Essa (2001),
//!   section 3 and figures 2-3 (pores on cheek and nose, crossing furrows on the forehead).
//! * [`surface`]: the analytic height function and its exact gradient ([`Surface`]).
//! * [`skin`]: [`generate`] rasterises a surface into a [`Heightfield`].
//! * [`mod@render`]: Lambertian photos with cast shadows, specular contamination, ambient light, sensor
//!   noise and quantisation, the input photometric stereo expects.
//! * [`dng`]: those photos as a camera would write them: a Bayer mosaic in a minimal DNG file.
//!
//! Everything is seeded by the caller and bit-for-bit reproducible whatever the thread count.
//!
//! ```
//! use skinkit_heightfield::{RenderConfig, RenderLight, SkinParams, render};
//! let field = SkinParams::cheek(64, 64, 7).generate().unwrap();
//! let lights = RenderLight::ring(4, 45.0, glam::Vec3::ONE);
//! let photos = render(&field, &lights, &RenderConfig::default()).unwrap();
//! assert_eq!(photos.len(), 4);
//! ```

pub mod dng;
pub mod error;
pub mod params;
pub mod periodic;
pub mod render;
pub mod skin;
pub mod surface;

pub use error::{Error, Result};
pub use params::{Bulge, FurrowFamily, NoiseParams, PoreParams, SkinParams};
pub use periodic::periodic;
pub use render::{Albedo, Quantise, RenderConfig, RenderLight, Specular, render, render_ambient};
pub use skin::{Heightfield, generate};
pub use surface::{HeightSample, Pore, Surface};
