//! PNG renderer: rasterises a laid-out [`Scene`] with tiny-skia (anti-aliased shapes) and
//! draws text from the public-domain 8×8 bitmap font, so no system font is needed.

use font8x8::{UnicodeFonts, BASIC_FONTS, BOX_FONTS, GREEK_FONTS, LATIN_FONTS, MISC_FONTS};
use tiny_skia::{
    FillRule, LineCap, LineJoin, Paint, PathBuilder, Pixmap, PremultipliedColorU8, Rect,
    StrokeDash, Transform,
};

use super::figure::Color;
use super::scene::{text_width, Item, Scene, Stroke, Text, GLYPH_SIZE};
use super::PlotError;

/// The scene as PNG file bytes.
pub(crate) fn encode_png(scene: &Scene) -> Result<Vec<u8>, PlotError> {
    let mut pixmap = Pixmap::new(scene.width, scene.height).ok_or(PlotError::Canvas {
        width: scene.width,
        height: scene.height,
    })?;
    pixmap.fill(skia_color(scene.background));
    for item in &scene.items {
        draw_item(&mut pixmap, item);
    }
    pixmap
        .encode_png()
        .map_err(|e| PlotError::PngEncode(e.to_string()))
}

fn skia_color(color: Color) -> tiny_skia::Color {
    tiny_skia::Color::from_rgba8(color.r, color.g, color.b, color.a)
}

fn paint_of(color: Color, anti_alias: bool) -> Paint<'static> {
    let mut paint = Paint::default();
    paint.set_color(skia_color(color));
    paint.anti_alias = anti_alias;
    paint
}

fn skia_stroke(stroke: &Stroke) -> tiny_skia::Stroke {
    tiny_skia::Stroke {
        width: stroke.width as f32,
        line_cap: LineCap::Butt,
        line_join: LineJoin::Round,
        dash: stroke
            .dash
            .and_then(|(dash, gap)| StrokeDash::new(vec![dash as f32, gap as f32], 0.0)),
        ..tiny_skia::Stroke::default()
    }
}

fn draw_item(pixmap: &mut Pixmap, item: &Item) {
    match item {
        Item::Rect {
            x,
            y,
            width,
            height,
            fill,
            stroke,
            crisp,
        } => {
            let Some(rect) = Rect::from_xywh(*x as f32, *y as f32, *width as f32, *height as f32)
            else {
                return;
            };
            if let Some(color) = fill {
                pixmap.fill_rect(rect, &paint_of(*color, !crisp), Transform::identity(), None);
            }
            if let Some(stroke) = stroke {
                let path = PathBuilder::from_rect(rect);
                pixmap.stroke_path(
                    &path,
                    &paint_of(stroke.color, true),
                    &skia_stroke(stroke),
                    Transform::identity(),
                    None,
                );
            }
        }
        Item::Polyline { points, stroke } => {
            let mut builder = PathBuilder::with_capacity(points.len(), points.len());
            for (i, &(x, y)) in points.iter().enumerate() {
                if i == 0 {
                    builder.move_to(x as f32, y as f32);
                } else {
                    builder.line_to(x as f32, y as f32);
                }
            }
            if let Some(path) = builder.finish() {
                pixmap.stroke_path(
                    &path,
                    &paint_of(stroke.color, true),
                    &skia_stroke(stroke),
                    Transform::identity(),
                    None,
                );
            }
        }
        Item::Dot {
            x,
            y,
            radius,
            color,
        } => {
            if let Some(path) = PathBuilder::from_circle(*x as f32, *y as f32, *radius as f32) {
                pixmap.fill_path(
                    &path,
                    &paint_of(*color, true),
                    FillRule::Winding,
                    Transform::identity(),
                    None,
                );
            }
        }
        Item::Text(text) => draw_text(pixmap, text),
    }
}

/// The 8×8 bitmap of `c`: each byte is a row, top first, least significant bit leftmost.
/// Characters the font lacks are replaced by a look-alike or `?`.
fn glyph(c: char) -> [u8; 8] {
    let c = match c {
        '\u{2010}'..='\u{2015}' | '\u{2212}' => '-',
        '\u{2018}' | '\u{2019}' => '\'',
        '\u{201C}' | '\u{201D}' => '"',
        '\u{2009}' | '\u{202F}' | '\u{00A0}' => ' ',
        c => c,
    };
    BASIC_FONTS
        .get(c)
        .or_else(|| LATIN_FONTS.get(c))
        .or_else(|| GREEK_FONTS.get(c))
        .or_else(|| MISC_FONTS.get(c))
        .or_else(|| BOX_FONTS.get(c))
        .or_else(|| BASIC_FONTS.get('?'))
        .unwrap_or([0; 8])
}

/// Draws a line of text glyph by glyph, each set font pixel a `scale`×`scale` block.
fn draw_text(pixmap: &mut Pixmap, text: &Text) {
    let scale = i64::from(text.scale.max(1));
    let advance = (GLYPH_SIZE as i64) * scale;
    let before_anchor = text_width(&text.content, text.scale) * text.anchor.offset_fraction();
    let (width, height) = (i64::from(pixmap.width()), i64::from(pixmap.height()));
    let pixels = pixmap.pixels_mut();
    let mut put = |x: i64, y: i64| {
        if (0..width).contains(&x) && (0..height).contains(&y) {
            let index = (y * width + x) as usize;
            if let Some(pixel) = pixels.get_mut(index) {
                *pixel = blend(*pixel, text.color);
            }
        }
    };
    // Position of glyph-space pixel (u along the line, v down the glyph) on the canvas.
    let origin_along = if text.vertical {
        (text.y + before_anchor).round() as i64
    } else {
        (text.x - before_anchor).round() as i64
    };
    let origin_across = if text.vertical {
        text.x.round() as i64
    } else {
        text.y.round() as i64
    };
    for (i, c) in text.content.chars().enumerate() {
        let bitmap = glyph(c);
        let glyph_start = i as i64 * advance;
        for (row, bits) in bitmap.iter().enumerate() {
            for column in 0..8 {
                if bits & (1 << column) == 0 {
                    continue;
                }
                for dv in 0..scale {
                    for du in 0..scale {
                        let u = glyph_start + column * scale + du;
                        let v = row as i64 * scale + dv;
                        if text.vertical {
                            put(origin_across + v, origin_along - 1 - u);
                        } else {
                            put(origin_along + u, origin_across + v);
                        }
                    }
                }
            }
        }
    }
}

/// `color` painted over a premultiplied pixel (source-over).
fn blend(under: PremultipliedColorU8, color: Color) -> PremultipliedColorU8 {
    let alpha = u32::from(color.a);
    let keep = 255 - alpha;
    let mix = |src: u8, dst: u8| -> u8 {
        let src = u32::from(src) * alpha / 255;
        (src + u32::from(dst) * keep / 255).min(255) as u8
    };
    let a = (alpha + u32::from(under.alpha()) * keep / 255).min(255) as u8;
    let (r, g, b) = (
        mix(color.r, under.red()).min(a),
        mix(color.g, under.green()).min(a),
        mix(color.b, under.blue()).min(a),
    );
    PremultipliedColorU8::from_rgba(r, g, b, a).unwrap_or(under)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glyphs_fall_back() {
        assert_ne!(glyph('A'), [0; 8]);
        assert_ne!(glyph('×'), glyph('?'));
        assert_ne!(glyph('±'), glyph('?'));
        assert_eq!(glyph('–'), glyph('-'));
        assert_eq!(glyph('\u{1F600}'), glyph('?'));
    }

    #[test]
    fn blending_opaque_replaces() {
        let white = PremultipliedColorU8::from_rgba(255, 255, 255, 255).unwrap();
        let out = blend(white, Color::rgb(10, 20, 30));
        assert_eq!(
            (out.red(), out.green(), out.blue(), out.alpha()),
            (10, 20, 30, 255)
        );
    }
}
