//! CODESYS's objects in a POU's `addData` (methods, properties) and in its interface's
//! (`EXTENDS`, `IMPLEMENTS`), written as the text of IEC 61131-3's 3rd edition and CODESYS
//! (`METHOD … END_METHOD`, `PROPERTY … GET … END_GET … END_PROPERTY`), which the type checker
//! and the simulator handle; the export writes them back in CODESYS's shapes.

use super::{var_keyword, var_list, Ctx};
use crate::xml::{self, attr, child, children, elements};
use roxmltree::Node;

/// `data` names (their ends) of CODESYS's objects.
const METHOD: &str = "/method";
const PROPERTY: &str = "/property";
const INHERITANCE: &str = "/pouinheritance";
/// An interface, in the project's (or an application's) `addData`.
pub(crate) const INTERFACE: &str = "http://www.3s-software.com/plcopenxml/interface";

/// Whether `n` is a `data` element holding an interface (written as text instead).
pub(super) fn is_interface_data(n: Node) -> bool {
    n.tag_name().name() == "data" && attr(n, "name") == Some(INTERFACE)
}

/// Every interface of the document, in document order: `data[@name=…/interface]/Interface`.
pub(super) fn interfaces<'a, 'i>(root: Node<'a, 'i>) -> Vec<Node<'a, 'i>> {
    root.descendants()
        .filter(|d| d.is_element() && is_interface_data(*d))
        .flat_map(|d| children(d, "Interface"))
        .collect()
}

/// An interface as text: `INTERFACE Name [EXTENDS A, B]`, its methods' and properties'
/// prototypes, `END_INTERFACE`. Its bases are read from an `Inheritance/Extends` in its
/// `addData` (the shape of a POU's `pouinheritance`).
pub(super) fn interface(cx: &mut Ctx, i: Node) {
    let name = attr(i, "name").unwrap_or("").trim().to_string();
    let bases: Vec<String> = children(i, "addData")
        .flat_map(|a| children(a, "data"))
        .filter_map(|d| child(d, "Inheritance"))
        .flat_map(|inh| children(inh, "Extends"))
        .map(|e| xml::text_of(e).text.trim().to_string())
        .filter(|n| !n.is_empty())
        .collect();
    cx.em.str(&format!("INTERFACE {name}"));
    if !bases.is_empty() {
        cx.em.str(&format!(" EXTENDS {}", bases.join(", ")));
    }
    cx.em.str(
        "
",
    );
    let methods: Vec<Node> =
        children(i, "Methods").flat_map(|l| children(l, "Method")).chain(children(i, "Method")).collect();
    let properties: Vec<Node> =
        children(i, "Properties").flat_map(|l| children(l, "Property")).chain(children(i, "Property")).collect();
    for m in methods {
        method(cx, m);
    }
    for q in properties {
        property(cx, q);
    }
    cx.em.str("END_INTERFACE\n\n");
}

/// ` EXTENDS A IMPLEMENTS B, C` for the header of POU `p`, from its interface's `addData`.
pub(super) fn inheritance(p: Node) -> String {
    let Some(inh) = child(p, "interface")
        .into_iter()
        .flat_map(|i| children(i, "addData"))
        .flat_map(|a| children(a, "data"))
        .filter(|d| attr(*d, "name").is_some_and(|n| n.ends_with(INHERITANCE)))
        .find_map(|d| child(d, "Inheritance"))
    else {
        return String::new();
    };
    let names = |tag: &str| -> Vec<String> {
        children(inh, tag).map(|e| xml::text_of(e).text.trim().to_string()).filter(|n| !n.is_empty()).collect()
    };
    let mut out = String::new();
    if let Some(base) = names("Extends").first() {
        out.push_str(&format!(" EXTENDS {base}"));
    }
    let implements = names("Implements");
    if !implements.is_empty() {
        out.push_str(&format!(" IMPLEMENTS {}", implements.join(", ")));
    }
    out
}

/// Whether `n` is a `data` element of a method or property (written as text instead).
pub(super) fn is_member_data(n: Node) -> bool {
    n.tag_name().name() == "data" && attr(n, "name").is_some_and(|a| a.ends_with(METHOD) || a.ends_with(PROPERTY))
}

/// The methods and properties of POU `p` as text, each after a blank line.
pub(super) fn members(cx: &mut Ctx, p: Node) {
    let datas: Vec<Node> = children(p, "addData").flat_map(|a| children(a, "data")).collect();
    for d in datas {
        let name = attr(d, "name").unwrap_or("");
        if name.ends_with(METHOD) {
            for m in children(d, "Method") {
                cx.em.str("\n");
                method(cx, m);
            }
        } else if name.ends_with(PROPERTY) {
            for q in children(d, "Property") {
                cx.em.str("\n");
                property(cx, q);
            }
        }
    }
}

/// `PRIVATE`, … from an object's `interface/addData/…/accessmodifiers`.
fn access(n: Node) -> String {
    let Some(am) = child(n, "interface")
        .into_iter()
        .flat_map(|i| children(i, "addData"))
        .flat_map(|a| children(a, "data"))
        .find_map(|d| child(d, "AccessModifiers"))
    else {
        return String::new();
    };
    ["Public", "Private", "Protected", "Internal", "Abstract", "Final"]
        .iter()
        .filter(|k| attr(am, k).is_some_and(|v| v.trim().eq_ignore_ascii_case("true")))
        .map(|k| format!(" {}", k.to_ascii_uppercase()))
        .collect()
}

/// The var blocks of an object's `interface` (the POU's own kinds) and its code, at `indent`.
fn code(cx: &mut Ctx, n: Node, indent: &str) {
    if let Some(i) = child(n, "interface") {
        for l in elements(i) {
            if let Some(kw) = var_keyword(l.tag_name().name()) {
                var_list(cx, l, kw, indent);
            }
        }
    }
    if let Some(st) = child(n, "body").and_then(|b| elements(b).find(|e| matches!(e.tag_name().name(), "ST" | "IL"))) {
        let t = super::dialect::map(cx, &xml::formatted_text(st));
        cx.em.lines(&t, indent);
    }
}

fn return_type(cx: &mut Ctx, n: Node) -> Option<crate::emit::Frag> {
    let rt = child(n, "interface").and_then(|i| child(i, "returnType"))?;
    Some(super::type_text(cx, rt, "    "))
}

fn method(cx: &mut Ctx, m: Node) {
    let name = attr(m, "name").unwrap_or("").trim().to_string();
    cx.em.str(&format!("    METHOD{} {name}", access(m)));
    if let Some(t) = return_type(cx, m) {
        cx.em.str(" : ");
        cx.em.frag(&t);
    }
    cx.em.str("\n");
    code(cx, m, "        ");
    cx.em.str("    END_METHOD\n");
}

fn property(cx: &mut Ctx, q: Node) {
    let name = attr(q, "name").unwrap_or("").trim().to_string();
    cx.em.str(&format!("    PROPERTY{} {name} : ", access(q)));
    match return_type(cx, q) {
        Some(t) => cx.em.frag(&t),
        None => cx.em.str("BOOL"),
    }
    cx.em.str("\n");
    for (tag, kw) in [("GetAccessor", "GET"), ("SetAccessor", "SET")] {
        if let Some(a) = child(q, tag) {
            cx.em.str(&format!("        {kw}{}\n", access(a)));
            code(cx, a, "            ");
            cx.em.str(&format!("        END_{kw}\n"));
        }
    }
    cx.em.str("    END_PROPERTY\n");
}
