//! Skin scattering on the CPU: the diffusion profile, the pre-integrated tables (diffuse falloff
//! and shadow scattering), their closed-form fits, the spherical-harmonic form for ambient light,
//! per-vertex curvature, and the exact texture-space reference every real-time effect is
//! measured against, and the scene's scattering settings. Physics only: nothing here imports
//! the GPU side ([`crate::pass`], [`crate::gpu`]), which reads from it.
//!
//! - [`profile`]: the sum-of-Gaussians diffusion profile and equation 1.1 by brute force.
//! - [`sphere`]: the same falloff over a sphere's surface, to about 1e-6.
//! - [`lut`], [`shadow`], [`lut_file`]: the pre-integrated diffuse and shadow-scattering tables
//!   and their EXR files (`skinkit lut`).
//! - [`fit`]: the blog's closed form and our own fit of the diffuse table.
//! - [`sh`]: order-2 SH environments and the skin's zonal convolution factors.
//! - [`curvature`]: per-vertex 1/r from the mesh.
//! - [`reference`](mod@reference): the exact texture-space convolution.
//! - [`tsd`]: texture-space diffusion's blur passes (single kernel or the profile's Gaussians).
//! - [`options`]: the scene's scattering settings.

pub mod curvature;
pub mod fit;
pub mod lut;
pub mod lut_file;
pub mod options;
pub mod poisson;
pub mod profile;
pub mod reference;
pub mod sh;
pub mod shadow;
pub mod sphere;
pub mod tsd;
