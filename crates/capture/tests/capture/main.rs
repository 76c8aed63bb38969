//! skinkit-capture's integration tests, one binary: each file a module.

/// `limits` measures heap peaks; the allocator counts only what measured threads allocate, so the
/// other tests of this binary, running meanwhile, do not disturb the measurement.
#[global_allocator]
static ALLOCATOR: skinkit_testkit::alloc::Counting = skinkit_testkit::alloc::Counting;

mod brackets;
mod flat_fields;
mod limits;
mod near_light;
mod noise_floor;
mod properties;
mod raw_photos;
mod rig_conditioning;
mod rig_files;
mod rig_import;
mod rig_sphere;
mod robust_molds;
mod session;
mod solve_subsets;
mod solve_synthetic;
