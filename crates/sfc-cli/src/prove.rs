//! `sfc prove`: the properties of `<chart>.props.toml` proved or refuted, with witness scenarios.

use sfc_diagnostics::{render_human, RenderOptions};
use sfc_prove::{Options, ProveError};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct ProveArgs {
    /// The chart (`.st`); its properties are read from `<chart>.props.toml` beside it.
    file: PathBuf,
    /// The property file (default: `<chart>.props.toml` beside the chart).
    #[arg(long, value_name = "P.toml")]
    properties: Option<PathBuf>,
    /// The POU whose chart to prove (over the property file's `pou`).
    #[arg(long, value_name = "NAME")]
    pou: Option<String>,
    /// Scan period: time is scans × period (default T#10ms, or the property file's `period`).
    #[arg(long, value_name = "TIME", value_parser = crate::sim::parse_period)]
    period: Option<i64>,
    /// The profile whose scan rules to prove under: iec or codesys (default: the property
    /// file's `profile`, else iec).
    #[arg(long, value_name = "iec|codesys", value_parser = parse_profile)]
    profile: Option<sfc_sim::Profile>,
    /// Output: a report per property (human) or one JSON object on stdout.
    #[arg(long, value_enum, default_value = "human")]
    format: crate::Format,
    /// Work allowed before a verdict is `unknown`: seconds for all properties (`60s`, `2.5`), or
    /// reached states per property (`500000states`).
    #[arg(long, value_name = "SECONDS|Nstates", value_parser = parse_budget)]
    budget: Option<Budget>,
    /// Where to write the witness scenarios (default: beside the chart).
    #[arg(long, value_name = "DIR")]
    witness_dir: Option<PathBuf>,
    /// Do not write witness scenarios.
    #[arg(long)]
    no_witness: bool,
}

#[derive(Debug, Clone, Copy)]
pub enum Budget {
    Seconds(f64),
    States(f64),
}

/// `--budget`: `60`, `60s`, `1.5s`, `500ms`, or `200000states`.
pub fn parse_budget(s: &str) -> Result<Budget, String> {
    let t = s.trim().to_ascii_lowercase().replace('_', "");
    if let Some(n) = t.strip_suffix("states") {
        return match n.trim().parse::<f64>() {
            Ok(v) if v > 0.0 => Ok(Budget::States(v)),
            _ => Err(format!("`{s}`: expected a number of states such as 500000states")),
        };
    }
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 0.001)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0)
    } else {
        (t.as_str(), 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v > 0.0 && v.is_finite() => Ok(Budget::Seconds(v * scale)),
        _ => Err(format!("`{s}`: expected seconds (`60s`, `2.5`) or states (`500000states`)")),
    }
}

/// `--profile`: a profile `prove` models.
pub fn parse_profile(s: &str) -> Result<sfc_sim::Profile, String> {
    let Some(p) = sfc_sim::Profile::from_name(s.trim()) else {
        return Err(format!("unknown profile `{s}` (expected iec or codesys)"));
    };
    match sfc_prove::unsupported_profile(p) {
        Some(why) => Err(why),
        None => Ok(p),
    }
}

/// `door.st` → `door.props.toml` in the same directory.
pub fn default_properties(chart: &Path) -> PathBuf {
    let stem = chart.file_stem().map_or_else(|| "chart".into(), |s| s.to_string_lossy().into_owned());
    chart.with_file_name(format!("{stem}.props.toml"))
}

pub fn prove(a: ProveArgs) -> u8 {
    let raw = match sfc_driver::read_source(&a.file) {
        Ok(d) => d.text,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    // A PLCopen XML file is proved as the IEC text it imports to (as `sim` runs it); an import
    // error stops it, located in the XML.
    let iec = sfc_driver::IecText::of(&a.file, &raw);
    if let Some(imported) = &iec.imported {
        let errors: Vec<_> = imported.diagnostics.iter().filter(|d| d.is_error()).collect();
        if !errors.is_empty() {
            let color = std::io::stderr().is_terminal();
            for d in errors {
                eprintln!("{}", render_human(d, std::slice::from_ref(&imported.xml), RenderOptions { color }));
            }
            eprintln!("error: `{}` cannot be proved until these errors are fixed", a.file.display());
            return 2;
        }
    }
    let vendor = sfc_sim::chart_vendor(&iec.text, iec.imported.as_ref());
    let chart_text = iec.text;
    let props_path = a.properties.clone().unwrap_or_else(|| default_properties(&a.file));
    let props_text = match std::fs::read(&props_path) {
        Ok(b) => match String::from_utf8(b) {
            Ok(t) => t,
            Err(_) => {
                eprintln!("error: `{}` is not UTF-8 text", props_path.display());
                return 2;
            }
        },
        Err(e) if a.properties.is_none() && e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!(
                "error: no property file for `{}`: `{}` does not exist (write it, or name one with --properties)",
                a.file.display(),
                props_path.display()
            );
            return 2;
        }
        Err(e) => {
            eprintln!("error: cannot read `{}`: {e}", props_path.display());
            return 2;
        }
    };
    let shown_props = props_path.display().to_string();
    let file = match sfc_prove::props::parse(&shown_props, &props_text) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("error: {e}");
            return 2;
        }
    };
    if file.properties.is_empty() {
        eprintln!("warning: `{shown_props}` declares no [[property]]: only ranges and runtime errors are checked");
    }
    let mut opts = Options { pou: a.pou.clone(), period: a.period, profile: a.profile, ..Options::default() };
    // Without --profile or the property file's `profile`, the rules of the tool that wrote the
    // file (said, as `sim` says it).
    if opts.profile.is_none() && file.profile.is_none() {
        match sfc_sim::file_profile(vendor) {
            (sfc_sim::Profile::Codesys, sfc_sim::ProfileSource::Vendor(v)) => {
                opts.profile = Some(sfc_sim::Profile::Codesys);
                eprintln!(
                    "note: {}",
                    sfc_sim::vendor_profile_note("proved", &a.file.display().to_string(), v, "--profile iec")
                );
            }
            (p, sfc_sim::ProfileSource::Vendor(v)) if sfc_prove::unsupported_profile(p).is_some() => {
                // Said, not silently replaced: the file's own rules are not modelled yet.
                eprintln!(
                    "note: proved with profile iec: {} is a {v} export, whose rules (profile {}) `sfc prove` does \
                     not model yet; `sfc sim` and `sfc test` follow them",
                    a.file.display(),
                    p.name()
                );
            }
            _ => {}
        }
    }
    match a.budget {
        Some(Budget::Seconds(s)) => opts.seconds = s,
        Some(Budget::States(n)) => opts.max_states = Some(n),
        None => {}
    }
    let chart_name = a.file.display().to_string();
    let report = match sfc_prove::prove(&chart_name, &chart_text, &file, &opts) {
        Ok(r) => r,
        Err(ProveError::Chart(b)) => {
            let (src, diags) = *b;
            let color = std::io::stderr().is_terminal();
            for d in &diags {
                eprintln!("{}", render_human(d, std::slice::from_ref(&src), RenderOptions { color }));
            }
            eprintln!("error: `{}` cannot be proved until these errors are fixed", a.file.display());
            return 2;
        }
        Err(ProveError::Props(e)) => {
            eprintln!("error: {e}");
            return 2;
        }
        Err(ProveError::Unsupported(why)) => {
            eprintln!("error: {why}");
            return 2;
        }
    };
    // Witness scenarios, beside the chart unless told otherwise.
    let dir = a.witness_dir.clone().unwrap_or_else(|| a.file.parent().map(Path::to_path_buf).unwrap_or_default());
    let mut shown_dir = dir.display().to_string();
    if !a.no_witness {
        if !dir.as_os_str().is_empty() {
            if let Err(e) = std::fs::create_dir_all(&dir) {
                eprintln!("error: cannot create `{}`: {e}", dir.display());
                return 2;
            }
        }
        for p in &report.properties {
            let Some(w) = &p.witness else { continue };
            if !w.write {
                continue;
            }
            // The witness names the chart relative to where it is written.
            let text = relocate_chart(&w.text, &a.file, &dir);
            let path = dir.join(&w.file);
            if let Err(e) = sfc_driver::write_atomically(&path, text.as_bytes()) {
                eprintln!("error: cannot write the witness `{}`: {e}", path.display());
                return 2;
            }
        }
    } else {
        shown_dir = sfc_prove::report::NOT_WRITTEN.to_string();
    }
    match a.format {
        crate::Format::Json => println!("{}", report.json(&shown_dir)),
        crate::Format::Human => print!("{}", report.human(&shown_dir)),
    }
    report.exit_code()
}

/// The witness's `chart = "…"` line pointing from `dir` to the chart.
fn relocate_chart(text: &str, chart: &Path, dir: &Path) -> String {
    let chart_abs = std::fs::canonicalize(chart).unwrap_or_else(|_| chart.to_path_buf());
    let dir_abs = std::fs::canonicalize(if dir.as_os_str().is_empty() { Path::new(".") } else { dir })
        .unwrap_or_else(|_| dir.to_path_buf());
    let rel = relative(&chart_abs, &dir_abs).unwrap_or(chart_abs);
    let line = format!("chart = {}", sfc_prove::witness::toml_string(&rel.to_string_lossy()));
    text.lines()
        .map(|l| if l.starts_with("chart = ") { line.clone() } else { l.to_string() })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

fn relative(path: &Path, base: &Path) -> Option<PathBuf> {
    let p: Vec<_> = path.components().collect();
    let b: Vec<_> = base.components().collect();
    let common = p.iter().zip(&b).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return None;
    }
    let mut out = PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &p[common..] {
        out.push(c);
    }
    Some(out)
}

/// Seconds `sfc lsp` gives a proof when a property file is saved (all its properties together).
const LSP_BUDGET_SECONDS: f64 = 10.0;

/// Diagnostics on property files (`<chart>.props.toml`) for `sfc lsp`: while typing, the file's
/// TOML and its names and types against the chart beside it (SFC1001); on save or after idle,
/// the proof itself: one diagnostic per violated (SFC1002) or undecided (SFC1003) property at its
/// `[[property]]` line.
pub struct PropertyDiagnostics;

impl sfc_lsp::DiagnosticsProvider for PropertyDiagnostics {
    fn handles(&self, path: &Path, _language: &str, _text: &str) -> bool {
        path.file_name().is_some_and(|n| n.to_string_lossy().to_ascii_lowercase().ends_with(".props.toml"))
    }

    fn check(
        &self,
        path: &Path,
        text: &str,
        analysis: bool,
    ) -> (sfc_diagnostics::SourceFile, Vec<sfc_diagnostics::Diagnostic>) {
        let shown = path.display().to_string();
        let src = sfc_diagnostics::SourceFile::new(shown.clone(), text.to_string());
        let file = match sfc_prove::props::parse(&shown, text) {
            Ok(f) => f,
            Err(e) => return (src, sfc_prove::property_diagnostics(0, text, Some(&e), None)),
        };
        let Some(chart) = chart_of_properties(path) else {
            return (src, Vec::new());
        };
        let chart_text = match sfc_driver::read_source(&chart) {
            Ok(d) => d.text,
            Err(e) => {
                let d = sfc_diagnostics::Diagnostic::error(
                    "SFC1001",
                    sfc_diagnostics::Span::new(0, 0, 0),
                    format!("the chart of this property file cannot be read: {e}"),
                );
                return (src, vec![d]);
            }
        };
        let opts = Options { check_only: !analysis, seconds: LSP_BUDGET_SECONDS, ..Options::default() };
        let diags = match sfc_prove::prove(&chart.display().to_string(), &chart_text, &file, &opts) {
            Ok(report) if analysis => sfc_prove::property_diagnostics(0, text, None, Some(&report)),
            Ok(_) => Vec::new(),
            Err(ProveError::Props(e)) => sfc_prove::property_diagnostics(0, text, Some(&e), None),
            Err(ProveError::Unsupported(why)) => {
                vec![sfc_diagnostics::Diagnostic::error("SFC1001", sfc_diagnostics::Span::new(0, 0, 0), why)]
            }
            Err(ProveError::Chart(b)) => {
                let first = b.1.iter().find(|d| d.is_error()).map_or_else(String::new, |d| d.message.clone());
                vec![sfc_diagnostics::Diagnostic::error(
                    "SFC1001",
                    sfc_diagnostics::Span::new(0, 0, 0),
                    format!("`{}` has errors, so its requirements cannot be checked: {first}", chart.display()),
                )]
            }
        };
        (src, diags)
    }
}

/// `door.props.toml` → `door.st` beside it (or `door.xml`), if it exists.
fn chart_of_properties(props: &Path) -> Option<PathBuf> {
    let name = props.file_name()?.to_string_lossy().into_owned();
    let stem = name.get(..name.len().checked_sub(".props.toml".len())?)?;
    ["st", "ST"].iter().map(|ext| props.with_file_name(format!("{stem}.{ext}"))).find(|p| p.is_file())
}
