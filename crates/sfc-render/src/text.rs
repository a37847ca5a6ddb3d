//! Text for the drawing: estimated widths, transition conditions on one or more lines, action
//! block rows, and the sizes of the elements those texts decide.
//!
//! Widths are *estimated*, never measured with a font: every character has a fixed advance
//! (the advance widths of DejaVu Sans for printable ASCII, a generous em-based width for other
//! characters), so the layout is the same on every machine and in the browser editor.

use crate::LayoutOptions;
use sfc_model::{Chart, Duration, StepNode, TransitionNode};
use sfc_syntax::ast;

/// Advance widths of DejaVu Sans for `' '..='~'`, in font units (2048 per em), from the font's
/// `hmtx` table. Kerning, which renderers apply, only makes real text a little narrower.
const ADVANCE: [u16; 95] = [
    651, 821, 942, 1716, 1303, 1946, 1597, 563, 799, 799, 1024, 1716, 651, 739, 651, 690, 1303, 1303, 1303, 1303, 1303,
    1303, 1303, 1303, 1303, 1303, 690, 690, 1716, 1716, 1716, 1087, 2048, 1401, 1405, 1430, 1577, 1294, 1178, 1587,
    1540, 604, 604, 1343, 1141, 1767, 1532, 1612, 1235, 1612, 1423, 1300, 1251, 1499, 1401, 2025, 1403, 1251, 1403,
    799, 690, 799, 1716, 1024, 1024, 1255, 1300, 1126, 1300, 1260, 721, 1300, 1298, 569, 569, 1186, 569, 1995, 1298,
    1253, 1300, 1300, 842, 1067, 803, 1298, 1212, 1675, 1212, 1212, 1075, 1303, 690, 1303, 1716,
];
const UNITS_PER_EM: f64 = 2048.0;

/// Estimated advance width of `text` at `font_size`: ASCII from the DejaVu Sans table, Latin
/// letters with diacritics as a wide lower-case letter, anything else (CJK, symbols) as one em.
pub fn text_width(text: &str, font_size: f64) -> f64 {
    let units: f64 = text
        .chars()
        .map(|c| match c as u32 {
            0x20..=0x7e => f64::from(ADVANCE[(c as u32 - 0x20) as usize]),
            0xa0..=0x24f => 1400.0,
            _ => UNITS_PER_EM,
        })
        .sum();
    units * font_size / UNITS_PER_EM
}

/// Height of one line of text: 1.3 em, so that the baseline sits one em below the line's top
/// with the glyphs of DejaVu Sans (ascent 0.93 em, descent 0.24 em) centred in the line.
pub fn line_height(font_size: f64) -> f64 {
    (font_size * 1.3).round()
}

/// The baseline of a line whose box starts at `top` (see [`line_height`]).
pub fn baseline(top: f64, font_size: f64) -> f64 {
    top + ((line_height(font_size) - font_size * 1.164) / 2.0 + font_size * 0.928)
}

/// The condition of a transition as the canonical printer of `sfc_syntax` writes it: an ST
/// expression on one line, IL instructions joined on one line with `;` between them.
pub fn condition_text(condition: &ast::Condition) -> String {
    match condition {
        ast::Condition::St(expr) => {
            let span = expr.span;
            let target = ast::Expr { kind: ast::ExprKind::Name(ast::Ident::new("C__", span)), span };
            let stmt = ast::Stmt {
                kind: ast::StmtKind::Assign { target: Box::new(target), value: Box::new(expr.clone()) },
                span,
            };
            let printed = print_body(ast::Body::St(vec![stmt]), span);
            let line = printed.lines().map(str::trim).find(|l| l.starts_with("C__ := ")).unwrap_or("");
            line.trim_start_matches("C__ := ").trim_end_matches(';').to_string()
        }
        ast::Condition::Il(il) => {
            let printed = print_body(ast::Body::Il(il.clone()), il.span);
            let mut lines: Vec<&str> = printed.lines().map(str::trim).filter(|l| !l.is_empty()).collect();
            // The synthetic POU's own lines.
            lines.retain(|l| *l != "PROGRAM C__" && *l != "END_PROGRAM");
            let mut out = String::new();
            for (i, line) in lines.iter().enumerate() {
                if i > 0 {
                    // `AND(` opens a nested list and `)` closes it: no `;` next to them.
                    let prev_opens = lines[i - 1].ends_with('(');
                    out.push_str(if prev_opens || *line == ")" { " " } else { "; " });
                }
                out.push_str(line);
            }
            out
        }
        ast::Condition::Missing => String::new(),
    }
}

/// Prints `body` as the body of a throw-away program, so the one canonical printer decides how
/// expressions and instructions look.
fn print_body(body: ast::Body, span: ast::Span) -> String {
    let pou = ast::Pou {
        kind: ast::PouKind::Program,
        name: ast::Ident::new("C__", span),
        return_type: None,
        attributes: Vec::new(),
        var_blocks: Vec::new(),
        body,
        actions: Vec::new(),
        modifiers: Vec::new(),
        extends: None,
        implements: Vec::new(),
        methods: Vec::new(),
        properties: Vec::new(),
        span,
    };
    let unit = ast::SourceUnit { items: vec![ast::Item::Pou(pou)], trivia: Vec::new(), blank_lines: Vec::new(), span };
    sfc_syntax::print::print(&unit)
}

/// Breaks `text` into lines of at most `max_width` (estimated) where it has spaces, as
/// engineers break long conditions: preferably before a keyword operator (`AND`, `OR`, …)
/// outside parentheses, so comparisons stay whole; a part that is too wide alone is broken at
/// other spaces, never leaving an operator at the end of a line. A single word wider than
/// `max_width` gets a line alone.
pub fn wrap(text: &str, max_width: f64, font_size: f64) -> Vec<String> {
    let words: Vec<&str> = text.split(' ').filter(|w| !w.is_empty()).collect();
    // Chunks start at top-level operators.
    let mut chunks: Vec<Vec<&str>> = Vec::new();
    let mut depth: i32 = 0;
    for word in words {
        if chunks.is_empty() || (depth == 0 && is_operator_word(word)) {
            chunks.push(Vec::new());
        }
        if let Some(c) = chunks.last_mut() {
            c.push(word);
        }
        depth += word.matches(['(', '[']).count() as i32 - word.matches([')', ']']).count() as i32;
    }
    let fits = |line: &str| text_width(line, font_size) <= max_width;
    let mut lines: Vec<String> = Vec::new();
    for chunk in chunks {
        let joined = chunk.join(" ");
        if let Some(last) = lines.last_mut() {
            let candidate = format!("{last} {joined}");
            if fits(&candidate) {
                *last = candidate;
                continue;
            }
        }
        if fits(&joined) {
            lines.push(joined);
        } else {
            lines.extend(wrap_words(&chunk, &fits));
        }
    }
    lines
}

/// Greedy word wrap that carries trailing operators over to the next line.
fn wrap_words(words: &[&str], fits: &dyn Fn(&str) -> bool) -> Vec<String> {
    let mut lines: Vec<Vec<&str>> = vec![Vec::new()];
    for &word in words {
        let Some(current) = lines.last_mut() else { break };
        let mut candidate = current.join(" ");
        if !candidate.is_empty() {
            candidate.push(' ');
        }
        candidate.push_str(word);
        if current.is_empty() || fits(&candidate) {
            current.push(word);
            continue;
        }
        let mut carried = Vec::new();
        while current.len() > 1 && current.last().is_some_and(|w| is_operator_word(w)) {
            if let Some(w) = current.pop() {
                carried.insert(0, w);
            }
        }
        carried.push(word);
        lines.push(carried);
    }
    lines.into_iter().filter(|l| !l.is_empty()).map(|l| l.join(" ")).collect()
}

fn is_operator_word(word: &str) -> bool {
    ["AND", "OR", "XOR", "AND_THEN", "OR_ELSE", "&", "MOD"].iter().any(|op| word.eq_ignore_ascii_case(op))
}

/// A TIME value in canonical IEC form, largest unit first: `T#1s500ms`, `T#2m`, `T#0s`.
pub fn duration_text(micros: i64) -> String {
    if micros == 0 {
        return "T#0s".to_string();
    }
    let sign = if micros < 0 { "-" } else { "" };
    let mut rest = micros.unsigned_abs();
    let mut out = format!("T#{sign}");
    for (unit, size) in
        [("d", 86_400_000_000u64), ("h", 3_600_000_000), ("m", 60_000_000), ("s", 1_000_000), ("ms", 1_000), ("us", 1)]
    {
        let n = rest / size;
        if n > 0 {
            out.push_str(&format!("{n}{unit}"));
            rest -= n * size;
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Element sizes

/// Fixed dimensions of the drawing, in pixels (the text sizes follow the font size).
pub mod dim {
    /// Everything is placed on whole pixels; widths of boxes are rounded up to this.
    pub const GRID: f64 = 8.0;
    /// Smallest step box.
    pub const STEP_MIN_W: f64 = 48.0;
    pub const STEP_MIN_H: f64 = 32.0;
    /// Space between a step's name and its frame.
    pub const STEP_PAD: f64 = 10.0;
    /// Inset of the inner frame of an initial step.
    pub const INITIAL_INSET: f64 = 3.0;
    /// Half the width of a transition bar, and its thickness.
    pub const BAR_HALF: f64 = 12.0;
    pub const BAR_THICKNESS: f64 = 3.0;
    /// Space between a bar and its condition (right) or name (left).
    pub const LABEL_GAP: f64 = 8.0;
    /// Smallest height of the row a transition occupies.
    pub const TRANSITION_MIN_H: f64 = 24.0;
    /// Conditions longer than this are wrapped (see [`super::wrap`]).
    pub const CONDITION_MAX_W: f64 = 260.0;
    /// Horizontal line from a step to its action block.
    pub const ACTION_GAP: f64 = 16.0;
    /// Padding of a cell of the action block.
    pub const CELL_PAD: f64 = 6.0;
    /// Vertical link between two elements of a sequence.
    pub const LINK: f64 = 12.0;
    /// Vertical line between a divergence or convergence bar and the branches.
    pub const STUB: f64 = 12.0;
    /// Distance of the two lines of a simultaneous divergence or convergence.
    pub const DOUBLE_GAP: f64 = 3.0;
    /// How far the double lines reach beyond the outermost branches.
    pub const DOUBLE_OVERHANG: f64 = 8.0;
    /// Horizontal space between the extents of two branches or two networks.
    pub const COLUMN_GAP: f64 = 24.0;
    /// Space between separate networks (and roots) side by side.
    pub const NETWORK_GAP: f64 = 48.0;
    /// A jump: a line of this length below its transition ends in an arrowhead.
    pub const JUMP_H: f64 = 16.0;
    pub const ARROW_LEN: f64 = 8.0;
    pub const ARROW_HALF: f64 = 5.0;
    /// Margin around the drawing.
    pub const MARGIN: f64 = 16.0;
}

use dim::*;

/// Rounds up to the grid.
pub fn to_grid(v: f64) -> f64 {
    (v / GRID).ceil() * GRID
}

/// Size of a step box and of its action block.
#[derive(Debug, Clone)]
pub struct StepSize {
    pub w: f64,
    pub h: f64,
    pub actions: Option<ActionSize>,
}

/// Cells of an action block: one row per association.
#[derive(Debug, Clone)]
pub struct ActionSize {
    pub rows: Vec<crate::ActionRow>,
    pub row_h: f64,
    pub qualifier_w: f64,
    pub action_w: f64,
    pub indicator_w: f64,
}

impl ActionSize {
    pub fn w(&self) -> f64 {
        self.qualifier_w + self.action_w + self.indicator_w
    }
    pub fn h(&self) -> f64 {
        self.row_h * self.rows.len() as f64
    }
    /// The block of `step` placed at `block`, linked from the right side of the step box `rect`
    /// at height `cy`.
    pub fn geom(&self, step: usize, block: crate::Rect, rect: crate::Rect, cy: f64) -> crate::ActionBlockGeom {
        crate::ActionBlockGeom {
            step,
            rect: block,
            row_height: self.row_h,
            qualifier_width: self.qualifier_w,
            action_width: self.action_w,
            indicator_width: self.indicator_w,
            rows: self.rows.clone(),
            link: (crate::Point::new(rect.right(), cy), crate::Point::new(block.x, cy)),
        }
    }
}

/// Size of a transition: its bar and the texts beside it.
#[derive(Debug, Clone)]
pub struct TransitionSize {
    pub condition: Vec<String>,
    pub condition_w: f64,
    pub name: Option<String>,
    pub name_w: f64,
    pub row_h: f64,
}

impl TransitionSize {
    /// Extent left of the axis.
    pub fn left(&self) -> f64 {
        if self.name.is_some() {
            BAR_HALF + LABEL_GAP + self.name_w
        } else {
            BAR_HALF
        }
    }
    /// Extent right of the axis.
    pub fn right(&self) -> f64 {
        if self.condition.is_empty() {
            BAR_HALF
        } else {
            BAR_HALF + LABEL_GAP + self.condition_w
        }
    }
}

impl StepSize {
    /// Vertical offset of the action block below the step's top: its first row is centred on the
    /// step, so the line from the step meets the middle of that row.
    pub fn action_dy(&self) -> f64 {
        match &self.actions {
            Some(a) => ((self.h - a.row_h) / 2.0).round(),
            None => 0.0,
        }
    }
    pub fn left(&self) -> f64 {
        self.w / 2.0
    }
    pub fn right(&self) -> f64 {
        match &self.actions {
            Some(a) => self.w / 2.0 + ACTION_GAP + a.w(),
            None => self.w / 2.0,
        }
    }
    /// Height of the step with its action block.
    pub fn height(&self) -> f64 {
        match &self.actions {
            Some(a) => self.h.max(self.action_dy() + a.h()),
            None => self.h,
        }
    }
}

/// The texts and sizes of every step and transition.
#[derive(Debug, Clone)]
pub struct Sizes {
    pub steps: Vec<StepSize>,
    pub transitions: Vec<TransitionSize>,
    pub font_size: f64,
}

impl Sizes {
    pub fn of(chart: &Chart, opts: &LayoutOptions) -> Sizes {
        let fs = opts.font_size;
        Sizes {
            steps: chart.steps.iter().map(|s| step_size(s, opts)).collect(),
            transitions: chart.transitions.iter().map(|t| transition_size(t, opts)).collect(),
            font_size: fs,
        }
    }

    /// The label of a jump to `target` and its width.
    pub fn jump_label(&self, chart: &Chart, target: usize) -> (String, f64) {
        let label = chart.steps.get(target).map(|s| s.name.clone()).unwrap_or_default();
        let w = text_width(&label, self.font_size).ceil();
        (label, w)
    }
}

/// Extent right of a jump's axis: the arrowhead and the target's name beside it.
pub fn jump_right(label_w: f64) -> f64 {
    ARROW_HALF + 4.0 + label_w
}

fn step_size(step: &StepNode, opts: &LayoutOptions) -> StepSize {
    let fs = opts.font_size;
    let w = to_grid((text_width(&step.name, fs) + 2.0 * STEP_PAD).max(STEP_MIN_W));
    // Even multiples of the grid keep the axis (the middle of the box) on whole pixels.
    let w = if (w / GRID) as i64 % 2 == 1 { w + GRID } else { w };
    let h = to_grid((line_height(fs) + 2.0 * STEP_PAD - 4.0).max(STEP_MIN_H));
    let actions = if opts.show_actions && !step.associations.is_empty() {
        let rows: Vec<crate::ActionRow> = step
            .associations
            .iter()
            .enumerate()
            .map(|(i, a)| crate::ActionRow {
                association: i,
                qualifier: match &a.duration {
                    Some(Duration::Literal(us)) => format!("{} {}", a.qualifier.name(), duration_text(*us)),
                    Some(Duration::Variable(v)) => format!("{} {}", a.qualifier.name(), v),
                    None => a.qualifier.name().to_string(),
                },
                action: a.action.clone(),
                indicator: a.indicators.join(", "),
            })
            .collect();
        let cell = |t: &str| (text_width(t, fs) + 2.0 * CELL_PAD).ceil();
        let qualifier_w = to_grid(rows.iter().map(|r| cell(&r.qualifier)).fold(32.0, f64::max));
        let action_w = to_grid(rows.iter().map(|r| cell(&r.action)).fold(48.0, f64::max));
        let indicator_w = if rows.iter().any(|r| !r.indicator.is_empty()) {
            to_grid(rows.iter().map(|r| cell(&r.indicator)).fold(32.0, f64::max))
        } else {
            0.0
        };
        let row_h = to_grid(line_height(fs) + 6.0).max(24.0);
        Some(ActionSize { rows, row_h, qualifier_w, action_w, indicator_w })
    } else {
        None
    };
    StepSize { w, h, actions }
}

fn transition_size(t: &TransitionNode, opts: &LayoutOptions) -> TransitionSize {
    let fs = opts.font_size;
    let condition = if opts.show_conditions {
        wrap(&condition_text(&t.condition), CONDITION_MAX_W * fs / 12.0, fs)
    } else {
        Vec::new()
    };
    let condition_w = condition.iter().map(|l| text_width(l, fs)).fold(0.0, f64::max).ceil();
    let name = if opts.show_transition_names { Some(t.name.clone()) } else { None };
    let name_w = name.as_deref().map(|n| text_width(n, fs)).unwrap_or(0.0).ceil();
    let text_h = line_height(fs) * condition.len().max(1) as f64;
    let row_h = to_grid((text_h + 4.0).max(TRANSITION_MIN_H));
    TransitionSize { condition, condition_w, name, name_w, row_h }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widths_follow_the_characters() {
        assert!(text_width("WWW", 12.0) > text_width("iii", 12.0));
        assert_eq!(text_width("", 12.0), 0.0);
        // "S1": 1300 + 1303 units at 12 px.
        assert!((text_width("S1", 12.0) - (1300.0 + 1303.0) * 12.0 / 2048.0).abs() < 1e-9);
        assert_eq!(text_width("中", 10.0), 10.0);
    }

    #[test]
    fn durations_are_canonical() {
        assert_eq!(duration_text(1_500_000), "T#1s500ms");
        assert_eq!(duration_text(0), "T#0s");
        assert_eq!(duration_text(90_000_000), "T#1m30s");
        assert_eq!(duration_text(-2_000), "T#-2ms");
        assert_eq!(duration_text(86_400_000_000 + 1), "T#1d1us");
    }

    #[test]
    fn wrapping_moves_operators_to_the_next_line() {
        let lines = wrap("StartButton AND CarPresent AND AtHome AND NOT StopButton", 180.0, 12.0);
        assert!(lines.len() >= 2, "{lines:?}");
        for l in &lines {
            assert!(!l.ends_with(" AND"), "{lines:?}");
            assert!(text_width(l, 12.0) <= 180.0, "{lines:?}");
        }
        assert_eq!(lines.join(" "), "StartButton AND CarPresent AND AtHome AND NOT StopButton");
        assert_eq!(wrap("", 100.0, 12.0), Vec::<String>::new());
        assert_eq!(wrap("Averyveryverylongsingleword", 10.0, 12.0), vec!["Averyveryverylongsingleword"]);
        // Comparisons stay whole; parenthesised groups are not split at their inner operators.
        assert_eq!(
            wrap("Request AND CarsGreen.T >= MinGreenTime", 260.0, 12.0),
            vec!["Request", "AND CarsGreen.T >= MinGreenTime"]
        );
        assert_eq!(wrap("(a OR b) AND c", 60.0, 12.0), vec!["(a OR b)", "AND c"]);
    }

    fn first_condition(src: &str) -> String {
        let (unit, diags) = sfc_syntax::parse(0, src);
        assert!(diags.is_empty(), "{diags:?}");
        for item in &unit.items {
            if let ast::Item::Pou(p) = item {
                if let Some(elements) = p.body.sfc() {
                    for el in elements {
                        if let ast::SfcElement::Transition(t) = el {
                            return condition_text(&t.condition);
                        }
                    }
                }
            }
        }
        panic!("no transition")
    }

    #[test]
    fn conditions_print_canonically() {
        let st = "PROGRAM P\nINITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n\
                  TRANSITION FROM A TO B := a and (b OR NOT c) and x.3 >= t#5s; END_TRANSITION\nEND_PROGRAM\n";
        assert_eq!(first_condition(st), "a AND (b OR NOT c) AND x.3 >= t#5s");
        let il = "PROGRAM P\nINITIAL_STEP A: END_STEP\nSTEP B: END_STEP\n\
                  TRANSITION FROM A TO B:\n LD a\n AND( b\n OR c\n )\n ANDN d\nEND_TRANSITION\nEND_PROGRAM\n";
        assert_eq!(first_condition(il), "LD a; AND( b; OR c ); ANDN d");
    }
}
