//! The SVG 1.1 writer: black lines on white, one font, fixed number format, no timestamps, so
//! the same chart always gives the same bytes.
//!
//! The whole drawing is shifted by half a pixel (`translate(0.5 0.5)`): layout coordinates are
//! whole pixels, and a one-pixel line centred on a pixel edge would be smeared over two pixels.

use crate::text::{baseline, dim::*, line_height};
use crate::{Layout, Point, SvgOptions, Wire};
use sfc_model::Chart;
use std::fmt::Write;

/// Formats a coordinate: at most two decimals, no trailing zeros, never `-0` or `NaN`.
pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "0".to_string();
    }
    let s = format!("{:.2}", (v * 100.0).round() / 100.0);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" || s.is_empty() {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// Escapes text for XML content and attribute values.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            // Characters XML 1.0 does not allow.
            c if (c as u32) < 0x20 && c != '\t' && c != '\n' && c != '\r' => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

pub fn write(chart: &Chart, l: &Layout, opts: &SvgOptions) -> String {
    let fs = if opts.font_size.is_finite() && opts.font_size > 0.0 { opts.font_size } else { 12.0 };
    let lh = line_height(fs);
    let (w, h) = (num(l.width.max(1.0)), num(l.height.max(1.0)));
    let mut o = String::new();
    let _ = writeln!(o, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{w}" height="{h}" viewBox="0 0 {w} {h}">"#
    );
    let _ = writeln!(o, "<title>{}</title>", esc(&chart.pou));
    let _ = writeln!(o, r##"<rect x="0" y="0" width="{w}" height="{h}" fill="#ffffff"/>"##);
    let _ = writeln!(
        o,
        r##"<g transform="translate(0.5 0.5)" font-family="{}" font-size="{}" fill="#000000" stroke="none">"##,
        esc(&opts.font_family),
        num(fs)
    );

    // Links, action links and branch lines: one path each.
    let _ = writeln!(o, r##"<g id="links" fill="none" stroke="#000000" stroke-width="1">"##);
    for wire in &l.wires {
        if let Some(d) = path(&wire.points) {
            let _ = writeln!(o, r#"<path d="{d}"/>"#);
        }
    }
    if opts.show_actions {
        for a in &l.actions {
            let _ = writeln!(o, r#"<path d="M{} {}H{}"/>"#, num(a.link.0.x), num(a.link.0.y), num(a.link.1.x));
        }
    }
    for b in &l.branches {
        let _ = writeln!(o, r#"<path d="M{} {}H{}"/>"#, num(b.x1), num(b.y), num(b.x2));
        if b.kind.is_double() && b.y2 != b.y {
            let _ = writeln!(o, r#"<path d="M{} {}H{}"/>"#, num(b.x1), num(b.y2), num(b.x2));
        }
    }
    let _ = writeln!(o, "</g>");
    for wire in l.wires.iter().filter(|w| w.upward_arrow) {
        if let Some(d) = upward_arrow(wire) {
            let _ = writeln!(o, r#"<path class="arrow" d="{d}"/>"#);
        }
    }

    // Steps.
    let _ = writeln!(o, r#"<g id="steps">"#);
    for s in &l.steps {
        let r = s.rect;
        let _ = writeln!(o, r#"<g id="step-{}">"#, s.step);
        let _ = writeln!(o, "<title>{}</title>", esc(&s.name));
        let _ = writeln!(
            o,
            r##"<rect x="{}" y="{}" width="{}" height="{}" fill="#ffffff" stroke="#000000" stroke-width="1"/>"##,
            num(r.x),
            num(r.y),
            num(r.w),
            num(r.h)
        );
        if s.initial && r.w > 2.0 * INITIAL_INSET && r.h > 2.0 * INITIAL_INSET {
            let i = INITIAL_INSET;
            let _ = writeln!(
                o,
                r##"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="#000000" stroke-width="1"/>"##,
                num(r.x + i),
                num(r.y + i),
                num(r.w - 2.0 * i),
                num(r.h - 2.0 * i)
            );
        }
        let top = r.y + (r.h - lh) / 2.0;
        let _ = writeln!(
            o,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            num(r.x + r.w / 2.0),
            num(baseline(top, fs)),
            esc(&s.name)
        );
        let _ = writeln!(o, "</g>");
    }
    let _ = writeln!(o, "</g>");

    // Transitions.
    let _ = writeln!(o, r#"<g id="transitions">"#);
    for t in &l.transitions {
        let name = chart.transitions.get(t.transition).map(|x| x.name.as_str()).unwrap_or("");
        let bar = t.bar_rect();
        let _ = writeln!(o, r#"<g id="transition-{}">"#, t.transition);
        let _ = writeln!(o, "<title>{}</title>", esc(name));
        let _ = writeln!(
            o,
            r#"<rect x="{}" y="{}" width="{}" height="{}"/>"#,
            num(bar.x - 0.5),
            num(bar.y),
            num(bar.w + 1.0),
            num(bar.h)
        );
        if let (true, Some(r)) = (opts.show_conditions, t.condition_rect) {
            for (i, line) in t.condition.iter().enumerate() {
                let _ = writeln!(
                    o,
                    r#"<text x="{}" y="{}">{}</text>"#,
                    num(r.x),
                    num(baseline(r.y + lh * i as f64, fs)),
                    esc(line)
                );
            }
        }
        if let (true, Some(r), Some(n)) = (opts.show_transition_names, t.name_rect, &t.name) {
            let _ = writeln!(
                o,
                r#"<text x="{}" y="{}" text-anchor="end">{}</text>"#,
                num(r.right()),
                num(baseline(r.y, fs)),
                esc(n)
            );
        }
        let _ = writeln!(o, "</g>");
    }
    let _ = writeln!(o, "</g>");

    // Action blocks.
    if opts.show_actions {
        let _ = writeln!(o, r#"<g id="actions">"#);
        for a in &l.actions {
            let r = a.rect;
            let _ = writeln!(o, r#"<g id="actions-{}">"#, a.step);
            let _ = writeln!(
                o,
                r##"<rect x="{}" y="{}" width="{}" height="{}" fill="#ffffff" stroke="#000000" stroke-width="1"/>"##,
                num(r.x),
                num(r.y),
                num(r.w),
                num(r.h)
            );
            let x1 = r.x + a.qualifier_width;
            let x2 = x1 + a.action_width;
            let mut d = format!("M{} {}V{}", num(x1), num(r.y), num(r.bottom()));
            if a.indicator_width > 0.0 {
                let _ = write!(d, "M{} {}V{}", num(x2), num(r.y), num(r.bottom()));
            }
            for i in 1..a.rows.len() {
                let y = r.y + a.row_height * i as f64;
                let _ = write!(d, "M{} {}H{}", num(r.x), num(y), num(r.right()));
            }
            let _ = writeln!(o, r##"<path d="{d}" fill="none" stroke="#000000" stroke-width="1"/>"##);
            for (i, row) in a.rows.iter().enumerate() {
                let top = r.y + a.row_height * i as f64 + (a.row_height - lh) / 2.0;
                let y = num(baseline(top, fs));
                let _ = writeln!(
                    o,
                    r#"<text x="{}" y="{y}" text-anchor="middle">{}</text>"#,
                    num(r.x + a.qualifier_width / 2.0),
                    esc(&row.qualifier)
                );
                let _ = writeln!(o, r#"<text x="{}" y="{y}">{}</text>"#, num(x1 + CELL_PAD), esc(&row.action));
                if a.indicator_width > 0.0 && !row.indicator.is_empty() {
                    let _ = writeln!(o, r#"<text x="{}" y="{y}">{}</text>"#, num(x2 + CELL_PAD), esc(&row.indicator));
                }
            }
            let _ = writeln!(o, "</g>");
        }
        let _ = writeln!(o, "</g>");
    }

    // Jumps.
    let _ = writeln!(o, r#"<g id="jumps">"#);
    for j in &l.jumps {
        let _ = writeln!(o, r#"<g id="jump-{}">"#, j.transition);
        let base = j.tip.y - ARROW_LEN;
        let _ = writeln!(
            o,
            r##"<path d="M{} {}V{}" fill="none" stroke="#000000" stroke-width="1"/>"##,
            num(j.from.x),
            num(j.from.y),
            num(base)
        );
        let _ = writeln!(
            o,
            r#"<path d="M{} {}L{} {}L{} {}Z"/>"#,
            num(j.tip.x - ARROW_HALF),
            num(base),
            num(j.tip.x + ARROW_HALF),
            num(base),
            num(j.tip.x),
            num(j.tip.y)
        );
        let _ = writeln!(
            o,
            r#"<text x="{}" y="{}">{}</text>"#,
            num(j.label_rect.x),
            num(baseline(j.label_rect.y, fs)),
            esc(&j.label)
        );
        let _ = writeln!(o, "</g>");
    }
    let _ = writeln!(o, "</g>");
    let _ = writeln!(o, "</g>");
    let _ = writeln!(o, "</svg>");
    o
}

/// `M x y` followed by `H`/`V` (or `L` for a slanted segment) commands.
fn path(points: &[Point]) -> Option<String> {
    let first = points.first()?;
    let mut d = format!("M{} {}", num(first.x), num(first.y));
    let mut prev = *first;
    for p in &points[1..] {
        if (p.x - prev.x).abs() < 0.005 && (p.y - prev.y).abs() < 0.005 {
            continue;
        }
        if (p.y - prev.y).abs() < 0.005 {
            let _ = write!(d, "H{}", num(p.x));
        } else if (p.x - prev.x).abs() < 0.005 {
            let _ = write!(d, "V{}", num(p.y));
        } else {
            let _ = write!(d, "L{} {}", num(p.x), num(p.y));
        }
        prev = *p;
    }
    Some(d)
}

/// An arrowhead pointing up in the middle of the longest upward segment of the wire.
fn upward_arrow(wire: &Wire) -> Option<String> {
    let (a, b) = wire
        .points
        .windows(2)
        .map(|w| (w[0], w[1]))
        .filter(|(a, b)| (a.x - b.x).abs() < 0.005 && b.y < a.y - 2.0 * ARROW_LEN)
        .max_by(|x, y| (x.0.y - x.1.y).total_cmp(&(y.0.y - y.1.y)))?;
    let mid = ((a.y + b.y) / 2.0).round();
    let x = a.x;
    Some(format!(
        "M{} {}L{} {}L{} {}Z",
        num(x - ARROW_HALF),
        num(mid + ARROW_LEN / 2.0),
        num(x + ARROW_HALF),
        num(mid + ARROW_LEN / 2.0),
        num(x),
        num(mid - ARROW_LEN / 2.0)
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_one_format() {
        assert_eq!(num(12.0), "12");
        assert_eq!(num(12.5), "12.5");
        assert_eq!(num(-0.001), "0");
        assert_eq!(num(1.0 / 3.0), "0.33");
        assert_eq!(num(f64::NAN), "0");
        assert_eq!(num(-7.25), "-7.25");
    }

    #[test]
    fn text_is_escaped() {
        assert_eq!(esc("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &apos;d&apos;&gt;");
        assert_eq!(esc("x\u{1}y"), "x y");
    }
}
