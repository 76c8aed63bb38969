//! skinkit-render's integration tests, one binary (issue 38): each file a module, named as the
//! test binary it was before (`cargo test -p skinkit-render --test render skin_lut::`).

mod brdf;
mod common;
mod debug_frames;
mod frames;
mod gpu;
mod head;
mod load;
mod mesh;
mod pass_graph;
mod properties;
mod scene;
mod session;
mod shading;
mod skin_curvature;
mod skin_fit;
mod skin_fit_gpu;
mod skin_gpu;
mod skin_lut;
mod skin_reference;
mod skin_reference_convergence;
mod skin_sh;
mod skin_tsd_convergence;
mod skin_tsd_taps;
mod view;
mod wgsl;
