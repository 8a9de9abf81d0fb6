//! SVG renderer: writes a laid-out [`Scene`] as hand-written SVG markup.
//!
//! Text is real `<text>` (searchable, selectable) in a monospace font sized so that one
//! character advances as far as a glyph of the PNG's 8×8 bitmap font; the layout is identical.

use std::fmt::Write;

use super::figure::Color;
use super::scene::{Anchor, Item, Scene, Stroke, Text, GLYPH_SIZE};

/// Monospace fonts advance about 0.6 em per character.
const MONOSPACE_ADVANCE_EM: f64 = 0.6;
/// Baseline below the top of the glyph box, as a share of the box height.
const BASELINE_FRACTION: f64 = 0.85;

/// The scene as a standalone SVG document.
pub(crate) fn write_svg(scene: &Scene) -> String {
    let mut out = String::with_capacity(64 * 1024);
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans Mono, Menlo, Consolas, monospace">"#,
        w = scene.width,
        h = scene.height,
    );
    let _ = writeln!(
        out,
        r#"<rect x="0" y="0" width="{}" height="{}"{}/>"#,
        scene.width,
        scene.height,
        paint("fill", scene.background),
    );
    for item in &scene.items {
        write_item(&mut out, item);
    }
    out.push_str("</svg>\n");
    out
}

fn write_item(out: &mut String, item: &Item) {
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
            let _ = write!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="{}""#,
                num(*x),
                num(*y),
                num(*width),
                num(*height),
            );
            match fill {
                Some(color) => out.push_str(&paint("fill", *color)),
                None => out.push_str(r#" fill="none""#),
            }
            if let Some(stroke) = stroke {
                out.push_str(&stroke_attributes(stroke));
            }
            if *crisp {
                out.push_str(r#" shape-rendering="crispEdges""#);
            }
            out.push_str("/>\n");
        }
        Item::Polyline { points, stroke } => {
            out.push_str(r#"<polyline points=""#);
            for (i, (x, y)) in points.iter().enumerate() {
                if i > 0 {
                    out.push(' ');
                }
                let _ = write!(out, "{},{}", num(*x), num(*y));
            }
            let _ = writeln!(
                out,
                r#"" fill="none"{} stroke-linejoin="round"/>"#,
                stroke_attributes(stroke)
            );
        }
        Item::Dot {
            x,
            y,
            radius,
            color,
        } => {
            let _ = writeln!(
                out,
                r#"<circle cx="{}" cy="{}" r="{}"{}/>"#,
                num(*x),
                num(*y),
                num(*radius),
                paint("fill", *color),
            );
        }
        Item::Text(text) => write_text(out, text),
    }
}

fn write_text(out: &mut String, text: &Text) {
    let box_height = GLYPH_SIZE * f64::from(text.scale);
    let font_size = box_height / MONOSPACE_ADVANCE_EM;
    let baseline = box_height * BASELINE_FRACTION;
    let anchor = match text.anchor {
        Anchor::Start => "start",
        Anchor::Middle => "middle",
        Anchor::End => "end",
    };
    let position = if text.vertical {
        format!(
            r#"transform="translate({},{}) rotate(-90)" x="0" y="0""#,
            num(text.x + baseline),
            num(text.y)
        )
    } else {
        format!(r#"x="{}" y="{}""#, num(text.x), num(text.y + baseline))
    };
    let _ = writeln!(
        out,
        r#"<text {position} font-size="{}" text-anchor="{anchor}"{}>{}</text>"#,
        num(font_size),
        paint("fill", text.color),
        escape_xml(&text.content),
    );
}

fn stroke_attributes(stroke: &Stroke) -> String {
    let mut s = format!(
        r#"{} stroke-width="{}""#,
        paint("stroke", stroke.color),
        num(stroke.width)
    );
    if let Some((dash, gap)) = stroke.dash {
        let _ = write!(s, r#" stroke-dasharray="{},{}""#, num(dash), num(gap));
    }
    s
}

/// ` fill="#rrggbb"` (or stroke), with an opacity attribute when the colour is translucent.
fn paint(attribute: &str, color: Color) -> String {
    let mut s = format!(
        r##" {attribute}="#{:02x}{:02x}{:02x}""##,
        color.r, color.g, color.b
    );
    if color.a != 255 {
        let _ = write!(
            s,
            r#" {attribute}-opacity="{}""#,
            num(f64::from(color.a) / 255.0)
        );
    }
    s
}

/// A coordinate with at most two decimals and no trailing zeros.
fn num(v: f64) -> String {
    if !v.is_finite() {
        return String::from("0");
    }
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        String::from("0")
    } else {
        s.to_string()
    }
}

/// Escapes the characters that XML gives meaning to, and drops those it forbids.
pub(crate) fn escape_xml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\t' | '\n' | '\r' => out.push(' '),
            c if (c as u32) < 0x20 || c == '\u{FFFE}' || c == '\u{FFFF}' => {}
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup() {
        assert_eq!(
            escape_xml(r#"a<b & "c" 'd'>"#),
            "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;"
        );
        assert_eq!(escape_xml("x\u{0}y\tz"), "xy z");
    }

    #[test]
    fn numbers_are_compact() {
        assert_eq!(num(1.0), "1");
        assert_eq!(num(1.25), "1.25");
        assert_eq!(num(-0.001), "0");
        assert_eq!(num(f64::NAN), "0");
    }
}
