//! A document drawn as a standalone SVG 1.1 file, the way the canvas draws it
//! (`web/src/diagram/render/SfcRenderer.ts`): `sfc build --target svg` and the editor's
//! *Export SVG* show the same drawing, on the same layout. The view box holds every block,
//! label and wire with a margin, left-hand labels included.

use crate::drawing::{self, action_columns, labels, labels_of, name_with_tag, qualifier_text, LabelKind, Rect, LINE_H};
use crate::layout::{pin_pos, BAR_PAD};
use crate::{EditorDoc, Element, ElementKind, Point};
use std::fmt::Write;

const INK: &str = "#1e293b";
const PAPER: &str = "#ffffff";
const FONT: &str = "'DejaVu Sans', 'Segoe UI', 'Noto Sans', Roboto, Helvetica, Arial, sans-serif";
const MONO: &str = "'DejaVu Sans Mono', 'Cascadia Mono', Consolas, monospace";
const MARGIN: f64 = 20.0;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn n(v: f64) -> String {
    let r = (v * 100.0).round() / 100.0;
    if r == r.trunc() {
        format!("{}", r as i64)
    } else {
        format!("{r}")
    }
}

/// The polyline of connection `c` as drawn: its bends, or straight from pin to pin.
fn wire_points(doc: &EditorDoc, c: &crate::Connection) -> Option<Vec<Point>> {
    if c.waypoints.len() >= 2 {
        return Some(c.waypoints.clone());
    }
    let s = doc.elements.iter().find(|e| e.id == c.source)?;
    let t = doc.elements.iter().find(|e| e.id == c.target)?;
    Some(vec![pin_pos(s, false, c.source_pin), pin_pos(t, true, c.target_pin)])
}

/// The area the drawing covers: blocks, labels and wires.
pub fn bounds(doc: &EditorDoc) -> Rect {
    let (mut x0, mut y0, mut x1, mut y1) = (f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    let mut add = |r: Rect| {
        x0 = x0.min(r.x);
        y0 = y0.min(r.y);
        x1 = x1.max(r.right());
        y1 = y1.max(r.bottom());
    };
    for e in doc.elements.iter().filter(|e| e.kind.is_some()) {
        add(Rect { x: e.x, y: e.y - 8.0, w: e.w, h: e.h + 8.0 });
    }
    for l in labels(doc) {
        add(l.rect);
    }
    for c in &doc.connections {
        for p in wire_points(doc, c).unwrap_or_default() {
            add(Rect { x: p.x - 1.0, y: p.y - 1.0, w: 2.0, h: 2.0 });
        }
    }
    if !x0.is_finite() {
        return Rect { x: 0.0, y: 0.0, w: 100.0, h: 100.0 };
    }
    Rect { x: x0, y: y0, w: x1 - x0, h: y1 - y0 }
}

/// The document as a standalone SVG file.
pub fn svg(doc: &EditorDoc) -> String {
    let b = bounds(doc);
    let (x, y) = ((b.x - MARGIN).floor(), (b.y - MARGIN).floor());
    let (w, h) = ((b.w + 2.0 * MARGIN).ceil(), (b.h + 2.0 * MARGIN).ceil());
    let mut out = String::new();
    let _ = writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" viewBox="{} {} {} {}" width="{}" height="{}" font-family="{}" font-size="12">"#,
        n(x),
        n(y),
        n(w),
        n(h),
        n(w),
        n(h),
        esc(FONT)
    );
    let _ = writeln!(out, "<title>{}</title>", esc(&doc.pou));
    let _ = writeln!(out, r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{PAPER}"/>"#, n(x), n(y), n(w), n(h));
    // Wires under the blocks, as on the canvas.
    for c in &doc.connections {
        let Some(points) = wire_points(doc, c) else { continue };
        let list: Vec<String> = points.iter().map(|p| format!("{},{}", n(p.x), n(p.y))).collect();
        let colour = c.color.as_deref().unwrap_or(INK);
        let _ = writeln!(
            out,
            r#"<polyline data-id="{}" points="{}" fill="none" stroke="{}" stroke-width="{}"/>"#,
            esc(&c.id),
            list.join(" "),
            esc(colour),
            n(c.line_width.unwrap_or(1.5))
        );
        // A wired input pin is an arrow (seed 001 §7.3).
        if let Some(p) = points.last() {
            let _ = writeln!(
                out,
                r#"<polygon points="{},{} {},{} {},{}" fill="{INK}"/>"#,
                n(p.x - 4.0),
                n(p.y - 7.0),
                n(p.x + 4.0),
                n(p.y - 7.0),
                n(p.x),
                n(p.y)
            );
        }
    }
    for (i, e) in doc.elements.iter().enumerate() {
        let _ = writeln!(out, r#"<g data-id="{}">"#, esc(&e.id));
        if !e.description.is_empty() {
            let _ = writeln!(out, "<title>{}</title>", esc(&e.description));
        }
        block(&mut out, doc, e, i);
        out.push_str("</g>\n");
    }
    out.push_str("</svg>\n");
    out
}

fn text(out: &mut String, x: f64, y: f64, s: &str, attrs: &str) {
    let _ = writeln!(out, r#"<text x="{}" y="{}" dominant-baseline="central" {attrs}>{}</text>"#, n(x), n(y), esc(s));
}

fn block(out: &mut String, doc: &EditorDoc, e: &Element, i: usize) {
    let fg = e.foreground.as_deref().unwrap_or(INK);
    let lw = e.line_width.unwrap_or(1.5);
    match e.kind {
        Some(ElementKind::Step) => {
            let bg = e.background.as_deref().unwrap_or(PAPER);
            let _ = writeln!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{}" stroke="{}" stroke-width="{}"/>"#,
                n(e.x),
                n(e.y),
                n(e.w),
                n(e.h),
                esc(bg),
                esc(fg),
                n(lw)
            );
            if e.initial {
                let inset = 3.0 + lw;
                let _ = writeln!(
                    out,
                    r#"<rect x="{}" y="{}" width="{}" height="{}" fill="none" stroke="{}" stroke-width="{}"/>"#,
                    n(e.x + inset),
                    n(e.y + inset),
                    n((e.w - 2.0 * inset).max(0.0)),
                    n((e.h - 2.0 * inset).max(0.0)),
                    esc(fg),
                    n(lw)
                );
            }
            let cy = if e.timeout.is_some() { e.y + e.h / 2.0 - 5.0 } else { e.y + e.h / 2.0 };
            let attrs = format!(r#"text-anchor="middle" font-weight="600" fill="{}""#, esc(fg));
            text(out, e.x + e.w / 2.0, cy, &name_with_tag(e), &attrs);
            if let Some(t) = &e.timeout {
                let attrs = format!(r#"text-anchor="middle" font-size="10" opacity="0.75" fill="{}""#, esc(fg));
                text(out, e.x + e.w / 2.0, cy + 12.0, t, &attrs);
            }
            // S7-GRAPH's interlock (C) and supervision (V), on the step's left side.
            for (k, (mark, condition)) in drawing::step_marks(e).into_iter().enumerate() {
                let (x, y) = (e.x - drawing::MARK - 2.0, e.y + 2.0 + k as f64 * (drawing::MARK + 2.0));
                let _ = writeln!(
                    out,
                    r#"<g><title>{}: {}</title><rect x="{}" y="{}" width="{}" height="{}" fill="{}" stroke="{}" stroke-width="1"/>"#,
                    if mark == "C" { "interlock" } else { "supervision" },
                    esc(&condition),
                    n(x),
                    n(y),
                    n(drawing::MARK),
                    n(drawing::MARK),
                    PAPER,
                    esc(fg)
                );
                let attrs = format!(r#"text-anchor="middle" font-size="10" font-weight="600" fill="{}""#, esc(fg));
                text(out, x + drawing::MARK / 2.0, y + drawing::MARK / 2.0, mark, &attrs);
                out.push_str("</g>\n");
            }
        }
        Some(ElementKind::Transition) => {
            let (cx, cy) = (e.x + e.w / 2.0, e.y + e.h / 2.0);
            let _ = writeln!(
                out,
                r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="{}"/>"#,
                n(cx),
                n(e.y),
                n(cx),
                n(e.y + e.h),
                esc(fg),
                n(lw)
            );
            let half = drawing::BAR_HALF;
            let _ = writeln!(
                out,
                r#"<rect x="{}" y="{}" width="{}" height="4" fill="{}"/>"#,
                n(cx - half),
                n(cy - 2.0),
                n(2.0 * half),
                esc(e.background.as_deref().unwrap_or(fg))
            );
            for l in labels_of(e, i) {
                match l.kind {
                    LabelKind::Condition => {
                        for (k, line) in l.lines.iter().enumerate() {
                            let attrs = format!(r#"font-family="{}" fill="{}""#, esc(MONO), esc(fg));
                            text(out, l.rect.x, l.rect.y + LINE_H / 2.0 + k as f64 * LINE_H, line, &attrs);
                        }
                    }
                    _ => {
                        let opacity = if l.rect.x < cx { r#" opacity="0.75""# } else { "" };
                        let attrs = format!(r#"text-anchor="end" fill="{}"{opacity}"#, esc(fg));
                        text(out, l.rect.right(), cy, &l.lines[0], &attrs);
                    }
                }
            }
        }
        Some(
            k @ (ElementKind::SelectionDivergence
            | ElementKind::SelectionConvergence
            | ElementKind::SimultaneousDivergence
            | ElementKind::SimultaneousConvergence),
        ) => {
            let cy = e.y + e.h / 2.0;
            let double = matches!(k, ElementKind::SimultaneousDivergence | ElementKind::SimultaneousConvergence);
            let lines: Vec<f64> = if double { vec![cy - 2.0, cy + 2.0] } else { vec![cy] };
            for ly in &lines {
                let _ = writeln!(
                    out,
                    r#"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="{}" stroke-width="{}"/>"#,
                    n(e.x),
                    n(*ly),
                    n(e.x + e.w),
                    n(*ly),
                    esc(fg),
                    n(lw)
                );
            }
            let (ins, outs) = crate::graph::pin_counts(e);
            for k in 0..ins {
                let p = pin_pos(e, true, k);
                let _ = writeln!(
                    out,
                    r#"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="{3}" stroke-width="1.5"/>"#,
                    n(p.x),
                    n(e.y),
                    n(lines[0]),
                    esc(fg)
                );
            }
            for k in 0..outs {
                let p = pin_pos(e, false, k);
                let last = lines[lines.len() - 1];
                let _ = writeln!(
                    out,
                    r#"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="{3}" stroke-width="1.5"/>"#,
                    n(p.x),
                    n(last),
                    n(e.y + e.h),
                    esc(fg)
                );
            }
            let _ = BAR_PAD;
        }
        Some(ElementKind::Jump) => {
            let cx = e.x + e.w / 2.0;
            let mid = e.y + e.h * 0.4;
            let _ = writeln!(
                out,
                r#"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="{3}" stroke-width="{4}"/>"#,
                n(cx),
                n(e.y),
                n(mid),
                esc(fg),
                n(lw)
            );
            let _ = writeln!(
                out,
                r#"<polygon points="{},{} {},{} {},{}" fill="{}"/>"#,
                n(e.x),
                n(mid),
                n(e.x + e.w),
                n(mid),
                n(cx),
                n(e.y + e.h),
                esc(e.background.as_deref().unwrap_or(fg))
            );
            for l in labels_of(e, i) {
                let attrs = format!(r#"font-weight="600" fill="{}""#, esc(fg));
                text(out, l.rect.x, l.rect.y + LINE_H / 2.0, &l.lines[0], &attrs);
            }
        }
        Some(ElementKind::Text) => {
            let _ = writeln!(
                out,
                r##"<rect x="{}" y="{}" width="{}" height="{}" fill="{}" stroke="#a3a3a3" stroke-dasharray="4 2"/>"##,
                n(e.x),
                n(e.y),
                n(e.w),
                n(e.h),
                esc(e.background.as_deref().unwrap_or("#fefce8"))
            );
            let fill = esc(e.foreground.as_deref().unwrap_or("#334155"));
            for (k, line) in e.text.as_deref().unwrap_or("").lines().enumerate() {
                let y = e.y + 5.0 + 8.0 + k as f64 * 16.0;
                if y > e.y + e.h {
                    break;
                }
                text(out, e.x + 5.0, y, line, &format!(r#"fill="{fill}""#));
            }
        }
        Some(ElementKind::ActionBlock) => action_block(out, doc, e, fg),
        None => {}
    }
}

fn action_block(out: &mut String, doc: &EditorDoc, e: &Element, fg: &str) {
    let rows = &e.associations;
    let count = rows.len().max(1) as f64;
    let row_h = e.h / count;
    let fg = esc(fg);
    if let Some(step) = e.step.as_ref().and_then(|s| doc.elements.iter().find(|x| &x.id == s)) {
        let (sx, sy) = (step.x + step.w, step.y + step.h / 2.0);
        let ty = e.y + row_h / 2.0;
        if sx < e.x {
            let mx = (sx + e.x) / 2.0;
            let _ = writeln!(
                out,
                r#"<polyline points="{},{} {},{} {},{} {},{}" fill="none" stroke="{fg}" stroke-width="1.5"/>"#,
                n(sx),
                n(sy),
                n(mx),
                n(sy),
                n(mx),
                n(ty),
                n(e.x),
                n(ty)
            );
        }
    }
    let lw = n(e.line_width.unwrap_or(1.0));
    let _ = writeln!(
        out,
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="{}" stroke="{fg}" stroke-width="{lw}"/>"#,
        n(e.x),
        n(e.y),
        n(e.w),
        n(e.h),
        esc(e.background.as_deref().unwrap_or(PAPER))
    );
    let (q, _, ind) = action_columns(rows);
    let q = q.min(e.w - 40.0).max(0.0);
    let iw = ind.min((e.w - q - 40.0).max(0.0));
    let _ = writeln!(
        out,
        r#"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="{fg}" stroke-width="{lw}"/>"#,
        n(e.x + q),
        n(e.y),
        n(e.y + e.h)
    );
    if iw > 0.0 {
        let xi = e.x + e.w - iw;
        let _ = writeln!(
            out,
            r#"<line x1="{0}" y1="{1}" x2="{0}" y2="{2}" stroke="{fg}" stroke-width="{lw}"/>"#,
            n(xi),
            n(e.y),
            n(e.y + e.h)
        );
    }
    for (k, r) in rows.iter().enumerate() {
        let top = e.y + k as f64 * row_h;
        let cy = top + row_h / 2.0;
        if k > 0 {
            let _ = writeln!(
                out,
                r#"<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="{fg}" stroke-width="{lw}"/>"#,
                n(e.x),
                n(top),
                n(e.x + e.w)
            );
        }
        text(
            out,
            e.x + q / 2.0,
            cy,
            &qualifier_text(r),
            &format!(r#"text-anchor="middle" font-weight="600" fill="{fg}""#),
        );
        text(out, e.x + q + 5.0, cy, &r.action, &format!(r#"fill="{fg}""#));
        if let Some(ind) = r.indicator.as_deref().filter(|i| !i.is_empty()) {
            text(out, e.x + e.w - iw / 2.0, cy, ind, &format!(r#"text-anchor="middle" fill="{fg}""#));
        }
    }
}
