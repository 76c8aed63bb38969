//! Skin scattering on the CPU: the diffusion profile, the pre-integrated tables (diffuse falloff
//! and shadow scattering), their closed-form fits, the spherical-harmonic form for ambient light,
//! per-vertex curvature, and the exact texture-space reference every real-time effect is
//! measured against.

pub mod curvature;
pub mod profile;
pub mod reference;
