//! The editor's TypeScript types for the document (`web/src/contracts/doc.ts`) are generated
//! from these Rust types with ts-rs; this test fails when the committed file is stale
//! (`UPDATE_CONTRACTS=1 cargo test -p sfc-doc contracts` writes it anew).

use crate::*;
use ts_rs::TS;

/// The generated declarations, in a fixed order, with a header saying where they come from.
pub fn declarations() -> String {
    let cfg = ts_rs::Config::default();
    let mut out = String::from(
        "// GENERATED from crates/sfc-doc/src/lib.rs by ts-rs: do not edit.\n\
         // `UPDATE_CONTRACTS=1 cargo test -p sfc-doc contracts` writes it anew; the test fails when it is stale.\n\n",
    );
    for decl in [
        EditorDoc::decl(&cfg),
        OtherAttribute::decl(&cfg),
        PouKind::decl(&cfg),
        ChartTarget::decl(&cfg),
        Language::decl(&cfg),
        ActionDef::decl(&cfg),
        ElementKind::decl(&cfg),
        Element::decl(&cfg),
        Association::decl(&cfg),
        Connection::decl(&cfg),
        Point::decl(&cfg),
    ] {
        out.push_str("export ");
        out.push_str(&decl);
        out.push_str("\n\n");
    }
    out.trim_end().to_string() + "\n"
}

#[test]
fn contracts_are_current() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web/src/contracts/doc.ts");
    let now = declarations();
    if std::env::var_os("UPDATE_CONTRACTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &now).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(committed == now, "{} is stale: run `UPDATE_CONTRACTS=1 cargo test -p sfc-doc contracts`", path.display());
}
