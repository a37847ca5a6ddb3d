//! The terminal: colour (`--color auto|always|never`, `NO_COLOR`), printing diagnostics, and
//! the progress bar of long simulations and test runs (indicatif, on a terminal only).

use sfc_diagnostics::{render_human, Diagnostic, RenderOptions, Severity, SourceFile};
use std::io::{IsTerminal, Write};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// `--color`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Default)]
pub enum ColorChoice {
    /// Colour on a terminal, unless `NO_COLOR` is set (and not empty).
    #[default]
    Auto,
    Always,
    Never,
}

static CHOICE: OnceLock<ColorChoice> = OnceLock::new();

/// Sets the choice for the whole run (once, from the command line).
pub fn set_color(choice: ColorChoice) {
    let _ = CHOICE.set(choice);
}

/// `NO_COLOR` (no-color.org): present and not empty turns colour off, unless `--color always`.
fn no_color_env() -> bool {
    std::env::var_os("NO_COLOR").is_some_and(|v| !v.is_empty())
}

fn color_for(is_terminal: bool) -> bool {
    match CHOICE.get().copied().unwrap_or_default() {
        ColorChoice::Always => true,
        ColorChoice::Never => false,
        ColorChoice::Auto => is_terminal && !no_color_env() && std::env::var_os("TERM").is_none_or(|t| t != "dumb"),
    }
}

/// Whether to colour what goes to standard error.
pub fn color_stderr() -> bool {
    color_for(std::io::stderr().is_terminal())
}

/// Whether to colour what goes to standard output.
pub fn color_stdout() -> bool {
    color_for(std::io::stdout().is_terminal())
}

/// Reads `--color` from the raw arguments before clap parses them, so clap's own help and
/// errors follow it too.
pub fn color_from_args(args: &[std::ffi::OsString]) -> ColorChoice {
    let mut choice = ColorChoice::Auto;
    let mut it = args.iter().map(|a| a.to_string_lossy().into_owned()).peekable();
    while let Some(a) = it.next() {
        let value = match a.strip_prefix("--color") {
            Some("") => it.peek().cloned(),
            Some(v) if v.starts_with('=') => Some(v.trim_start_matches('=').to_string()),
            _ => None,
        };
        match value.as_deref() {
            Some("always") => choice = ColorChoice::Always,
            Some("never") => choice = ColorChoice::Never,
            Some("auto") => choice = ColorChoice::Auto,
            _ => {}
        }
    }
    choice
}

/// `text` in bold red/green/yellow when `on`.
pub fn paint(on: bool, code: &str, text: &str) -> String {
    if on {
        format!("\x1b[{code}m{text}\x1b[0m")
    } else {
        text.to_string()
    }
}

/// Prints diagnostics in the human form on stderr; returns the number of errors.
pub fn print_diagnostics(diags: &[Diagnostic], files: &[SourceFile]) -> usize {
    let color = color_stderr();
    let mut err = std::io::stderr().lock();
    for d in diags {
        let _ = writeln!(err, "{}", render_human(d, files, RenderOptions { color }));
    }
    diags.iter().filter(|d| d.severity == Severity::Error).count()
}

/// `error: message` on stderr, `error` in red on a terminal.
pub fn error(message: &str) {
    eprintln!("{}: {message}", paint(color_stderr(), "1;31", "error"));
}

/// `note: message` on stderr.
pub fn note(message: &str) {
    eprintln!("{}: {message}", paint(color_stderr(), "1;36", "note"));
}

/// `warning: message` on stderr.
pub fn warning(message: &str) {
    eprintln!("{}: {message}", paint(color_stderr(), "1;33", "warning"));
}

pub fn plural(n: usize, word: &str) -> String {
    format!("{n} {word}{}", if n == 1 { "" } else { "s" })
}

/// `2 errors and 1 warning emitted`.
pub fn summary(errors: usize, warnings: usize) -> String {
    match (errors, warnings) {
        (0, w) => format!("{} emitted", plural(w, "warning")),
        (e, 0) => format!("{} emitted", plural(e, "error")),
        (e, w) => format!("{} and {} emitted", plural(e, "error"), plural(w, "warning")),
    }
}

/// How long work must take before a progress bar appears (1 s; `SFC_PROGRESS_AFTER_MS`
/// changes it, for tests).
fn progress_delay() -> Duration {
    let ms = std::env::var("SFC_PROGRESS_AFTER_MS").ok().and_then(|v| v.parse().ok()).unwrap_or(1000);
    Duration::from_millis(ms)
}

/// A progress bar that appears only when the work has taken longer than a second and standard
/// error is a terminal: short runs and pipes (CI logs) never see it.
pub struct Progress {
    total: u64,
    unit: &'static str,
    start: Instant,
    delay: Duration,
    enabled: bool,
    bar: Option<indicatif::ProgressBar>,
    calls: u64,
}

impl Progress {
    /// Progress over `total` units (`scans`, `scenarios`).
    pub fn new(total: u64, unit: &'static str) -> Progress {
        Progress {
            total,
            unit,
            start: Instant::now(),
            delay: progress_delay(),
            enabled: std::io::stderr().is_terminal(),
            bar: None,
            calls: 0,
        }
    }

    /// Moves to `pos`; `message` is asked only when the bar is drawn.
    pub fn set(&mut self, pos: u64, message: impl FnOnce() -> String) {
        if !self.enabled {
            return;
        }
        self.calls += 1;
        // The clock is read once per 256 calls: a scan costs far less than reading it.
        if self.bar.is_none() && self.calls % 256 != 1 {
            return;
        }
        if self.bar.is_none() {
            if self.start.elapsed() < self.delay {
                return;
            }
            let bar =
                indicatif::ProgressBar::with_draw_target(Some(self.total), indicatif::ProgressDrawTarget::stderr());
            let template =
                format!("{{spinner}} [{{elapsed_precise}}] {{wide_bar}} {{pos}}/{{len}} {} {{msg}}", self.unit);
            if let Ok(style) = indicatif::ProgressStyle::with_template(&template) {
                bar.set_style(style);
            }
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_position(pos);
            if self.calls % 256 == 1 {
                bar.set_message(message());
            }
        }
    }

    /// Runs `f` (which writes to standard error) with the bar, if drawn, hidden meanwhile.
    pub fn suspend<R>(&self, f: impl FnOnce() -> R) -> R {
        match &self.bar {
            Some(bar) => bar.suspend(f),
            None => f(),
        }
    }

    /// Removes the bar (the final report follows on a clean line).
    pub fn finish(self) {
        if let Some(bar) = self.bar {
            bar.finish_and_clear();
        }
    }
}
