//! How the canvas draws a document's texts: block sizes that fit their text, and where the
//! labels outside the blocks go (a transition's condition right of its bar and its name left of
//! it, a jump's target right of its arrow). `web/src/diagram/render/SfcRenderer.ts` draws them
//! at exactly these places, the layout keeps them clear of other blocks and labels, and the
//! SVG of a document (`sfc build --target svg`) is drawn from the same geometry.
//!
//! Widths are estimated from the characters (DejaVu Sans advances for names, a fixed advance
//! for the monospaced conditions), never measured, so the layout is the same everywhere.

use crate::{Association, EditorDoc, Element, ElementKind};

/// Label font size (names, conditions, action rows).
pub const FONT: f64 = 12.0;
/// Height of one label line.
pub const LINE_H: f64 = 14.0;
/// Advance of one character of the monospaced condition font (DejaVu Sans Mono: 1233/2048 em).
pub const MONO_ADVANCE: f64 = FONT * 1233.0 / 2048.0;
/// Bold text (step names, jump targets) is this much wider than regular text.
pub const BOLD: f64 = 1.2;
/// Characters of a condition line before it wraps (about 230 px at 12 px).
pub const CONDITION_CHARS: usize = 32;
/// Half the drawn transition bar.
pub const BAR_HALF: f64 = 14.0;
/// Distance between a transition bar's end and its labels.
pub const LABEL_GAP: f64 = 6.0;

/// An axis-aligned rectangle (canvas units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn right(&self) -> f64 {
        self.x + self.w
    }
    pub fn bottom(&self) -> f64 {
        self.y + self.h
    }
    /// Whether the interiors intersect (touching edges do not count).
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.x < o.right() && o.x < self.right() && self.y < o.bottom() && o.y < self.bottom()
    }
    pub fn of(e: &Element) -> Rect {
        Rect { x: e.x, y: e.y, w: e.w, h: e.h }
    }
}

/// Estimated advance of `s` in the sans-serif label font.
pub fn text_width(s: &str, size: f64) -> f64 {
    sfc_render::text_width(s, size)
}

/// `name : tag` (seed 001: the name before the tag, separated by a colon).
pub fn name_with_tag(e: &Element) -> String {
    match e.tag {
        None => e.name.clone(),
        Some(t) if e.name.is_empty() => format!(": {t}"),
        Some(t) => format!("{} : {t}", e.name),
    }
}

fn ceil_to(v: f64, step: f64) -> f64 {
    (v / step).ceil() * step
}

/// The S7-GRAPH conditions drawn on a step's left side, as S7-GRAPH shows them: `C` for the
/// interlock (`sfc.s7graph.interlock`), `V` for the supervision (`sfc.s7graph.supervision`),
/// each with its condition (ST) for the tooltip. Steps of other charts have none.
pub fn step_marks(e: &Element) -> Vec<(&'static str, String)> {
    [("C", "sfc.s7graph.interlock"), ("V", "sfc.s7graph.supervision")]
        .into_iter()
        .filter_map(|(mark, name)| {
            let a = e.attributes.iter().rev().find(|a| a.name.eq_ignore_ascii_case(name))?;
            Some((mark, crate::pragma::unescape(a.value.as_deref().unwrap_or(""))))
        })
        .collect()
}

/// The side of a step mark's box, and the gap between it and the step.
pub const MARK: f64 = 14.0;

/// A step box wide enough for its name (bold) with its tag and its timeout line: at least
/// 80 × 40, widths in steps of 20 so the axis stays on the grid of 10.
pub fn step_size(e: &Element) -> (f64, f64) {
    let name = text_width(&name_with_tag(e), FONT) * BOLD;
    let timeout = e.timeout.as_deref().map_or(0.0, |t| text_width(t, 10.0));
    let inner = name.max(timeout) + if e.initial { 28.0 } else { 22.0 };
    (ceil_to(inner, 20.0).max(80.0), 40.0)
}

/// Height of one action block row.
pub const ROW_H: f64 = 24.0;

/// `Q` or `Q, duration` as the first column of an action row shows it.
pub fn qualifier_text(a: &Association) -> String {
    match &a.duration {
        Some(d) => format!("{}, {d}", a.qualifier),
        None => a.qualifier.clone(),
    }
}

/// The columns of an action block: qualifier, action, indicator (0 without indicators).
pub fn action_columns(assocs: &[Association]) -> (f64, f64, f64) {
    let q = assocs.iter().map(|a| text_width(&qualifier_text(a), FONT) * BOLD + 12.0).fold(28.0, f64::max);
    let act = assocs.iter().map(|a| text_width(&a.action, FONT) + 12.0).fold(60.0, f64::max);
    let has_ind = assocs.iter().any(|a| a.indicator.as_deref().is_some_and(|i| !i.is_empty()));
    let ind = if has_ind {
        assocs.iter().map(|a| text_width(a.indicator.as_deref().unwrap_or(""), FONT) + 12.0).fold(36.0, f64::max)
    } else {
        0.0
    };
    (q.ceil(), act.ceil(), ind.ceil())
}

/// An action block: one row per association, each column as wide as its widest text.
pub fn action_block_size(assocs: &[Association]) -> (f64, f64) {
    let (q, a, i) = action_columns(assocs);
    (ceil_to(q + a + i, 10.0).max(100.0), ROW_H * assocs.len().max(1) as f64)
}

/// The condition of a transition as the canvas prints it: every line of it, each line longer
/// than [`CONDITION_CHARS`] wrapped at its spaces ([`wrap_condition`]). Never cut: the label
/// is as tall as its lines, and the layout makes room for it. `web/src/diagram/drawing.ts`
/// follows the same rule, on the cases of `tests/shared/condition_lines.json`.
pub fn condition_lines(e: &Element) -> Vec<String> {
    let Some(c) = e.condition.as_deref().map(str::trim).filter(|c| !c.is_empty()) else { return Vec::new() };
    c.lines().map(str::trim).filter(|l| !l.is_empty()).flat_map(wrap_condition).collect()
}

fn chars(s: &str) -> usize {
    s.chars().count()
}

/// One line of a condition as lines of whole words of at most [`CONDITION_CHARS`] characters
/// (greedy; runs of white space become one space); a word longer than that stands on a line
/// of its own, whole. A line that fits is kept as written.
pub fn wrap_condition(line: &str) -> Vec<String> {
    let max = CONDITION_CHARS;
    if chars(line) <= max {
        return vec![line.to_string()];
    }
    let mut out: Vec<String> = Vec::new();
    let mut cur = String::new();
    for word in line.split_whitespace() {
        if !cur.is_empty() && chars(&cur) + 1 + chars(word) > max {
            out.push(std::mem::take(&mut cur));
            cur = word.to_string();
        } else if cur.is_empty() {
            cur = word.to_string();
        } else {
            cur.push(' ');
            cur.push_str(word);
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// What a label is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LabelKind {
    Condition,
    TransitionName,
    JumpTarget,
}

/// A text drawn outside its block.
#[derive(Debug, Clone, PartialEq)]
pub struct Label {
    /// Index of the block in `doc.elements`.
    pub block: usize,
    pub kind: LabelKind,
    pub lines: Vec<String>,
    pub rect: Rect,
}

/// The labels of block `i` of `doc`, where the canvas draws them.
pub fn labels_of(e: &Element, i: usize) -> Vec<Label> {
    let mut out = Vec::new();
    if e.hide_label {
        return out;
    }
    match e.kind {
        Some(ElementKind::Transition) => {
            let cx = e.x + e.w / 2.0;
            let cy = e.y + e.h / 2.0;
            let lines = condition_lines(e);
            let name = name_with_tag(e);
            if !lines.is_empty() {
                let w = lines.iter().map(|l| chars(l) as f64 * MONO_ADVANCE).fold(0.0, f64::max);
                let h = LINE_H * lines.len() as f64;
                let rect = Rect { x: cx + BAR_HALF + LABEL_GAP, y: cy - h / 2.0, w, h };
                out.push(Label { block: i, kind: LabelKind::Condition, lines, rect });
                if !name.is_empty() {
                    let w = text_width(&name, FONT);
                    let rect = Rect { x: cx - BAR_HALF - LABEL_GAP - w, y: cy - LINE_H / 2.0, w, h: LINE_H };
                    out.push(Label { block: i, kind: LabelKind::TransitionName, lines: vec![name], rect });
                }
            } else if !name.is_empty() {
                let w = text_width(&name, FONT);
                let rect = Rect { x: cx + BAR_HALF + LABEL_GAP, y: cy - LINE_H / 2.0, w, h: LINE_H };
                out.push(Label { block: i, kind: LabelKind::TransitionName, lines: vec![name], rect });
            }
        }
        Some(ElementKind::Jump) => {
            let target = e.target.clone().unwrap_or_else(|| "?".to_string());
            let w = text_width(&target, FONT) * BOLD;
            let rect = Rect { x: e.x + e.w + 8.0, y: e.y + e.h * 0.62 - LINE_H / 2.0, w, h: LINE_H };
            out.push(Label { block: i, kind: LabelKind::JumpTarget, lines: vec![target], rect });
        }
        _ => {}
    }
    out
}

/// Every label of the document, in block order.
pub fn labels(doc: &EditorDoc) -> Vec<Label> {
    doc.elements.iter().enumerate().flat_map(|(i, e)| labels_of(e, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conditions_wrap_like_the_canvas() {
        assert_eq!(wrap_condition("a AND b"), ["a AND b"]);
        let long = "StartButton AND CarPresent AND AtHome AND NOT StopButton";
        assert_eq!(wrap_condition(long), ["StartButton AND CarPresent AND", "AtHome AND NOT StopButton"]);
        let longer = "aaaa bbbb cccc dddd eeee ffff gggg hhhh iiii jjjj kkkk llll mmmm nnnn oooo";
        let w = wrap_condition(longer);
        assert_eq!(w.len(), 3);
        assert_eq!(w.join(" "), longer, "nothing is cut");
        assert!(w.iter().all(|l| l.chars().count() <= CONDITION_CHARS), "{w:?}");
    }

    #[test]
    fn blocks_fit_their_text() {
        let step = |name: &str, tag: Option<u32>| Element { name: name.into(), tag, ..Element::default() };
        assert_eq!(step_size(&step("S1", None)), (80.0, 40.0));
        let (w, _) = step_size(&step("ReturningToTheStartPosition", Some(12)));
        assert!(w >= text_width("ReturningToTheStartPosition : 12", FONT) * BOLD + 20.0, "{w}");
        let rows = [
            Association {
                qualifier: "L".into(),
                duration: Some("BeepTime".into()),
                action: "Beep".into(),
                indicator: None,
            },
            Association {
                qualifier: "D".into(),
                duration: Some("CameraDelay".into()),
                action: "Camera".into(),
                indicator: None,
            },
        ];
        let (q, a, _) = action_columns(&rows);
        assert!(q >= text_width("D, CameraDelay", FONT) * BOLD, "{q}");
        assert!(a >= text_width("Camera", FONT));
        assert_eq!(action_block_size(&rows).1, 48.0);
    }
}
