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

/// Probes, with a cache for names (charts repeat them in FROM/TO lists and jumps) and comments.
#[derive(Default)]
pub struct Probe {
    names: HashMap<String, bool>,
    comments: HashMap<String, bool>,
    /// The chart's POU is marked `{attribute 'sfc.dialect' := 'codesys'}`: names with doubled
    /// or trailing underscores (`Move__Pos3`) are names.
    codesys: bool,
}

/// The SFC elements of the only POU of a probe, when it parsed without any diagnostic.
fn parse_probe(text: &str) -> Option<(ast::Pou, Vec<SfcElement>)> {
    parse_probe_with_trivia(text).map(|(pou, elements, _)| (pou, elements))
}

/// [`parse_probe`] with the probe's comments.
fn parse_probe_with_trivia(text: &str) -> Option<(ast::Pou, Vec<SfcElement>, Vec<ast::Trivia>)> {
    let (unit, mut diags) = sfc_syntax::parse(0, text);
    // The note that a CODESYS name was read (a probe of a POU marked `sfc.dialect`).
    diags.retain(|d| d.code != "SFC0013");
    let comments: Vec<ast::Trivia> = unit.trivia.iter().filter(|t| region::is_comment(t)).cloned().collect();
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
    Some((pou, elements, comments))
}

impl Probe {
    /// A probe for a chart whose POU carries `attributes` (those the editor keeps as they are).
    pub fn for_attributes(attributes: &[crate::OtherAttribute]) -> Probe {
        let codesys = attributes.iter().any(|a| {
            a.name.eq_ignore_ascii_case("sfc.dialect")
                && a.value.as_deref().is_some_and(|v| v.eq_ignore_ascii_case("codesys"))
        });
        Probe { codesys, ..Probe::default() }
    }

    /// The pragma a probe starts with in a CODESYS POU, whose names (`Run__Pump.t`) its
    /// conditions, bodies and step actions may use.
    fn dialect(&self) -> &'static str {
        if self.codesys {
            "{attribute 'sfc.dialect' := 'codesys'}\n"
        } else {
            ""
        }
    }

    /// Whether `s` can be written as a POU, step, transition and action name.
    pub fn is_name(&mut self, s: &str) -> bool {
        if let Some(&v) = self.names.get(s) {
            return v;
        }
        let ok = !s.is_empty() && s.len() <= 1000 && Self::name_probe(s, self.codesys);
        self.names.insert(s.to_string(), ok);
        ok
    }

    fn name_probe(s: &str, codesys: bool) -> bool {
        let dialect = if codesys { "{attribute 'sfc.dialect' := 'codesys'}\n" } else { "" };
        let text = format!(
            "{dialect}PROGRAM {s}\n    INITIAL_STEP {s}: {s}(N); END_STEP\n    TRANSITION {s} FROM {s} TO {s}\n        := TRUE;\n    END_TRANSITION\n{END}END_PROGRAM\n"
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

    /// Whether `c` can be written on a line of its own and reads back as exactly this one
    /// comment.
    pub fn is_comment(&mut self, c: &str) -> bool {
        if let Some(&v) = self.comments.get(c) {
            return v;
        }
        let ok = c.len() <= 100_000 && Self::comment_probe(c);
        self.comments.insert(c.to_string(), ok);
        ok
    }

    fn comment_probe(c: &str) -> bool {
        let text = format!("PROGRAM P\n    INITIAL_STEP S: END_STEP\n\n    {c}\n{END}END_PROGRAM\n");
        match parse_probe_with_trivia(&text) {
            Some((_, elements, comments)) => elements.len() == 2 && comments.len() == 1 && comments[0].text == c,
            None => false,
        }
    }

    /// The comments of a list that can be written (see [`Probe::is_comment`]), in order.
    pub fn comments(&mut self, list: &[String]) -> Vec<String> {
        list.iter().filter(|c| self.is_comment(c)).cloned().collect()
    }

    /// What to write after a transition's `FROM … TO …` for a condition, and what it reads
    /// back as. A condition that does not parse is written `FALSE`; one with a comment outside
    /// the condition (`go (* c *)`: the comment would belong to the transition) is written as
    /// it reads back.
    pub fn condition(&mut self, cond: Option<&str>, lang: Language) -> (String, Option<String>, Language) {
        let mut cond = cond.map(str::to_string);
        for _ in 0..2 {
            let Some(c) = cond.take() else { break };
            let fragment = condition_fragment(&c, lang);
            let dialect = self.dialect();
            let text = format!(
                "{dialect}PROGRAM P\n    INITIAL_STEP S: END_STEP\n\n    TRANSITION FROM S TO S{fragment}    END_TRANSITION\n\n{END}END_PROGRAM\n"
            );
            if let Some((_, elements, comments)) = parse_probe_with_trivia(&text) {
                if let (3, SfcElement::Transition(t)) = (elements.len(), &elements[1]) {
                    let (read, read_lang) = region::condition(&text, &t.condition);
                    let range = region::condition_range(&text, &t.condition);
                    if comments.iter().all(|k| region::within(k, range)) {
                        if read.is_some() {
                            return (fragment, read, read_lang);
                        }
                    } else if read_lang == lang {
                        cond = read;
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
        // An action written in SFC of a CODESYS POU may use its names (`Move__Pos3`).
        let dialect = self.dialect();
        let text = format!("{dialect}PROGRAM P\n    INITIAL_STEP S: END_STEP\n\n{action}\n{END}END_PROGRAM\n");
        if let Some((_, elements)) = parse_probe(&text) {
            if let (3, SfcElement::Action(a)) = (elements.len(), &elements[1]) {
                let read = ActionDef {
                    name: a.name.text.clone(),
                    language: region::action_language(&a.body),
                    body: region::action_body(&text, a.span, a.name.span),
                    description: def.description.clone(),
                    attributes: pragma::readable(&def.attributes, pragma::ACTION),
                    comments: self.comments(&def.comments),
                    chart: None,
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
            comments: self.comments(&def.comments),
            chart: None,
        };
        (text_of(""), empty)
    }

    /// The declarations as written (indented, with a final line break, or empty) and what they
    /// read back as. Declarations that do not parse are not written; those with a comment
    /// outside their `VAR … END_VAR` blocks (it would belong to the first element) are written
    /// as they read back.
    pub fn declarations(&mut self, decl: &str) -> (String, String) {
        let mut decl = decl.to_string();
        for _ in 0..2 {
            let written = declarations_text(&decl);
            if written.is_empty() {
                return (written, String::new());
            }
            // In the POU's dialect: CODESYS names (`bLoop__Under`) are declared as written.
            let dialect = self.dialect();
            let text = format!("{dialect}PROGRAM P\n{written}\n{END}END_PROGRAM\n");
            let Some((pou, elements, comments)) = parse_probe_with_trivia(&text) else { break };
            if elements.len() != 1 {
                break;
            }
            let read = region::declarations(&text, &pou);
            let range = region::declarations_range(&text, &pou);
            if comments.iter().all(|k| region::within(k, range)) {
                return (written, read);
            }
            decl = read;
        }
        (String::new(), String::new())
    }

    /// The text of a step action (`ENTRY_ACTION := Name`) as the text writes it, when it reads
    /// back as one step action; `None` otherwise.
    pub fn step_action(&mut self, written: &str) -> Option<String> {
        let written = written.trim().trim_end_matches(';').trim().to_string();
        let dialect = self.dialect();
        let text =
            format!("{dialect}PROGRAM P\n    INITIAL_STEP S:\n        {written};\n    END_STEP\n\n{END}END_PROGRAM\n");
        let (_, elements) = parse_probe(&text)?;
        match (elements.len(), &elements[0]) {
            (2, SfcElement::Step(s)) if s.step_actions.len() == 1 && s.associations.is_empty() => {
                let a = &s.step_actions[0];
                Some(format!("{} := {}", a.kind.keyword(), a.name()))
            }
            _ => None,
        }
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
            comments: vec!["(* fills *)".into()],
            chart: None,
        };
        assert_eq!(p.action(&def).1, def);
        let broken = ActionDef { body: "x := ;".into(), ..def.clone() };
        assert_eq!(p.action(&broken).1.body, "");
    }

    #[test]
    fn comments_read_back() {
        let mut p = Probe::default();
        for ok in ["(* a *)", "// b", "(* two\n   lines *)", "(**)", "//"] {
            assert!(p.is_comment(ok), "{ok}");
        }
        for bad in ["", "x", "(* a", "(* a *) b", "// a\nb", "{attribute 'x'}", "(* a *)(* b *)", "a *)"] {
            assert!(!p.is_comment(bad), "{bad}");
        }
        let (_, read, _) = p.condition(Some("go (* c *)"), Language::St);
        assert_eq!(read.as_deref(), Some("go"));
        let (fragment, read, _) = p.condition(Some("go (* c *) AND x"), Language::St);
        assert_eq!(
            (fragment.as_str(), read.as_deref()),
            ("\n        := go (* c *) AND x;\n", Some("go (* c *) AND x"))
        );
        assert_eq!(
            p.declarations("VAR\nEND_VAR\n(* trailing *)"),
            ("    VAR\n    END_VAR\n".into(), "VAR\nEND_VAR".into())
        );
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
