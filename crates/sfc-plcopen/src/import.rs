//! PLCopen XML → textual IEC 61131-3: the project, data types, global variables, POUs with their
//! interfaces and bodies, configurations. SFC bodies are in [`sfc`], FBD/LD networks in
//! [`network`].

mod codesys;
mod dialect;
mod network;
mod sfc;

use crate::attrs;
use crate::emit::{Emitter, Frag, SourceMap};
use crate::xml::{self, anchor, attr, attr_range, child, children, elements, XText};
use roxmltree::Node;
use sfc_diagnostics::{Diagnostic, Span};
use sfc_syntax::keywords::cannot_name;
use std::collections::HashSet;
use std::ops::Range;

/// PLCopen TC6 namespaces: v2.01, v2.0, v1.0.
pub const NAMESPACES: &[&str] = &[
    "http://www.plcopen.org/xml/tc6_0201",
    "http://www.plcopen.org/xml/tc6_0200",
    "http://www.plcopen.org/xml/tc6.xsd",
];

pub(crate) use sfc_xmlmap::names::{is_ident, sanitize};

/// A name CODESYS and TwinCAT accept and IEC 61131-3 does not: a letter, then letters, digits
/// and underscores, with a doubled or trailing underscore (`Move_Forwards__Pos3`). A leading
/// `__` is CODESYS's operators' (`__TRUNC`), not such a name.
pub(crate) fn is_codesys_ident(s: &str) -> bool {
    let b = s.as_bytes();
    b.first().is_some_and(u8::is_ascii_alphabetic)
        && b.iter().all(|c| c.is_ascii_alphanumeric() || *c == b'_')
        && (s.contains("__") || s.ends_with('_'))
        && !cannot_name(s)
}

/// The state of one import: the XML, the text being written, the diagnostics.
pub(crate) struct Ctx<'i> {
    pub file: u32,
    pub src: &'i str,
    pub em: Emitter,
    pub diags: Vec<Diagnostic>,
    /// Names declared in the POU being imported, upper-cased (one namespace per POU).
    pub used: HashSet<String>,
    /// Variables the translation of networks declares (`R_TRIG1 : R_TRIG`).
    pub extra_vars: Vec<(String, String)>,
    /// Function block calls needed by condition networks (for `COMPUTE_FUNCTION_BLOCKS`).
    pub compute: Vec<Frag>,
    /// Resources keep their own global scopes (two of them declare the same name).
    pub scoped_globals: bool,
    /// Upper-case names of the global variable lists (CODESYS GVLs: `GVL.X` is `X`).
    pub gvl_names: HashSet<String>,
    /// With scoped globals: the globals of the POU's resource, with their types, which the POU
    /// reaches through VAR_EXTERNAL.
    pub externals: Vec<(String, Frag)>,
    /// Upper-case names of the enumerated types of the file (`Enum.Value` is `Enum#Value`).
    pub enum_types: HashSet<String>,
    /// Variables named by a word that sfc's text reserves for charts and CODESYS's ST does not
    /// (`Step`, `Action`, `Transition`): upper-case name → the name they are imported as; their
    /// uses in the code are renamed alike (`dialect::map`).
    pub renamed: std::collections::HashMap<String, String>,
    /// The file's PROGRAMs (upper case): CODESYS code may read their variables (`Main.X`).
    pub programs: HashSet<String>,
    /// Upper-case names of every global variable of the file.
    pub global_names: HashSet<String>,
    /// The name of the POU being written.
    pub pou_name: String,
    /// Functions generated for conditions whose logic shares values, written after the POU.
    pub functions: Vec<String>,
    /// How many of them the file has.
    pub condition_functions: usize,
    /// The POU being written is kept as written: its code is copied without mapping.
    pub verbatim: bool,
    /// The file comes from CODESYS or a tool built on it (TwinCAT, e!COCKPIT): each POU is
    /// marked `sfc.dialect`, so CODESYS's names and typing rules apply to its code.
    pub codesys_file: bool,
    /// The POU being written names things as CODESYS allows (`Move__Pos3`): such names are kept
    /// (the POU is marked `sfc.dialect`), see [`Ctx::is_name`].
    pub codesys_names: bool,
    /// Transitions of the SFC body being written that are not connected on both sides: they go
    /// into `sfc.loose` attributes of the POU.
    pub loose: Vec<sfc_syntax::attr_value::Loose>,
    /// The file's headers and foreign project `addData`, written before the first POU.
    pub header_attrs: Vec<(String, String)>,
    /// While writing the resources' lists at file level: the globals written so far (a
    /// repeated identical declaration is written once).
    pub emitted_globals: Option<HashSet<String>>,
}

impl<'i> Ctx<'i> {
    /// Whether `s` can name something of the POU being written in text: an IEC identifier, or
    /// in a POU marked `sfc.dialect` a CODESYS one ([`is_codesys_ident`]).
    pub(crate) fn is_name(&self, s: &str) -> bool {
        is_ident(s) || (self.codesys_names && is_codesys_ident(s))
    }

    /// `base`, or `base_1`, `base_2`, … : a name not yet used in the POU, now taken.
    pub fn fresh_name(&mut self, base: &str) -> String {
        let mut name = base.to_string();
        let mut k = 0;
        while self.used.contains(&name.to_ascii_uppercase()) {
            k += 1;
            name = format!("{base}_{k}");
        }
        self.used.insert(name.to_ascii_uppercase());
        name
    }

    /// A new variable `base1`, `base2`, … of type `ty`, declared in the POU.
    pub fn fresh_var(&mut self, base: &str, ty: &str) -> String {
        let mut k = 1;
        let mut name = format!("{base}{k}");
        while self.used.contains(&name.to_ascii_uppercase()) {
            k += 1;
            name = format!("{base}{k}");
        }
        self.used.insert(name.to_ascii_uppercase());
        self.extra_vars.push((name.clone(), ty.to_string()));
        name
    }

    pub fn diag(&mut self, code: &'static str, at: Range<u32>, msg: impl Into<String>) -> &mut Diagnostic {
        self.diags.push(Diagnostic::new(code, Span::new(self.file, at.start, at.end), msg));
        // (`Vec::push_mut` would say it in one call, but needs Rust 1.95.)
        self.diags.last_mut().unwrap_or_else(|| unreachable!("a diagnostic was just pushed"))
    }

    /// A name from attribute `name` of `n` as a located fragment; reports and repairs a name
    /// that is not an IEC identifier. `what` says what it names.
    pub fn name(&mut self, n: Node, name: &str, what: &str) -> Frag {
        let range = attr_range(n, name).unwrap_or_else(|| anchor(n));
        let raw = attr(n, name).unwrap_or("").trim();
        if self.is_name(raw) && attr(n, name).is_some_and(|v| v == raw) {
            let mut f = Frag::plain(raw);
            f.marks.push(crate::emit::MapEntry { text: 0..raw.len() as u32, xml: range, exact: true });
            return f;
        }
        let fixed = sanitize(raw);
        if what == "variable" && self.renamed.contains_key(&raw.to_ascii_uppercase()) {
            self.diag(
                "SFC0715",
                range.clone(),
                format!("the variable `{raw}` is imported as `{fixed}`, and so are its uses in the code"),
            )
            .notes
            .push(format!("`{}` begins a chart element in sfc's text (IEC 61131-3 reserves it); CODESYS lets a variable be called so", raw.to_ascii_uppercase()));
            return Frag::located(fixed, range);
        }
        self.diag(
            "SFC0704",
            range.clone(),
            format!("`{raw}` is not an IEC 61131-3 identifier; the {what} is imported as `{fixed}`"),
        )
        .notes
        .push(
            "identifiers are letters, digits and single underscores, start with a letter, and are not keywords".into(),
        );
        Frag::located(fixed, range)
    }

    /// Writes `{attribute 'name' := 'value'}` lines at `indent` (and the element's comments,
    /// kept by an export, as they were written).
    pub fn attributes(&mut self, list: &[(String, String)], indent: &str) {
        for (k, v) in list {
            if k == COMMENTS_KEY {
                // Each comment on its own line, its later lines as written.
                for c in v.split('\n').scan(false, |inside, line| {
                    let start = !*inside;
                    let t = line.trim_start();
                    let opens = t.starts_with("(*") || t.starts_with("/*") || t.starts_with("//");
                    if start && opens && !t.starts_with("//") {
                        *inside = !(t.ends_with("*)") || t.ends_with("*/"));
                    } else if !start && (line.trim_end().ends_with("*)") || line.trim_end().ends_with("*/")) {
                        *inside = false;
                    }
                    Some((start && opens, line))
                }) {
                    match c {
                        (true, line) => self.em.str(&format!("{indent}{}\n", line.trim_start())),
                        (false, line) => self.em.str(&format!("{line}\n")),
                    }
                }
                continue;
            }
            let v = if v.contains(['\'', '}']) { v.replace('\'', "$27").replace('}', "$7D") } else { v.clone() };
            self.em.str(&format!("{indent}{{attribute '{k}' := '{v}'}}\n"));
        }
    }
}

/// The key of [`element_attrs`]'s entry that holds an element's comments (not an attribute).
pub(crate) const COMMENTS_KEY: &str = "\u{0}comments";

/// Attributes kept for an element: `documentation` → `sfc.description`, our `addData` → its
/// attributes, foreign `addData` → `sfc.adddata`. Comments an export kept (in our `addData`,
/// their text also in `documentation`) come back as comments.
pub(crate) fn element_attrs(n: Node) -> Vec<(String, String)> {
    element_attrs_without(n, &|_| false)
}

/// [`element_attrs`] leaving out of the foreign `addData` the elements `skip` names (what the
/// text holds in its own words, such as a step's step actions).
pub(crate) fn element_attrs_without(n: Node, skip: &dyn Fn(Node) -> bool) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let comments = own_data(n, "comments").and_then(|c| attr(c, "text")).filter(|t| !t.trim().is_empty());
    if let Some(c) = comments {
        out.push((COMMENTS_KEY.to_string(), c.to_string()));
    }
    if let Some(add) = child(n, "addData") {
        let mut foreign = String::new();
        for data in children(add, "data") {
            if attr(data, "name") == Some(attrs::DATA_NAME) {
                for payload in elements(data) {
                    for a in children(payload, "attribute") {
                        if let (Some(k), Some(v)) = (attr(a, "name"), attr(a, "value")) {
                            // Attributes the export could not write natively (say `sfc.inline`
                            // of an action used twice) come back from here too.
                            if k.to_ascii_lowercase().starts_with("sfc.") && !k.eq_ignore_ascii_case(attrs::ADDDATA) {
                                out.push((k.to_string(), v.to_string()));
                            }
                        }
                    }
                }
            } else {
                foreign.push_str(&xml::serialize_without(data, skip));
            }
        }
        if !foreign.is_empty() {
            out.push((attrs::ADDDATA.to_string(), attrs::escape(&foreign)));
        }
    }
    if let Some(doc) = child(n, "documentation").filter(|_| comments.is_none()) {
        let text = xml::formatted_text(doc).text;
        let text = text.trim();
        if !text.is_empty() {
            out.push((attrs::DESCRIPTION.to_string(), attrs::escape(text)));
        }
    }
    out
}

/// A special entry of our `addData` (`<name value="…"/>`, `<access path="…" mode="…"/>`).
pub(crate) fn own_data<'a, 'i: 'a>(n: Node<'a, 'i>, what: &str) -> Option<Node<'a, 'i>> {
    let add = child(n, "addData")?;
    children(add, "data")
        .filter(|d| attr(*d, "name") == Some(attrs::DATA_NAME))
        .flat_map(elements)
        .flat_map(|p| elements(p).collect::<Vec<_>>())
        .find(|e| e.tag_name().name() == what)
}

/// Imports a document; `root` is its `project` element.
pub(crate) fn project(cx: &mut Ctx, root: Node) {
    let types = child(root, "types");
    cx.codesys_file = dialect::codesys_file(root);
    // The headers and the project's foreign `addData` travel on the first POU, so an export
    // writes them back.
    // (Not those of sfc's own export, which it writes again.)
    let ours = child(root, "fileHeader").is_some_and(|h| attr(h, "productName") == Some("sfc"));
    for (name, key) in [("fileHeader", attrs::FILEHEADER), ("contentHeader", attrs::CONTENTHEADER)] {
        if let Some(h) = child(root, name).filter(|_| !ours) {
            let mut text = xml::serialize(h);
            if name == "fileHeader" {
                text = crate::export::canonical_file_header(&text).unwrap_or(text);
            } else if child(h, "coordinateInfo").is_none() {
                // v2.01 requires the coordinate info: kept as the export writes it.
                let a: String =
                    h.attributes().map(|a| format!(" {}=\"{}\"", a.name(), xml::escape_attr(a.value()))).collect();
                let rest: String = elements(h).map(xml::serialize).collect();
                text = format!("<contentHeader{a}>{}{rest}</contentHeader>", crate::export::COORDINATE_INFO);
            }
            cx.header_attrs.push((key.to_string(), attrs::escape(&text)));
        }
    }
    if !ours && child(root, "contentHeader").is_none() && child(root, "fileHeader").is_some() {
        // v2.01 requires one: kept as the export writes it, so the way back is stable.
        let h = format!("<contentHeader name=\"project\">{}</contentHeader>", crate::export::COORDINATE_INFO);
        cx.header_attrs.push((attrs::CONTENTHEADER.to_string(), attrs::escape(&h)));
    }
    // The project's own addData travels with the file, but for the application and the global
    // variable lists of the project's pool, which are imported (below).
    let project_data: String = child(root, "addData")
        .into_iter()
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name") != Some(CODESYS_APPLICATION) && !is_pool_lists(*d))
        .filter(|d| !codesys::is_interface_data(*d))
        .map(xml::serialize)
        .collect();
    if !project_data.is_empty() {
        cx.header_attrs.push((attrs::PROJECTDATA.to_string(), attrs::escape(&project_data)));
    }
    // Names the CODESYS dialect qualifies: enumerated types, global variable lists, globals.
    cx.enum_types = dialect::enum_types(root);
    let lists: Vec<Node> =
        root.descendants().filter(|d| d.is_element() && d.tag_name().name() == "globalVars").collect();
    cx.gvl_names = lists
        .iter()
        .filter_map(|g| attr(*g, "name").map(|n| n.trim().to_ascii_uppercase()))
        .filter(|n| !n.is_empty())
        .collect();
    cx.programs = root
        .descendants()
        .filter(|d| d.is_element() && d.tag_name().name() == "pou" && attr(*d, "pouType") == Some("program"))
        .filter_map(|p| attr(p, "name").map(|n| n.trim().to_ascii_uppercase()))
        .collect();
    cx.renamed = root
        .descendants()
        .filter(|d| d.is_element() && d.tag_name().name() == "variable")
        .filter_map(|v| attr(v, "name").map(str::trim))
        .filter(|n| sfc_syntax::keywords::CHART_WORDS.iter().any(|w| w.eq_ignore_ascii_case(n)))
        .map(|n| (n.to_ascii_uppercase(), sanitize(n)))
        .collect();
    cx.global_names = lists
        .iter()
        .flat_map(|g| children(*g, "variable"))
        .filter_map(|v| attr(v, "name").map(|n| n.trim().to_ascii_uppercase()))
        .collect();
    // Data types: the project's, and those CODESYS keeps in a resource's `addData` (an
    // application's data types, one per `…/datatype` data).
    let dt = types.and_then(|t| child(t, "dataTypes"));
    let mut list: Vec<Node> = dt.map(|dt| children(dt, "dataType").collect()).unwrap_or_default();
    list.extend(root.descendants().filter(|d| {
        d.is_element()
            && d.tag_name().name() == "dataType"
            && d.parent().is_some_and(|p| p.tag_name().name() == "data" && attr(p, "name") == Some(CODESYS_DATATYPE))
    }));
    if let Some(first) = list.first().copied() {
        {
            cx.em.open(anchor(dt.unwrap_or(first)));
            cx.em.str("TYPE\n");
            for d in list {
                cx.em.open(anchor(d));
                let name = cx.name(d, "name", "data type");
                cx.em.str("    ");
                cx.em.frag(&name);
                cx.em.str(" : ");
                match child(d, "baseType") {
                    Some(b) => {
                        let t = type_text(cx, b, "    ");
                        cx.em.frag(&t);
                    }
                    None => {
                        cx.diag("SFC0705", anchor(d), "the data type has no `baseType`");
                        cx.em.str("INT");
                    }
                }
                if let Some(v) = child(d, "initialValue") {
                    cx.em.str(" := ");
                    let f = value_text(cx, v);
                    cx.em.frag(&f);
                }
                cx.em.str(";\n");
                cx.em.close();
            }
            cx.em.str("END_TYPE\n\n");
            cx.em.close();
        }
    }
    // Interfaces (CODESYS keeps them in the project's or an application's `addData`).
    for i in codesys::interfaces(root) {
        cx.em.open(anchor(i));
        codesys::interface(cx, i);
        cx.em.close();
    }
    // Configurations, and the resources of a CODESYS/e!COCKPIT project export (under
    // `project/addData/data[@name=…/application]`, with an empty `types/pous`).
    let configs: Vec<Node> = child(root, "instances")
        .and_then(|i| child(i, "configurations"))
        .map(|c| children(c, "configuration").collect())
        .unwrap_or_default();
    let app_resources: Vec<Node> = child(root, "addData")
        .into_iter()
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name") == Some(CODESYS_APPLICATION))
        .flat_map(|d| children(d, "resource"))
        .collect();
    let mut resources: Vec<(Option<Node>, Node)> = Vec::new();
    for c in &configs {
        resources.extend(children(*c, "resource").map(|r| (Some(*c), r)));
    }
    resources.extend(app_resources.iter().map(|r| (None, *r)));

    // Every POU: the project's, then each resource's (CODESYS keeps an application's POUs in the
    // resource's `addData`), each with the resource it belongs to.
    let mut pous: Vec<(Node, Option<usize>)> = Vec::new();
    if let Some(list) = types.and_then(|t| child(t, "pous")) {
        pous.extend(children(list, "pou").map(|p| (p, None)));
    }
    for (k, (_, r)) in resources.iter().enumerate() {
        pous.extend(resource_pous(*r).into_iter().map(|p| (p, Some(k))));
    }
    // A program instantiated in a resource belongs to it.
    for (k, (_, r)) in resources.iter().enumerate() {
        let instances =
            children(*r, "task").flat_map(|t| children(t, "pouInstance")).chain(children(*r, "pouInstance"));
        for pi in instances.collect::<Vec<_>>() {
            let ty = instance_type(pi).to_ascii_uppercase();
            for (p, owner) in pous.iter_mut() {
                if owner.is_none() && attr(*p, "name").is_some_and(|n| n.trim().eq_ignore_ascii_case(&ty)) {
                    *owner = Some(k);
                }
            }
        }
    }

    // Global variables: a configuration's and, when no two resources declare the same name, the
    // resources' are file-level VAR_GLOBAL blocks. Resources that share a name each keep their
    // own scope, as in IEC 61131-3 and CODESYS: their lists stay inside RESOURCE, and each POU of
    // a resource reaches them through VAR_EXTERNAL.
    // Two resources declaring one name differently need their own scopes; the same
    // declaration twice (a constant every application repeats) is one global.
    let mut decl_of: std::collections::HashMap<String, String> = std::collections::HashMap::new();
    let mut scoped = false;
    for (_, r) in &resources {
        for v in children(*r, "globalVars").flat_map(|g| children(g, "variable")) {
            let n = attr(v, "name").unwrap_or("").trim().to_ascii_uppercase();
            if n.is_empty() {
                continue;
            }
            let sig = ["type", "initialValue"]
                .iter()
                .filter_map(|k| child(v, k))
                .map(xml::serialize)
                .collect::<Vec<_>>()
                .join("");
            match decl_of.get(&n) {
                Some(prev) if *prev != sig => scoped = true,
                Some(_) => {}
                None => {
                    decl_of.insert(n, sig);
                }
            }
        }
    }
    cx.scoped_globals = scoped;
    for c in &configs {
        for g in children(*c, "globalVars").collect::<Vec<_>>() {
            global_list(cx, g, "");
        }
    }
    // CODESYS: the global variable lists of the project's pool (`addData/data[…/globalvars]`),
    // which every application of the project sees.
    let pool: Vec<Node> = child(root, "addData")
        .into_iter()
        .flat_map(|a| children(a, "data"))
        .filter(|d| is_pool_lists(*d))
        .flat_map(|d| children(d, "globalVars"))
        .collect();
    for g in pool {
        global_list(cx, g, "");
    }
    if !scoped {
        cx.emitted_globals = Some(HashSet::new());
        for (_, r) in &resources {
            for g in children(*r, "globalVars").collect::<Vec<_>>() {
                global_list(cx, g, "");
            }
        }
        cx.emitted_globals = None;
    }
    // Derived types that nothing in the file declares (a library's, or an extension's such as
    // Beremiz's `python_eval` or `HMI_*` blocks): opaque function blocks, with a warning.
    opaque_types(cx, root, &pous);
    // POUs.
    // A chart is a POU's body or an action's (CODESYS's SFC action).
    let is_chart = |n: Node| child(n, "body").is_some_and(|b| elements(b).any(|e| e.tag_name().name() == "SFC"));
    let any_sfc = pous
        .iter()
        .any(|(p, _)| is_chart(*p) || child(*p, "actions").is_some_and(|a| children(a, "action").any(is_chart)));
    let mut externals: Vec<Vec<(String, Frag)>> = Vec::new();
    for (_, r) in &resources {
        let mut list = Vec::new();
        if scoped {
            for v in children(*r, "globalVars").flat_map(|g| children(g, "variable")).collect::<Vec<_>>() {
                let Some(n) = attr(v, "name").map(str::trim).filter(|n| is_ident(n)) else { continue };
                if let Some(t) = child(v, "type") {
                    let ty = type_text(cx, t, "        ");
                    list.push((n.to_string(), ty));
                }
            }
        }
        externals.push(list);
    }
    for (p, owner) in &pous {
        cx.externals = match owner {
            Some(k) if scoped => externals.get(*k).cloned().unwrap_or_default(),
            _ => Vec::new(),
        };
        pou(cx, *p);
    }
    cx.externals.clear();
    if !any_sfc {
        let at = types.and_then(|t| child(t, "pous")).map(anchor).unwrap_or_else(|| anchor(root));
        cx.diag("SFC0712", at, "the file has no SFC POU: there is no chart to check, simulate or edit")
            .notes
            .push(format!("POUs found: {}", pou_list(&pous)));
    }
    // Configurations with resources keep their tasks and program instances as text.
    for c in &configs {
        let list: Vec<Node> = children(*c, "resource").collect();
        configuration(cx, *c, &list, scoped);
    }
    for r in &app_resources {
        configuration(cx, *r, std::slice::from_ref(r), scoped);
    }
}

/// `NAME, NAME, …` of the POUs, or `none`.
fn pou_list(pous: &[(Node, Option<usize>)]) -> String {
    if pous.is_empty() {
        return "none".into();
    }
    pous.iter().map(|(p, _)| attr(*p, "name").unwrap_or("?").trim().to_string()).collect::<Vec<_>>().join(", ")
}

/// The `name` of CODESYS's application data (a project export's resources and their POUs).
pub(crate) const CODESYS_APPLICATION: &str = "http://www.3s-software.com/plcopenxml/application";
/// The `name` of CODESYS's data holding one POU of a resource.
pub(crate) const CODESYS_POU: &str = "http://www.3s-software.com/plcopenxml/pou";

/// The `data` name under which CODESYS keeps an application's data types.
pub(crate) const CODESYS_DATATYPE: &str = "http://www.3s-software.com/plcopenxml/datatype";

/// The POUs a CODESYS resource keeps in its `addData`.
fn resource_pous<'a, 'i>(r: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
    children(r, "addData")
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name") == Some(CODESYS_POU))
        .flat_map(|d| children(d, "pou"))
        .collect()
}

/// The type of a `pouInstance`: `typeName` (v2), `type` (v1.0); CODESYS writes an empty
/// `typeName`, which means the POU named like the instance.
fn instance_type<'a>(pi: Node<'a, '_>) -> &'a str {
    let ty = attr(pi, "typeName").or_else(|| attr(pi, "type")).unwrap_or("").trim();
    if ty.is_empty() {
        attr(pi, "name").unwrap_or("").trim()
    } else {
        ty
    }
}

/// A `globalVars` list as `VAR_GLOBAL … END_VAR` at `indent`.
fn global_list(cx: &mut Ctx, g: Node, indent: &str) {
    // CODESYS writes a list holding VAR_GLOBAL and VAR_GLOBAL CONSTANT blocks as an empty list
    // whose `mixedattrsvarlist` holds one list per block.
    if children(g, "variable").next().is_none() {
        let blocks: Vec<Node> = children(g, "addData")
            .flat_map(|a| children(a, "data"))
            .filter(|d| attr(*d, "name").is_some_and(|n| n.ends_with("/mixedattrsvarlist")))
            .flat_map(|d| elements(d).flat_map(|m| children(m, "globalVars")))
            .collect();
        if !blocks.is_empty() {
            for b in blocks {
                global_list(cx, b, indent);
            }
            return;
        }
    }
    cx.em.open(anchor(g));
    var_list(cx, g, "VAR_GLOBAL", indent);
    if indent.is_empty() {
        cx.em.str("\n");
    }
    cx.em.close();
}

/// CODESYS's global variable lists of the project's pool: `project/addData/data[…/globalvars]`.
fn is_pool_lists(d: Node) -> bool {
    attr(d, "name").is_some_and(|n| n.ends_with("plcopenxml/globalvars"))
}

/// Standard function blocks and those of CODESYS's `Standard` library (`Standard.TON`).
fn is_standard_type(name: &str) -> bool {
    sfc_st::stdlib::std_function_block(name).is_some() || sfc_st::stdlib::std_function(name).is_some()
}

/// The data types of Beremiz's svghmi library (its `pous.xml`: each an alias of an elementary
/// type), which a Beremiz project with an SVG HMI uses without declaring: its HMI variables are
/// plain values the program reads and writes. (`HMI_NODE` is a block, not among them.)
pub(crate) fn library_alias(name: &str) -> Option<&'static str> {
    Some(match name.to_ascii_uppercase().as_str() {
        "HMI_BOOL" | "HMI_CLASS" | "HMI_LABEL" => "BOOL",
        "HMI_INT" => "INT",
        "HMI_REAL" => "REAL",
        "HMI_STRING" => "STRING",
        _ => return None,
    })
}

/// Declares every derived type the file uses but does not declare as an opaque function block
/// (a POU kept as written: not analysed, and everything done with its instances accepted), so
/// one unknown library block does not fail every POU that uses it.
fn opaque_types(cx: &mut Ctx, root: Node, pous: &[(Node, Option<usize>)]) {
    let mut declared: HashSet<String> = HashSet::new();
    for d in root.descendants().filter(|d| d.is_element()) {
        let n = d.tag_name().name();
        // (An interface is declared in CODESYS's `addData`, `…/interface`.)
        if n == "dataType" || n == "pou" || (n == "Interface" && d.parent().is_some_and(codesys::is_interface_data)) {
            if let Some(name) = attr(d, "name") {
                declared.insert(name.trim().to_ascii_uppercase());
            }
        }
    }
    let mut missing: Vec<(String, Range<u32>, &str)> = Vec::new();
    let mut seen = HashSet::new();
    let scopes = pous.iter().map(|(p, _)| *p).chain(child(root, "types").and_then(|t| child(t, "dataTypes")));
    let scopes = scopes.chain(root.descendants().filter(|d| d.is_element() && d.tag_name().name() == "globalVars"));
    for p in scopes.collect::<Vec<_>>() {
        for d in p.descendants().filter(|d| d.is_element()) {
            let (name, range, what) = match d.tag_name().name() {
                "derived" => (attr(d, "name"), attr_range(d, "name"), "type"),
                "block" if attr(d, "instanceName").is_some_and(|i| !i.trim().is_empty()) => {
                    (attr(d, "typeName"), attr_range(d, "typeName"), "function block")
                }
                _ => continue,
            };
            let Some(raw) = name.map(str::trim).filter(|n| !n.is_empty()) else { continue };
            // `Lib.Type`: a library's type through its namespace.
            if dialect::map_type(raw).is_some() {
                continue;
            }
            let name = if raw.contains('.') { sanitize(raw) } else { raw.to_string() };
            if !is_ident(&name) {
                continue;
            }
            let key = name.to_ascii_uppercase();
            if declared.contains(&key) || is_standard_type(&name) || !seen.insert(key) {
                continue;
            }
            let what = if raw.contains('.') { "library type" } else { what };
            missing.push((name, range.unwrap_or_else(|| anchor(d)), what));
        }
    }
    let functions = opaque_functions(root, pous, &declared, &seen);
    for (name, at, what) in missing {
        if let Some(base) = library_alias(&name) {
            cx.diag(
                "SFC0714",
                at.clone(),
                format!(
                    "type `{name}` is not declared in the file: declared as {base}, as Beremiz's svghmi library does"
                ),
            );
            cx.em.open(at);
            cx.em.str(&format!("TYPE\n    {name} : {base};\nEND_TYPE\n\n"));
            cx.em.close();
            continue;
        }
        cx.diag(
            "SFC0713",
            at.clone(),
            format!("{what} `{name}` is not declared in the file: imported as an opaque function block"),
        )
        .notes
        .push(
            "its instances are kept and passed on, but not analysed or simulated (a library or extension block: \
             Beremiz's svghmi, py_ext and svgui blocks, a CODESYS library)"
                .into(),
        );
        cx.em.open(at);
        cx.em.str(&format!("{{attribute 'sfc.verbatim' := 'opaque'}}\nFUNCTION_BLOCK {name}\nEND_FUNCTION_BLOCK\n\n"));
        cx.em.close();
    }
    for (name, at) in functions {
        cx.diag(
            "SFC0713",
            at.clone(),
            format!("function `{name}` is not declared in the file: imported as an opaque function"),
        )
        .notes
        .push(
            "its calls are kept, but not analysed or simulated (a library's function: a CODESYS library such as \
             SysMem or OSCAT, or a Beremiz extension)"
                .into(),
        );
        cx.em.open(at);
        cx.em.str(&format!("{{attribute 'sfc.verbatim' := 'opaque'}}\nFUNCTION {name}\nEND_FUNCTION\n\n"));
        cx.em.close();
    }
}

/// The functions the code of the POUs calls (`Name(`, not `x.Name(`) that nothing of the file
/// declares under that name (no POU, type, variable, action, transition, step, method or
/// property) and that are not standard or built in: a library's functions, each with where it
/// is first called.
fn opaque_functions(
    root: Node,
    pous: &[(Node, Option<usize>)],
    declared: &HashSet<String>,
    types: &HashSet<String>,
) -> Vec<(String, Range<u32>)> {
    const BUILT_IN: &[&str] = &["ADR", "REF", "SIZEOF", "LOWER_BOUND", "UPPER_BOUND", "THIS", "SUPER"];
    let mut names: HashSet<String> = HashSet::new();
    for d in root.descendants().filter(|d| d.is_element()) {
        if let Some(n) = attr(d, "name").or_else(|| attr(d, "Name")) {
            names.insert(n.trim().to_ascii_uppercase());
        }
    }
    let mut out: Vec<(String, Range<u32>)> = Vec::new();
    let mut seen: HashSet<String> = HashSet::new();
    for (p, _) in pous {
        for e in p.descendants().filter(|e| e.is_element() && matches!(e.tag_name().name(), "ST" | "IL")) {
            let t = xml::formatted_text(e);
            let (toks, _) = sfc_syntax::lexer::lex(0, &t.text);
            let sig: Vec<_> = toks.iter().filter(|t| !t.kind.is_trivia()).collect();
            for (i, tok) in sig.iter().enumerate() {
                if tok.kind != sfc_syntax::lexer::TokenKind::Ident
                    || sig.get(i + 1).is_none_or(|n| n.kind != sfc_syntax::lexer::TokenKind::LParen)
                    || i.checked_sub(1).and_then(|k| sig.get(k)).is_some_and(|b| {
                        matches!(b.kind, sfc_syntax::lexer::TokenKind::Dot | sfc_syntax::lexer::TokenKind::Caret)
                    })
                {
                    continue;
                }
                let w = &t.text[tok.start as usize..tok.end as usize];
                let key = w.to_ascii_uppercase();
                if names.contains(&key)
                    || declared.contains(&key)
                    || types.contains(&key)
                    || BUILT_IN.contains(&key.as_str())
                    || cannot_name(w)
                    || sfc_st::stdlib::std_function(w).is_some()
                    || sfc_st::stdlib::std_function_block(w).is_some()
                    || key.starts_with("__")
                    || !is_ident(w)
                    || !seen.insert(key)
                {
                    continue;
                }
                let at = t
                    .runs
                    .iter()
                    .find(|r| r.text <= tok.start && tok.end <= r.text + r.len)
                    .map(|r| r.raw + (tok.start - r.text)..r.raw + (tok.end - r.text))
                    .unwrap_or_else(|| anchor(e));
                out.push((w.to_string(), at));
            }
        }
    }
    out
}

/// `CONFIGURATION … END_CONFIGURATION` for a configuration (or a CODESYS application, `c` then
/// being its resource) with resources. Its global variables are at file level already, unless
/// resources keep their own scopes (`scoped`): then each resource's lists are written inside it.
fn configuration(cx: &mut Ctx, c: Node, resources: &[Node], scoped: bool) {
    if resources.is_empty() {
        return;
    }
    cx.em.open(anchor(c));
    let name = cx.name(c, "name", "configuration");
    cx.em.str("CONFIGURATION ");
    cx.em.frag(&name);
    cx.em.str("\n");
    for &r in resources {
        cx.em.open(anchor(r));
        let rname = cx.name(r, "name", "resource");
        cx.em.str("    RESOURCE ");
        cx.em.frag(&rname);
        cx.em.str(" ON PLC\n");
        if scoped {
            for g in children(r, "globalVars").collect::<Vec<_>>() {
                global_list(cx, g, "        ");
            }
        }
        let tasks: Vec<Node> = children(r, "task").collect();
        for t in &tasks {
            cx.em.open(anchor(*t));
            let tname = cx.name(*t, "name", "task");
            cx.em.str("        TASK ");
            cx.em.frag(&tname);
            let mut args = Vec::new();
            if let Some(s) = attr(*t, "single").filter(|s| !s.trim().is_empty()) {
                args.push(format!("SINGLE := {}", s.trim()));
            }
            if let Some(i) = attr(*t, "interval").filter(|s| !s.trim().is_empty()) {
                args.push(format!("INTERVAL := {}", interval(i.trim())));
            }
            args.push(format!("PRIORITY := {}", attr(*t, "priority").map(str::trim).unwrap_or("0")));
            cx.em.str(&format!("({});\n", args.join(", ")));
            cx.em.close();
        }
        for t in &tasks {
            for pi in children(*t, "pouInstance") {
                let tname = attr(*t, "name").unwrap_or("");
                pou_instance(cx, pi, Some(tname));
            }
        }
        for pi in children(r, "pouInstance") {
            pou_instance(cx, pi, None);
        }
        cx.em.str("    END_RESOURCE\n");
        cx.em.close();
    }
    cx.em.str("END_CONFIGURATION\n\n");
    cx.em.close();
}

fn pou_instance(cx: &mut Ctx, pi: Node, task: Option<&str>) {
    cx.em.open(anchor(pi));
    let name = cx.name(pi, "name", "program instance");
    let ty_attr = if attr(pi, "typeName").is_some() { "typeName" } else { "type" };
    let ty = if attr(pi, ty_attr).is_some_and(|t| !t.trim().is_empty()) {
        cx.name(pi, ty_attr, "program type")
    } else {
        // CODESYS: an empty type names the POU the instance is named after.
        let mut f = name.clone();
        f.marks.clear();
        f.locate(attr_range(pi, "name").unwrap_or_else(|| anchor(pi)))
    };
    cx.em.str("        PROGRAM ");
    cx.em.frag(&name);
    if let Some(t) = task.filter(|t| is_ident(t)) {
        cx.em.str(&format!(" WITH {t}"));
    }
    cx.em.str(" : ");
    cx.em.frag(&ty);
    cx.em.str(";\n");
    cx.em.close();
}

/// A task interval as an IEC duration: v2 writes `T#100ms`, v1.0 `00:00:00.100000`.
fn interval(s: &str) -> String {
    let parts: Vec<&str> = s.split(':').collect();
    if let [h, m, sec] = parts.as_slice() {
        let h: Option<u64> = h.parse().ok();
        let m: Option<u64> = m.parse().ok();
        let sec: Option<f64> = sec.parse().ok();
        if let (Some(h), Some(m), Some(sec)) = (h, m, sec) {
            let us = ((h * 3600 + m * 60) as f64 * 1e6 + sec * 1e6).round() as i64;
            return crate::export::fmt_duration(us);
        }
    }
    s.to_string()
}

/// One POU.
fn pou(cx: &mut Ctx, p: Node) {
    // A POU sfc's export could not write as PLCopen (it had errors): its text, as it was.
    if let Some(text) = children(p, "addData")
        .flat_map(|a| children(a, "data"))
        .find(|d| attr(*d, "name") == Some(crate::export::SOURCE_DATA))
        .and_then(|d| child(d, "text"))
    {
        let t = xml::formatted_text(text);
        cx.diag(
            "SFC0716",
            anchor(p),
            format!(
                "`{}` had errors when it was exported: its text is read as it was written",
                attr(p, "name").unwrap_or("?").trim()
            ),
        );
        cx.em.open(anchor(p));
        cx.em.lines(&t, "");
        cx.em.str("\n");
        cx.em.close();
        return;
    }
    let diags_before = cx.diags.len();
    cx.em.open(anchor(p));
    let kind = match attr(p, "pouType").unwrap_or("") {
        "program" => "PROGRAM",
        "functionBlock" => "FUNCTION_BLOCK",
        "function" => "FUNCTION",
        other => {
            cx.diag(
                "SFC0705",
                attr_range(p, "pouType").unwrap_or_else(|| anchor(p)),
                format!("unknown POU type `{other}`; imported as a program"),
            );
            "PROGRAM"
        }
    };
    // Methods and properties are written as text (`codesys::members`), not carried as data.
    let attrs_list = element_attrs_without(p, &codesys::is_member_data);
    cx.used.clear();
    cx.extra_vars.clear();
    cx.compute.clear();
    for d in p.descendants().filter(|d| d.is_element()) {
        let key = match d.tag_name().name() {
            "variable" if d.parent().is_some_and(|l| l.tag_name().name().ends_with("Vars")) => "name",
            "step" | "macroStep" | "action" | "transition" => "name",
            _ => continue,
        };
        if let Some(n) = attr(d, key) {
            cx.used.insert(n.trim().to_ascii_uppercase());
        }
    }
    let body = child(p, "body");
    let lang = body.and_then(|b| elements(b).find(|e| ["IL", "ST", "FBD", "LD", "SFC"].contains(&e.tag_name().name())));
    let is_sfc = lang.is_some_and(|l| l.tag_name().name() == "SFC");
    // Comment boxes of an SFC body are kept on the POU.
    let mut pou_attrs = attrs_list;
    if let Some(l) = lang.filter(|_| is_sfc) {
        for c in children(l, "comment") {
            let pos = xml::position(c).unwrap_or((0.0, 0.0));
            let w = xml::num(c, "width").unwrap_or(0.0);
            let h = xml::num(c, "height").unwrap_or(0.0);
            let text = child(c, "content").map(|t| xml::formatted_text(t).text).unwrap_or_default();
            let v = format!(
                "{} {} {} {}\n{}",
                attrs::fmt_num(pos.0),
                attrs::fmt_num(pos.1),
                attrs::fmt_num(w),
                attrs::fmt_num(h),
                text
            );
            pou_attrs.push((attrs::COMMENT.to_string(), attrs::escape(&v)));
        }
    }
    // Vendor code without an IEC meaning: the POU is kept as written (its XML travels with it,
    // so an export writes it back unchanged) and not analysed.
    let header = std::mem::take(&mut cx.header_attrs);
    pou_attrs.splice(0..0, header);
    let verbatim = dialect::reasons(cx, p);
    cx.verbatim = verbatim.is_some();
    // A POU of a CODESYS project, or one naming things with doubled or trailing underscores as
    // CODESYS does: marked, so CODESYS's names and typing rules apply to it.
    let marked = pou_attrs.iter().any(|(k, v)| k == attrs::DIALECT && v.trim().eq_ignore_ascii_case("codesys"));
    cx.codesys_names = !cx.verbatim && (marked || cx.codesys_file || dialect::codesys_names(p));
    if cx.codesys_names && !marked {
        pou_attrs.push((attrs::DIALECT.to_string(), "codesys".to_string()));
    }
    if let Some(why) = &verbatim {
        pou_attrs.insert(0, (attrs::VERBATIM.to_string(), attrs::escape(&format!("not analysed: {why}"))));
        pou_attrs.push((attrs::POUXML.to_string(), attrs::escape(&xml::serialize(p))));
    }
    cx.attributes(&pou_attrs, "");
    let attrs_end = cx.em.out.len();
    let name = cx.name(p, "name", "POU");
    cx.pou_name = name.text.clone();
    cx.em.str(kind);
    cx.em.str(" ");
    cx.em.frag(&name);
    cx.em.str(&codesys::inheritance(p));
    let iface = child(p, "interface");
    if kind == "FUNCTION" {
        cx.em.str(" : ");
        match iface.and_then(|i| child(i, "returnType")) {
            Some(rt) => {
                let t = type_text(cx, rt, "    ");
                cx.em.frag(&t);
            }
            None => {
                cx.diag("SFC0705", anchor(p), "the function has no `returnType`; imported as returning BOOL");
                cx.em.str("BOOL");
            }
        }
    }
    cx.em.str("\n");
    if let Some(i) = iface {
        for l in elements(i) {
            let Some(kw) = var_keyword(l.tag_name().name()) else { continue };
            cx.em.open(anchor(l));
            var_list(cx, l, kw, "    ");
            cx.em.close();
        }
    }
    // With resource-scoped globals: those of the POU's resource it uses, through VAR_EXTERNAL.
    if !cx.externals.is_empty() {
        let mut ids = HashSet::new();
        for t in dialect::code_texts(p) {
            dialect::identifiers(&t, &mut ids);
        }
        let list: Vec<(String, Frag)> = cx
            .externals
            .iter()
            .filter(|(n, _)| ids.contains(&n.to_ascii_uppercase()) && !cx.used.contains(&n.to_ascii_uppercase()))
            .cloned()
            .collect();
        if !list.is_empty() {
            cx.em.str("    VAR_EXTERNAL\n");
            for (n, ty) in list {
                cx.used.insert(n.to_ascii_uppercase());
                cx.em.str(&format!("        {n} : "));
                cx.em.frag(&ty);
                cx.em.str(";\n");
            }
            cx.em.str("    END_VAR\n");
        }
    }
    let actions: Vec<Node> = child(p, "actions").map(|a| children(a, "action").collect()).unwrap_or_default();
    // The body is written apart, so the variables its translation declares can go before it.
    let head = std::mem::replace(&mut cx.em, Emitter::new(anchor(p)));
    let transitions: Vec<Node> =
        child(p, "transitions").map(|a| children(a, "transition").collect()).unwrap_or_default();
    match lang {
        None => {
            if body.is_some() {
                cx.diag(
                    "SFC0705",
                    body.map(anchor).unwrap_or_else(|| anchor(p)),
                    "the body has no IL, ST, FBD, LD or SFC",
                );
            }
        }
        Some(l) => {
            cx.em.open(anchor(l));
            match l.tag_name().name() {
                "ST" | "IL" => {
                    let t = dialect::map(cx, &xml::formatted_text(l));
                    cx.em.lines(&t, "    ")
                }
                "SFC" => sfc::chart(cx, l, &actions, &transitions),
                _ => {
                    let stmts = network::statements(cx, l, "    ");
                    cx.em.frag(&stmts);
                }
            }
            cx.em.close();
        }
    }
    for extra in children(p, "body").skip(1).collect::<Vec<_>>() {
        cx.diag("SFC0710", anchor(extra), "only the first body of a POU is imported");
    }
    if !is_sfc {
        // The actions of a POU that is no chart (CODESYS's actions of a function block), after
        // its statements.
        if !actions.is_empty() {
            cx.em.str("\n");
            sfc::write_actions(cx, &actions);
        }
        for t in &transitions {
            cx.diag("SFC0710", anchor(*t), "a transition condition of a POU whose body is not SFC is never used");
        }
    }
    // Methods and properties, in text (an export writes them back as CODESYS data).
    codesys::members(cx, p);
    let body_text = std::mem::replace(&mut cx.em, head);
    // Transitions of the SFC body left unconnected go with the POU's attributes.
    let mut lines = String::new();
    for t in std::mem::take(&mut cx.loose) {
        lines.push_str(&format!("{{attribute '{}' := '{}'}}\n", attrs::LOOSE, attrs::escape(&t.write())));
    }
    cx.em.insert(attrs_end, &lines);
    if !cx.extra_vars.is_empty() {
        cx.em.str("    VAR\n");
        for (n, t) in std::mem::take(&mut cx.extra_vars) {
            cx.em.str(&format!("        {n} : {t};\n"));
        }
        cx.em.str("    END_VAR\n");
    }
    cx.em.str("\n");
    cx.em.append(body_text);
    cx.em.str(match kind {
        "FUNCTION_BLOCK" => "END_FUNCTION_BLOCK\n\n",
        "FUNCTION" => "END_FUNCTION\n\n",
        _ => "END_PROGRAM\n\n",
    });
    cx.em.close();
    for f in std::mem::take(&mut cx.functions) {
        cx.em.open(anchor(p));
        cx.em.str(&f);
        cx.em.close();
    }
    // A POU kept as written is not analysed: what its import found is not reported either.
    if verbatim.is_some() {
        cx.diags.truncate(diags_before);
    }
}

/// The body of an action (`body` element): ST or IL copied, FBD or LD translated.
pub(crate) fn action_body(cx: &mut Ctx, body: Node, indent: &str) {
    let lang = elements(body).find(|e| ["IL", "ST", "FBD", "LD", "SFC"].contains(&e.tag_name().name()));
    match lang {
        None => {
            cx.diag("SFC0705", anchor(body), "the action body has no IL, ST, FBD, LD or SFC");
        }
        Some(l) => {
            cx.em.open(anchor(l));
            match l.tag_name().name() {
                "ST" | "IL" => {
                    let t = dialect::map(cx, &xml::formatted_text(l));
                    cx.em.lines(&t, indent)
                }
                "SFC" => sfc::action_chart(cx, l),
                _ => {
                    let stmts = network::statements(cx, l, indent);
                    cx.em.frag(&stmts);
                }
            }
            cx.em.close();
        }
    }
}

/// `VAR … END_VAR` from a `varList`.
/// The keyword of the var block an `interface` child element holds (`inputVars` → VAR_INPUT).
pub(crate) fn var_keyword(element: &str) -> Option<&'static str> {
    Some(match element {
        "localVars" => "VAR",
        "tempVars" => "VAR_TEMP",
        "inputVars" => "VAR_INPUT",
        "outputVars" => "VAR_OUTPUT",
        "inOutVars" => "VAR_IN_OUT",
        "externalVars" => "VAR_EXTERNAL",
        "globalVars" => "VAR_GLOBAL",
        "accessVars" => "VAR_ACCESS",
        _ => return None,
    })
}

pub(crate) fn var_list(cx: &mut Ctx, l: Node, kw: &str, indent: &str) {
    let vars: Vec<Node> = children(l, "variable").collect();
    let mut head = kw.to_string();
    if xml::flag(l, "constant") {
        head.push_str(" CONSTANT");
    }
    if xml::flag(l, "retain") {
        head.push_str(" RETAIN");
    } else if xml::flag(l, "nonretain") {
        head.push_str(" NON_RETAIN");
    }
    if xml::flag(l, "persistent") {
        // Not an IEC keyword, but the CODESYS/TwinCAT one `sfc run` keeps over cold starts.
        head.push_str(" PERSISTENT");
    }
    cx.em.str(&format!("{indent}{head}\n"));
    let inner = format!("{indent}    ");
    for v in vars {
        if kw == "VAR_GLOBAL" {
            let key = attr(v, "name").unwrap_or("").trim().to_ascii_uppercase();
            if let Some(seen) = cx.emitted_globals.as_mut() {
                if !key.is_empty() && !seen.insert(key) {
                    continue;
                }
            }
        }
        cx.em.open(anchor(v));
        let list = element_attrs(v);
        cx.attributes(&list, &inner);
        cx.em.str(&inner);
        let access = own_data(v, "access");
        let raw_name = attr(v, "name").unwrap_or("");
        let has_name = !raw_name.trim().is_empty();
        if has_name {
            let n = cx.name(v, "name", "variable");
            cx.em.frag(&n);
        }
        if let Some(a) = attr(v, "address").map(str::trim).filter(|a| !a.is_empty()) {
            let range = attr_range(v, "address").unwrap_or_else(|| anchor(v));
            if has_name {
                cx.em.str(" ");
            }
            cx.em.str("AT ");
            let f = if a.starts_with('%') { Frag::located(a, range) } else { Frag::located(format!("%{a}"), range) };
            cx.em.frag(&f);
        } else if !has_name {
            cx.diag("SFC0704", anchor(v), "a variable without a name or an address");
            cx.em.str("Unnamed");
        }
        if kw == "VAR_ACCESS" {
            let path = access.and_then(|a| attr(a, "path")).unwrap_or("");
            cx.em.str(&format!(" : {path}"));
        }
        cx.em.str(" : ");
        match child(v, "type") {
            Some(t) => {
                let f = type_text(cx, t, &inner);
                cx.em.frag(&f);
            }
            None => {
                cx.diag("SFC0705", anchor(v), "the variable has no type; imported as BOOL");
                cx.em.str("BOOL");
            }
        }
        if kw == "VAR_ACCESS" {
            if let Some(m) = access.and_then(|a| attr(a, "mode")).filter(|m| is_ident(m) || m.contains('_')) {
                cx.em.str(&format!(" {m}"));
            }
        }
        if let Some(iv) = child(v, "initialValue") {
            cx.em.str(" := ");
            let f = value_text(cx, iv);
            cx.em.frag(&f);
        }
        cx.em.str(";\n");
        cx.em.close();
    }
    cx.em.str(&format!("{indent}END_VAR\n"));
}

/// The type inside a `type`, `baseType` or `returnType` element.
pub(crate) fn type_text(cx: &mut Ctx, t: Node, indent: &str) -> Frag {
    let Some(e) = elements(t).find(|e| e.tag_name().name() != "addData" && e.tag_name().name() != "documentation")
    else {
        cx.diag("SFC0705", anchor(t), "an empty type; imported as BOOL");
        return Frag::located("BOOL", anchor(t));
    };
    let at = anchor(e);
    let name = e.tag_name().name();
    let f = match name {
        "BOOL" | "BYTE" | "WORD" | "DWORD" | "LWORD" | "SINT" | "INT" | "DINT" | "LINT" | "USINT" | "UINT"
        | "UDINT" | "ULINT" | "REAL" | "LREAL" | "TIME" | "DATE" | "DT" | "TOD" => Frag::located(name, at),
        "string" | "wstring" => {
            let kw = if name == "string" { "STRING" } else { "WSTRING" };
            match attr(e, "length").map(str::trim).filter(|l| !l.is_empty()) {
                Some(l) => {
                    // CODESYS: `GVL.LEN`, a constant of a global variable list.
                    let l = match l.split_once('.') {
                        Some((gvl, c)) if !cx.verbatim && cx.gvl_names.contains(&gvl.trim().to_ascii_uppercase()) => {
                            c.trim()
                        }
                        _ => l,
                    };
                    Frag::located(format!("{kw}[{l}]"), at)
                }
                None => Frag::located(kw, at),
            }
        }
        "derived" => {
            let raw = attr(e, "name").unwrap_or("").trim();
            // CODESYS writes a reference as a derived type: `<derived name="REFERENCE TO INT"/>`.
            let words: Vec<&str> = raw.split_whitespace().collect();
            if let [r, t, target] = words.as_slice() {
                if r.eq_ignore_ascii_case("REFERENCE") && t.eq_ignore_ascii_case("TO") && is_ident(target) {
                    let at = attr_range(e, "name").unwrap_or_else(|| at.clone());
                    return Frag::located(format!("REFERENCE TO {target}"), at);
                }
            }
            match dialect::map_type(raw) {
                Some(std) => Frag::located(std, attr_range(e, "name").unwrap_or_else(|| at.clone())),
                // A library type through its namespace: an opaque block (`opaque_types`).
                None if raw.contains('.') => {
                    Frag::located(sanitize(raw), attr_range(e, "name").unwrap_or_else(|| at.clone()))
                }
                None => cx.name(e, "name", "type"),
            }
        }
        "array" => {
            let mut f = Frag::plain("ARRAY [");
            for (i, d) in children(e, "dimension").enumerate() {
                if i > 0 {
                    f.push_str(", ");
                }
                let lo = attr(d, "lower").unwrap_or("0").trim().to_string();
                let hi = attr(d, "upper").unwrap_or("0").trim().to_string();
                f.push(&Frag::located(format!("{lo}..{hi}"), anchor(d)));
            }
            f.push_str("] OF ");
            match child(e, "baseType") {
                Some(b) => {
                    let bt = type_text(cx, b, indent);
                    f.push(&bt);
                }
                None => {
                    cx.diag("SFC0705", at.clone(), "an array without `baseType`; imported as ARRAY OF BOOL");
                    f.push_str("BOOL");
                }
            }
            f.locate(at)
        }
        "enum" => {
            let mut f = Frag::default();
            if let Some(b) = child(e, "baseType") {
                let bt = type_text(cx, b, indent);
                f.push(&bt);
                f.push_str(" ");
            }
            f.push_str("(");
            let values = child(e, "values").map(|v| children(v, "value").collect::<Vec<_>>()).unwrap_or_default();
            for (i, v) in values.iter().enumerate() {
                if i > 0 {
                    f.push_str(", ");
                }
                let n = cx.name(*v, "name", "enumerated value");
                f.push(&n);
                if let Some(val) = attr(*v, "value").map(str::trim).filter(|s| !s.is_empty()) {
                    f.push_str(" := ");
                    f.push(&Frag::located(val, attr_range(*v, "value").unwrap_or_else(|| anchor(*v))));
                }
            }
            f.push_str(")");
            f.locate(at)
        }
        "struct" => {
            let mut f = Frag::plain("STRUCT\n");
            for v in children(e, "variable") {
                let inner = format!("{indent}    ");
                f.push_str(&inner);
                let n = cx.name(v, "name", "structure member");
                f.push(&n);
                f.push_str(" : ");
                match child(v, "type") {
                    Some(tt) => {
                        let tf = type_text(cx, tt, &inner);
                        f.push(&tf);
                    }
                    None => {
                        cx.diag("SFC0705", anchor(v), "a structure member without a type; imported as BOOL");
                        f.push_str("BOOL");
                    }
                }
                if let Some(iv) = child(v, "initialValue") {
                    f.push_str(" := ");
                    let vf = value_text(cx, iv);
                    f.push(&vf);
                }
                f.push_str(";\n");
            }
            f.push_str(indent);
            f.push_str("END_STRUCT");
            f.locate(at)
        }
        "subrangeSigned" | "subrangeUnsigned" => {
            let mut f = Frag::default();
            match child(e, "baseType") {
                Some(b) => {
                    let bt = type_text(cx, b, indent);
                    f.push(&bt);
                }
                None => f.push_str(if name == "subrangeSigned" { "DINT" } else { "UDINT" }),
            }
            let r = child(e, "range");
            let lo = r.and_then(|r| attr(r, "lower")).unwrap_or("0").trim();
            let hi = r.and_then(|r| attr(r, "upper")).unwrap_or("0").trim();
            f.push_str(&format!(" ({lo}..{hi})"));
            f.locate(at)
        }
        // `POINTER TO T` (CODESYS, typed and simulated).
        "pointer" => {
            let mut f = Frag::plain("POINTER TO ");
            match child(e, "baseType") {
                Some(b) => f.push(&type_text(cx, b, indent)),
                None => f.push_str("BYTE"),
            }
            f.locate(at)
        }
        other => {
            cx.diag("SFC0705", at.clone(), format!("`{other}` cannot be the type of a variable"));
            Frag::located(other.to_ascii_uppercase(), at)
        }
    };
    f
}

/// An initial value (`initialValue` or `value` element).
pub(crate) fn value_text(cx: &mut Ctx, v: Node) -> Frag {
    let Some(e) = elements(v).find(|e| e.tag_name().name().ends_with("Value")) else {
        cx.diag("SFC0705", anchor(v), "an empty initial value");
        return Frag::located("0", anchor(v));
    };
    match e.tag_name().name() {
        "simpleValue" => match attr(e, "value") {
            Some(val) => {
                let range = attr_range(e, "value").unwrap_or_else(|| anchor(e));
                // CODESYS: `E_Mode.Manual` is the IEC `E_Mode#Manual`.
                if let Some((ty, v)) = val.trim().split_once('.') {
                    if !cx.verbatim && cx.enum_types.contains(&ty.trim().to_ascii_uppercase()) && is_ident(v.trim()) {
                        return Frag::located(format!("{}#{}", ty.trim(), v.trim()), range);
                    }
                }
                let t = val.trim();
                let lead = val.len() - val.trim_start().len();
                let mut f = Frag::plain(t);
                if attr_is_raw(cx.src, &range, val) {
                    let s = range.start + lead as u32;
                    f.marks.push(crate::emit::MapEntry {
                        text: 0..t.len() as u32,
                        xml: s..s + t.len() as u32,
                        exact: true,
                    });
                } else {
                    f = f.locate(range);
                }
                f
            }
            None => Frag::plain(""),
        },
        "arrayValue" => {
            let mut f = Frag::plain("[");
            for (i, item) in children(e, "value").enumerate() {
                if i > 0 {
                    f.push_str(", ");
                }
                let rep = attr(item, "repetitionValue").map(str::trim).filter(|r| !r.is_empty() && *r != "1");
                let inner = if elements(item).next().is_some() { value_text(cx, item) } else { Frag::plain("") };
                match rep {
                    Some(r) => {
                        f.push_str(&format!("{r}("));
                        f.push(&inner);
                        f.push_str(")");
                    }
                    None => f.push(&inner),
                }
            }
            f.push_str("]");
            f.locate(anchor(e))
        }
        "structValue" => {
            let mut f = Frag::plain("(");
            for (i, item) in children(e, "value").enumerate() {
                if i > 0 {
                    f.push_str(", ");
                }
                let m = cx.name(item, "member", "structure member");
                f.push(&m);
                f.push_str(" := ");
                let inner = value_text(cx, item);
                f.push(&inner);
            }
            f.push_str(")");
            f.locate(anchor(e))
        }
        other => {
            cx.diag("SFC0705", anchor(e), format!("unknown initial value `{other}`"));
            Frag::located("0", anchor(e))
        }
    }
}

/// Whether an attribute value appears in the source exactly as decoded (no entities).
pub(crate) fn attr_is_raw(src: &str, range: &Range<u32>, value: &str) -> bool {
    src.get(range.start as usize..range.end as usize) == Some(value)
}

/// The located text of an attribute value, exact when the source holds it verbatim.
pub(crate) fn attr_xtext(cx: &Ctx, n: Node, name: &str) -> Option<XText> {
    let v = attr(n, name)?;
    let range = attr_range(n, name)?;
    let mut t = XText::synthetic(v, range.clone());
    if attr_is_raw(cx.src, &range, v) {
        t.runs.push(xml::Run { text: 0, raw: range.start, len: v.len() as u32 });
    }
    Some(t)
}

/// The tool of the CODESYS family that wrote the project `root` (`dialect::vendor`).
pub(crate) fn vendor(root: Node) -> Option<crate::Vendor> {
    dialect::vendor(root)
}

/// What [`run`] gives: IEC text, source map, diagnostics, and the tool that wrote the file.
pub(crate) type Run = (String, SourceMap, Vec<Diagnostic>, Option<crate::Vendor>);

/// Runs the whole import: XML text to IEC text, source map, diagnostics, vendor.
pub(crate) fn run(file: u32, xml_text: &str) -> Run {
    let doc = match sfc_xmlmap::parse(file, xml_text) {
        Ok(d) => d,
        Err(d) => return (String::new(), SourceMap::default(), vec![d], None),
    };
    let root = doc.root_element();
    // The other vendors' exports are read by their own crates, into the same text.
    if sfc_l5x::is_l5x(root) {
        let out = sfc_l5x::import(file, xml_text);
        return (out.text, out.map, out.diagnostics, Some(crate::Vendor::Studio5000));
    }
    if sfc_simaticml::is_simaticml(root) {
        let out = sfc_simaticml::import(file, xml_text);
        return (out.text, out.map, out.diagnostics, Some(crate::Vendor::TiaPortal));
    }
    let vendor = if root.tag_name().name() == "project" { dialect::vendor(root) } else { None };
    let mut cx = Ctx {
        file,
        src: xml_text,
        em: Emitter::new(anchor(root)),
        diags: Vec::new(),
        used: HashSet::new(),
        extra_vars: Vec::new(),
        compute: Vec::new(),
        scoped_globals: false,
        gvl_names: HashSet::new(),
        renamed: Default::default(),
        programs: HashSet::new(),
        externals: Vec::new(),
        enum_types: HashSet::new(),
        global_names: HashSet::new(),
        emitted_globals: None,
        header_attrs: Vec::new(),
        verbatim: false,
        codesys_names: false,
        codesys_file: false,
        loose: Vec::new(),
        pou_name: String::new(),
        functions: Vec::new(),
        condition_functions: 0,
    };
    if root.tag_name().name() != "project" {
        let note = not_a_project_note(root);
        cx.diag(
            "SFC0702",
            anchor(root),
            format!("the document element is `{}`, not a PLCopen `project`", root.tag_name().name()),
        )
        .notes
        .push(note);
    } else {
        match root.tag_name().namespace() {
            Some(ns) if NAMESPACES.contains(&ns) => {}
            ns => {
                cx.diag(
                    "SFC0703",
                    anchor(root),
                    format!("unknown namespace `{}`; reading the file as PLCopen TC6 XML anyway", ns.unwrap_or("")),
                )
                .notes
                .push(format!("known namespaces: {}", NAMESPACES.join(", ")));
            }
        }
        project(&mut cx, root);
    }
    let (text, map) = cx.em.finish();
    (text, map, cx.diags, vendor)
}

/// What to do with an XML file that is not a PLCopen project: the vendor formats users bring
/// by mistake are named, with the export that gives PLCopen XML.
fn not_a_project_note(root: Node) -> String {
    let name = root.tag_name().name();
    if name == "TcPlcObject" {
        "this is a TwinCAT 3 source file (.TcPOU, .TcGVL, .TcDUT), not PLCopen XML; in TwinCAT, \
         right-click the POU or its folder, choose `Export PLCopenXML...`, and give sfc that file"
            .to_string()
    } else {
        "sfc reads PLCopen TC6 XML, whose document element is `<project \
         xmlns=\"http://www.plcopen.org/xml/tc6_0201\">` (or tc6_0200, tc6_0100); export the POU \
         as PLCopen XML from the tool that made this file"
            .to_string()
    }
}
