//! Studio 5000 L5X → sfc text: the SFC routines of an L5X export (controller, program or
//! routine export) with the program's and controller's tags and data types.
//!
//! Each `<Routine Type="SFC">` becomes a `PROGRAM` marked `{attribute 'sfc.dialect' :=
//! 'logix'}`; what IEC text cannot hold (IDs, the description boxes, the links as drawn, the
//! tags' L5K data, the controller's SFC settings) is kept in `sfc.logix.*` attributes for a
//! later export. `docs/dev/logix-sfc.md` holds the research this is built on; the user's view
//! is in `docs/targets.md`, "Studio 5000 (Logix) L5X".

pub mod export;
mod chart;
mod st;
mod tags;

use roxmltree::Node;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_xmlmap::xml::{anchor, attr, attr_range, child, children};
use sfc_xmlmap::{Emitter, Frag, SourceMap};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::ops::Range;
use tags::{TagKind, Types, Var};

/// The result of importing one L5X file.
#[derive(Debug, Clone, Default)]
pub struct Output {
    /// The generated sfc text.
    pub text: String,
    /// Where each part of `text` came from in the XML.
    pub map: SourceMap,
    /// Problems of the import, located in the XML.
    pub diagnostics: Vec<Diagnostic>,
}

/// Whether `root` is the document element of an L5X export.
pub fn is_l5x(root: roxmltree::Node) -> bool {
    root.tag_name().name() == "RSLogix5000Content"
}

/// The controller's SFC settings Studio uses when a project does not change them, written when
/// a program or routine export does not carry the controller's.
pub const DEFAULT_SETTINGS: [(&str, &str, &str); 3] = [
    ("SFCExecutionControl", "sfc.logix.exec", "CurrentActive"),
    ("SFCRestartPosition", "sfc.logix.restart", "MostRecent"),
    ("SFCLastScan", "sfc.logix.lastscan", "DontScan"),
];

/// Imports an L5X file (`xml`, diagnostics in file `file`). Never panics.
pub fn import(file: u32, xml: &str) -> Output {
    let doc = match sfc_xmlmap::parse(file, xml) {
        Ok(d) => d,
        Err(d) => return Output { diagnostics: vec![d], ..Default::default() },
    };
    let root = doc.root_element();
    let mut cx = Ctx {
        file,
        em: Emitter::new(anchor(root)),
        diags: Vec::new(),
        types: Types::default(),
        names: HashMap::new(),
        renamed: HashMap::new(),
    };
    l5x(&mut cx, root);
    let (text, map) = cx.em.finish();
    Output { text, map, diagnostics: cx.diags }
}

/// The state of one import.
pub(crate) struct Ctx {
    pub file: u32,
    pub em: Emitter,
    pub diags: Vec<Diagnostic>,
    pub types: Types,
    /// Names read from `Operand` attributes, by the attribute's position (each reported once).
    names: HashMap<u32, Frag>,
    /// Tags imported under another name (upper-case Logix name → name in text).
    pub renamed: HashMap<String, String>,
}

impl Ctx {
    pub(crate) fn diag(&mut self, code: &'static str, at: Range<u32>, msg: impl Into<String>) -> &mut Diagnostic {
        self.diags.push(Diagnostic::new(code, Span::new(self.file, at.start, at.end), msg));
        let last = self.diags.len() - 1;
        // Just pushed: the index exists.
        match self.diags.get_mut(last) {
            Some(d) => d,
            None => unreachable!("a diagnostic was just pushed"),
        }
    }

    pub(crate) fn problems(&mut self, list: &[st::Problem]) {
        for (code, at, msg, note) in list {
            let d = self.diag(code, at.clone(), msg.clone());
            if let Some(n) = note {
                d.notes.push(n.clone());
            }
        }
    }

    /// The name in `Operand` of a step, stop, transition or action, located exactly; a name that
    /// is not an IEC identifier is repaired and reported (once).
    pub(crate) fn operand_name(&mut self, n: Node, what: &str) -> Frag {
        let at = attr_range(n, "Operand").unwrap_or_else(|| anchor(n));
        if let Some(f) = self.names.get(&at.start) {
            return f.clone();
        }
        let raw = attr(n, "Operand").unwrap_or("");
        let f = if sfc_syntax::keywords::is_identifier(raw) {
            let mut f = Frag::plain(raw);
            f.marks.push(sfc_xmlmap::MapEntry { text: 0..raw.len() as u32, xml: at.clone(), exact: true });
            f
        } else if raw.trim().is_empty() {
            let id = attr(n, "ID").unwrap_or("").trim();
            let fixed = sfc_syntax::keywords::sanitize_identifier(&format!("{what}_{id}"));
            self.diag("SFC0727", anchor(n), format!("the {what} has no `Operand` (tag name): imported as `{fixed}`"));
            Frag::located(fixed, at.clone())
        } else {
            let fixed = sfc_syntax::keywords::sanitize_identifier(raw);
            self.diag(
                "SFC0704",
                at.clone(),
                format!("`{raw}` is not an IEC 61131-3 identifier; the {what} is imported as `{fixed}`"),
            )
            .notes
            .push(
                "identifiers are letters, digits and single underscores, start with a letter, and are not keywords"
                    .into(),
            );
            Frag::located(fixed, at.clone())
        };
        self.names.insert(at.start, f.clone());
        f
    }

    /// Writes `{attribute 'name' := 'value'}` lines at `indent`.
    fn attributes(&mut self, list: &[(String, String)], indent: &str) {
        for (k, v) in list {
            let v = sfc_syntax::attr_value::escape(v);
            self.em.str(&format!("{indent}{{attribute '{k}' := '{v}'}}\n"));
        }
    }
}

/// One program's tags.
#[derive(Default)]
struct Scope {
    vars: Vec<Var>,
    /// Aliases by upper name: name, target, where.
    aliases: BTreeMap<String, (String, String, Range<u32>)>,
    sfc: chart::SfcTags,
    /// Upper-case names of everything declared or skipped (reported already).
    known: HashSet<String>,
}

fn read_tags(cx: &mut Ctx, list: Option<Node>) -> Scope {
    let mut s = Scope::default();
    for t in list.into_iter().flat_map(|l| children(l, "Tag")) {
        match tags::tag(cx, t) {
            TagKind::Var(v) => {
                s.known.insert(v.name.to_ascii_uppercase());
                if let Some((_, d)) = v.attrs.iter().find(|(k, _)| k == "sfc.description") {
                    s.sfc.desc.insert(v.name.to_ascii_uppercase(), d.clone());
                }
                s.vars.push(v);
            }
            TagKind::Sfc { name, ty, pre, l5k, desc } => {
                let up = name.to_ascii_uppercase();
                if let Some(d) = desc {
                    s.sfc.desc.insert(up.clone(), d);
                }
                if let Some(p) = pre.filter(|_| ty != "SFC_STOP") {
                    s.sfc.pre.insert(up.clone(), p);
                }
                if let Some(l) = l5k {
                    s.sfc.l5k.insert(up.clone(), l);
                }
                s.known.insert(up);
            }
            TagKind::Alias { name, target, at } => {
                s.aliases.insert(name.to_ascii_uppercase(), (name, target, at));
            }
            TagKind::Skipped { name } => {
                s.known.insert(name.to_ascii_uppercase());
            }
        }
    }
    s
}

/// One SFC routine to write.
struct Pou {
    name: String,
    anchor: Range<u32>,
    attrs: Vec<(String, String)>,
    vars: Vec<Var>,
    chart: chart::ChartOut,
}

fn l5x(cx: &mut Ctx, root: Node) {
    if !is_l5x(root) {
        cx.diag(
            "SFC0731",
            anchor(root),
            format!("the document element is `{}`, not `RSLogix5000Content`", root.tag_name().name()),
        );
        return;
    }
    let Some(ctrl) = child(root, "Controller") else {
        cx.diag("SFC0731", anchor(root), "the L5X file has no `Controller` element: nothing to import");
        return;
    };
    let target = attr(root, "TargetType").unwrap_or("Controller");
    // The controller's SFC settings, or Studio's defaults.
    let mut settings = Vec::new();
    let mut missing = Vec::new();
    for (xml_name, key, default) in DEFAULT_SETTINGS {
        match attr(ctrl, xml_name) {
            Some(v) => settings.push((key.to_string(), v.to_string())),
            None => {
                settings.push((key.to_string(), default.to_string()));
                missing.push(format!("{xml_name}={default}"));
            }
        }
    }
    if let Some(v) = attr(ctrl, "SFCForcesEnabled") {
        settings.push(("sfc.logix.forces".into(), v.to_string()));
    }
    for (key, v) in &settings {
        let known = match key.as_str() {
            "sfc.logix.exec" => ["CurrentActive", "UntilFalse"].contains(&v.as_str()),
            "sfc.logix.restart" => ["MostRecent", "InitialStep"].contains(&v.as_str()),
            "sfc.logix.lastscan" => ["DontScan", "ProgrammaticReset", "AutomaticReset"].contains(&v.as_str()),
            _ => true,
        };
        if !known {
            let xml_name = DEFAULT_SETTINGS.iter().find(|d| d.1 == key).map_or("", |d| d.0);
            cx.diag(
                "SFC0727",
                attr_range(ctrl, xml_name).unwrap_or_else(|| anchor(ctrl)),
                format!("the SFC setting `{xml_name}=\"{v}\"` is not known; kept as written"),
            );
        }
    }
    let programs: Vec<Node> = child(ctrl, "Programs").into_iter().flat_map(|p| children(p, "Program")).collect();
    let is_sfc = |r: &Node| attr(*r, "Type") == Some("SFC");
    let sfc_count: usize = programs.iter().map(|p| routines(*p).iter().filter(|r| is_sfc(r)).count()).sum();
    if !missing.is_empty() && sfc_count > 0 {
        cx.diag("SFC0720", anchor(ctrl), format!("this {target} export carries no controller SFC settings: Studio's defaults are written ({})", missing.join(", ")))
            .notes
            .push("the settings belong to the controller; change `sfc.logix.exec`, `sfc.logix.restart` and `sfc.logix.lastscan` if the project's differ".into());
    }
    let udts = Types::read(cx, child(ctrl, "DataTypes"));
    for aoi in
        child(ctrl, "AddOnInstructionDefinitions").into_iter().flat_map(|a| children(a, "AddOnInstructionDefinition"))
    {
        let n = attr(aoi, "Name").unwrap_or("");
        cx.diag(
            "SFC0722",
            attr_range(aoi, "Name").unwrap_or_else(|| anchor(aoi)),
            format!("the Add-On Instruction `{n}` is not imported"),
        )
        .notes
        .push("sfc imports SFC routines; tags of this type are not declared".into());
    }
    let globals = read_tags(cx, child(ctrl, "Tags"));
    // Routine names shared by programs are written `Program_Routine`.
    let mut by_name: HashMap<String, usize> = HashMap::new();
    for p in &programs {
        for r in routines(*p).iter().filter(|r| is_sfc(r)) {
            *by_name.entry(attr(*r, "Name").unwrap_or("").to_ascii_uppercase()).or_default() += 1;
        }
    }
    let mut pous: Vec<Pou> = Vec::new();
    let mut pou_names: HashSet<String> = HashSet::new();
    for p in &programs {
        let sfc: Vec<Node> = routines(*p).into_iter().filter(is_sfc).collect();
        if sfc.is_empty() {
            continue;
        }
        let pname = attr(*p, "Name").unwrap_or("").to_string();
        let scope = read_tags(cx, child(*p, "Tags"));
        let mut sfc_tags = chart::SfcTags::default();
        for src in [&globals.sfc, &scope.sfc] {
            sfc_tags.pre.extend(src.pre.iter().map(|(k, v)| (k.clone(), *v)));
            sfc_tags.l5k.extend(src.l5k.iter().map(|(k, v)| (k.clone(), v.clone())));
            sfc_tags.desc.extend(src.desc.iter().map(|(k, v)| (k.clone(), v.clone())));
        }
        for r in sfc {
            let rname = attr(r, "Name").unwrap_or("").to_string();
            let Some(content) = child(r, "SFCContent") else {
                cx.diag("SFC0731", anchor(r), format!("the SFC routine `{rname}` has no `SFCContent`: not imported"));
                continue;
            };
            let shared = by_name.get(&rname.to_ascii_uppercase()).is_some_and(|n| *n > 1);
            let wanted = if shared { format!("{pname}_{rname}") } else { rname.clone() };
            let mut name = sfc_syntax::keywords::sanitize_identifier(&wanted);
            let mut k = 1;
            while !pou_names.insert(name.to_ascii_uppercase()) {
                k += 1;
                name = format!("{}_{k}", sfc_syntax::keywords::sanitize_identifier(&wanted));
            }
            if name != rname {
                let why = if shared {
                    "another program has an SFC routine of the same name"
                } else {
                    "its name is no IEC 61131-3 identifier or is taken"
                };
                cx.diag(
                    "SFC0720",
                    attr_range(r, "Name").unwrap_or_else(|| anchor(r)),
                    format!("the SFC routine `{pname}/{rname}` is imported as the PROGRAM `{name}`: {why}"),
                );
            }
            let chart = chart::read(cx, content, &sfc_tags);
            let mut attrs = vec![
                ("sfc.dialect".to_string(), "logix".to_string()),
                ("sfc.logix.routine".to_string(), format!("{pname}/{rname}")),
            ];
            attrs.extend(settings.iter().cloned());
            attrs.extend(chart.attrs.iter().cloned());
            if let Some(rev) = attr(root, "SoftwareRevision") {
                attrs.push(("sfc.logix.rev".into(), rev.to_string()));
            }
            if let Some(text) = tags::description(r) {
                attrs.push(("sfc.description".into(), text));
            }
            if attr(*p, "MainRoutineName") == Some(rname.as_str()) {
                attrs.push(("sfc.logix.main".into(), "true".into()));
            }
            let vars = pou_vars(cx, &scope, &globals, &chart);
            pous.push(Pou { name, anchor: anchor(r), attrs, vars, chart });
        }
    }
    let others: Vec<String> = programs
        .iter()
        .flat_map(|p| {
            routines(*p).into_iter().filter(|r| !is_sfc(r)).map(move |r| {
                format!(
                    "{}/{} ({})",
                    attr(*p, "Name").unwrap_or(""),
                    attr(r, "Name").unwrap_or(""),
                    attr(r, "Type").unwrap_or("?")
                )
            })
        })
        .collect();
    if !pous.is_empty() && !others.is_empty() {
        let at = child(ctrl, "Programs").map(anchor).unwrap_or_else(|| anchor(ctrl));
        let d = cx.diag(
            "SFC0722",
            at,
            format!("{} routine(s) of other languages are not imported: {}", others.len(), others.join(", ")),
        );
        d.severity = sfc_diagnostics::Severity::Note;
        d.notes.push("sfc reads the SFC routines; ladder, ST and FBD routines that the chart calls or that drive its tags are not simulated".into());
    }
    if pous.is_empty() {
        let found: Vec<String> = programs
            .iter()
            .flat_map(|p| {
                routines(*p).into_iter().map(move |r| {
                    format!(
                        "{}/{} ({})",
                        attr(*p, "Name").unwrap_or(""),
                        attr(r, "Name").unwrap_or(""),
                        attr(r, "Type").unwrap_or("?")
                    )
                })
            })
            .collect();
        let d = cx.diag("SFC0730", anchor(root), "the L5X file holds no SFC routine: there is no chart to import");
        if !found.is_empty() {
            d.notes.push(format!("routines found: {}", found.join(", ")));
        }
    }
    // The data types.
    let used: Vec<&'static str> = cx.types.used_structs.iter().copied().collect();
    if !used.is_empty() || !udts.is_empty() {
        cx.em.str("TYPE\n");
        for n in used {
            let members = tags::STRUCTS.iter().find(|(s, _)| *s == n).map(|(_, m)| *m).unwrap_or_default();
            cx.em.str(&format!("    {{attribute 'sfc.logix.builtin' := 'true'}}\n    {n} : STRUCT\n"));
            for (m, t) in members {
                cx.em.str(&format!("        {m} : {t};\n"));
            }
            cx.em.str("    END_STRUCT;\n");
        }
        for (name, at, members) in &udts {
            cx.em.open(at.clone());
            cx.em.str(&format!("    {name} : STRUCT\n"));
            for (m, t) in members {
                cx.em.str(&format!("        {m} : {t};\n"));
            }
            cx.em.str("    END_STRUCT;\n");
            cx.em.close();
        }
        cx.em.str("END_TYPE\n\n");
    }
    if !globals.vars.is_empty() {
        cx.em.str("VAR_GLOBAL\n");
        for v in &globals.vars {
            var_decl(cx, v, "    ");
        }
        cx.em.str("END_VAR\n\n");
    }
    for p in pous {
        pou(cx, p);
    }
}

fn routines<'a, 'i>(p: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
    child(p, "Routines").into_iter().flat_map(|r| children(r, "Routine")).collect()
}

/// The POU's variables: the program's tags, then the tags the chart uses that the file does not
/// declare (aliases, tags of a program export), from their use.
fn pou_vars(cx: &mut Ctx, scope: &Scope, globals: &Scope, chart: &chart::ChartOut) -> Vec<Var> {
    let mut vars = Vec::new();
    let mut transition_tags = Vec::new();
    for v in &scope.vars {
        let up = v.name.to_ascii_uppercase();
        if chart.transition_names.contains(&up) && v.ty == "BOOL" {
            // Studio gives every transition a BOOL tag of its name: the transition keeps it.
            transition_tags.push(v.name.clone());
            continue;
        }
        if chart.names.contains(&up) {
            cx.diag("SFC0728", v.name_at.clone(), format!("the tag `{}` has the name of an element of the chart; the element keeps the name and the tag is not declared", v.name))
                .notes
                .push("in sfc's text a step, transition or action and a variable of the same POU cannot share a name".into());
            continue;
        }
        vars.push(v.clone());
    }
    if !transition_tags.is_empty() {
        let first = scope
            .vars
            .iter()
            .find(|v| transition_tags.first() == Some(&v.name))
            .map(|v| v.name_at.clone())
            .unwrap_or_default();
        cx.diag(
            "SFC0728",
            first,
            format!(
                "the transitions' BOOL tags ({}) are not declared: in sfc's text the transitions have their names",
                transition_tags.join(", ")
            ),
        )
        .severity = sfc_diagnostics::Severity::Note;
    }
    let mut declared: HashSet<String> = scope.known.iter().chain(&globals.known).cloned().collect();
    declared.extend(chart.names.iter().cloned());
    // How each undeclared name is used over the whole chart: DINT wins over BOOL, a structure
    // or array use counts only when there is no other.
    let mut uses: HashMap<String, st::Use> = HashMap::new();
    for (name, u, _) in &chart.idents {
        let e = uses.entry(name.to_ascii_uppercase()).or_insert(*u);
        *e = match (*e, *u) {
            (st::Use::Dint, _) | (_, st::Use::Dint) => st::Use::Dint,
            (st::Use::Bool, _) | (_, st::Use::Bool) => st::Use::Bool,
            _ => st::Use::Other,
        };
    }
    for (name, _, at) in &chart.idents {
        let up = name.to_ascii_uppercase();
        if declared.contains(&up) || cx.types.udts.contains(&up) {
            continue;
        }
        declared.insert(up.clone());
        let u = uses.get(&up).unwrap_or(&st::Use::Bool);
        let alias = scope.aliases.get(&up).or_else(|| globals.aliases.get(&up));
        let bit = alias.is_some_and(|(_, t, _)| {
            t.rsplit('.').next().is_some_and(|b| !b.is_empty() && b.bytes().all(|c| c.is_ascii_digit()))
        });
        let ty = match (bit, u) {
            (true, _) | (false, st::Use::Bool) => "BOOL",
            (false, st::Use::Dint) => "DINT",
            (false, st::Use::Other) => {
                cx.diag("SFC0721", at.clone(), format!("`{name}` is used as a structure or an array and the file does not declare it: not declared"))
                    .notes
                    .push("export the program with its controller (or the controller) so that its tags and data types come along".into());
                continue;
            }
        };
        let (name_at, mut attrs) = (at.clone(), Vec::new());
        match alias {
            Some((aname, target, aat)) => {
                attrs.push(("sfc.logix.alias".into(), target.clone()));
                cx.diag(
                    "SFC0722",
                    aat.clone(),
                    format!("the alias `{aname}` for `{target}` is declared as a {ty} variable of its own"),
                )
                .notes
                .push(if bit {
                    "the alias names a bit of a module's data".to_string()
                } else {
                    "its type is inferred from how the chart uses it".to_string()
                });
                vars.push(Var {
                    name: aname.clone(),
                    name_at: aat.clone(),
                    anchor: aat.clone(),
                    ty: ty.into(),
                    init: None,
                    attrs,
                    usage: None,
                });
            }
            None => {
                attrs.push(("sfc.logix.inferred".into(), "true".into()));
                cx.diag(
                    "SFC0721",
                    at.clone(),
                    format!("`{name}` is not declared in the file: declared as {ty} from its use"),
                )
                .notes
                .push(if ty == "BOOL" {
                    "it is read as a condition or written 0/1".to_string()
                } else {
                    "it takes part in arithmetic or comparisons with numbers".to_string()
                });
                vars.push(Var { name: name.clone(), name_at, anchor: at.clone(), ty: ty.into(), init: None, attrs, usage: None });
            }
        }
    }
    vars
}

fn var_decl(cx: &mut Ctx, v: &Var, indent: &str) {
    cx.em.open(v.anchor.clone());
    cx.attributes(&v.attrs, indent);
    cx.em.str(indent);
    let name = Frag::located(v.name.clone(), v.name_at.clone());
    cx.em.frag(&name);
    cx.em.str(&format!(" : {}", v.ty));
    if let Some(i) = &v.init {
        cx.em.str(&format!(" := {i}"));
    }
    cx.em.str(";\n");
    cx.em.close();
}

fn pou(cx: &mut Ctx, p: Pou) {
    cx.em.open(p.anchor.clone());
    cx.attributes(&p.attrs, "");
    cx.em.str(&format!("PROGRAM {}\n", p.name));
    // The program's parameters (by their `Usage`), then its other tags.
    for (usage, kw) in [(Some("Input"), "VAR_INPUT"), (Some("Output"), "VAR_OUTPUT"), (Some("InOut"), "VAR_IN_OUT"), (None, "VAR")] {
        let vars: Vec<&Var> = p.vars.iter().filter(|v| v.usage.as_deref() == usage).collect();
        if vars.is_empty() {
            continue;
        }
        cx.em.str(&format!("    {kw}\n"));
        for v in vars {
            var_decl(cx, v, "        ");
        }
        cx.em.str("    END_VAR\n");
    }
    let c = p.chart;
    for s in &c.steps {
        let kw = if s.initial { "INITIAL_STEP" } else { "STEP" };
        block(cx, s.anchor.clone(), &s.attrs, kw, &s.name, &s.assoc, "END_STEP");
    }
    for t in &c.transitions {
        cx.em.str("\n");
        cx.em.open(t.anchor.clone());
        cx.attributes(&t.attrs, "    ");
        cx.em.str("    TRANSITION ");
        cx.em.frag(&t.name);
        if let Some(n) = t.priority {
            cx.em.str(&format!(" (PRIORITY := {n})"));
        }
        let list = |v: &[String]| if v.len() == 1 { v.join("") } else { format!("({})", v.join(", ")) };
        cx.em.str(&format!(" FROM {} TO {}\n        := ", list(&t.from), list(&t.to)));
        cx.em.frag(&t.cond);
        // A condition ending in a `//` comment: the `;` on a line of its own.
        let last = st::tokens(&t.cond.text).into_iter().rev().find(|k| k.kind != st::Tok::Space);
        if last.is_some_and(|k| {
            k.kind == st::Tok::Comment && t.cond.text.get(k.range.clone()).is_some_and(|c| c.starts_with("//"))
        }) {
            cx.em.str("\n        ");
        }
        cx.em.str(";\n    END_TRANSITION\n");
        cx.em.close();
    }
    for a in &c.actions {
        block(cx, a.anchor.clone(), &a.attrs, "ACTION", &a.name, &a.body, "END_ACTION");
    }
    cx.em.str("END_PROGRAM\n\n");
    cx.em.close();
}

/// A step or an action: its attributes, `KEYWORD name:`, its lines (an association or a line of
/// code each; blank lines kept inside), `END_KEYWORD`, all standing for the element at `anchor`.
fn block(
    cx: &mut Ctx,
    anchor: Range<u32>,
    attrs: &[(String, String)],
    kw: &str,
    name: &Frag,
    lines: &[Frag],
    end: &str,
) {
    cx.em.str("\n");
    cx.em.open(anchor);
    cx.attributes(attrs, "    ");
    cx.em.str(&format!("    {kw} "));
    cx.em.frag(name);
    cx.em.str(":");
    if lines.iter().all(|l| l.text.trim().is_empty()) {
        cx.em.str(&format!(" {end}\n"));
    } else {
        cx.em.str("\n");
        for l in lines {
            if l.text.trim().is_empty() {
                cx.em.str("\n");
            } else {
                cx.em.str("        ");
                cx.em.frag(l);
                cx.em.str("\n");
            }
        }
        cx.em.str(&format!("    {end}\n"));
    }
    cx.em.close();
}
