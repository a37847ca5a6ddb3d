//! A POU's text cut into the regions of its elements, for saves that change only what changed
//! and for three-way merges by element (`sfc-doc`, `sfc-diff`).
//!
//! The regions cover the POU from its first attribute pragma (at the start of its line) to
//! `END_PROGRAM` / `END_FUNCTION_BLOCK` without gaps: each POU attribute, the header (up to the
//! end of the line of the POU's name), the declarations, then each step, transition and action,
//! and the tail. A region runs from the end of the one before to the end of its element's line
//! (a comment ending that line included), so the comments and blank lines between two elements
//! belong to the element after them, as the editor reads them.

use crate::ast::{Attribute, Body, Pou, SfcElement};
use std::ops::Range;

/// What a region holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RegionKind {
    /// One attribute pragma before the POU.
    Attribute,
    /// The editor's layout: `sfc.graph` and its `sfc.graph.e` / `sfc.graph.c` lines.
    Graph,
    /// The POU keyword and name (and what follows on that line).
    Head,
    /// The variable blocks.
    Declarations,
    Step,
    Transition,
    Action,
    /// A body that is no chart (statements), whole.
    Body,
    /// What follows the last element, up to the end keyword.
    Tail,
}

/// One region of a POU's text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Region {
    /// Stable within a POU: `@name#k` (the k-th attribute of that name, lower case), `graph`,
    /// `head`, `decl`, `step:name`, `transition:name` (`transition#k` for the k-th unnamed one),
    /// `action:name` (names lower case), `body`, `tail`.
    pub key: String,
    /// The element's name as written (a step's, a transition's, an action's, an attribute's);
    /// empty for the others.
    pub name: String,
    pub kind: RegionKind,
    /// Byte range in the text.
    pub range: Range<usize>,
    /// Where the element itself begins (its attribute pragmas or keyword), after the comments
    /// and blank lines before it.
    pub lead: usize,
}

/// The line end after `at`: past the line break when only white space or a comment follows
/// on the line, else `at` itself.
fn line_end(text: &str, at: usize) -> usize {
    let Some(rest) = text.get(at..) else { return at };
    let (line, brk) = match rest.find('\n') {
        Some(i) => (&rest[..i], i + 1),
        None => (rest, rest.len()),
    };
    let t = line.trim();
    if t.is_empty() || t.starts_with("//") || (t.starts_with("(*") && t.ends_with("*)")) {
        at + brk
    } else {
        at
    }
}

/// The start of `at`'s line when only white space precedes it there.
fn line_start(text: &str, at: usize) -> usize {
    let before = text.get(..at).unwrap_or("");
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    if before.get(start..).is_some_and(|s| s.chars().all(|c| c == ' ' || c == '\t')) {
        start
    } else {
        at
    }
}

fn lead_of(attributes: &[Attribute], start: u32) -> usize {
    attributes.iter().map(|a| a.span.start).chain([start]).min().unwrap_or(start) as usize
}

/// Is this attribute one of the editor's layout lines?
fn is_graph(a: &Attribute) -> bool {
    let n = a.name.to_ascii_lowercase();
    n == "sfc.graph" || n == "sfc.graph.e" || n == "sfc.graph.c"
}

/// The regions of `pou` in `text` (the text it was parsed from), in text order.
pub fn regions(text: &str, pou: &Pou) -> Vec<Region> {
    let mut out: Vec<Region> = Vec::new();
    let pou_start = lead_of(&pou.attributes, pou.span.start);
    let mut at = line_start(text, pou_start);
    let push = |out: &mut Vec<Region>, (key, name): (String, &str), kind: RegionKind, end: usize, lead: usize, at: &mut usize| {
        let end = end.max(*at).min(text.len());
        out.push(Region { key, name: name.to_string(), kind, range: *at..end, lead: lead.clamp(*at, end) });
        *at = end;
    };
    // The attributes before the POU keyword, the layout's as one region when they follow
    // each other.
    let mut seen: Vec<(String, usize)> = Vec::new();
    let mut attrs: Vec<&Attribute> = pou.attributes.iter().filter(|a| a.span.start < pou.span.start).collect();
    attrs.sort_by_key(|a| a.span.start);
    let mut k = 0;
    while let Some(a) = attrs.get(k) {
        if is_graph(a) {
            let mut last = k;
            while attrs.get(last + 1).is_some_and(|b| is_graph(b)) {
                last += 1;
            }
            let end = attrs.get(last).map_or(a.span.end, |b| b.span.end) as usize;
            let key = if out.iter().any(|r| r.key == "graph") { format!("graph#{k}") } else { "graph".to_string() };
            push(&mut out, (key, ""), RegionKind::Graph, line_end(text, end), line_start(text, a.span.start as usize), &mut at);
            k = last + 1;
            continue;
        }
        let name = a.name.to_ascii_lowercase();
        let n = match seen.iter_mut().find(|(s, _)| *s == name) {
            Some((_, n)) => {
                *n += 1;
                *n
            }
            None => {
                seen.push((name.clone(), 0));
                0
            }
        };
        let lead = line_start(text, a.span.start as usize);
        push(&mut out, (format!("@{name}#{n}"), &a.name), RegionKind::Attribute, line_end(text, a.span.end as usize), lead, &mut at);
        k += 1;
    }
    // The header: up to the end of the name's line (`PROGRAM P`, `FUNCTION_BLOCK F EXTENDS B`).
    let head_end = [pou.name.span.end as usize]
        .into_iter()
        .chain(pou.extends.iter().map(|e| e.span.end as usize))
        .chain(pou.implements.iter().map(|e| e.span.end as usize))
        .max()
        .unwrap_or(pou.span.start as usize);
    let head_line = text.get(head_end..).and_then(|r| r.find('\n')).map_or(text.len(), |i| head_end + i + 1);
    let lead = line_start(text, pou.span.start as usize);
    push(&mut out, ("head".into(), &pou.name.text), RegionKind::Head, head_line, lead, &mut at);
    if let Some(last) = pou.var_blocks.iter().map(|b| b.span.end).max() {
        let first = pou.var_blocks.iter().map(|b| b.span.start).min().unwrap_or(last) as usize;
        push(&mut out, ("decl".into(), ""), RegionKind::Declarations, line_end(text, last as usize), line_start(text, first), &mut at);
    }
    match &pou.body {
        Body::Sfc(elements) => {
            let mut unnamed = 0;
            for e in elements {
                let (key, kind, lead) = match e {
                    SfcElement::Step(s) => (
                        (format!("step:{}", s.name.text.to_ascii_lowercase()), s.name.text.as_str()),
                        RegionKind::Step,
                        lead_of(&s.attributes, s.span.start),
                    ),
                    SfcElement::Transition(t) => {
                        let key = match &t.name {
                            Some(n) => (format!("transition:{}", n.text.to_ascii_lowercase()), n.text.as_str()),
                            None => {
                                unnamed += 1;
                                (format!("transition#{}", unnamed - 1), "")
                            }
                        };
                        (key, RegionKind::Transition, lead_of(&t.attributes, t.span.start))
                    }
                    SfcElement::Action(a) => (
                        (format!("action:{}", a.name.text.to_ascii_lowercase()), a.name.text.as_str()),
                        RegionKind::Action,
                        lead_of(&a.attributes, a.span.start),
                    ),
                };
                let lead = line_start(text, lead);
                push(&mut out, key, kind, line_end(text, e.span().end as usize), lead, &mut at);
            }
        }
        _ => {
            // Statements, then the actions of a POU in ST: the statements end where the first
            // action (or method, property) begins.
            let next = pou
                .actions
                .iter()
                .map(|a| lead_of(&a.attributes, a.span.start))
                .chain(pou.methods.iter().map(|m| m.span.start as usize))
                .chain(pou.properties.iter().map(|p| p.span.start as usize))
                .min();
            if let Some(n) = next {
                let end = line_start(text, n);
                push(&mut out, ("body".into(), ""), RegionKind::Body, end, at, &mut at);
            }
        }
    }
    if !matches!(pou.body, Body::Sfc(_)) {
        for a in &pou.actions {
            let lead = line_start(text, lead_of(&a.attributes, a.span.start));
            let key = format!("action:{}", a.name.text.to_ascii_lowercase());
            push(&mut out, (key, &a.name.text), RegionKind::Action, line_end(text, a.span.end as usize), lead, &mut at);
        }
    }
    let end = line_end(text, pou.span.end as usize);
    // Without a break after the end keyword the tail ends with it.
    let end = if end == pou.span.end as usize { pou.span.end as usize } else { end };
    let key = if matches!(pou.body, Body::Sfc(_)) || !pou.actions.is_empty() { "tail" } else { "body" };
    let kind = if key == "tail" { RegionKind::Tail } else { RegionKind::Body };
    push(&mut out, (key.into(), ""), kind, end, at, &mut at);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ast::Item;

    fn cut(text: &str) -> Vec<(String, String)> {
        let (unit, diags) = crate::parse(0, text);
        assert!(diags.is_empty(), "{diags:?}");
        let Some(Item::Pou(p)) = unit.items.first() else { panic!("no POU") };
        let r = regions(text, p);
        // Without gaps.
        for w in r.windows(2) {
            assert_eq!(w[0].range.end, w[1].range.start, "{r:?}");
        }
        r.iter().map(|r| (r.key.clone(), text[r.range.clone()].to_string())).collect()
    }

    #[test]
    fn cuts_a_chart_into_its_elements() {
        let text = "{attribute 'sfc.target' := 'blank'}\n{attribute 'sfc.graph' := '{}'}\n{attribute 'sfc.graph.e' := '{}'}\nPROGRAM P\n    VAR\n        A : BOOL;\n    END_VAR\n\n    (* first *)\n    {attribute 'sfc.x' := '1'}\n    INITIAL_STEP S1: END_STEP (* one *)\n    STEP S2: END_STEP\n    TRANSITION FROM S1 TO S2 := A; END_TRANSITION\n    TRANSITION T2 FROM S2 TO S1\n        := NOT A;\n    END_TRANSITION\n    ACTION Go: A := TRUE; END_ACTION\nEND_PROGRAM\n";
        let r = cut(text);
        let keys: Vec<&str> = r.iter().map(|(k, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            ["@sfc.target#0", "graph", "head", "decl", "step:s1", "step:s2", "transition#0", "transition:t2", "action:go", "tail"]
        );
        assert_eq!(r[4].1, "\n    (* first *)\n    {attribute 'sfc.x' := '1'}\n    INITIAL_STEP S1: END_STEP (* one *)\n");
        assert_eq!(r[9].1, "END_PROGRAM\n");
        assert_eq!(r.iter().map(|(_, t)| t.as_str()).collect::<String>(), text);
    }

    #[test]
    fn cuts_a_program_in_st_with_actions() {
        let text = "PROGRAM P\nVAR x : INT; END_VAR\nx := x + 1;\nACTION A: x := 0; END_ACTION\nEND_PROGRAM";
        let keys: Vec<String> = cut(text).into_iter().map(|(k, _)| k).collect();
        assert_eq!(keys, ["head", "decl", "body", "action:a", "tail"]);
    }
}
