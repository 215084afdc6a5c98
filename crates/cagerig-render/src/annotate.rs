//! Annotations drawn on finished pictures: text labels (an 8×8 bitmap font, Latin and Greek so
//! that Ω, Φ, Ψ print) and a colour-map legend with its end values.

use font8x8::UnicodeFonts;

use crate::image::RgbaImage;
use crate::palette::ColorMap;

const GLYPH: u32 = 8;

fn glyph(c: char) -> [u8; 8] {
    font8x8::BASIC_FONTS
        .get(c)
        .or_else(|| font8x8::GREEK_FONTS.get(c))
        .or_else(|| font8x8::LATIN_FONTS.get(c))
        .unwrap_or(font8x8::BASIC_FONTS.get('?').unwrap_or([0; 8]))
}

/// Width in pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: u32) -> u32 {
    text.chars().count() as u32 * GLYPH * scale
}

/// Draws `text` with its top-left corner at `(x, y)`, each font pixel `scale × scale`, in
/// `color` over a soft light halo so it reads on any background. Clipped to the image.
pub fn draw_text(image: &mut RgbaImage, x: u32, y: u32, text: &str, scale: u32, color: [u8; 4]) {
    let halo = [250, 250, 252, 200];
    for (pass, c) in [(0, halo), (1, color)] {
        for (k, ch) in text.chars().enumerate() {
            let rows = glyph(ch);
            for (row, bits) in rows.iter().enumerate() {
                for col in 0..GLYPH {
                    if bits >> col & 1 == 0 {
                        continue;
                    }
                    let px = x + (k as u32 * GLYPH + col) * scale;
                    let py = y + row as u32 * scale;
                    if pass == 0 {
                        // The halo: the glyph pixel grown by one font pixel.
                        let grow = scale as i64;
                        image.fill_rect(
                            px as i64 - grow,
                            py as i64 - grow,
                            3 * scale,
                            3 * scale,
                            c,
                        );
                    } else {
                        image.fill_rect(px as i64, py as i64, scale, scale, c);
                    }
                }
            }
        }
    }
}

/// A ring of outer radius `radius` and width `width` pixels centred on `(cx, cy)` in `color`,
/// over a dark outline one pixel wider on each side (it reads on light and dark backgrounds):
/// the mark of a cage vertex an edit moved. Clipped to the image.
pub fn draw_ring(image: &mut RgbaImage, cx: f64, cy: f64, radius: f64, width: f64, color: [u8; 4]) {
    let outline = [40, 10, 40, 255];
    let reach = (radius + 2.0).ceil() as i64;
    let (x0, y0) = (cx.floor() as i64, cy.floor() as i64);
    for y in y0 - reach..=y0 + reach {
        for x in x0 - reach..=x0 + reach {
            let d = ((x as f64 + 0.5 - cx).powi(2) + (y as f64 + 0.5 - cy).powi(2)).sqrt();
            if d <= radius && d >= radius - width {
                image.fill_rect(x, y, 1, 1, color);
            } else if d <= radius + 1.0 && d >= radius - width - 1.0 {
                image.fill_rect(x, y, 1, 1, outline);
            }
        }
    }
}

/// A vertical colour bar `width × height` at `(x, y)` from `lo` (bottom) to `hi` (top), with
/// the end values (and 0 for a diverging map) written to its right, and `title` above it.
#[expect(clippy::too_many_arguments)]
pub fn draw_legend(
    image: &mut RgbaImage,
    map: ColorMap,
    x: u32,
    y: u32,
    width: u32,
    height: u32,
    scale: u32,
    title: &str,
) {
    let (lo, hi) = match map {
        ColorMap::Sequential { lo, hi } => (lo, hi),
        ColorMap::Diverging { limit } => (-limit, limit),
    };
    let ink = [30, 32, 38, 255];
    draw_text(image, x, y, title, scale, ink);
    let top = legend_bar_top(y, scale);
    image.fill_rect(x as i64 - 1, top as i64 - 1, width + 2, height + 2, ink);
    for row in 0..height {
        let t = 1.0 - row as f64 / (height.max(2) - 1) as f64;
        let color = map.color_u8(lo + t * (hi - lo));
        image.fill_rect(x as i64, (top + row) as i64, width, 1, color);
    }
    let label_x = x + width + 3 * scale;
    let half = GLYPH * scale / 2;
    draw_text(
        image,
        label_x,
        top.saturating_sub(half),
        &format_value(hi),
        scale,
        ink,
    );
    draw_text(
        image,
        label_x,
        (top + height).saturating_sub(half),
        &format_value(lo),
        scale,
        ink,
    );
    if matches!(map, ColorMap::Diverging { .. }) {
        draw_text(
            image,
            label_x,
            (top + height / 2).saturating_sub(half),
            "0",
            scale,
            ink,
        );
    }
}

/// Where a legend's colour bar starts below its title at `y`: far enough that the top value,
/// written centred on the bar's top edge, clears the title and its halo.
pub fn legend_bar_top(y: u32, scale: u32) -> u32 {
    y + (GLYPH + 4) * scale + GLYPH * scale / 2
}

/// Width in pixels of a legend drawn by [`draw_legend`] for `map` with a bar `width` wide:
/// the title or the bar and its widest value label, whichever is wider.
pub fn legend_width(map: ColorMap, title: &str, width: u32, scale: u32) -> u32 {
    let (lo, hi) = match map {
        ColorMap::Sequential { lo, hi } => (lo, hi),
        ColorMap::Diverging { limit } => (-limit, limit),
    };
    let labels = text_width(&format_value(lo), scale).max(text_width(&format_value(hi), scale));
    text_width(title, scale).max(width + 3 * scale + labels)
}

/// `text` split at spaces into lines at most `max_width` pixels wide at `scale` (a word longer
/// than a line gets a line of its own, clipped when drawn).
pub fn wrap_text(text: &str, max_width: u32, scale: u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let candidate = if line.is_empty() {
            word.to_string()
        } else {
            format!("{line} {word}")
        };
        if !line.is_empty() && text_width(&candidate, scale) > max_width {
            lines.push(std::mem::replace(&mut line, word.to_string()));
        } else {
            line = candidate;
        }
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

/// A short label for a legend value: up to 3 significant digits.
pub fn format_value(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if v.abs() >= 1e-3 && v.abs() < 1e4 {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    } else {
        format!("{v:.2e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blank(w: u32, h: u32) -> RgbaImage {
        RgbaImage::new(w, h, vec![255; (w * h * 4) as usize])
    }

    #[test]
    fn text_marks_pixels_in_its_box_only_and_clips_at_the_border() {
        let mut image = blank(64, 32);
        draw_text(&mut image, 4, 4, "Ω1", 2, [0, 0, 0, 255]);
        let dark = |x, y| image.pixel(x, y)[0] < 50;
        let inside = (4..36)
            .flat_map(|x| (4..20).map(move |y| (x, y)))
            .filter(|&(x, y)| dark(x, y))
            .count();
        assert!(inside > 20, "{inside} glyph pixels");
        assert!(!(40..64).any(|x| (0..32).any(|y| dark(x, y))));
        assert_eq!(text_width("Ω1", 2), 32);
        // Drawing past the edges must not panic.
        draw_text(&mut image, 60, 30, "clipped", 3, [0, 0, 0, 255]);
    }

    #[test]
    fn legend_runs_from_the_low_colour_at_the_bottom_to_the_high_colour_at_the_top() {
        let mut image = blank(120, 140);
        let map = ColorMap::Sequential { lo: 0.0, hi: 1.0 };
        draw_legend(&mut image, map, 10, 10, 12, 100, 1, "w");
        let top = legend_bar_top(10, 1);
        assert_eq!(image.pixel(15, top), map.color_u8(1.0));
        assert_eq!(image.pixel(15, top + 99), map.color_u8(0.0));
    }

    #[test]
    fn the_legend_top_value_clears_the_title() {
        // A diverging Φ legend as `render --color-by cage-vertex:K` draws it, at scale 2.
        let (scale, y) = (2, 10);
        let mut image = blank(240, 300);
        let map = ColorMap::Diverging { limit: 0.013 };
        draw_legend(&mut image, map, 20, y, 12, 200, scale, "Φ cage vertex 20");
        let top = legend_bar_top(y, scale);
        // The title's glyphs and halo end at y + (8 + 1)·scale; the value label "0.013"
        // (centred on the bar's top edge, with its halo) starts below that.
        let title_bottom = y + (GLYPH + 1) * scale;
        let label_top = top - GLYPH * scale / 2 - scale;
        assert!(label_top >= title_bottom, "{label_top} < {title_bottom}");
        // Nothing is drawn in the blank row between them, right of the bar.
        let label_x = 20 + 12 + 3 * scale;
        let row_has_ink = |row: u32| {
            (label_x..label_x + text_width("0.013", scale)).any(|x| image.pixel(x, row)[0] < 200)
        };
        assert!(!(title_bottom..label_top).any(row_has_ink));
        assert!(legend_width(map, "Φ", 12, scale) >= 12 + 3 * scale + text_width("-0.013", scale));
    }

    #[test]
    fn a_ring_marks_its_circle_and_leaves_its_centre() {
        let mut image = blank(40, 40);
        draw_ring(&mut image, 20.0, 20.0, 8.0, 3.0, [200, 20, 160, 255]);
        assert_eq!(image.pixel(20, 13), [200, 20, 160, 255]);
        assert_eq!(image.pixel(20, 20), [255, 255, 255, 255]);
        assert_eq!(image.pixel(2, 2), [255, 255, 255, 255]);
        // Past the edges: clipped, no panic.
        draw_ring(&mut image, 39.0, 0.0, 8.0, 3.0, [200, 20, 160, 255]);
    }

    #[test]
    fn captions_wrap_at_spaces_within_the_width() {
        let text = "move rest-cage vertices 0, 2, 4, 5, 6 by [0.2, -0.1, 0.15]";
        let lines = wrap_text(text, 160, 1);
        assert!(lines.len() > 1, "{lines:?}");
        assert!(lines.iter().all(|l| text_width(l, 1) <= 160), "{lines:?}");
        assert_eq!(lines.join(" "), text);
        assert_eq!(wrap_text("", 100, 1), Vec::<String>::new());
    }

    #[test]
    fn values_are_short() {
        assert_eq!(format_value(1.0), "1");
        assert_eq!(format_value(-0.25), "-0.25");
        assert_eq!(format_value(0.0), "0");
        assert_eq!(format_value(1.23456e-5), "1.23e-5");
    }
}
