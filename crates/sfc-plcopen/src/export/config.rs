//! `instances/configurations` from the file's `CONFIGURATION` blocks (kept as text by the
//! parser, read here token by token) and its file-level `VAR_GLOBAL` blocks.

use super::{slice, write_var_block, X};
use sfc_diagnostics::Span;
use sfc_syntax::ast;
use sfc_syntax::lexer::{lex, TokenKind};

struct Task {
    name: String,
    single: Option<String>,
    interval: Option<String>,
    priority: String,
}

struct Instance {
    name: String,
    type_name: String,
    task: Option<String>,
}

struct Resource {
    name: String,
    tasks: Vec<Task>,
    instances: Vec<Instance>,
    /// `VAR_GLOBAL … END_VAR` texts of the resource (its own scope).
    globals: Vec<String>,
}

struct Config {
    name: String,
    resources: Vec<Resource>,
    /// `VAR_GLOBAL … END_VAR` texts written inside the configuration.
    globals: Vec<String>,
}

/// Reads `CONFIGURATION name … END_CONFIGURATION`. Unknown parts are skipped: VAR_ACCESS,
/// VAR_CONFIG and function block instances of a resource have no counterpart here.
fn parse(text: &str) -> Option<Config> {
    let (all, _) = lex(0, text);
    let toks: Vec<(TokenKind, &str, u32, u32)> = all
        .iter()
        .filter(|t| !t.kind.is_trivia() && t.kind != TokenKind::Eof)
        .map(|t| (t.kind, text.get(t.start as usize..t.end as usize).unwrap_or(""), t.start, t.end))
        .collect();
    let kw = |i: usize, k: &str| toks.get(i).is_some_and(|t| t.0 == TokenKind::Ident && t.1.eq_ignore_ascii_case(k));
    let ident = |i: usize| toks.get(i).filter(|t| t.0 == TokenKind::Ident).map(|t| t.1.to_string());
    if !kw(0, "CONFIGURATION") {
        return None;
    }
    let mut cfg = Config { name: ident(1)?, resources: Vec::new(), globals: Vec::new() };
    let mut i = 2;
    // Tasks and programs directly in the configuration go to an implicit resource.
    let mut implicit =
        Resource { name: "resource1".into(), tasks: Vec::new(), instances: Vec::new(), globals: Vec::new() };
    let mut current: Option<Resource> = None;
    while i < toks.len() {
        if kw(i, "END_CONFIGURATION") {
            break;
        } else if kw(i, "RESOURCE") {
            if let Some(r) = current.take() {
                cfg.resources.push(r);
            }
            current = Some(Resource {
                name: ident(i + 1).unwrap_or_else(|| "resource1".into()),
                tasks: Vec::new(),
                instances: Vec::new(),
                globals: Vec::new(),
            });
            // Skip `ON type`.
            i += 2;
            if kw(i, "ON") {
                i += 2;
            }
            continue;
        } else if kw(i, "END_RESOURCE") {
            if let Some(r) = current.take() {
                cfg.resources.push(r);
            }
        } else if kw(i, "VAR_GLOBAL") {
            let start = toks[i].2;
            let mut j = i;
            while j < toks.len() && !kw(j, "END_VAR") {
                j += 1;
            }
            let end = toks.get(j).map(|t| t.3).unwrap_or(text.len() as u32);
            let g = slice(text, Span::new(0, start, end)).to_string();
            match current.as_mut() {
                Some(r) => r.globals.push(g),
                None => cfg.globals.push(g),
            }
            i = j + 1;
            continue;
        } else if kw(i, "TASK") {
            let name = ident(i + 1).unwrap_or_default();
            let mut task = Task { name, single: None, interval: None, priority: "0".into() };
            let mut j = i + 2;
            if toks.get(j).is_some_and(|t| t.0 == TokenKind::LParen) {
                j += 1;
                while j < toks.len() && toks[j].0 != TokenKind::RParen {
                    let key = toks[j].1.to_ascii_uppercase();
                    j += 1;
                    if toks.get(j).is_some_and(|t| t.0 == TokenKind::Assign) {
                        j += 1;
                    }
                    let vstart = toks.get(j).map(|t| t.2).unwrap_or(0);
                    let mut vend = vstart;
                    let mut depth = 0;
                    while j < toks.len() {
                        match toks[j].0 {
                            TokenKind::LParen => depth += 1,
                            TokenKind::RParen if depth == 0 => break,
                            TokenKind::RParen => depth -= 1,
                            TokenKind::Comma if depth == 0 => break,
                            _ => {}
                        }
                        vend = toks[j].3;
                        j += 1;
                    }
                    let value = slice(text, Span::new(0, vstart, vend)).trim().to_string();
                    match key.as_str() {
                        "INTERVAL" => task.interval = Some(value),
                        "PRIORITY" => task.priority = value,
                        "SINGLE" => task.single = Some(value),
                        _ => {}
                    }
                    if toks.get(j).is_some_and(|t| t.0 == TokenKind::Comma) {
                        j += 1;
                    }
                }
            }
            current.as_mut().unwrap_or(&mut implicit).tasks.push(task);
            i = j;
        } else if kw(i, "PROGRAM") {
            let mut j = i + 1;
            if kw(j, "RETAIN") || kw(j, "NON_RETAIN") {
                j += 1;
            }
            let name = ident(j).unwrap_or_default();
            j += 1;
            let mut task = None;
            if kw(j, "WITH") {
                task = ident(j + 1);
                j += 2;
            }
            if toks.get(j).is_some_and(|t| t.0 == TokenKind::Colon) {
                j += 1;
            }
            let type_name = ident(j).unwrap_or_default();
            current.as_mut().unwrap_or(&mut implicit).instances.push(Instance { name, type_name, task });
            // Skip to the end of the declaration.
            while j < toks.len() && toks[j].0 != TokenKind::Semi {
                j += 1;
            }
            i = j;
        }
        i += 1;
    }
    if let Some(r) = current.take() {
        cfg.resources.push(r);
    }
    if !implicit.tasks.is_empty() || !implicit.instances.is_empty() {
        cfg.resources.push(implicit);
    }
    Some(cfg)
}

/// Writes `VAR_GLOBAL … END_VAR` texts as `globalVars` lists.
fn write_globals(x: &mut X, texts: &[String]) {
    for g in texts {
        // Parsed in a wrapper so the declarations come out as for a POU.
        let wrapped = format!("PROGRAM W\n{g}\nEND_PROGRAM\n");
        let (u, _) = sfc_syntax::parse(0, &wrapped);
        for it in &u.items {
            if let ast::Item::Pou(p) = it {
                for b in &p.var_blocks {
                    write_var_block(x, &wrapped, b, "globalVars");
                }
            }
        }
    }
}

fn write_resource(x: &mut X, r: &Resource) {
    x.open("resource", &[("name", r.name.clone())]);
    for t in &r.tasks {
        let mut a: Vec<(&str, String)> = vec![("name", t.name.clone())];
        if let Some(s) = &t.single {
            a.push(("single", s.clone()));
        }
        if let Some(iv) = &t.interval {
            a.push(("interval", iv.clone()));
        }
        let prio = t.priority.trim().parse::<u32>().map(|p| p.min(65535)).unwrap_or(0);
        a.push(("priority", prio.to_string()));
        let inst: Vec<&Instance> =
            r.instances.iter().filter(|i| i.task.as_deref().is_some_and(|n| n.eq_ignore_ascii_case(&t.name))).collect();
        if inst.is_empty() {
            x.empty("task", &a);
        } else {
            x.open("task", &a);
            for i in inst {
                x.empty("pouInstance", &[("name", i.name.clone()), ("typeName", i.type_name.clone())]);
            }
            x.close("task");
        }
    }
    write_globals(x, &r.globals);
    for i in &r.instances {
        let bound = i.task.as_deref().is_some_and(|n| r.tasks.iter().any(|t| t.name.eq_ignore_ascii_case(n)));
        if !bound {
            x.empty("pouInstance", &[("name", i.name.clone()), ("typeName", i.type_name.clone())]);
        }
    }
    x.close("resource");
}

/// Writes `instances`: every configuration, with the file-level global variables in the first
/// one (a configuration named `config` is made for them when the file has none).
pub(super) fn write_instances(x: &mut X, src: &str, unit: &ast::SourceUnit) {
    let mut configs: Vec<Config> = unit
        .items
        .iter()
        .filter_map(|it| match it {
            ast::Item::Verbatim(v) if v.keyword.eq_ignore_ascii_case("CONFIGURATION") => parse(&v.text),
            _ => None,
        })
        .collect();
    let globals: Vec<&ast::VarBlock> =
        unit.items.iter().filter_map(|it| if let ast::Item::Globals(b) = it { Some(b) } else { None }).collect();
    if configs.is_empty() && !globals.is_empty() {
        configs.push(Config { name: "config".into(), resources: Vec::new(), globals: Vec::new() });
    }
    x.open("instances", &[]);
    x.open("configurations", &[]);
    for (k, c) in configs.iter().enumerate() {
        x.open("configuration", &[("name", c.name.clone())]);
        for r in &c.resources {
            write_resource(x, r);
        }
        if k == 0 {
            for b in &globals {
                write_var_block(x, src, b, "globalVars");
            }
        }
        write_globals(x, &c.globals);
        x.close("configuration");
    }
    x.close("configurations");
    x.close("instances");
}
