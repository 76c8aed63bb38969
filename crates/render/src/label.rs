//! Labels drawn into figure panels: a line of text in white on a dark box, in the bundled font
//! (`assets/DejaVuSans-Bold-ascii.ttf`, DejaVu Sans Bold cut down to printable ASCII; its licence
//! is beside it). Characters outside printable ASCII are drawn as `?`.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont, point};

/// The bundled font file.
const FONT: &[u8] = include_bytes!("../assets/DejaVuSans-Bold-ascii.ttf");

/// An 8-bit RGB image, row major, row 0 at the top.
pub struct RgbImage<'a> {
    /// `3 * width * height` bytes.
    pub pixels: &'a mut [u8],
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
}

/// Draws `text` with its top-left corner at `(x, y)`, `size` pixels tall, white over a box that
/// darkens what is behind it to a quarter; whatever falls outside the image is clipped. Returns
/// the box's width and height.
pub fn draw_label(image: &mut RgbImage<'_>, x: usize, y: usize, text: &str, size: f32) -> (usize, usize) {
    let font = FontRef::try_from_slice(FONT).expect("the bundled font parses");
    let scale = PxScale::from(size.max(1.0));
    let scaled = font.as_scaled(scale);
    let text: String = text.chars().map(|c| if (' '..='~').contains(&c) { c } else { '?' }).collect();
    let pad = (size * 0.3).ceil() as usize;
    let width: f32 = text.chars().map(|c| scaled.h_advance(scaled.glyph_id(c))).sum();
    let (box_w, box_h) = (width.ceil() as usize + 2 * pad, scaled.height().ceil() as usize + 2 * pad);
    for row in y..(y + box_h).min(image.height) {
        for col in x..(x + box_w).min(image.width) {
            let i = 3 * (row * image.width + col);
            for c in &mut image.pixels[i..i + 3] {
                *c /= 4;
            }
        }
    }
    let mut caret = point((x + pad) as f32, (y + pad) as f32 + scaled.ascent());
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(previous) = previous {
            caret.x += scaled.kern(previous, id);
        }
        previous = Some(id);
        let glyph = id.with_scale_and_position(scale, caret);
        caret.x += scaled.h_advance(id);
        let Some(outline) = font.outline_glyph(glyph) else { continue };
        let bounds = outline.px_bounds();
        outline.draw(|gx, gy, coverage| {
            let (px, py) = (bounds.min.x as i64 + gx as i64, bounds.min.y as i64 + gy as i64);
            if px < 0 || py < 0 || px as usize >= image.width || py as usize >= image.height {
                return;
            }
            let i = 3 * (py as usize * image.width + px as usize);
            let a = coverage.clamp(0.0, 1.0);
            for c in &mut image.pixels[i..i + 3] {
                *c = (*c as f32 * (1.0 - a) + 255.0 * a).round() as u8;
            }
        });
    }
    (box_w, box_h)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(width: usize, height: usize) -> Vec<u8> {
        vec![128; 3 * width * height]
    }

    #[test]
    fn a_label_draws_white_text_inside_its_box_only() {
        let (w, h) = (200, 60);
        let mut pixels = grey(w, h);
        let (bw, bh) = draw_label(&mut RgbImage { pixels: &mut pixels, width: w, height: h }, 10, 5, "LUT 256", 20.0);
        assert!(bw > 60 && bw < 190 && bh > 20 && bh < 40, "{bw}x{bh}");
        let at = |x: usize, y: usize| pixels[3 * (y * w + x)];
        let inside: Vec<u8> =
            (5..5 + bh).flat_map(|y| (10..10 + bw).map(move |x| (x, y))).map(|(x, y)| at(x, y)).collect();
        assert!(inside.iter().any(|&v| v > 240), "white text");
        assert!(inside.contains(&32), "the darkened box");
        for (x, y) in [(5, 5), (10 + bw + 2, 10), (20, 5 + bh + 2)] {
            assert_eq!(at(x, y), 128, "({x}, {y}) is outside the box");
        }
    }

    #[test]
    fn labels_clip_at_the_edges_and_take_any_text() {
        let (w, h) = (40, 20);
        let mut pixels = grey(w, h);
        let mut image = RgbImage { pixels: &mut pixels, width: w, height: h };
        draw_label(&mut image, 30, 15, "a long label past the corner", 16.0);
        draw_label(&mut image, 0, 0, "Größe 1/r", 12.0);
        draw_label(&mut image, 0, 0, "", 0.0);
    }
}
