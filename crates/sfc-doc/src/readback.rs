//! What a piece of a document reads back as once written: each name, condition, action body,
//! association and the declarations are written into a small program, parsed, and read with
//! the functions `open` uses (`region.rs`). A piece that does not parse alone (or would change
//! its neighbours, as a stray pragma does) is not written as typed; what was typed then travels
//! in the layout attribute, so saving never loses it and the text always parses.

use crate::pragma;
use crate::region;
use crate::{ActionDef, Association, Language};
use sfc_syntax::ast::{self, Body, Item, SfcElement};
use std::collections::HashMap;

/// The element written after every probed piece: a pragma or comment that would attach to the
/// next element shows up on it.
const END: &str = "    STEP Zz_probe_end: END_STEP\n";

/// Probes, with a cache for names (charts repeat them in FROM/TO lists and jumps).
#[derive(Default)]
pub struct Probe {
    names: HashMap<String, bool>,
}

/// The SFC elements of the only POU of a probe, when it parsed without any diagnostic.
fn parse_probe(text: &str) -> Option<(ast::Pou, Vec<SfcElement>)> {
    let (unit, diags) = sfc_syntax::parse(0, text);
    if !diags.is_empty() || unit.items.len() != 1 {
        return None;
    }
    let Some(Item::Pou(mut pou)) = unit.items.into_iter().next() else { return None };
    let body = std::mem::replace(&mut pou.body, Body::St(Vec::new()));
    let Body::Sfc(elements) = body else { return None };
    // The closing probe step must come back alone, without attributes.
    match elements.last() {
        Some(SfcElement::Step(s)) if s.name.text == "Zz_probe_end" && s.attributes.is_empty() => {}
        _ => return None,
    }
    Some((pou, elements))
}

impl Probe {
    /// Whether `s` can be written as a POU, step, transition and action name.
    pub fn is_name(&mut self, s: &str) -> bool {
        if let Some(&v) = self.names.get(s) {
            return v;
        }
        let ok = !s.is_empty() && s.len() <= 1000 && Self::name_probe(s);
        self.names.insert(s.to_string(), ok);
        ok
    }

    fn name_probe(s: &str) -> bool {
        let text = format!(
            "PROGRAM {s}\n    INITIAL_STEP {s}: {s}(N); END_STEP\n    TRANSITION {s} FROM {s} TO {s}\n        := TRUE;\n    END_TRANSITION\n{END}END_PROGRAM\n"
        );
        let Some((pou, elements)) = parse_probe(&text) else { return false };
        if pou.name.text != s || elements.len() != 3 {
            return false;
        }
        let step_ok = matches!(&elements[0], SfcElement::Step(st)
            if st.name.text == s && st.associations.len() == 1 && st.associations[0].action.text == s);
        let transition_ok = matches!(&elements[1], SfcElement::Transition(t)
            if t.name.as_ref().is_some_and(|n| n.text == s)
                && t.from.len() == 1 && t.from[0].text == s && t.to.len() == 1 && t.to[0].text == s);
        step_ok && transition_ok
    }

    /// What to write after a transition's `FROM … TO …` for a condition, and what it reads
    /// back as. A condition that does not parse is written `FALSE`.
    pub fn condition(&mut self, cond: Option<&str>, lang: Language) -> (String, Option<String>, Language) {
        if let Some(c) = cond {
            let fragment = condition_fragment(c, lang);
            let text = format!(
                "PROGRAM P\n    INITIAL_STEP S: END_STEP\n\n    TRANSITION FROM S TO S{fragment}    END_TRANSITION\n\n{END}END_PROGRAM\n"
            );
            if let Some((_, elements)) = parse_probe(&text) {
                if let (2.., SfcElement::Transition(t)) = (elements.len(), &elements[1]) {
                    if elements.len() == 3 {
                        let (read, read_lang) = region::condition(&text, &t.condition);
                        if read.is_some() {
                            return (fragment, read, read_lang);
                        }
                    }
                }
            }
        }
        (condition_fragment("FALSE", Language::St), Some("FALSE".to_string()), Language::St)
    }

    /// The text of an action (its name is valid) and the definition it reads back as. A body
    /// that does not parse is written empty.
    pub fn action(&mut self, def: &ActionDef) -> (String, ActionDef) {
        let text_of = |body: &str| action_text(&def.name, body);
        let action = text_of(&def.body);
        let text = format!("PROGRAM P\n    INITIAL_STEP S: END_STEP\n\n{action}\n{END}END_PROGRAM\n");
        if let Some((_, elements)) = parse_probe(&text) {
            if let (3, SfcElement::Action(a)) = (elements.len(), &elements[1]) {
                let read = ActionDef {
                    name: a.name.text.clone(),
                    language: region::action_language(&a.body),
                    body: region::action_body(&text, a.span, a.name.span),
                    description: def.description.clone(),
                    attributes: pragma::readable(&def.attributes, pragma::ACTION),
                };
                return (action, read);
            }
        }
        let empty = ActionDef {
            name: def.name.clone(),
            language: Language::St,
            body: String::new(),
            description: def.description.clone(),
            attributes: pragma::readable(&def.attributes, pragma::ACTION),
        };
        (text_of(""), empty)
    }

    /// The declarations as written (indented, with a final line break, or empty) and what they
    /// read back as. Declarations that do not parse are not written.
    pub fn declarations(&mut self, decl: &str) -> (String, String) {
        let written = declarations_text(decl);
        if written.is_empty() {
            return (written, String::new());
        }
        let text = format!("PROGRAM P\n{written}\n{END}END_PROGRAM\n");
        if let Some((pou, elements)) = parse_probe(&text) {
            if elements.len() == 1 {
                let read = region::declarations(&text, &pou);
                return (written, read);
            }
        }
        (String::new(), String::new())
    }

    /// The text of an association (`Action(Q, T#1s, Indicator)`), when it reads back exactly.
    pub fn association(&mut self, a: &Association) -> Option<String> {
        let written = association_text(a);
        let text = format!("PROGRAM P\n    INITIAL_STEP S:\n        {written};\n    END_STEP\n\n{END}END_PROGRAM\n");
        let (_, elements) = parse_probe(&text)?;
        match (elements.len(), &elements[0]) {
            (2, SfcElement::Step(s)) if s.associations.len() == 1 => {
                (region::association(&text, &s.associations[0]) == *a).then_some(written)
            }
            _ => None,
        }
    }
}

/// What follows `FROM … TO …`: `\n        := cond;\n` or `:\n        IL…\n`.
pub fn condition_fragment(cond: &str, lang: Language) -> String {
    match lang {
        Language::St => format!("\n        := {cond};\n"),
        Language::Il => format!(":\n{}\n", region::indent(cond, "        ")),
    }
}

/// `    ACTION name:` … `    END_ACTION` with a final line break.
pub fn action_text(name: &str, body: &str) -> String {
    if body.trim().is_empty() {
        format!("    ACTION {name}: END_ACTION\n")
    } else {
        format!("    ACTION {name}:\n{}\n    END_ACTION\n", region::indent(body, "        "))
    }
}

/// The declarations indented into a POU, with a final line break (empty when there are none).
pub fn declarations_text(decl: &str) -> String {
    if decl.trim().is_empty() {
        String::new()
    } else {
        format!("{}\n", region::indent(decl, "    "))
    }
}

/// `Action(Q, duration, indicator)`.
pub fn association_text(a: &Association) -> String {
    let mut parts = vec![a.qualifier.clone()];
    parts.extend(a.duration.iter().cloned());
    parts.extend(a.indicator.iter().cloned());
    format!("{}({})", a.action, parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names() {
        let mut p = Probe::default();
        for ok in ["S1", "Fill_Tank", "N", "x"] {
            assert!(p.is_name(ok), "{ok}");
        }
        for bad in ["", "1a", "a b", "END_STEP", "a__b", "a(*x*)", "S1;", "TRANSITION", "FROM"] {
            assert!(!p.is_name(bad), "{bad}");
        }
    }

    #[test]
    fn conditions_read_back() {
        let mut p = Probe::default();
        assert_eq!(p.condition(Some("a AND b"), Language::St).1.as_deref(), Some("a AND b"));
        assert_eq!(p.condition(Some("a AND"), Language::St).1.as_deref(), Some("FALSE"));
        assert_eq!(p.condition(Some("a; END_TRANSITION"), Language::St).1.as_deref(), Some("FALSE"));
        assert_eq!(p.condition(None, Language::St).1.as_deref(), Some("FALSE"));
        let (_, read, lang) = p.condition(Some("LD a\nAND b"), Language::Il);
        assert_eq!((read.as_deref(), lang), (Some("LD a\nAND b"), Language::Il));
    }

    #[test]
    fn actions_read_back() {
        let mut p = Probe::default();
        let def = ActionDef {
            name: "A".into(),
            language: Language::St,
            body: "x := 1;\nIF y THEN\n    z := 2;\nEND_IF;".into(),
            description: String::new(),
            attributes: Vec::new(),
        };
        assert_eq!(p.action(&def).1, def);
        let broken = ActionDef { body: "x := ;".into(), ..def.clone() };
        assert_eq!(p.action(&broken).1.body, "");
    }

    #[test]
    fn associations_read_back() {
        let mut p = Probe::default();
        let a =
            Association { qualifier: "D".into(), duration: Some("T#1s".into()), action: "A".into(), indicator: None };
        assert_eq!(p.association(&a).as_deref(), Some("A(D, T#1s)"));
        let bad =
            Association { qualifier: "N".into(), duration: Some("x".into()), action: "A".into(), indicator: None };
        assert_eq!(p.association(&bad), None);
    }
}
