//! Stitching: the sample face (`samples/face/layout.toml`, seven regions from the four sample
//! molds' true normals) at a reduced size, with the spline's levels, random-curve or straight
//! boundaries, and blending on or off. Each choice is scored by the seam measures of
//! [`skinkit_stitch::seam`] (the normal jump across every boundary; the band's slope gradient
//! over the interiors beside it, 1 when the boundary does not show).
//!
//! Cost: the stitching's own seconds (partition with its curves, the spline, the seam measure),
//! not the regions' synthesis, which every choice pays alike. The exemplars are resampled so each
//! is about 128 texels on the map (64 in quick mode) whatever its size (at a reduced map size the
//! molds' physical scale would leave a handful of texels).

use std::path::Path;

use skinkit_maps::io::{Limits, read_normal_map};
use skinkit_maps::{NormalEncoding, NormalMap};
use skinkit_stitch::curve::CurveParams;
use skinkit_stitch::layout::{ExemplarSource, Layout};
use skinkit_stitch::{ComposeOptions, compose};
use skinkit_synth::SynthConfig;

use crate::choice::{Choice, Stage, StageReport, knobs, metrics};
use crate::{Config, Result};

/// Texels an exemplar spans on the face map after resampling.
fn exemplar_side(config: &Config) -> f64 {
    if config.quick { 64.0 } else { 128.0 }
}

/// One stitching choice: series, label, spline levels (`None`: automatic), curves, blend.
struct Try {
    series: &'static str,
    label: String,
    levels: Option<usize>,
    curved: bool,
    blend: bool,
}

fn plan(config: &Config) -> ((usize, usize), Vec<Try>) {
    let t = |series, label: &str, levels, curved, blend| Try { series, label: label.into(), levels, curved, blend };
    let mut tries = vec![
        t("default", "curves + spline", None, true, true),
        // Categorical choices: a series each, so no line joins them.
        t("straight + spline", "straight + spline", None, false, true),
        t("curves, no blend", "curves, no blend", None, true, false),
        t("straight, no blend", "straight, no blend", None, false, false),
    ];
    let (size, levels) = if config.quick { ((512, 256), vec![2, 3]) } else { ((2048, 1024), vec![1, 2, 3, 4, 5, 6]) };
    tries.extend(levels.into_iter().map(|l| t("spline levels", &format!("{l} levels"), Some(l), true, true)));
    (size, tries)
}

/// Measures every stitching choice.
///
/// # Errors
/// When the layout or a mold's truth cannot be read, or a choice is refused.
pub fn measure(config: &Config, progress: &dyn skinkit_maps::progress::Progress) -> Result<StageReport> {
    let ((w, h), tries) = plan(config);
    let original = Layout::load(&config.samples.join("face/layout.toml"))?;
    let mut layout = original.with_size(w, h)?;
    let side = exemplar_side(config);
    let exemplars = load_exemplars(&mut layout, side)?;
    let setup = format!(
        "The sample face layout at {w}x{h} ({} regions; exemplars: the sample molds' truth.png, about \
         {side} texels on the map), default synthesis with 3 levels, seed {}; mean jump: the \
         mean angle between neighbours across each boundary, averaged over the boundaries; gradient \
         ratio: slope gradient in a 4-texel band along a boundary over the interiors beside it (1: \
         the boundary does not show); time: partition + spline + seam measure, one run per choice",
        layout.regions.len(),
        config.seed
    );
    let mut report = StageReport::new(Stage::Stitching, setup, "mean normal jump (deg)", "seconds");
    let tally = crate::Tally::start(progress, Stage::Stitching, tries.len());
    for t in &tries {
        report.choices.push(stitch(&layout, &exemplars, t, config)?);
        tally.done(report.choices.len());
    }
    Ok(report)
}

/// Reads every region's true normals and sets its scale so it spans `side` texels.
fn load_exemplars(layout: &mut Layout, side: f64) -> Result<Vec<NormalMap>> {
    let mm = layout.mm_per_texel;
    layout
        .regions
        .iter_mut()
        .map(|region| {
            let path = match &region.exemplar {
                ExemplarSource::Session(dir) => dir.join("truth.png"),
                ExemplarSource::NormalMap(p) => p.clone(),
            };
            let map = read(&path)?;
            region.exemplar_mm_per_texel = mm * side / map.width().max(1) as f64;
            Ok(map)
        })
        .collect()
}

fn read(path: &Path) -> Result<NormalMap> {
    Ok(read_normal_map(path, NormalEncoding::default(), &Limits::default())?)
}

/// One choice, composed once, full mode included: each composition grows every region again, which
/// at 2048x1024 costs far more than the stitching it would time (the full run took over 17
/// minutes with 3 runs a choice), so the stitching's seconds are one run's.
fn stitch(layout: &Layout, exemplars: &[NormalMap], t: &Try, config: &Config) -> Result<Choice> {
    let amplitude = if t.curved { ComposeOptions::default_amplitude(layout.width) } else { 0.0 };
    let options = ComposeOptions {
        curve: CurveParams::new(amplitude, config.seed),
        levels: t.levels,
        blend: t.blend,
        synth: SynthConfig { levels: 3, ..SynthConfig::default() },
        seed: config.seed,
        seam_band: 4,
    };
    let composed = compose(layout, exemplars, &options, &skinkit_maps::progress::NoProgress)?;
    let s = &composed.seconds;
    let seconds = s.partition + s.blend + s.seams;
    let summary = &composed.seams.summary;
    let mut measured = vec![
        ("mean normal jump (deg)", summary.mean_jump_degrees),
        ("largest normal jump (deg)", summary.max_jump_degrees),
    ];
    measured.extend(summary.mean_gradient_ratio.map(|r| ("mean gradient ratio", r)));
    measured.extend(summary.max_gradient_ratio.map(|r| ("max gradient ratio", r)));
    Ok(Choice::timed(
        t.series,
        &t.label,
        knobs(&[
            ("levels", composed.levels.to_string()),
            ("boundaries", if t.curved { "random curves" } else { "straight" }.into()),
            ("blend", t.blend.to_string()),
        ]),
        metrics(&measured),
        seconds,
        1,
    ))
}
