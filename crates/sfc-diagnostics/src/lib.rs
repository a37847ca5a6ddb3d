//! Diagnostics shared by every sfc crate: a [`Diagnostic`] has a stable code, a severity, a
//! message, a primary [`Span`] in a [`SourceFile`], optional secondary labels and notes.
//! Rendering (rustc-like text, the JSON contract of `interfaces.md`, SARIF 2.1.0) lives here too, so
//! every front end reports the same way.

mod codes;
mod render;
mod sarif;
mod source;

pub use codes::{explain, CodeInfo, CODES};
pub use render::{render_human, render_json, to_json_value, RenderOptions};
pub use sarif::{render_sarif, sarif_uri, SarifNotification, SarifTool};
pub use source::{LineCol, SourceFile, Span};

use serde::Serialize;

/// How serious a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
    Note,
}

impl Severity {
    /// The lowercase word used in output (`error`, `warning`, `note`).
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "note",
        }
    }
}

/// A secondary location with a short message ("first declared here").
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Label {
    pub span: Span,
    pub message: String,
}

/// Witness of an analysis finding: a firing sequence or a valuation of inputs.
#[derive(Debug, Clone, PartialEq)]
pub enum Witness {
    /// Transition names fired from the initial situation.
    Firing(Vec<String>),
    /// Variable name -> value (JSON) that makes the finding true.
    Valuation(Vec<(String, serde_json::Value)>),
}

/// One finding about the input.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Stable code, `SFCnnnn`.
    pub code: &'static str,
    pub severity: Severity,
    pub message: String,
    /// Primary location (byte offsets into the file named by `span.file`).
    pub span: Span,
    /// The chart element (step, transition, action) it concerns, if any.
    pub element: Option<String>,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
    pub witness: Option<Witness>,
}

impl Diagnostic {
    /// A diagnostic with the severity registered for `code`.
    pub fn new(code: &'static str, span: Span, message: impl Into<String>) -> Self {
        let severity = codes::default_severity(code);
        Diagnostic {
            code,
            severity,
            message: message.into(),
            span,
            element: None,
            labels: Vec::new(),
            notes: Vec::new(),
            witness: None,
        }
    }
    pub fn error(code: &'static str, span: Span, message: impl Into<String>) -> Self {
        Self::new(code, span, message).with_severity(Severity::Error)
    }
    pub fn warning(code: &'static str, span: Span, message: impl Into<String>) -> Self {
        Self::new(code, span, message).with_severity(Severity::Warning)
    }
    pub fn note_diag(code: &'static str, span: Span, message: impl Into<String>) -> Self {
        Self::new(code, span, message).with_severity(Severity::Note)
    }
    pub fn with_severity(mut self, severity: Severity) -> Self {
        self.severity = severity;
        self
    }
    pub fn with_element(mut self, element: impl Into<String>) -> Self {
        self.element = Some(element.into());
        self
    }
    pub fn with_label(mut self, span: Span, message: impl Into<String>) -> Self {
        self.labels.push(Label { span, message: message.into() });
        self
    }
    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }
    pub fn with_witness(mut self, witness: Witness) -> Self {
        self.witness = Some(witness);
        self
    }
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// Sorts diagnostics by file, position, then code, the order every output uses.
pub fn sort(diags: &mut [Diagnostic]) {
    diags.sort_by(|a, b| {
        (a.span.file, a.span.start, a.span.end, a.code).cmp(&(b.span.file, b.span.start, b.span.end, b.code))
    });
}
