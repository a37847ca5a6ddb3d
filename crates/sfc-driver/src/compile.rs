//! Checking and compiling a chart file for a target: the one implementation behind `sfc check`,
//! `sfc build` and the editor's `check` and `build` calls (moved here from `sfc-server`).

use crate::load::FileKind;
use sfc_diagnostics::{Diagnostic, SourceFile};
use sfc_model::{Chart, CheckOptions, Checked, Limits, Target};
use std::path::Path;

/// What a build produces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildTarget {
    Atmt,
    Eatmt,
    St,
    Stl,
    Plcopen,
    Svg,
    Text,
    /// Studio 5000: an L5X file with the chart as an SFC routine (`sfc-l5x`).
    L5x,
    /// TIA Portal: a SimaticML file with the chart as an S7-GRAPH block (`sfc-simaticml`).
    Simaticml,
}

impl BuildTarget {
    /// Every target, in the order the documentation lists them.
    pub const ALL: [BuildTarget; 9] = [
        BuildTarget::Atmt,
        BuildTarget::Eatmt,
        BuildTarget::St,
        BuildTarget::Stl,
        BuildTarget::Plcopen,
        BuildTarget::Svg,
        BuildTarget::Text,
        BuildTarget::L5x,
        BuildTarget::Simaticml,
    ];

    /// The name used on the command line and in the HTTP API (`atmt`, `st`, …).
    pub fn name(self) -> &'static str {
        match self {
            BuildTarget::Atmt => "atmt",
            BuildTarget::Eatmt => "eatmt",
            BuildTarget::St => "st",
            BuildTarget::Stl => "stl",
            BuildTarget::Plcopen => "plcopen",
            BuildTarget::Svg => "svg",
            BuildTarget::Text => "text",
            BuildTarget::L5x => "l5x",
            BuildTarget::Simaticml => "simaticml",
        }
    }

    /// Parses a target name (exact, lowercase).
    pub fn from_name(name: &str) -> Option<BuildTarget> {
        BuildTarget::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The REX block whose rules the chart must follow when building a transition table.
    pub fn table_target(self) -> Option<Target> {
        match self {
            BuildTarget::Atmt => Some(Target::Atmt),
            BuildTarget::Eatmt => Some(Target::Eatmt),
            _ => None,
        }
    }
}

/// A file is PLCopen XML by its extension, or by its first non-blank character (after a
/// byte order mark).
pub fn is_xml(path: &Path, text: &str) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("xml"))
        || text.trim_start_matches('\u{feff}').trim_start().starts_with('<')
}

/// A chart file as the IEC text that runs it (`sfc run`): the text itself, or for PLCopen XML
/// the text it imports to, with what the import said and the map that locates the later
/// diagnostics in the XML the user wrote.
pub struct IecText {
    pub text: String,
    /// The import, for a PLCopen XML file.
    pub imported: Option<sfc_plcopen::Imported>,
}

impl IecText {
    /// Reads `text` (named `path`) as IEC text, importing it when it is PLCopen XML.
    pub fn of(path: &Path, text: &str) -> IecText {
        if !is_xml(path, text) {
            return IecText { text: text.to_string(), imported: None };
        }
        let imported = sfc_plcopen::import(0, &path.display().to_string(), text);
        IecText { text: imported.text.clone(), imported: Some(imported) }
    }

    /// The import's own diagnostics (located in the XML); none for IEC text.
    pub fn import_diagnostics(&self) -> &[Diagnostic] {
        self.imported.as_ref().map_or(&[], |i| i.diagnostics.as_slice())
    }

    /// Diagnostics of the IEC text (file id 0, in `file`) located in the file the user wrote,
    /// with that file to render them.
    pub fn locate(&self, file: SourceFile, diags: Vec<Diagnostic>) -> (SourceFile, Vec<Diagnostic>) {
        match &self.imported {
            None => (file, diags),
            Some(i) => (i.xml.clone(), diags.iter().map(|d| sfc_plcopen::relocate(d, &i.map, 0)).collect()),
        }
    }
}

/// Checks a file of either kind: the diagnostics are located in the file the user wrote (for
/// XML, the importer maps them back to XML lines and columns); `Checked` is the IEC text.
pub fn check_any(file_id: u32, path: &Path, text: &str, opts: &CheckOptions) -> (SourceFile, Checked, Vec<Diagnostic>) {
    let kind = if is_xml(path, text) { FileKind::PlcOpen } else { FileKind::Iec };
    check_text(file_id, &path.display().to_string(), text, kind, opts)
}

/// Moves diagnostics of the IEC text a PLCopen file imports to (findings made on the checked
/// charts after [`check_any`]) to the XML, as the check's own are.
pub fn locate_in_xml(file_id: u32, name: &str, xml: &str, diags: &[Diagnostic]) -> Vec<Diagnostic> {
    let imported = sfc_plcopen::import(file_id, name, xml);
    diags.iter().map(|d| sfc_plcopen::relocate(d, &imported.map, file_id)).collect()
}

/// [`check_any`] for a text in memory (an editor buffer, a language server's document):
/// `name` is how diagnostics name the file, `kind` says how to read it.
pub fn check_text(
    file_id: u32,
    name: &str,
    text: &str,
    kind: FileKind,
    opts: &CheckOptions,
) -> (SourceFile, Checked, Vec<Diagnostic>) {
    match kind {
        FileKind::PlcOpen => {
            let imported = sfc_plcopen::import(file_id, name, text);
            let checked = sfc_analysis::check_source(file_id, &format!("{name} (imported)"), &imported.text, opts);
            let diags = sfc_plcopen::with_check(&imported, &checked.diagnostics, file_id);
            (imported.xml, checked, diags)
        }
        FileKind::Iec => {
            let checked = sfc_analysis::check_source(file_id, name, text, opts);
            let diags = checked.diagnostics.clone();
            (checked.file.clone(), checked, diags)
        }
    }
}

/// [`check_text`] of IEC text already parsed: `parsed` is `sfc_syntax::parse(file_id, text)`
/// (the language server parses each version once, for its index and for this check), the tree
/// owned or shared with the index ([`sfc_model::Tree`]).
pub fn check_parsed_text(
    file_id: u32,
    name: &str,
    text: &str,
    parsed: (impl Into<sfc_model::Tree>, Vec<Diagnostic>),
    opts: &CheckOptions,
) -> (SourceFile, Checked, Vec<Diagnostic>) {
    let checked = sfc_analysis::check_parsed(file_id, name, text, parsed, opts);
    let diags = checked.diagnostics.clone();
    (checked.file.clone(), checked, diags)
}

/// The options of the check that validates a chart before it is built: the target rules of
/// ATMT/EATMT are part of it (a table target overrides `sfc.target`); the analysis is not (that
/// is `sfc check`'s job).
pub fn validation_options(target: BuildTarget, nstep: Option<u32>, ntr: Option<u32>) -> CheckOptions {
    CheckOptions { target: target.table_target(), nstep, ntr, analysis: false, ..CheckOptions::default() }
}

/// The chart to build: the one named by `pou`, or the only SFC POU of the file.
pub fn pick_chart<'a>(checked: &'a Checked, pou: Option<&str>) -> Result<&'a Chart, String> {
    let names = || checked.charts.iter().map(|c| c.pou.as_str()).collect::<Vec<_>>().join(", ");
    match pou {
        Some(p) => checked
            .charts
            .iter()
            .find(|c| c.pou.eq_ignore_ascii_case(p))
            .ok_or_else(|| format!("`{p}` is not an SFC POU of the file (SFC POUs: {})", names())),
        None => match checked.charts.as_slice() {
            [one] => Ok(one),
            [] => Err("the file has no SFC POU to build".to_string()),
            _ => Err(format!("the file has several SFC POUs; choose one with --pou ({})", names())),
        },
    }
}

/// How to compile a checked file.
#[derive(Debug, Clone, Default)]
pub struct CompileOptions<'a> {
    /// The SFC POU to build when the file has several.
    pub pou: Option<&'a str>,
    /// ATMT/EATMT: compile simultaneous branches into one automaton.
    pub flatten: bool,
    /// ATMT/EATMT state and rule limit overrides.
    pub nstep: Option<u32>,
    pub ntr: Option<u32>,
    /// STL: set/reset or SCR.
    pub stl_method: sfc_codegen::stl::StlMethod,
    /// ST: the compiler it is written for.
    pub st_dialect: sfc_codegen::st::StDialect,
    /// PLCopen: the PLCopen file the checked text was imported from, whose element a POU with
    /// errors is written as (`sfc_plcopen::export_with`).
    pub original: Option<&'a str>,
}

/// A successful compilation.
#[derive(Debug, Clone)]
pub struct Compiled {
    /// The output (for ATMT/EATMT the one-line table, without a line break).
    pub text: String,
    /// Notes for the user, located in the checked text (flattening: what each state stands for).
    pub notes: Vec<Diagnostic>,
    /// With flattening: the number of states produced.
    pub flattened: Option<usize>,
    /// STL: Micro/WIN's symbol table as CSV.
    pub symbols: Option<String>,
}

/// Why a checked file could not be compiled.
#[derive(Debug, Clone)]
pub enum CompileError {
    /// No chart, or not the one asked for (a usage problem, not a problem of the chart).
    Chart(String),
    /// The chart breaks a rule of the target; located in the checked text.
    Diagnostics(Vec<Diagnostic>),
}

/// SFC0805 for what the ST target copies as CODESYS writes it and IEC 61131-3 compilers such as
/// MatIEC (Beremiz, OpenPLC v3) and STruC++ (OpenPLC v4) do not take: actions outside a chart,
/// methods, properties, `EXTENDS`/`IMPLEMENTS` and interfaces (not for `--st-dialect codesys`).
fn codesys_extensions(checked: &Checked, dialect: sfc_codegen::st::StDialect) -> Vec<Diagnostic> {
    if dialect == sfc_codegen::st::StDialect::Codesys {
        return Vec::new();
    }
    let warn = |span, what: String| {
        Diagnostic::warning(
            "SFC0805",
            span,
            format!(
                "{what}: the ST output keeps it as CODESYS writes it, which MatIEC (Beremiz, OpenPLC v3) and \
                 STruC++ (OpenPLC v4) do not compile"
            ),
        )
    };
    let mut out = Vec::new();
    for item in &checked.unit.items {
        match item {
            sfc_syntax::ast::Item::Pou(p) => {
                let name = &p.name.text;
                if let Some(a) = p.actions.first() {
                    out.push(warn(a.name.span, format!("`{name}` has actions outside a chart")));
                }
                if let Some(m) = p.methods.first() {
                    out.push(warn(m.name.span, format!("`{name}` has methods")));
                }
                if let Some(pr) = p.properties.first() {
                    out.push(warn(pr.name.span, format!("`{name}` has properties")));
                }
                if let Some(e) = &p.extends {
                    out.push(warn(e.span, format!("`{name}` extends `{}`", e.text)));
                }
                if let Some(i) = p.implements.first() {
                    out.push(warn(i.span, format!("`{name}` implements `{}`", i.text)));
                }
            }
            sfc_syntax::ast::Item::Interface(i) => {
                out.push(warn(i.name.span, format!("`{}` is an interface", i.name.text)));
            }
            _ => {}
        }
    }
    out
}

/// SFC0840 for a chart written for Studio 5000 or S7-GRAPH (`sfc.dialect`) that a PLCopen or ST
/// output hands to IEC 61131-3 tools (CODESYS, Beremiz, OpenPLC …): what runs differently there,
/// per construct (`sfc_model::RunRules`), and the S7-GRAPH conditions that act nowhere else.
fn vendor_conversion_notes(checked: &Checked, target: BuildTarget) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    for c in &checked.charts {
        let iec = sfc_model::RunRules::of(None, c);
        let Some(sfc_syntax::ast::Item::Pou(p)) = checked.unit.items.get(c.item) else { continue };
        let dialect = p
            .attributes
            .iter()
            .rev()
            .find(|a| a.name.eq_ignore_ascii_case("sfc.dialect"))
            .and_then(|a| a.value.clone());
        let source = sfc_model::RunRules::of(dialect.as_deref(), c);
        if !matches!(source.name, "Studio 5000" | "S7-GRAPH") {
            continue;
        }
        let warn = |span, msg: String| Diagnostic::warning("SFC0840", span, msg);
        let tools = format!("the {} output runs by IEC 61131-3's rules (CODESYS, Beremiz, OpenPLC)", target.name());
        if let Some(why) = sfc_model::RunRules::order_change(source, iec) {
            out.push(warn(c.name_span, format!("`{}` was written for {}: {tools}, whose call differs", c.pou, source.name)).with_note(why));
        }
        if source.first_call_tests {
            for t in c.transitions.iter().filter(|t| t.from.iter().all(|&s| c.steps.get(s).is_some_and(|s| s.initial))) {
                out.push(warn(
                    t.header_span,
                    format!("{} is tested in the first call under {}'s rules, not in IEC 61131-3's first scan", t.name, source.name),
                ));
            }
        }
        if !source.final_run {
            for s in &c.steps {
                for a in s.associations.iter().filter(|a| matches!(a.qualifier, sfc_model::Qualifier::N | sfc_model::Qualifier::L | sfc_model::Qualifier::D)) {
                    if matches!(a.target, sfc_model::ActionTarget::Action(_)) {
                        out.push(warn(
                            a.span,
                            format!("`{}` runs once more, with Q FALSE, when it stops under IEC 61131-3's rules; not under {}'s", a.action, source.name),
                        ));
                    }
                }
            }
        }
        let conditions = c.steps.iter().filter(|s| s.interlock.is_some() || s.supervision.is_some()).count();
        if conditions > 0 {
            out.push(warn(
                c.name_span,
                format!("`{}` has {conditions} step(s) with an S7-GRAPH interlock or supervision: kept in the output's attributes, they act in no IEC 61131-3 tool", c.pou),
            ));
        }
    }
    out
}

/// Compiles a checked file (without errors) for `target`.
pub fn compile(checked: &Checked, target: BuildTarget, opts: &CompileOptions) -> Result<Compiled, CompileError> {
    let plain = |text: String| Compiled { text, notes: Vec::new(), flattened: None, symbols: None };
    match target {
        BuildTarget::Text => {
            // `checked.unit` lent its conditions and action bodies to the charts: print a fresh
            // parse of the checked text (without errors, or the check would have failed).
            let (unit, _) = sfc_syntax::parse(0, &checked.file.text);
            return Ok(plain(sfc_syntax::print::print(&unit)));
        }
        BuildTarget::Plcopen => {
            let refused: Vec<Diagnostic> = checked
                .charts
                .iter()
                .flat_map(|c| sfc_model::vendor::logix_step_counts(checked, c, "PLCopen XML for IEC 61131-3 tools"))
                .collect();
            if !refused.is_empty() {
                return Err(CompileError::Diagnostics(refused));
            }
            return sfc_plcopen::export_with(checked, opts.original)
                .map(|(text, mut notes)| {
                    notes.extend(vendor_conversion_notes(checked, target));
                    Compiled { text, notes, flattened: None, symbols: None }
                })
                .map_err(CompileError::Diagnostics)
        }
        BuildTarget::L5x | BuildTarget::Simaticml => {
            if checked.charts.is_empty() {
                return Err(CompileError::Chart("the file has no SFC POU to build".to_string()));
            }
            if let Some(p) = opts.pou {
                pick_chart(checked, Some(p)).map_err(CompileError::Chart)?;
            }
            let out = if target == BuildTarget::L5x {
                sfc_l5x::export::export(checked, opts.pou)
            } else {
                sfc_simaticml::export::export(checked, opts.pou)
            };
            return out
                .map(|(text, notes)| Compiled { text, notes, flattened: None, symbols: None })
                .map_err(CompileError::Diagnostics);
        }
        BuildTarget::St => {
            // Every chart of the file unless one is named, so a chart function block and the
            // chart program calling it both become plain ST.
            if checked.charts.is_empty() {
                return Err(CompileError::Chart("the file has no SFC POU to build".to_string()));
            }
            if let Some(p) = opts.pou {
                pick_chart(checked, Some(p)).map_err(CompileError::Chart)?;
            }
            let st = sfc_codegen::st::StOptions { dialect: opts.st_dialect };
            return sfc_codegen::st::build_st_file(checked, opts.pou, &st)
                .map(|(text, mut notes)| {
                    notes.extend(codesys_extensions(checked, opts.st_dialect));
                    notes.extend(vendor_conversion_notes(checked, target));
                    Compiled { text, notes, flattened: None, symbols: None }
                })
                .map_err(CompileError::Diagnostics);
        }
        _ => {}
    }
    let chart = pick_chart(checked, opts.pou).map_err(CompileError::Chart)?;
    // (What the generators refuse, SFC0806, is their own check: `sfc_codegen::codesys_actions`;
    // a transition table has no actions, so the charts of SFC actions are refused here for it.)
    if target.table_target().is_some() {
        let refused: Vec<Diagnostic> =
            sfc_codegen::codesys_actions(Some(checked), chart, &format!("--target {}", target.name()));
        if !refused.is_empty() {
            return Err(CompileError::Diagnostics(refused));
        }
    }
    let built = match (target, target.table_target()) {
        (_, Some(table)) => {
            let limits = Limits::of(table, opts.nstep, opts.ntr);
            sfc_codegen::atmt::build_table(chart, table, limits, opts.flatten).map(|t| Compiled {
                text: t.text,
                notes: t.notes,
                flattened: t.flattened,
                symbols: None,
            })
        }
        (BuildTarget::Stl, _) => {
            let opts = sfc_codegen::stl::StlOptions { method: opts.stl_method };
            sfc_codegen::stl::build_stl(checked, chart, opts).map(|p| Compiled {
                text: p.text,
                notes: p.warnings,
                flattened: None,
                symbols: Some(p.symbols),
            })
        }
        _ => {
            // The chart as the editor draws it: the same document (its saved layout, or the
            // structured layout), drawn the same way.
            let opened = sfc_doc::open(0, &checked.file.name, &checked.file.text);
            match opened.charts.iter().find(|d| d.pou.eq_ignore_ascii_case(&chart.pou)) {
                Some(doc) => Ok(plain(sfc_doc::svg(doc))),
                None => {
                    let layout = sfc_render::layout(chart);
                    Ok(plain(sfc_render::svg(chart, &layout, &sfc_render::SvgOptions::default())))
                }
            }
        }
    };
    built.map_err(CompileError::Diagnostics)
}

/// One rule of a transition table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct TableRule {
    pub state: u32,
    /// The input index, `1000 + index` when negated.
    pub condition: u32,
    pub next: u32,
}

/// A transition table read back from its one-line form.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Table {
    pub rules: Vec<TableRule>,
    /// The timeout of each state in seconds, `0` for none.
    pub timeouts: Vec<f64>,
}

/// Reads a one-line table `N[s c n;…][t …]`; `None` when the line is not of that form.
pub fn parse_table(line: &str) -> Option<Table> {
    let (rules, timeouts) = sfc_codegen::atmt::parse_table(line)?;
    Some(Table {
        rules: rules.iter().map(|r| TableRule { state: r.state, condition: r.condition, next: r.next }).collect(),
        timeouts: timeouts.iter().map(|&us| us as f64 / 1e6).collect(),
    })
}
