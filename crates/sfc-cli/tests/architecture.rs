//! ARCHITECTURE.md's crate table is the truth about dependencies: every workspace crate has a
//! row, and its "may depend on" column names exactly the crate's normal dependencies (those of
//! every target; dev-dependencies are free). Add a crate or a dependency to the table first.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `name → allowed dependencies`, from the table under "## Crates".
fn table() -> Vec<(String, BTreeSet<String>)> {
    let text = std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md");
    let mut rows = Vec::new();
    let mut in_table = false;
    for line in text.lines() {
        if line.starts_with("| crate | job | may depend on |") {
            in_table = true;
            continue;
        }
        if !in_table {
            continue;
        }
        if !line.starts_with('|') {
            break;
        }
        let cells: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        if cells.len() < 3 || cells[0].starts_with("---") {
            continue;
        }
        let name = cells[0].trim_matches('`').to_string();
        rows.push((name, names(cells[cells.len() - 1])));
    }
    assert!(!rows.is_empty(), "no crate table found in ARCHITECTURE.md");
    rows
}

/// The names of a "may depend on" cell: outside parentheses, separated by commas or "and".
fn names(cell: &str) -> BTreeSet<String> {
    let mut plain = String::new();
    let mut depth = 0usize;
    for c in cell.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            _ if depth == 0 => plain.push(c),
            _ => {}
        }
    }
    plain
        .split(',')
        .flat_map(|part| part.split(" and "))
        .map(|n| n.trim().trim_matches('`').to_string())
        .filter(|n| !n.is_empty())
        .collect()
}

/// The workspace members' directories, from the root Cargo.toml.
fn members() -> Vec<PathBuf> {
    let text = std::fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let doc: toml_edit::DocumentMut = text.parse().unwrap();
    doc["workspace"]["members"]
        .as_array()
        .expect("workspace.members")
        .iter()
        .map(|m| root().join(m.as_str().unwrap()))
        .collect()
}

/// A crate's name and its normal dependencies (all targets).
fn manifest(dir: &Path) -> (String, BTreeSet<String>) {
    let text = std::fs::read_to_string(dir.join("Cargo.toml")).unwrap();
    let doc: toml_edit::DocumentMut = text.parse().unwrap();
    let name = doc["package"]["name"].as_str().unwrap().to_string();
    let mut deps = BTreeSet::new();
    let mut add = |t: Option<&dyn toml_edit::TableLike>| {
        if let Some(t) = t {
            deps.extend(t.iter().map(|(k, _)| k.to_string()));
        }
    };
    add(doc.get("dependencies").and_then(|d| d.as_table_like()));
    if let Some(targets) = doc.get("target").and_then(|t| t.as_table_like()) {
        for (_, t) in targets.iter() {
            add(t.get("dependencies").and_then(|d| d.as_table_like()));
        }
    }
    (name, deps)
}

#[test]
fn crate_table_matches_the_manifests() {
    let table = table();
    let mut problems = Vec::new();
    let mut crates = BTreeSet::new();
    for dir in members() {
        let (name, deps) = manifest(&dir);
        crates.insert(name.clone());
        let Some((_, allowed)) = table.iter().find(|(n, _)| *n == name) else {
            problems.push(format!("`{name}` has no row in ARCHITECTURE.md's crate table"));
            continue;
        };
        for d in deps.difference(allowed) {
            problems.push(format!("`{name}` depends on `{d}`, which its row does not allow"));
        }
        for d in allowed.difference(&deps) {
            problems.push(format!("`{name}`'s row names `{d}`, which is not among its dependencies"));
        }
    }
    for (n, _) in &table {
        if !crates.contains(n) {
            problems.push(format!("ARCHITECTURE.md has a row for `{n}`, which is not a workspace member"));
        }
    }
    assert!(problems.is_empty(), "ARCHITECTURE.md and the manifests disagree:\n  {}", problems.join("\n  "));
}

/// The layering rule the table encodes: the syntax crate depends on no sfc crate but
/// diagnostics, and no library crate depends on the binaries' crates.
#[test]
fn layers_point_one_way() {
    let table = table();
    let deps_of = |n: &str| table.iter().find(|(c, _)| c == n).map(|(_, d)| d.clone()).unwrap_or_default();
    let sfc_deps = |n: &str| deps_of(n).into_iter().filter(|d| d.starts_with("sfc-")).collect::<Vec<_>>();
    assert_eq!(sfc_deps("sfc-syntax"), ["sfc-diagnostics"]);
    for (name, deps) in &table {
        assert!(!deps.contains("sfc-cli"), "{name} depends on the binary crate");
        if name != "sfc-cli" {
            assert!(!deps.contains("sfc-server"), "{name} depends on the server");
        }
    }
    for front in ["sfc-cli", "sfc-server"] {
        assert!(deps_of(front).contains("sfc-driver"), "{front} goes through the driver");
    }
    assert!(!deps_of("sfc-driver").contains("sfc-server"));
}
