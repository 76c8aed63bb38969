//! The guards every synthesis runs behind ([`crate::synthesize`], [`crate::synthesize_normals`]).
//!
//! * Collapse guard: an output whose variation (slope or channel deviation over the exemplar's,
//!   [`metrics::variation_ratio`]) falls under [`metrics::COLLAPSE_RATIO`] is grown again with
//!   [`SynthConfig::collapse_retry`]; the better output is kept and a warning says what happened.
//! * Histogram guard: an output whose slope or channel histograms drifted more than
//!   [`metrics::HISTOGRAM_RATIO`] of the exemplar's deviation from the exemplar's
//!   ([`metrics::histogram_mismatch`]) is grown again with [`SynthConfig::histogram_retry`] (Kopf
//!   et al. 2007's occurrence penalty, which weights texels by their use); the output nearer the
//!   exemplar's histogram is kept if it has not collapsed (outputs of at least 64 x 64 texels;
//!   smaller ones are too few to judge a histogram by). The figure and whether it retried are
//!   in the result, not a warning: a retry that helped is the guard working. The measured case is
//!   the suite's heightfield nose with squared L2 at the coarser levels, which grew too much of
//!   its bulge's slopes (`docs/synthesis-notes.md`); the default's robust matching keeps it
//!   under the limit (0.07-0.10, seeds 1-3).

use super::{RunNotes, Texels};
use crate::{Result, SynthConfig, metrics};

/// What the guards measured on an output, as a synthesis returns it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guards {
    /// The collapse guard: the output's slope (normals) or channel (colours) deviation over the
    /// exemplar's, the smallest over axes or channels ([`metrics::variation_ratio`]); under
    /// [`metrics::COLLAPSE_RATIO`] a warning says so.
    pub variation: f64,
    /// The histogram guard: how far the output's slope or channel histograms are from the
    /// exemplar's, in the exemplar's deviations ([`metrics::histogram_mismatch`]).
    pub histogram: f64,
    /// Whether the histogram guard grew the output again and kept the second growth (see
    /// [`SynthConfig::histogram_retry`]).
    pub histogram_retry: bool,
}

/// The histogram guard judges outputs of at least this many texels: the histogram of a random
/// sample of `n` values lies about `1 / sqrt(n)` deviations from its population's in
/// Wasserstein-1, so a smaller output could be regrown for its size alone.
const HISTOGRAM_MIN_TEXELS: usize = 64 * 64;

/// One growth of an output (see [`super::attempt`]): what took its rows, its notes and the
/// guards' figures measured on it.
pub(crate) struct Attempt<A> {
    pub(crate) output: A,
    pub(crate) notes: RunNotes,
    pub(crate) guards: Guards,
}

/// `grow` behind the collapse guard, then the histogram guard (on the config that made the kept
/// output, so a collapse retry's stronger penalty is not weakened). `grow` grows and measures one
/// output with the config it is given; the output not kept is dropped.
pub(crate) fn guarded<A>(
    config: &SynthConfig,
    kind: Texels,
    mut grow: impl FnMut(&SynthConfig) -> Result<Attempt<A>>,
) -> Result<Attempt<A>> {
    let what = kind.name();
    let mut s = grow(config)?;
    let mut used = config.clone();
    if let Some(retry) = config.collapse_retry().filter(|_| s.guards.variation < metrics::COLLAPSE_RATIO) {
        let again = grow(&retry)?;
        let note = format!(
            "collapse guard: the output kept {:.0} % of the exemplar's {what} variation, so it was grown again \
             with occurrence penalty {} at the coarser levels ({:.0} %{})",
            100.0 * s.guards.variation,
            retry.occurrence_penalty,
            100.0 * again.guards.variation,
            if again.guards.variation > s.guards.variation { ", kept" } else { ", not better: the first was kept" }
        );
        if again.guards.variation > s.guards.variation {
            s = again;
            used = retry;
        }
        s.notes.warnings.push(note);
    }
    s.notes.warnings.extend(collapse_warning(s.guards.variation, what));
    let drifted = s.guards.histogram > metrics::HISTOGRAM_RATIO
        && s.guards.variation >= metrics::COLLAPSE_RATIO
        && config.width * config.height >= HISTOGRAM_MIN_TEXELS;
    if let Some(retry) = used.histogram_retry().filter(|_| drifted) {
        let mut again = grow(&retry)?;
        if again.guards.histogram < s.guards.histogram && again.guards.variation >= metrics::COLLAPSE_RATIO {
            again.notes.warnings = std::mem::take(&mut s.notes.warnings);
            again.guards.histogram_retry = true;
            s = again;
        }
    }
    Ok(s)
}

/// The warning of an output that kept less than [`metrics::COLLAPSE_RATIO`] of the exemplar's
/// variation, if it did.
fn collapse_warning(variation: f64, what: &str) -> Option<String> {
    (variation < metrics::COLLAPSE_RATIO).then(|| {
        format!(
            "the output kept {:.0} % of the exemplar's {what} variation (under {:.0} %): it may be \
             nearly blank; try another seed",
            100.0 * variation,
            100.0 * metrics::COLLAPSE_RATIO
        )
    })
}
