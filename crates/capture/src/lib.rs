//! Photometric stereo for skin molds (Haro et al. 2001, section 3).
//!
//! A mold photographed under k >= 3 known lights gives, per pixel, `albedo * E_i * (n . L_i) = I_i`.
//! * [`rig`]: light rigs (TOML files), their validation and conditioning.
//! * [`import`]: rigs from public formats (DiLiGenT, UW/Seitz `lights.txt`).
//! * [`sphere`]: light directions (and intensities) from photos of a mirror or matte sphere.
//! * [`solve`]: the least-squares and robust per-pixel solves (distant lights); [`near`]: near
//!   point lights; [`readings`]: the rules on readings both share.
//! * [`session`]: a whole capture session as one call (decode, solve, detrend, statistics).
//! * [`robust`]: the robust per-pixel fit (rank-trimmed start, reweighting, inlier refit).
//! * [`bracket`]: exposure brackets merged into one linear reading per pixel.
//! * [`detrend`]: removal of the mold's low-frequency tilt (mean normal of a block rotated to +Z).

pub mod bracket;
pub mod detrend;
pub mod error;
pub mod flat;
pub mod import;
pub mod near;
pub mod outputs;
pub mod readings;
pub mod rig;
pub mod robust;
pub mod session;
pub mod solve;
pub mod sphere;

pub use error::{Error, Result};
pub use rig::{Light, Rig};
