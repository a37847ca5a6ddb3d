//! Saving one POU into a PLCopen XML file with the fewest changes ([`patch_pou`]): the file's
//! POU is imported, compared by meaning with the POU the editor saves, and when they differ only
//! where the file's own elements can say it in place, only those bytes of the file change. Every
//! element keeps its `localId`, a vendor's attributes (`executionOrderId`) and `addData`, its
//! connection points and wires.
//!
//! What is written in place:
//! - the place and size of a step, macro step or transition (`<position x= y=>`, `width`,
//!   `height`), of an action block and of a jump (its `<position>`), each value that changed and
//!   no other, in the file's units (the import copies them into `sfc.x`, `sfc.y`, `sfc.w`,
//!   `sfc.h`, `sfc.actionblock` and `sfc.jump` unscaled); a size the file does not hold
//!   (`width` and `height` are optional) is not added;
//! - an inline ST condition of a transition (the text inside its `CDATA` or `xhtml:p`), when
//!   the condition is not negated and the import copied it from the file as it stands;
//! - a renamed step: its `name` and the `targetName` of the jumps to it.
//!
//! Every other change falls back, for now, to [`splice_pou`], which replaces the whole `pou`
//! element by a fresh export (`localId`s numbered afresh, foreign attributes such as
//! `executionOrderId` not kept): a step, transition or action added or deleted, a transition
//! rewired, an association, an action body, a declaration, a description or another attribute
//! edited, a negated, IL, wired or referenced condition edited, a rename that the file's
//! generated names follow (a step with inline actions), the POU renamed, and a block moved in a
//! chart the file holds without a layout (CODESYS's positions 0, 0). An edit in place is kept
//! only when importing the edited file gives the new POU again (same meaning, same places);
//! otherwise the fallback is taken too.

use crate::attrs;
use crate::export::export_pou;
use crate::splice::{splice_pou, SpliceError};
use crate::xml::{attr, attr_range, child, children, elements};
use roxmltree::{Document, Node, NodeId};
use sfc_diagnostics::Span;
use sfc_model::Checked;
use sfc_syntax::ast::{self, Body, Condition, Item, Pou, SfcElement, SourceUnit, TriviaKind};
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

/// How [`patch_pou`] wrote the POU.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Patched {
    /// The POU is the file's, in meaning and layout: the file is returned byte for byte.
    Unchanged,
    /// Only the attributes and texts that changed were rewritten.
    InPlace,
    /// The change cannot be written in place: the `pou` element was replaced by an export
    /// ([`splice_pou`]), or added to the file.
    Replaced,
}

/// `xml` with its POU `replacing` made the POU of `checked` (a checked text holding that one
/// POU, named as it is now), changing as few bytes as the change allows (see the module's
/// documentation): nothing when nothing changed, the changed positions, sizes, inline ST
/// conditions and step names in place, and otherwise, as [`splice_pou`] does, the whole `pou`
/// element replaced by its export (also when the file has no such POU: it is added). Fails as
/// [`splice_pou`] does.
pub fn patch_pou(xml: &str, replacing: &str, checked: &Checked) -> Result<(String, Patched), SpliceError> {
    match in_place(xml, replacing, checked) {
        Some(Ok(done)) => Ok(done),
        Some(Err(e)) => Err(e),
        None => splice_pou(xml, replacing, checked).map(|x| (x, Patched::Replaced)),
    }
}

/// The attributes that say where an element is drawn.
const GEOMETRY: [&str; 4] = [attrs::X, attrs::Y, attrs::W, attrs::H];

/// The patch in place, `None` when the change needs the fallback.
fn in_place(xml: &str, replacing: &str, checked: &Checked) -> Option<Result<(String, Patched), SpliceError>> {
    let opts = roxmltree::ParsingOptions { allow_dtd: false, ..Default::default() };
    let doc = Document::parse_with_options(xml, opts).ok()?;
    if doc.root_element().tag_name().name() != "project" {
        return None;
    }
    let imported = crate::import(0, "", xml);
    let (old_unit, _) = sfc_syntax::parse(0, &imported.text);
    let old_pou = find_pou(&old_unit, replacing)?;
    let new_text = checked.file.text.as_str();
    let (new_unit, parse_diags) = sfc_syntax::parse(0, new_text);
    if parse_diags.iter().any(|d| d.is_error()) {
        return None;
    }
    let new_pou = new_unit.items.iter().find_map(|i| if let Item::Pou(p) = i { Some(p) } else { None })?;
    if !new_pou.name.text.eq_ignore_ascii_case(&old_pou.name.text) {
        return None;
    }
    let new = Shape::of(&new_unit, new_pou, &HashMap::new());
    // A renamed step: the old chart read with the new name, so the two compare element by
    // element.
    let renames = renamed_steps(old_pou, new_pou);
    let old = Shape::of(&old_unit, old_pou, &renames);
    let shared = old.shared_jumps(&new);
    let mut plan = Plan { doc: &doc, map: &imported.map, old_text: &imported.text, edits: Vec::new(), content: false };
    plan.compare(&old, &new, new_text, &shared)?;
    if !renames.is_empty() {
        plan.rename(&old, &renames)?;
    }
    if plan.edits.is_empty() && !plan.content {
        return Some(Ok((xml.to_string(), Patched::Unchanged)));
    }
    // What the POU says changed: its text must be one the export would write too.
    if plan.content {
        if let Err(errors) = export_pou(checked) {
            return Some(Err(SpliceError::Diagnostics(errors)));
        }
    }
    let out = apply(xml, plan.edits)?;
    // The file as written must give the new POU back.
    let again = crate::import(0, "", &out);
    let (again_unit, _) = sfc_syntax::parse(0, &again.text);
    let again_pou = find_pou(&again_unit, replacing)?;
    let written = Shape::of(&again_unit, again_pou, &HashMap::new());
    if !written.same_as(&new, &shared) {
        return None;
    }
    Some(Ok((out, Patched::InPlace)))
}

/// The POU named `name` (case-insensitive) of a parsed text.
fn find_pou<'u>(unit: &'u SourceUnit, name: &str) -> Option<&'u Pou> {
    unit.items.iter().find_map(|i| match i {
        Item::Pou(p) if p.name.text.eq_ignore_ascii_case(name.trim()) => Some(p),
        _ => None,
    })
}

/// The SFC elements of a POU's body.
fn sfc_elements(pou: &Pou) -> &[SfcElement] {
    pou.body.sfc().unwrap_or_default()
}

/// The one step of `old` whose name `new` does not have, and the one of `new` that `old` does
/// not have, as a rename (upper-case old name → new name); empty unless exactly one step each.
fn renamed_steps(old: &Pou, new: &Pou) -> HashMap<String, String> {
    let names = |p: &Pou| -> Vec<String> {
        sfc_elements(p)
            .iter()
            .filter_map(|e| if let SfcElement::Step(s) = e { Some(s.name.text.clone()) } else { None })
            .collect()
    };
    let (o, n) = (names(old), names(new));
    let gone: Vec<&String> = o.iter().filter(|a| !n.iter().any(|b| b.eq_ignore_ascii_case(a))).collect();
    let came: Vec<&String> = n.iter().filter(|b| !o.iter().any(|a| a.eq_ignore_ascii_case(b))).collect();
    match (gone.as_slice(), came.as_slice()) {
        ([g], [c]) => HashMap::from([(g.to_ascii_uppercase(), (*c).clone())]),
        _ => HashMap::new(),
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Step,
    Transition,
    Action,
}

/// One step, transition or action as compared.
struct Elem<'u> {
    kind: Kind,
    node: &'u SfcElement,
    /// The element printed canonically, without its pragmas and comments.
    printed: String,
    /// A transition printed without its condition.
    bare: String,
    /// The attributes that are not layout, unescaped and sorted, with the parts of
    /// `sfc.actionblock` and `sfc.jump` that are not places (how many associations each block
    /// shows, the jumps' targets).
    attrs: Vec<(String, String)>,
    /// `sfc.x`, `sfc.y`, `sfc.w`, `sfc.h`.
    geometry: [Option<f64>; 4],
    /// The action blocks' `x y w h`.
    blocks: Vec<[f64; 4]>,
    /// The jumps' target and `x y`.
    jumps: Vec<(String, f64, f64)>,
}

/// A POU as compared: what it means, and where its elements are drawn.
struct Shape<'u> {
    /// The POU printed canonically without its chart, pragmas and comments.
    head: String,
    /// The POU's attributes that are not layout.
    attrs: Vec<(String, String)>,
    /// The comments of the POU, sorted.
    comments: Vec<String>,
    /// Steps by name, transitions in their order among those leaving the same steps, actions
    /// by name: the text's order of steps and of unrelated transitions means nothing.
    elems: Vec<Elem<'u>>,
}

/// An attribute name as compared.
fn key(name: &str) -> String {
    name.to_ascii_lowercase()
}

/// A place or size as compared: as PLCopen writes it.
fn same_num(a: Option<f64>, b: Option<f64>) -> bool {
    a.map(attrs::fmt_num) == b.map(attrs::fmt_num)
}

impl<'u> Shape<'u> {
    /// The shape of `pou` of `unit`, its step names read through `renames` (upper-case old
    /// name → new name).
    fn of(unit: &SourceUnit, pou: &'u Pou, renames: &HashMap<String, String>) -> Shape<'u> {
        let rename = |id: &ast::Ident| -> ast::Ident {
            match renames.get(&id.text.to_ascii_uppercase()) {
                Some(n) => ast::Ident { text: n.clone(), span: id.span },
                None => id.clone(),
            }
        };
        let mut head = pou.clone();
        head.attributes.clear();
        if let Some(list) = head.body.sfc_mut() {
            list.clear();
        }
        let head = print_pou(head);
        let mut pou_attrs = Vec::new();
        for a in &pou.attributes {
            let k = key(&a.name);
            let v = a.value.as_deref().map(sfc_syntax::attr_value::unescape).unwrap_or_default();
            // The editor's own drawing, which the file has no place for; `blank` is what a
            // chart without `sfc.target` is.
            if k.starts_with("sfc.graph") || (k == "sfc.target" && v == "blank") {
                continue;
            }
            pou_attrs.push((k, v));
        }
        pou_attrs.sort();
        let from = pou.attributes.iter().map(|a| a.span.start).fold(pou.span.start, u32::min);
        let mut comments: Vec<String> = unit
            .trivia
            .iter()
            .filter(|t| t.kind != TriviaKind::Pragma && t.span.start >= from && t.span.end <= pou.span.end)
            .map(|t| t.text.trim().to_string())
            .collect();
        comments.sort();

        let mut elems = Vec::new();
        for e in sfc_elements(pou) {
            let (kind, attributes) = match e {
                SfcElement::Step(s) => (Kind::Step, &s.attributes),
                SfcElement::Transition(t) => (Kind::Transition, &t.attributes),
                SfcElement::Action(a) => (Kind::Action, &a.attributes),
            };
            let mut list = Vec::new();
            let mut geometry = [None; 4];
            let mut blocks = Vec::new();
            let mut jumps = Vec::new();
            for a in attributes {
                let k = key(&a.name);
                let v = a.value.as_deref().map(sfc_syntax::attr_value::unescape).unwrap_or_default();
                if let Some(i) = GEOMETRY.iter().position(|g| *g == k) {
                    if let (Some(slot), Ok(n)) = (geometry.get_mut(i), v.trim().parse::<f64>()) {
                        *slot = Some(n);
                        continue;
                    }
                }
                if k == attrs::ACTIONBLOCK {
                    if let Some((places, counts)) = action_blocks(&v) {
                        blocks.extend(places);
                        list.push((format!("{k}#n"), counts));
                        continue;
                    }
                }
                if k == attrs::JUMP {
                    if let Some(places) = jump_places(&v) {
                        let targets: Vec<String> = places
                            .iter()
                            .map(|(t, _, _)| match renames.get(&t.to_ascii_uppercase()) {
                                Some(n) => n.clone(),
                                None => t.clone(),
                            })
                            .collect();
                        list.push((format!("{k}#to"), targets.join(";")));
                        jumps.extend(places);
                        continue;
                    }
                }
                list.push((k, v));
            }
            list.sort();
            let mut alone = e.clone();
            match &mut alone {
                SfcElement::Step(s) => s.name = rename(&s.name),
                SfcElement::Transition(t) => {
                    t.from = t.from.iter().map(rename).collect();
                    t.to = t.to.iter().map(rename).collect();
                    t.from_parens = t.from.len() > 1;
                    t.to_parens = t.to.len() > 1;
                }
                SfcElement::Action(_) => {}
            }
            let printed = print_element(pou, alone.clone());
            let bare = match &mut alone {
                SfcElement::Transition(t) => {
                    t.condition = Condition::Missing;
                    print_element(pou, alone)
                }
                _ => String::new(),
            };
            elems.push(Elem { kind, node: e, printed, bare, attrs: list, geometry, blocks, jumps });
        }
        // Steps and actions by name; transitions by the steps they leave, stable.
        let from_key = |e: &Elem| -> Vec<String> {
            match e.node {
                SfcElement::Transition(t) => {
                    let mut v: Vec<String> = t.from.iter().map(|f| rename(f).text.to_ascii_uppercase()).collect();
                    v.sort();
                    v
                }
                _ => Vec::new(),
            }
        };
        let name_key = |e: &Elem| -> String {
            match e.node {
                SfcElement::Step(s) => rename(&s.name).text.to_ascii_uppercase(),
                SfcElement::Action(a) => a.name.text.to_ascii_uppercase(),
                SfcElement::Transition(_) => String::new(),
            }
        };
        let rank = |k: Kind| match k {
            Kind::Step => 0,
            Kind::Transition => 1,
            Kind::Action => 2,
        };
        elems.sort_by(|a, b| {
            rank(a.kind)
                .cmp(&rank(b.kind))
                .then_with(|| name_key(a).cmp(&name_key(b)))
                .then_with(|| from_key(a).cmp(&from_key(b)))
        });
        Shape { head, attrs: pou_attrs, comments, elems }
    }

    /// The places of jumps the file draws once for several transitions (one `jumpStep` after
    /// a convergence, which the editor draws as a jump per transition, side by side) that
    /// `new` puts at different places: the file's one `jumpStep` cannot follow, and keeps its
    /// place. Target and place as PLCopen writes them. (Moved together, they move it.)
    fn shared_jumps(&self, new: &Shape) -> SharedJumps {
        let mut seen: HashMap<(String, String, String), std::collections::HashSet<(String, String)>> = HashMap::new();
        let mut count: HashMap<(String, String, String), usize> = HashMap::new();
        for (o, n) in self.elems.iter().zip(&new.elems) {
            for (a, b) in o.jumps.iter().zip(&n.jumps) {
                seen.entry(jump_key(a)).or_default().insert((attrs::fmt_num(b.1), attrs::fmt_num(b.2)));
                *count.entry(jump_key(a)).or_default() += 1;
            }
        }
        seen.into_iter()
            .filter(|(k, places)| places.len() > 1 && count.get(k).is_some_and(|n| *n > 1))
            .map(|(k, _)| k)
            .collect()
    }

    /// The same meaning and the same places as `other` (`self` read from a file: a size the
    /// file does not hold is any size; a jump the file draws once for several transitions,
    /// `shared`, may be anywhere: the file has one place for all of them).
    fn same_as(&self, other: &Shape, shared: &SharedJumps) -> bool {
        self.head == other.head
            && self.attrs == other.attrs
            && self.comments == other.comments
            && self.elems.len() == other.elems.len()
            && self.elems.iter().zip(&other.elems).all(|(a, b)| {
                a.kind == b.kind
                    && a.printed == b.printed
                    && a.attrs == b.attrs
                    && a.geometry
                        .iter()
                        .zip(&b.geometry)
                        .enumerate()
                        .all(|(i, (x, y))| same_num(*x, *y) || (i >= 2 && x.is_none()))
                    && a.blocks.len() == b.blocks.len()
                    && a.blocks
                        .iter()
                        .zip(&b.blocks)
                        .all(|(x, y)| x.iter().zip(y).all(|(p, q)| same_num(Some(*p), Some(*q))))
                    && a.jumps.len() == b.jumps.len()
                    && a.jumps.iter().zip(&b.jumps).all(|(x, y)| {
                        x.0.eq_ignore_ascii_case(&y.0)
                            && (shared.contains(&jump_key(x))
                                || (same_num(Some(x.1), Some(y.1)) && same_num(Some(x.2), Some(y.2))))
                    })
            })
    }
}

/// Jumps by target and place, as PLCopen writes the place.
type SharedJumps = std::collections::HashSet<(String, String, String)>;

fn jump_key(j: &(String, f64, f64)) -> (String, String, String) {
    (j.0.to_ascii_lowercase(), attrs::fmt_num(j.1), attrs::fmt_num(j.2))
}

/// `x y w h n;…` → the places and the counts (`;`-joined), `None` when malformed.
fn action_blocks(v: &str) -> Option<(Vec<[f64; 4]>, String)> {
    let mut places = Vec::new();
    let mut counts = Vec::new();
    for block in v.split(';').filter(|b| !b.trim().is_empty()) {
        let parts: Vec<&str> = block.split_whitespace().collect();
        let [x, y, w, h, n] = parts.as_slice() else { return None };
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
        places.push([num(x)?, num(y)?, num(w)?, num(h)?]);
        counts.push(n.to_string());
    }
    Some((places, counts.join(";")))
}

/// `Target x y;…` → the jumps, `None` when malformed.
fn jump_places(v: &str) -> Option<Vec<(String, f64, f64)>> {
    let mut out = Vec::new();
    for jump in v.split(';').filter(|b| !b.trim().is_empty()) {
        let parts: Vec<&str> = jump.split_whitespace().collect();
        let [t, x, y] = parts.as_slice() else { return None };
        let num = |s: &str| s.parse::<f64>().ok().filter(|v| v.is_finite());
        out.push((t.to_string(), num(x)?, num(y)?));
    }
    Some(out)
}

/// A POU printed alone, without its pragmas and comments.
fn print_pou(pou: Pou) -> String {
    let span = pou.span;
    let unit = SourceUnit { items: vec![Item::Pou(pou)], trivia: Vec::new(), blank_lines: Vec::new(), span };
    sfc_syntax::print::print(&unit)
}

/// One chart element printed alone (in an empty POU of `pou`'s kind and name).
fn print_element(pou: &Pou, e: SfcElement) -> String {
    let shell = Pou {
        kind: pou.kind,
        name: pou.name.clone(),
        return_type: None,
        attributes: Vec::new(),
        var_blocks: Vec::new(),
        body: Body::Sfc(vec![e]),
        actions: Vec::new(),
        modifiers: Vec::new(),
        extends: None,
        implements: Vec::new(),
        methods: Vec::new(),
        properties: Vec::new(),
        span: pou.span,
    };
    print_pou(shell)
}

/// The edits in place that make the file's POU the new one.
struct Plan<'d, 'i> {
    doc: &'d Document<'i>,
    map: &'d crate::SourceMap,
    old_text: &'d str,
    /// Byte ranges of the file and what replaces them.
    edits: Vec<(Range<usize>, String)>,
    /// Something else than places changes (a condition, a name).
    content: bool,
}

impl<'d, 'i> Plan<'d, 'i> {
    /// The element of the file the import wrote the text at `at` (of the imported text) from.
    fn element_at(&self, at: u32) -> Option<Node<'d, 'i>> {
        let r = self.map.to_xml(Span::new(0, at, at.saturating_add(1)));
        let start = r.start as usize;
        self.doc.descendants().find(|n| n.is_element() && n.range().start == start)
    }

    /// Sets the value of attribute `name` of `n` to the number `v`.
    fn set_num(&mut self, n: Node, name: &str, v: f64) -> Option<()> {
        let r = attr_range(n, name)?;
        self.edit(r.start as usize..r.end as usize, attrs::fmt_num(v))
    }

    fn edit(&mut self, r: Range<usize>, text: String) -> Option<()> {
        // The same edit twice (a jump two transitions lead to) is one; two different ones at one
        // place are a contradiction.
        if let Some((_, t)) = self.edits.iter().find(|(q, _)| q.start < r.end && r.start < q.end) {
            return (t == &text && self.edits.iter().any(|(q, _)| *q == r)).then_some(());
        }
        self.edits.push((r, text));
        Some(())
    }

    /// Compares the old POU with the new one element by element and plans the edits; `None`
    /// when a difference cannot be written in place.
    fn compare(&mut self, old: &Shape, new: &Shape, new_text: &str, shared: &SharedJumps) -> Option<()> {
        if old.head != new.head || old.attrs != new.attrs || old.comments != new.comments {
            return None;
        }
        if old.elems.len() != new.elems.len() {
            return None;
        }
        for (o, n) in old.elems.iter().zip(&new.elems) {
            if o.kind != n.kind || o.attrs != n.attrs {
                return None;
            }
            if o.printed != n.printed {
                if o.kind != Kind::Transition || o.bare != n.bare {
                    return None;
                }
                self.condition(o, n, new_text)?;
            }
            let moved = !o.geometry.iter().zip(&n.geometry).all(|(a, b)| same_num(*a, *b));
            if moved {
                self.geometry(o, n)?;
            }
            if o.blocks.len() != n.blocks.len() || o.jumps.len() != n.jumps.len() {
                return None;
            }
            let blocks_moved = o
                .blocks
                .iter()
                .zip(&n.blocks)
                .any(|(a, b)| !a.iter().zip(b).all(|(p, q)| same_num(Some(*p), Some(*q))));
            if blocks_moved {
                self.action_blocks(o, n)?;
            }
            for (a, b) in o.jumps.iter().zip(&n.jumps) {
                // A jump the file draws once for several transitions keeps its one place.
                if shared.contains(&jump_key(a)) {
                    continue;
                }
                if !same_num(Some(a.1), Some(b.1)) || !same_num(Some(a.2), Some(b.2)) {
                    self.jump(o, a, b)?;
                }
            }
        }
        Some(())
    }

    /// The file's element of a step or transition of the old POU.
    fn element_of(&self, e: &Elem) -> Option<Node<'d, 'i>> {
        let (start, kinds): (u32, &[&str]) = match e.node {
            SfcElement::Step(s) => (s.span.start, &["step", "macroStep"]),
            SfcElement::Transition(t) => (t.span.start, &["transition"]),
            SfcElement::Action(_) => return None,
        };
        self.element_at(start).filter(|n| kinds.contains(&n.tag_name().name()))
    }

    /// A step or transition moved or resized: its `position` and `width`/`height`.
    fn geometry(&mut self, o: &Elem, n: &Elem) -> Option<()> {
        let node = self.element_of(o)?;
        let position = child(node, "position");
        for (i, (a, b)) in o.geometry.iter().zip(&n.geometry).enumerate() {
            if same_num(*a, *b) {
                continue;
            }
            // A size the file does not hold (PLCopen's `width` and `height` are optional) is
            // not added: the tool that reads the file sizes the element itself.
            if i >= 2 && a.is_none() {
                continue;
            }
            // The file has no place to change (a chart without layout), or the new POU lost it.
            let (Some(_), Some(v)) = (a, b) else { return None };
            match i {
                0 => self.set_num(position?, "x", *v)?,
                1 => self.set_num(position?, "y", *v)?,
                2 => self.set_num(node, "width", *v)?,
                _ => self.set_num(node, "height", *v)?,
            }
        }
        Some(())
    }

    /// A step's action blocks moved or resized: the `actionBlock` elements wired to the step,
    /// in document order, are its `sfc.actionblock` entries.
    fn action_blocks(&mut self, o: &Elem, n: &Elem) -> Option<()> {
        let step = self.element_of(o)?;
        let id = attr(step, "localId")?.trim().to_string();
        let body = step.parent()?;
        let wired: Vec<Node> = elements(body)
            .filter(|e| e.tag_name().name() == "actionBlock")
            .filter(|e| {
                children(*e, "connectionPointIn")
                    .next()
                    .and_then(|c| children(c, "connection").next())
                    .and_then(|c| attr(c, "refLocalId"))
                    .is_some_and(|r| r.trim() == id)
            })
            .collect();
        if wired.len() != o.blocks.len() {
            return None;
        }
        for ((block, a), b) in wired.iter().zip(&o.blocks).zip(&n.blocks) {
            let position = child(*block, "position");
            for (i, (p, q)) in a.iter().zip(b).enumerate() {
                if same_num(Some(*p), Some(*q)) {
                    continue;
                }
                match i {
                    0 => self.set_num(position?, "x", *q)?,
                    1 => self.set_num(position?, "y", *q)?,
                    2 => self.set_num(*block, "width", *q)?,
                    _ => self.set_num(*block, "height", *q)?,
                }
            }
        }
        Some(())
    }

    /// A jump below transition `o` moved from `a` to `b`: the one `jumpStep` of the chart to
    /// that step at the old place.
    fn jump(&mut self, o: &Elem, a: &(String, f64, f64), b: &(String, f64, f64)) -> Option<()> {
        let transition = self.element_of(o)?;
        let body = transition.parent()?;
        let at = |n: Node| -> bool {
            let p = crate::xml::position(n);
            p.is_some_and(|(x, y)| same_num(Some(x), Some(a.1)) && same_num(Some(y), Some(a.2)))
        };
        let mut found = elements(body).filter(|e| {
            e.tag_name().name() == "jumpStep"
                && attr(*e, "targetName").is_some_and(|t| t.trim().eq_ignore_ascii_case(&a.0))
                && at(*e)
        });
        let jump = found.next()?;
        if found.next().is_some() {
            return None;
        }
        let position = child(jump, "position")?;
        if !same_num(Some(a.1), Some(b.1)) {
            self.set_num(position, "x", b.1)?;
        }
        if !same_num(Some(a.2), Some(b.2)) {
            self.set_num(position, "y", b.2)?;
        }
        Some(())
    }

    /// An inline ST condition edited: the text inside its `xhtml:p` (or `ST`) replaced by the
    /// new expression, as typed.
    fn condition(&mut self, o: &Elem, n: &Elem, new_text: &str) -> Option<()> {
        let (SfcElement::Transition(ot), SfcElement::Transition(nt)) = (o.node, n.node) else { return None };
        let (Condition::St(old_expr), Condition::St(new_expr)) = (&ot.condition, &nt.condition) else {
            return None;
        };
        let node = self.element_of(o)?;
        let cond = child(node, "condition")?;
        // A negated condition is imported as `NOT (…)`: not the file's text.
        if crate::xml::flag(cond, "negated") {
            return None;
        }
        let st = child(child(cond, "inline")?, "ST")?;
        let old_slice = self.old_text.get(old_expr.span.start as usize..old_expr.span.end as usize)?;
        let r = self.map.to_xml(old_expr.span);
        let r = r.start as usize..r.end as usize;
        let src = self.doc.input_text();
        // The import copied the expression from the file as it is there (no escapes, no
        // words mapped), inside the `ST` element.
        if src.get(r.clone())? != old_slice || r.start < st.range().start || r.end > st.range().end {
            return None;
        }
        let typed = new_text.get(new_expr.span.start as usize..new_expr.span.end as usize)?;
        let before = src.get(st.range().start..r.start)?;
        let in_cdata = before.rfind("<![CDATA[").is_some_and(|c| before.rfind("]]>").is_none_or(|e| e < c));
        let text = if in_cdata {
            if typed.contains("]]>") {
                return None;
            }
            typed.to_string()
        } else {
            crate::xml::escape_text(typed)
        };
        self.content = true;
        self.edit(r, text)
    }

    /// Renamed steps: the step's `name` and every jump to it.
    fn rename(&mut self, old: &Shape, renames: &HashMap<String, String>) -> Option<()> {
        // The chart's steps, by their old names.
        let mut steps: BTreeMap<String, (Node<'d, 'i>, String)> = BTreeMap::new();
        for e in old.elems.iter().filter(|e| e.kind == Kind::Step) {
            let SfcElement::Step(s) = e.node else { continue };
            let Some(new_name) = renames.get(&s.name.text.to_ascii_uppercase()) else { continue };
            let node = self.element_of(e)?;
            if node.tag_name().name() != "step" || attr(node, "name").map(str::trim) != Some(s.name.text.as_str()) {
                return None;
            }
            steps.insert(s.name.text.to_ascii_uppercase(), (node, new_name.clone()));
        }
        if steps.len() != renames.len() {
            return None;
        }
        for (old_name, (node, new_name)) in steps {
            let r = attr_range(node, "name")?;
            self.edit(r.start as usize..r.end as usize, crate::xml::escape_attr(&new_name))?;
            let body = node.parent()?;
            let jumps: Vec<NodeId> = body
                .descendants()
                .filter(|e| {
                    e.tag_name().name() == "jumpStep"
                        && attr(*e, "targetName").is_some_and(|t| t.trim().eq_ignore_ascii_case(&old_name))
                })
                .map(|e| e.id())
                .collect();
            for id in jumps {
                let j = self.doc.get_node(id)?;
                let r = attr_range(j, "targetName")?;
                self.edit(r.start as usize..r.end as usize, crate::xml::escape_attr(&new_name))?;
            }
        }
        self.content = true;
        Some(())
    }
}

/// `xml` with the edits made.
fn apply(xml: &str, mut edits: Vec<(Range<usize>, String)>) -> Option<String> {
    edits.sort_by_key(|(r, _)| r.start);
    let mut out = String::with_capacity(xml.len() + 64);
    let mut at = 0;
    for (r, text) in edits {
        out.push_str(xml.get(at..r.start)?);
        out.push_str(&text);
        at = r.end;
    }
    out.push_str(xml.get(at..)?);
    Some(out)
}
