//! One PNG per stage: the stage's error metric against its cost on a log axis, one curve per
//! series and one labelled point per choice (plotters' bitmap backend; text in the bundled
//! DejaVu Sans subset through ab_glyph, so no system fonts are needed).

use std::sync::Once;

use plotters::coord::combinators::BindKeyPoints;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::choice::{Choice, StageReport};
use crate::{Error, Result};

/// Plot size in pixels.
pub const SIZE: (u32, u32) = (900, 600);
/// The font family every text of the plots uses (registered from the bundled file).
const FAMILY: &str = "sans-serif";
/// DejaVu Sans Bold cut down to printable ASCII, the font the renderer's figure labels use
/// (`crates/render/assets`, licence beside it).
const FONT: &[u8] = include_bytes!("../../render/assets/DejaVuSans-Bold-ascii.ttf");

fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bundled file parses (the renderer's label tests draw with it); a failure would only
        // leave the plots without text, which the PNG check of the end-to-end test still passes.
        let _ = register_font(FAMILY, FontStyle::Normal, FONT);
    });
}

/// The stage's plot as PNG bytes: error against cost, or a panel saying why it was skipped.
///
/// # Errors
/// [`Error::Plot`] when drawing or encoding fails.
pub fn png(stage: &StageReport) -> Result<Vec<u8>> {
    register();
    let (w, h) = SIZE;
    let mut rgb = vec![255u8; (w * h * 3) as usize];
    let fail = |message: String| Error::Plot { stage: stage.stage.name().into(), message };
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(e.to_string()))?;
        match &stage.skipped {
            Some(reason) => skipped_panel(&root, stage, reason),
            None => chart(&root, stage),
        }
        .map_err(fail)?;
        root.present().map_err(|e| fail(e.to_string()))?;
    }
    encode(w, h, rgb).map_err(fail)
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn skipped_panel(root: &Area<'_>, stage: &StageReport, reason: &str) -> std::result::Result<(), String> {
    let style = (FAMILY, 22).into_font().color(&BLACK);
    root.draw(&Text::new(format!("{}: skipped", stage.stage.name()), (40, 60), style.clone()))
        .map_err(|e| e.to_string())?;
    let small = (FAMILY, 16).into_font().color(&BLACK);
    for (i, line) in wrap(reason, 90).iter().enumerate() {
        root.draw(&Text::new(line.clone(), (40, 110 + 24 * i as i32), small.clone())).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Splits `text` into lines of at most about `width` characters at spaces.
fn wrap(text: &str, width: usize) -> Vec<String> {
    let mut lines = vec![String::new()];
    for word in text.split_whitespace() {
        let line = lines.last_mut().expect("one line at least");
        if !line.is_empty() && line.len() + word.len() > width {
            lines.push(word.to_owned());
        } else {
            if !line.is_empty() {
                line.push(' ');
            }
            line.push_str(word);
        }
    }
    lines
}

/// The axes' ranges: cost padded on a log scale, error from 0 (or below the least) to above the most.
fn ranges(choices: &[Choice]) -> ((f64, f64), (f64, f64)) {
    let costs = choices.iter().map(|c| c.cost).filter(|c| *c > 0.0 && c.is_finite());
    let (lo, hi) = costs.fold((f64::INFINITY, 0.0f64), |(lo, hi), c| (lo.min(c), hi.max(c)));
    let (lo, hi) = if hi > 0.0 { (lo / 1.6, hi * 1.6) } else { (1e-3, 1.0) };
    let errors = choices.iter().map(Choice::error).filter(|e| e.is_finite());
    let (elo, ehi) = errors.fold((0.0f64, 0.0f64), |(lo, hi), e| (lo.min(e), hi.max(e)));
    let span = (ehi - elo).max(1e-9);
    ((lo, hi), (elo - 0.02 * span, ehi + 0.12 * span))
}

/// The series in first-appearance order, each with its choices.
fn series(choices: &[Choice]) -> Vec<(&str, Vec<&Choice>)> {
    let mut out: Vec<(&str, Vec<&Choice>)> = Vec::new();
    for c in choices {
        match out.iter_mut().find(|(name, _)| *name == c.series) {
            Some((_, members)) => members.push(c),
            None => out.push((&c.series, vec![c])),
        }
    }
    out
}

fn chart(root: &Area<'_>, stage: &StageReport) -> std::result::Result<(), String> {
    let ((x0, x1), (y0, y1)) = ranges(&stage.choices);
    let title = format!("{}: {} against {}", stage.stage.name(), stage.error_metric, stage.cost_axis);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 20))
        .margin(16)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d((x0..x1).log_scale().with_key_points(ticks(x0, x1)), y0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(format!("{} (log scale)", stage.cost_axis))
        .y_desc(stage.error_metric.clone())
        .label_style((FAMILY, 13))
        .axis_desc_style((FAMILY, 15))
        .x_label_formatter(&|v| short(*v))
        .draw()
        .map_err(|e| e.to_string())?;
    for (i, (name, members)) in series(&stage.choices).into_iter().enumerate() {
        let colour = colour(i);
        // A series' curve runs left to right (its choices may vary more than one knob, so their
        // own order can double back, and plotters clips a backward segment on a log axis badly).
        let mut points: Vec<(f64, f64)> = members.iter().map(|c| (c.cost, c.error())).collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(name.to_owned())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(3)));
        let label_style = (FAMILY, 12).into_font().color(&BLACK);
        chart
            .draw_series(members.iter().map(|c| {
                EmptyElement::at((c.cost, c.error()))
                    + Circle::new((0, 0), 4, colour.filled())
                    + Text::new(c.label.clone(), (5, -14), label_style.clone())
            }))
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .label_font((FAMILY, 12))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(())
}

/// The `i`-th series colour: ten well-separated colours on white (no pale yellow), then
/// plotters' palette.
fn colour(i: usize) -> RGBAColor {
    const TEN: [(u8, u8, u8); 10] = [
        (31, 119, 180),
        (214, 39, 40),
        (44, 160, 44),
        (255, 127, 14),
        (148, 103, 189),
        (140, 86, 75),
        (227, 119, 194),
        (90, 90, 90),
        (23, 190, 207),
        (188, 189, 34),
    ];
    match TEN.get(i) {
        Some(&(r, g, b)) => RGBColor(r, g, b).to_rgba(),
        None => Palette99::pick(i).to_rgba(),
    }
}

/// Log-axis ticks at 1, 2 and 5 times the powers of ten within `[lo, hi]`.
fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo > 0.0 && hi > lo && lo.is_finite() && hi.is_finite()) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for exponent in lo.log10().floor() as i32..=hi.log10().ceil() as i32 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(exponent);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
    }
    out
}

/// A tick label: few digits, no trailing zeros.
fn short(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.3}").trim_end_matches('0').trim_end_matches('.').to_owned()
    } else if v > 0.0 {
        // Enough decimals for two significant digits: 0.05, 0.0012.
        let decimals = ((-v.log10()).ceil() as usize + 1).min(9);
        format!("{v:.decimals$}").trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        "0".into()
    }
}

fn encode(w: u32, h: u32, rgb: Vec<u8>) -> std::result::Result<Vec<u8>, String> {
    let image = image::RgbImage::from_raw(w, h, rgb).ok_or("the plot buffer has the wrong size")?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::choice::{Stage, knobs, metrics};

    fn stage(choices: Vec<Choice>) -> StageReport {
        let mut s = StageReport::new(Stage::Detrend, "test".into(), "error (deg)", "seconds");
        s.choices = choices;
        s
    }

    fn decode(bytes: &[u8]) -> image::RgbImage {
        image::load_from_memory_with_format(bytes, image::ImageFormat::Png).unwrap().to_rgb8()
    }

    #[test]
    fn a_plot_decodes_and_has_ink() {
        let c = |s: &str, l: &str, e: f64, t: f64| {
            Choice::timed(s, l, knobs(&[("k", l.into())]), metrics(&[("error (deg)", e)]), t, 1)
        };
        let png = png(&stage(vec![c("a", "1", 2.0, 0.01), c("a", "2", 1.0, 0.1), c("b", "x", 1.5, 1.0)])).unwrap();
        let image = decode(&png);
        assert_eq!(image.dimensions(), SIZE);
        let dark = image.pixels().filter(|p| p.0.iter().all(|&v| v < 100)).count();
        assert!(dark > 2000, "{dark} dark pixels: no axes or text drawn");
    }

    #[test]
    fn log_ticks_are_one_two_five() {
        assert_eq!(ticks(0.15, 3.0), vec![0.2, 0.5, 1.0, 2.0]);
        assert!(ticks(0.0, 1.0).is_empty());
        assert_eq!(short(0.05), "0.05");
        assert_eq!(short(0.0012), "0.0012");
        assert_eq!(short(2.0), "2");
    }

    #[test]
    fn degenerate_stages_still_plot() {
        assert_eq!(decode(&png(&stage(Vec::new())).unwrap()).dimensions(), SIZE);
        let one = Choice::timed("a", "1", Vec::new(), metrics(&[("e", 0.0)]), 0.0, 1);
        assert_eq!(decode(&png(&stage(vec![one])).unwrap()).dimensions(), SIZE);
        let mut skipped = stage(Vec::new());
        skipped.skipped = Some("no GPU adapter: none found".into());
        assert_eq!(decode(&png(&skipped).unwrap()).dimensions(), SIZE);
    }
}
