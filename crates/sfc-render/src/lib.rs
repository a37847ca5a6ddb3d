//! Chart layout in the IEC 61131-3 look, and SVG rendering, shared by `sfc build --target svg`
//! and the browser editor.
//!
//! [`layout`] turns a [`Chart`] into plain geometry ([`Layout`]): step boxes (the initial step
//! double-framed), transitions as short bars on the vertical links with their conditions to the
//! right, single lines for selection divergences and convergences, double lines for
//! simultaneous ones, jumps as arrows with the target step's name, and action blocks (qualifier
//! and duration | action | indicator) to the right of their step. [`svg`] draws a layout as a
//! standalone SVG 1.1 document.
//!
//! Three ways to lay a chart out, tried in this order ([`LayoutKind`]):
//!
//! 1. **Stored**: when every step and transition carries `sfc.x` and `sfc.y` attributes (written
//!    by the PLCopen import or the editor: pixels, top-left corner; sizes in `sfc.w`/`sfc.h` or
//!    `sfc.width`/`sfc.height` are optional), the elements are drawn where they are and the
//!    links are routed orthogonally between them (`stored.rs`).
//! 2. **Structured**: the block structure is recovered from the net (sequences, selections and
//!    simultaneous branches with their matching convergences, jumps for links back up or across)
//!    and drawn as nested columns whose widths are computed bottom-up (`structure.rs`,
//!    `place.rs`).
//! 3. **Layered**: a net that is not well nested (a simultaneous convergence that does not
//!    close the divergence it belongs to, say) is drawn in layers by longest path, ordered by
//!    barycentres, with jumps for the links back up (`layered.rs`). Every step, transition and
//!    connection is still drawn, and drawn correctly.
//!
//! Everything is deterministic: text widths are estimated from the characters (see
//! [`text_width`]), coordinates are whole pixels, numbers are printed in one fixed format.

mod layered;
mod place;
mod stored;
pub mod structure;
mod svg_out;
mod text;

pub use sfc_model::{StepId, TransitionId};
pub use text::{condition_text, duration_text, text_width};

use sfc_model::Chart;

/// A point in pixels (y grows downwards, as in SVG).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Point {
    pub x: f64,
    pub y: f64,
}

impl Point {
    pub fn new(x: f64, y: f64) -> Point {
        Point { x, y }
    }
}

/// An axis-aligned rectangle: top-left corner, width and height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    pub x: f64,
    pub y: f64,
    pub w: f64,
    pub h: f64,
}

impl Rect {
    pub fn new(x: f64, y: f64, w: f64, h: f64) -> Rect {
        Rect { x, y, w, h }
    }
    pub fn right(&self) -> f64 {
        self.x + self.w
    }
    pub fn bottom(&self) -> f64 {
        self.y + self.h
    }
    /// Whether the interiors intersect (touching edges do not count).
    pub fn overlaps(&self, other: &Rect) -> bool {
        self.x < other.right() && other.x < self.right() && self.y < other.bottom() && other.y < self.bottom()
    }
}

/// How a [`Layout`] was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutKind {
    /// The block structure of the net, in nested columns.
    Structured,
    /// Layers by longest path: the fallback for nets that are not well nested.
    Layered,
    /// The positions stored in `sfc.x`/`sfc.y` attributes.
    Stored,
}

/// What the layout makes room for.
#[derive(Debug, Clone, PartialEq)]
pub struct LayoutOptions {
    /// Font size the text widths are estimated for (pixels).
    pub font_size: f64,
    /// Conditions beside the transitions.
    pub show_conditions: bool,
    /// Action blocks beside the steps.
    pub show_actions: bool,
    /// Transition names left of their bars (off by default: the IEC look shows conditions).
    pub show_transition_names: bool,
}

impl Default for LayoutOptions {
    fn default() -> Self {
        LayoutOptions { font_size: 12.0, show_conditions: true, show_actions: true, show_transition_names: false }
    }
}

/// A step box.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxGeom {
    pub step: StepId,
    pub name: String,
    /// Initial steps are drawn with a double frame.
    pub initial: bool,
    pub rect: Rect,
}

impl BoxGeom {
    /// Where links from above end: the middle of the top edge.
    pub fn top(&self) -> Point {
        Point::new(self.rect.x + self.rect.w / 2.0, self.rect.y)
    }
    /// Where links downwards start: the middle of the bottom edge.
    pub fn bottom(&self) -> Point {
        Point::new(self.rect.x + self.rect.w / 2.0, self.rect.bottom())
    }
}

/// A transition: a short horizontal bar centred on its vertical link.
#[derive(Debug, Clone, PartialEq)]
pub struct TransitionGeom {
    pub transition: TransitionId,
    /// The axis (the vertical link through the bar).
    pub x: f64,
    /// The middle of the bar.
    pub y: f64,
    pub half_width: f64,
    pub thickness: f64,
    /// The condition, one entry per printed line (empty when hidden or missing).
    pub condition: Vec<String>,
    /// Where the condition lines go (left-aligned, one line height each).
    pub condition_rect: Option<Rect>,
    /// The name, when shown (right-aligned left of the bar).
    pub name: Option<String>,
    pub name_rect: Option<Rect>,
}

impl TransitionGeom {
    /// Where links from above end: the top edge of the bar.
    pub fn in_port(&self) -> Point {
        Point::new(self.x, self.y - self.thickness / 2.0)
    }
    /// Where links downwards start: the bottom edge of the bar.
    pub fn out_port(&self) -> Point {
        Point::new(self.x, self.y + self.thickness / 2.0)
    }
    pub fn bar_rect(&self) -> Rect {
        Rect::new(self.x - self.half_width, self.y - self.thickness / 2.0, 2.0 * self.half_width, self.thickness)
    }
}

/// One row of an action block: one association of the step.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionRow {
    /// Index into the step's `associations`.
    pub association: usize,
    /// The qualifier with its duration, e.g. `D T#1s`, `L BeepTime`, `N`.
    pub qualifier: String,
    pub action: String,
    /// The indicator variables, comma-separated (empty if none).
    pub indicator: String,
}

/// The action block of a step: a table with one row per association.
#[derive(Debug, Clone, PartialEq)]
pub struct ActionBlockGeom {
    pub step: StepId,
    pub rect: Rect,
    pub row_height: f64,
    /// Column widths: qualifier, action, indicator (0 when no row has an indicator).
    pub qualifier_width: f64,
    pub action_width: f64,
    pub indicator_width: f64,
    pub rows: Vec<ActionRow>,
    /// The horizontal line from the step's right edge to the block.
    pub link: (Point, Point),
}

/// A link drawn as a polyline of horizontal and vertical segments.
#[derive(Debug, Clone, PartialEq)]
pub struct Wire {
    pub points: Vec<Point>,
    /// The link runs upwards somewhere (a connection back to an earlier element that is drawn as
    /// a line rather than a jump): IEC marks such links with an arrow, drawn on its longest
    /// upward segment.
    pub upward_arrow: bool,
}

/// The kind of a divergence or convergence line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BranchKind {
    SelectionDivergence,
    SelectionConvergence,
    SimultaneousDivergence,
    SimultaneousConvergence,
}

impl BranchKind {
    /// Simultaneous branches are drawn with double lines.
    pub fn is_double(self) -> bool {
        matches!(self, BranchKind::SimultaneousDivergence | BranchKind::SimultaneousConvergence)
    }
}

/// A horizontal divergence or convergence line (double for simultaneous branches).
#[derive(Debug, Clone, PartialEq)]
pub struct BranchBar {
    pub kind: BranchKind,
    pub x1: f64,
    pub x2: f64,
    /// The (upper) line: links from above end here.
    pub y: f64,
    /// The lower line of a double bar (equal to `y` for a single line): links below start here.
    pub y2: f64,
}

/// A jump: an arrow below a transition pointing down, with the target step's name beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct JumpGeom {
    pub transition: TransitionId,
    pub target: StepId,
    /// The transition's out port, where the line starts.
    pub from: Point,
    /// The point of the arrowhead.
    pub tip: Point,
    pub label: String,
    pub label_rect: Rect,
}

/// The geometry of a whole chart.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    pub kind: LayoutKind,
    pub width: f64,
    pub height: f64,
    /// The font size the texts were sized for.
    pub font_size: f64,
    /// One per step, in [`StepId`] order.
    pub steps: Vec<BoxGeom>,
    /// One per transition, in [`TransitionId`] order.
    pub transitions: Vec<TransitionGeom>,
    /// One per step with associations (when actions are shown).
    pub actions: Vec<ActionBlockGeom>,
    pub wires: Vec<Wire>,
    pub branches: Vec<BranchBar>,
    pub jumps: Vec<JumpGeom>,
}

/// How [`svg`] draws.
#[derive(Debug, Clone, PartialEq)]
pub struct SvgOptions {
    pub font_family: String,
    pub font_size: f64,
    pub show_conditions: bool,
    pub show_actions: bool,
    pub show_transition_names: bool,
}

impl Default for SvgOptions {
    fn default() -> Self {
        SvgOptions {
            font_family: "DejaVu Sans".to_string(),
            font_size: 12.0,
            show_conditions: true,
            show_actions: true,
            show_transition_names: false,
        }
    }
}

impl SvgOptions {
    /// The layout options that make room for exactly what these options draw.
    pub fn layout_options(&self) -> LayoutOptions {
        LayoutOptions {
            font_size: self.font_size,
            show_conditions: self.show_conditions,
            show_actions: self.show_actions,
            show_transition_names: self.show_transition_names,
        }
    }
}

/// Lays a chart out with the default options: stored coordinates when every step and transition
/// has them, the structured layout otherwise, the layered one for nets that are not well nested.
pub fn layout(chart: &Chart) -> Layout {
    layout_with(chart, &LayoutOptions::default())
}

/// [`layout`] with explicit options (font size, which texts to make room for).
pub fn layout_with(chart: &Chart, opts: &LayoutOptions) -> Layout {
    let opts = LayoutOptions {
        font_size: if opts.font_size.is_finite() && opts.font_size > 0.0 { opts.font_size.min(200.0) } else { 12.0 },
        ..opts.clone()
    };
    let sane;
    let chart = match sanitized(chart) {
        Some(c) => {
            sane = c;
            &sane
        }
        None => chart,
    };
    let sizes = text::Sizes::of(chart, &opts);
    if let Some(positions) = stored::positions(chart) {
        return stored::layout(chart, &sizes, &positions);
    }
    structure::recover(chart)
        .and_then(|tree| place::layout(chart, &sizes, &tree))
        .unwrap_or_else(|| layered::layout(chart, &sizes))
}

/// A copy of `chart` whose transitions name only existing steps, each once, or `None` when the
/// chart is already like that (as every chart from `sfc_model` is). `Chart` has public fields, so
/// a hand-made one could say anything; the layout never indexes out of range.
fn sanitized(chart: &Chart) -> Option<Chart> {
    let ns = chart.steps.len();
    let clean =
        |list: &[StepId]| list.iter().all(|&s| s < ns) && list.iter().enumerate().all(|(i, s)| !list[..i].contains(s));
    if chart.transitions.iter().all(|t| clean(&t.from) && clean(&t.to)) {
        return None;
    }
    let mut copy = chart.clone();
    for t in copy.transitions.iter_mut() {
        for list in [&mut t.from, &mut t.to] {
            let mut seen = Vec::new();
            list.retain(|&s| {
                let keep = s < ns && !seen.contains(&s);
                seen.push(s);
                keep
            });
        }
    }
    Some(copy)
}

/// Draws `layout` (made for `chart`) as a standalone SVG 1.1 document. Lay the chart out with
/// [`SvgOptions::layout_options`] so the texts fit the room made for them.
pub fn svg(chart: &Chart, layout: &Layout, opts: &SvgOptions) -> String {
    svg_out::write(chart, layout, opts)
}
