//! The page's height figures: a height map (`height.exr`) drawn as relief lit from its own
//! normals (what a displacement shows) and in false colour with a scale bar in micrometres.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use skinkit_height::compare::normals_of;
use skinkit_maps::{io, preview};

use super::page::{figure, save};

/// Longest side of a height preview, pixels.
const SIDE: usize = 512;
/// Stops of the scale bar's gradient.
const BAR_STOPS: usize = 9;

/// Adds the relief and the false-colour picture of the height at `exr` (in mm when `mm`, else in
/// texels), named `name` in `page/`.
///
/// # Errors
/// When the height cannot be read or a preview cannot be written.
pub fn figures(html: &mut String, out: &Path, exr: &Path, name: &str, mm: bool, wraps: bool) -> Result<()> {
    let heights = io::read_exr_channel(exr, "Y", &Default::default()).context("cannot read the height map")?;
    // The relief's slopes only scale its contrast, which the shading stretches anyway.
    let relief = preview::shade_normals(&normals_of(&heights, 1.0, wraps), preview::raking_light());
    let src = save(out, &preview::shrink(&relief, SIDE), &format!("{name}-height-relief.png"))?;
    figure(html, &src, "height, lit from its own normals", "map");
    if wraps {
        // A grown map's height tiles: three by three copies show no seam.
        let (w, h) = relief.size();
        let tiled = skinkit_maps::Grid::from_fn(3 * w, 3 * h, |x, y| *relief.get(x % w, y % h));
        let src = save(out, &preview::shrink(&tiled, SIDE), &format!("{name}-height-tiled.png"))?;
        figure(html, &src, "the same, tiled 3x3", "map");
    }
    let (lo, hi) = preview::value_range(heights.as_slice());
    let colour = preview::false_colour(&heights, lo, hi);
    let src = save(out, &preview::shrink(&colour, SIDE), &format!("{name}-height.png"))?;
    figure(html, &src, "height", "map");
    scale_bar(html, lo, hi, mm);
    Ok(())
}

/// A vertical gradient bar from `lo` (bottom) to `hi` (top) labelled in micrometres (or texels).
fn scale_bar(html: &mut String, lo: f32, hi: f32, mm: bool) {
    let stops: Vec<String> = (0..BAR_STOPS)
        .map(|i| {
            let [r, g, b] = preview::ramp(i as f32 / (BAR_STOPS - 1) as f32);
            format!("rgb({r},{g},{b})")
        })
        .collect();
    let (unit, factor) = if mm { ("µm", 1000.0) } else { ("texels", 1.0) };
    let _ = write!(
        html,
        "<figure class=\"bar\"><div class=\"scale\"><div class=\"ramp\" style=\"background:linear-gradient(to top,{})\"></div>\
         <div class=\"labels\"><span>{:.1} {unit}</span><span>{:.1} {unit}</span></div></div><figcaption>scale</figcaption></figure>",
        stops.join(","),
        hi * factor,
        lo * factor
    );
}
