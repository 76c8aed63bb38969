//! Batches of capture sessions and face subjects, what `skinkit batch` runs: the units of a
//! sessions folder ([`units`]), each session captured or skipped when up to date ([`outcome`],
//! [`resume`]), the review's signs and previews ([`review`]) and page ([`page`]), shards of a
//! batch over a cluster and their merge ([`shard`], [`scheduler`]), and the batch's report
//! ([`report`]).
//!
//! The CLI runs the units in parallel, shows progress, handles interrupts and stitches the
//! subjects' faces; everything a batch decides or writes about a session is here. Errors are
//! `anyhow` chains: a batch reports each session's failure as one line of its report
//! ([`skinkit_maps::error::one_line`]) and goes on, so the causes matter more than their types.

pub mod outcome;
pub mod page;
pub mod report;
pub mod resume;
pub mod review;
pub mod scheduler;
pub mod shard;
pub mod units;

pub use outcome::SessionOutcome;
pub use report::BatchReport;
pub use units::{FaceOutcome, Job, Subject, Unit};
