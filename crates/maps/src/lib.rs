//! Core map types and image IO shared by every skinkit stage.
//!
//! * [`Grid`] is a row-major 2-D array; [`ScalarMap`] and [`ColorMap`] are grids of `f32` and
//!   linear RGB.
//! * [`NormalMap`] holds unit vectors in the camera/tangent frame (x right, y up, z toward the
//!   viewer); `(0, 0, 0)` marks an invalid texel. Encodings only exist at the IO boundary
//!   ([`encoding`]).
//! * [`Photo`] is a decoded photograph kept in its native sample type (8-bit, 16-bit or float), so
//!   a stack of large 16-bit photos costs two bytes a sample, not four.
//! * [`io`] reads PNG, TIFF and EXR (and camera RAW through [`raw`]) under [`Limits`] and writes every output atomically;
//!   [`OutputSet`] makes a command's several outputs appear all together or not at all.
//! * [`input`] is the gate every file read passes: regular files only, each kind under a byte
//!   limit, checked from metadata before reading.
//! * [`limits`] states every resource limit (image sizes, lights, frames, threads, memory) and
//!   checks them from headers and arithmetic before anything is allocated.
//! * [`preview`] draws maps as 8-bit pictures people read (relief under a raking light).
//!
//! Image rows grow downward, against +y: row 0 is the top of the picture. UV origin: skinkit puts
//! texture coordinate (0, 0) at the top-left texel (as glTF and wgpu do); loaders of bottom-left
//! formats (OBJ) flip v.

pub mod documents;
pub mod encoding;
pub mod error;
mod exr_write;
pub mod format;
pub mod gate;
pub mod grid;
pub mod input;
pub mod io;
pub mod limits;
pub mod names;
pub mod normal;
pub mod output_set;
pub mod photo;
pub mod preview;
pub mod progress;
pub mod pyramid;
pub mod raw;
pub mod resample;
mod signature;
pub mod stream;
mod tiff_grey;
pub mod udim;

pub use encoding::{GreenAxis, NormalEncoding};
pub use error::{Error, Result};
pub use glam::Vec3;
pub use grid::{ColorMap, Grid, ScalarMap};
pub use io::Limits;
pub use normal::NormalMap;
pub use output_set::OutputSet;
pub use photo::{Channels, Photo, Samples, Transfer};
