//! Streamed runs (issue 43): the finest level's rows handed to a [`BandSink`] band by band as
//! they finish ([`crate::band`]), so an output need never be held whole; the guards measure it
//! as it passes ([`metrics::GuardMeter`]), and a retry grows into a new sink, the one not kept
//! being dropped. [`crate::synthesize`] is a streamed run whose sink collects the rows.

use glam::Vec3;
use skinkit_maps::progress::Progress;
use skinkit_maps::{Grid, NormalMap};

use super::guard::{self, Attempt, Guards};
use super::{RunNotes, Texels, grow_into};
use crate::band::Collect;
use crate::metrics::GuardMeter;
use crate::{Result, SynthConfig};

/// Takes the finest level's rows as the bands finish, top to bottom.
pub trait BandSink {
    /// Rows `first_row..first_row + texels.height()` of the output: their texels and the exemplar
    /// texels `[x, y]` they copy, handed over (a sink keeps them without a copy).
    ///
    /// # Errors
    /// The sink's own (a write that failed): the run stops with it.
    fn band(&mut self, first_row: usize, texels: Grid<Vec3>, coords: Grid<[u32; 2]>) -> Result<()>;
}

/// A streamed run's result: the sink that took the kept output, and what the run tells.
pub struct Streamed<S> {
    pub sink: S,
    /// What validation changed and what the guards did, as [`crate::Synthesis::warnings`].
    pub warnings: Vec<String>,
    /// Wall-clock seconds per level, `[0]` the finest.
    pub level_seconds: Vec<f64>,
    pub guards: Guards,
}

/// [`crate::synthesize`] into sinks: `open` makes a sink for each growth (one, or two when a
/// guard grows the output again); the sink of the output kept is returned, the other dropped.
///
/// # Errors
/// When [`SynthConfig::validate`] fails, `open` fails or a sink does.
pub fn synthesize_streamed<S: BandSink>(
    exemplar: &Grid<Vec3>,
    config: &SynthConfig,
    progress: &dyn Progress,
    open: impl FnMut() -> Result<S>,
) -> Result<Streamed<S>> {
    streamed(exemplar, config, progress, Texels::Colour, open)
}

/// [`crate::synthesize_normals`] into sinks (see [`synthesize_streamed`]): the texels a sink takes
/// are unit normals, or zero where the exemplar texel copied was invalid.
///
/// # Errors
/// As [`crate::synthesize_normals`], and when `open` fails or a sink does.
pub fn synthesize_normals_streamed<S: BandSink>(
    exemplar: &NormalMap,
    config: &SynthConfig,
    progress: &dyn Progress,
    open: impl FnMut() -> Result<S>,
) -> Result<Streamed<S>> {
    let exemplar_warning = crate::exemplar::check_normal_exemplar(exemplar)?;
    let mut s = streamed(exemplar.grid(), config, progress, Texels::Normals, open)?;
    s.warnings.splice(0..0, exemplar_warning);
    Ok(s)
}

fn streamed<S: BandSink>(
    exemplar: &Grid<Vec3>,
    config: &SynthConfig,
    progress: &dyn Progress,
    kind: Texels,
    mut open: impl FnMut() -> Result<S>,
) -> Result<Streamed<S>> {
    let a = guard::guarded(config, kind, |config| attempt(exemplar, config, progress, kind, open()?))?;
    let RunNotes { warnings, level_seconds } = a.notes;
    Ok(Streamed { sink: a.output, warnings, level_seconds, guards: a.guards })
}

/// One growth into `sink`, measured by the guards' meter as the rows pass.
fn attempt<S: BandSink>(
    exemplar: &Grid<Vec3>,
    config: &SynthConfig,
    progress: &dyn Progress,
    kind: Texels,
    mut sink: S,
) -> Result<Attempt<S>> {
    let mut meter = GuardMeter::new(kind == Texels::Normals, (config.width, config.height));
    let notes = grow_into(exemplar, config, progress, kind, &mut |first_row, texels, coords| {
        meter.add(texels.as_slice());
        sink.band(first_row, texels, coords)
    })?;
    let (variation, histogram) = meter.figures(exemplar);
    Ok(Attempt { output: sink, notes, guards: Guards { variation, histogram, histogram_retry: false } })
}

impl BandSink for Collect {
    fn band(&mut self, _: usize, texels: Grid<Vec3>, coords: Grid<[u32; 2]>) -> Result<()> {
        self.push(texels, coords);
        Ok(())
    }
}

/// A run whose rows are collected whole.
pub(super) fn collected(
    exemplar: &Grid<Vec3>,
    config: &SynthConfig,
    progress: &dyn Progress,
    kind: Texels,
) -> Result<Streamed<Collect>> {
    streamed(exemplar, config, progress, kind, || Ok(Collect::new(config.width, config.height)))
}
