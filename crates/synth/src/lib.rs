//! Wei-Levoy multiresolution texture synthesis of normal and colour maps (Haro et al. 2001,
//! section 4.1; Wei and Levoy 2000). Work in progress for issue 3: see the module list as it grows.

pub mod metrics;
