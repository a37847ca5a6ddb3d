//! The documents the server knows: those open in the editor (their text is the editor's) and
//! the chart files under the workspace folders (read from disk when a cross-file request needs
//! them, re-read when they change), each with its index, parsed at most once per version.

use crate::index::FileIndex;
use crate::text::{Edit, LineIndex, Shift};
use lsp_types::Uri;
use sfc_syntax::ast::SourceUnit;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::SystemTime;

/// A text parsed and indexed.
#[derive(Debug)]
pub struct Analysis {
    pub text: Arc<String>,
    pub lines: LineIndex,
    pub unit: SourceUnit,
    pub index: FileIndex,
}

impl Analysis {
    pub fn new(text: Arc<String>) -> Analysis {
        let (unit, _) = sfc_syntax::parse(0, &text);
        Analysis::from_parsed(text, unit)
    }

    /// The analysis of `text` from its syntax tree (`sfc_syntax::parse(0, &text)`).
    pub fn from_parsed(text: Arc<String>, unit: sfc_syntax::ast::SourceUnit) -> Analysis {
        let index = FileIndex::new(&unit, &text);
        Analysis { lines: LineIndex::new(&text), text, unit, index }
    }

    pub fn range(&self, span: sfc_diagnostics::Span) -> lsp_types::Range {
        self.lines.range(&self.text, span.start, span.end)
    }

    pub fn offset(&self, pos: lsp_types::Position) -> u32 {
        self.lines.offset(&self.text, pos)
    }
}

impl Drop for Analysis {
    /// The tree and the index are freed off the thread that let go of them (the reader,
    /// mostly): see [`crate::dispose`].
    fn drop(&mut self) {
        crate::dispose::later((std::mem::take(&mut self.unit), std::mem::take(&mut self.index)));
    }
}

/// Completion answers from an older analysis for at most this many edits (then it parses).
const MAX_STALE_EDITS: usize = 200;

/// How a document is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DocKind {
    /// IEC 61131-3 text.
    Iec,
    /// PLCopen TC6 XML: diagnostics only, at XML positions.
    PlcOpen,
    /// Anything else a diagnostics provider may know (see `check::DiagnosticsProvider`).
    Other,
}

/// A document open in the editor.
#[derive(Debug)]
pub struct Document {
    pub uri: Uri,
    pub path: PathBuf,
    pub language: String,
    pub version: i32,
    pub text: Arc<String>,
    pub kind: DocKind,
    analysis: Option<Arc<Analysis>>,
    /// The last analysis made, of an earlier version, and the edits made since (completion
    /// answers from it while the current text is not analysed yet).
    stale: Option<(Arc<Analysis>, Vec<Edit>)>,
    /// The edits that made each version since the last analysis (version made, its edits), so
    /// an analysis of an earlier version that arrives late can still serve; empty after a
    /// whole-text replacement.
    log: Vec<(i32, Vec<Edit>)>,
    /// The version the first entry of `log` was made from.
    log_base: i32,
}

/// An analysis with the current text: the analysis of this version, or of an earlier one with
/// the edits made since (offsets in `index` are then those of `analysis.text`).
#[derive(Debug, Clone)]
pub struct View {
    pub analysis: Arc<Analysis>,
    pub text: Arc<String>,
    pub lines: Arc<LineIndex>,
    pub edits: Vec<Edit>,
}

impl View {
    pub fn shift(&self) -> Shift<'_> {
        Shift(&self.edits)
    }

    /// The offset in the current text of a position.
    pub fn offset(&self, pos: lsp_types::Position) -> u32 {
        self.lines.offset(&self.text, pos)
    }
}

impl Document {
    pub fn new(uri: Uri, language: String, version: i32, text: String) -> Document {
        let path = path_of(&uri);
        let kind = kind_of(&path, &language, &text);
        Document {
            uri,
            path,
            language,
            version,
            text: Arc::new(text),
            kind,
            analysis: None,
            stale: None,
            log: Vec::new(),
            log_base: version,
        }
    }

    /// Replaces the text (an edit); the analysis is recomputed on the next request. `edits` are
    /// the replacements that made it from the previous text (None: replaced whole).
    pub fn set_text(&mut self, version: i32, text: String) {
        self.set_text_edited(version, text, None);
    }

    /// As [`Document::set_text`], keeping the last analysis for completion when the edits are
    /// known.
    pub fn set_text_edited(&mut self, version: i32, text: String, edits: Option<Vec<Edit>>) {
        let previous = self.version;
        self.version = version;
        self.kind = kind_of(&self.path, &self.language, &text);
        self.text = Arc::new(text);
        let analysis = self.analysis.take();
        let Some(edits) = edits else {
            self.stale = None;
            self.log.clear();
            self.log_base = version;
            return;
        };
        if analysis.is_some() || self.log.is_empty() {
            self.log.clear();
            self.log_base = previous;
        }
        self.log.push((version, edits.clone()));
        self.stale = match (analysis, self.stale.take()) {
            (Some(a), _) => Some((a, edits)),
            (None, Some((a, mut before))) if before.len() + edits.len() <= MAX_STALE_EDITS => {
                before.extend(edits);
                Some((a, before))
            }
            _ => None,
        };
        if self.log.iter().map(|(_, e)| e.len()).sum::<usize>() > MAX_STALE_EDITS {
            self.log.clear();
            self.log_base = version;
        }
    }

    /// The current text is parsed and indexed.
    pub fn analysed(&self) -> bool {
        self.analysis.is_some()
    }

    /// The analysis of version `version` made elsewhere (the index worker): the current one if
    /// it is of this text, else the base of completion's view when the edits since are known
    /// and it is newer than the one there.
    pub fn offer(&mut self, version: i32, analysis: Arc<Analysis>) {
        if self.kind != DocKind::Iec || self.analysis.is_some() {
            return;
        }
        if version == self.version {
            if Arc::ptr_eq(&analysis.text, &self.text) {
                self.analysis = Some(analysis);
                self.stale = None;
                self.log.clear();
                self.log_base = version;
            }
            return;
        }
        // The log must hold every change made after `version`.
        if version != self.log_base && !self.log.iter().any(|(v, _)| *v == version) {
            return;
        }
        let edits: Vec<Edit> =
            self.log.iter().filter(|(v, _)| *v > version).flat_map(|(_, e)| e.iter().copied()).collect();
        let newer = self.stale.as_ref().is_none_or(|(_, since)| since.len() > edits.len());
        if newer {
            self.stale = Some((analysis, edits));
        }
    }

    /// The current analysis if there is one, else the last one with the edits since (no
    /// parsing: completion answers at once while typing in a long chart); None for a text never
    /// analysed or not IEC text.
    pub fn quick_view(&self) -> Option<View> {
        if self.kind != DocKind::Iec {
            return None;
        }
        if let Some(a) = &self.analysis {
            return Some(View {
                analysis: a.clone(),
                text: a.text.clone(),
                lines: Arc::new(a.lines.clone()),
                edits: Vec::new(),
            });
        }
        let (a, edits) = self.stale.as_ref()?;
        Some(View {
            analysis: a.clone(),
            text: self.text.clone(),
            lines: Arc::new(LineIndex::new(&self.text)),
            edits: edits.clone(),
        })
    }

    /// The parse and index of the current text (IEC text only).
    pub fn analysis(&mut self) -> Option<Arc<Analysis>> {
        if self.kind != DocKind::Iec {
            return None;
        }
        if self.analysis.is_none() {
            self.analysis = Some(Arc::new(Analysis::new(self.text.clone())));
        }
        self.analysis.clone()
    }
}

fn kind_of(path: &Path, language: &str, text: &str) -> DocKind {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    if language == "xml" || ext == "xml" || (ext != "st" && sfc_driver::is_xml(path, text)) {
        DocKind::PlcOpen
    } else if language == "sfc" || language == "iec-st" || language == "st" || ext == "st" || ext.is_empty() {
        DocKind::Iec
    } else {
        DocKind::Other
    }
}

/// The files of the workspace.
#[derive(Debug, Default)]
pub struct Workspace {
    pub roots: Vec<PathBuf>,
    pub open: HashMap<String, Document>,
    disk: HashMap<PathBuf, (Option<SystemTime>, Arc<Analysis>)>,
}

/// At most this many files of the workspace folders are indexed (bounded work per request).
pub const MAX_FILES: usize = 5000;

impl Workspace {
    pub fn new(roots: Vec<PathBuf>) -> Workspace {
        Workspace { roots, ..Workspace::default() }
    }

    pub fn doc(&mut self, uri: &Uri) -> Option<&mut Document> {
        self.open.get_mut(uri.as_str())
    }

    /// The analysis of a file by URI: the open document, or the file on disk.
    pub fn analysis(&mut self, uri: &Uri) -> Option<Arc<Analysis>> {
        if let Some(d) = self.open.get_mut(uri.as_str()) {
            return d.analysis();
        }
        self.disk_analysis(&path_of(uri))
    }

    fn disk_analysis(&mut self, path: &Path) -> Option<Arc<Analysis>> {
        let modified = std::fs::metadata(path).ok()?.modified().ok();
        if let Some((m, a)) = self.disk.get(path) {
            if *m == modified && modified.is_some() {
                return Some(a.clone());
            }
        }
        let text = sfc_driver::read_source(path).ok()?.text;
        if sfc_driver::is_xml(path, &text) {
            return None;
        }
        let a = Arc::new(Analysis::new(Arc::new(text)));
        self.disk.insert(path.to_path_buf(), (modified, a.clone()));
        Some(a)
    }

    /// Every IEC text of the workspace with its URI: the open documents, then the `.st` files
    /// under the roots that are not open (sorted by path, at most [`MAX_FILES`]).
    pub fn files(&mut self) -> Vec<(Uri, Arc<Analysis>)> {
        let mut out = Vec::new();
        let mut open_paths = std::collections::HashSet::new();
        let keys: Vec<String> = self.open.keys().cloned().collect();
        for k in keys {
            if let Some(d) = self.open.get_mut(&k) {
                open_paths.insert(d.path.clone());
                let uri = d.uri.clone();
                if let Some(a) = d.analysis() {
                    out.push((uri, a));
                }
            }
        }
        let is_st = |p: &Path| p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("st"));
        let found = sfc_driver::load::collect(&self.roots, is_st);
        for f in found.into_iter().take(MAX_FILES) {
            let sfc_driver::load::Found::File(p) = f else { continue };
            let p = std::fs::canonicalize(&p).unwrap_or(p);
            if open_paths.contains(&p) {
                continue;
            }
            if let (Some(a), Some(uri)) = (self.disk_analysis(&p), uri_of(&p)) {
                out.push((uri, a));
            }
        }
        out
    }
}

/// The path of a `file:` URI (percent-decoded); other schemes give their path as it is.
pub fn path_of(uri: &Uri) -> PathBuf {
    let s = uri.as_str();
    let rest = s.strip_prefix("file://").unwrap_or(s);
    // `file://host/path`: drop the authority (empty or `localhost` on Unix).
    let rest = match rest.find('/') {
        Some(i) if !rest.starts_with('/') => rest.get(i..).unwrap_or(rest),
        _ => rest,
    };
    let bytes = rest.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let b = bytes.get(i).copied().unwrap_or(0);
        if b == b'%' {
            let hex = rest.get(i + 1..i + 3).and_then(|h| u8::from_str_radix(h, 16).ok());
            if let Some(v) = hex {
                out.push(v);
                i += 3;
                continue;
            }
        }
        out.push(b);
        i += 1;
    }
    let decoded = String::from_utf8_lossy(&out).into_owned();
    // Windows: `/c:/x` → `c:/x`.
    let decoded = match decoded.as_bytes() {
        [b'/', d, b':', ..] if d.is_ascii_alphabetic() => decoded.get(1..).unwrap_or(&decoded).to_string(),
        _ => decoded,
    };
    let p = PathBuf::from(decoded);
    std::fs::canonicalize(&p).unwrap_or(p)
}

/// The `file:` URI of an absolute path.
pub fn uri_of(path: &Path) -> Option<Uri> {
    let s = path.to_string_lossy().replace('\\', "/");
    let mut out = String::from("file://");
    if !s.starts_with('/') {
        out.push('/');
    }
    for b in s.bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/:".contains(&b) {
            out.push(b as char);
        } else {
            out.push_str(&format!("%{b:02X}"));
        }
    }
    out.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_uris() {
        let u: Uri = "file:///tmp/no%20such/a%C5%BE.st".parse().unwrap();
        assert_eq!(path_of(&u), PathBuf::from("/tmp/no such/až.st"));
        assert_eq!(uri_of(Path::new("/tmp/no such/až.st")).unwrap().as_str(), "file:///tmp/no%20such/a%C5%BE.st");
    }
}

#[cfg(test)]
mod stale_tests {
    use super::*;

    #[test]
    fn a_late_analysis_serves_completion_with_the_edits_made_since() {
        let text = "PROGRAM P\n    INITIAL_STEP S1:\n    END_STEP\nEND_PROGRAM\n";
        let uri: Uri = "file:///t.st".parse().unwrap();
        let mut d = Document::new(uri, "sfc".into(), 1, text.into());
        let first = Arc::new(Analysis::new(d.text.clone()));
        d.set_text_edited(2, format!("(*a*){text}"), Some(vec![Edit { start: 0, end: 0, len: 5 }]));
        d.set_text_edited(3, format!("(*a*)(*b*){text}"), Some(vec![Edit { start: 5, end: 5, len: 5 }]));
        // Nothing analysed yet: completion must wait.
        assert!(d.quick_view().is_none());
        // The worker's analysis of version 1 arrives late: it serves, with both edits.
        d.offer(1, first.clone());
        let v = d.quick_view().unwrap();
        assert!(Arc::ptr_eq(&v.analysis, &first));
        assert_eq!(v.edits.len(), 2);
        assert_eq!(v.shift().forward(0), 10);
        // An analysis of a version that is not the one it claims is refused.
        d.offer(3, first.clone());
        assert!(!d.analysed());
        // The current version's analysis replaces the view's base.
        let current = Arc::new(Analysis::new(d.text.clone()));
        d.offer(3, current);
        assert!(d.analysed() && d.quick_view().unwrap().edits.is_empty());
        // A whole-text replacement leaves nothing to shift from.
        d.set_text_edited(4, text.into(), None);
        assert!(d.quick_view().is_none());
    }
}
