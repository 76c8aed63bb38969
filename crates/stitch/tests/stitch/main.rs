//! skinkit-stitch's integration tests, one binary: each file a module.

/// `limits` measures heap peaks; the allocator counts only what measured threads allocate, so the
/// other tests of this binary, running meanwhile, do not disturb the measurement.
#[global_allocator]
static ALLOCATOR: skinkit_testkit::alloc::Counting = skinkit_testkit::alloc::Counting;

mod compose;
mod layout;
mod limits;
mod partition;
mod properties;
mod seam;
mod spline;
mod surface;
