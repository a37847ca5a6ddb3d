//! Reading chart files: text from a path or standard input, the kind of a file, and the chart
//! files under directories (for `sfc check DIR`, `sfc fmt DIR`).

use sfc_syntax::encoding::Decoded;
use std::io::Read;
use std::path::{Path, PathBuf};

/// How a chart file is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// IEC 61131-3 text (`.st`, or any file that is not XML).
    Iec,
    /// PLCopen TC6 XML (`.xml`, or a text that starts with `<`).
    PlcOpen,
}

impl FileKind {
    /// The kind of a file by its extension, else by its first non-blank character.
    pub fn of(path: &Path, text: &str) -> FileKind {
        if crate::is_xml(path, text) {
            FileKind::PlcOpen
        } else {
            FileKind::Iec
        }
    }
}

/// A file that could not be read as text: a usage or I/O problem (exit status 2), not a
/// problem of the chart.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoadError {
    /// The path as given (`-` for standard input).
    pub path: PathBuf,
    /// `cannot read `a.st`: No such file or directory (os error 2)`, `` `a.st` is a directory ``.
    pub message: String,
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for LoadError {}

/// Files larger than this are not read (a chart is text written by people or tools: 256 MiB is
/// far beyond any real one, and bounds the work per input).
pub const MAX_SOURCE: u64 = 256 << 20;

/// Reads a chart file as text; `-` reads standard input. UTF-8 with or without a byte order
/// mark, or Latin-1 / Windows-1252 (then `first_non_utf8` is set and
/// `sfc_syntax::encoding::warning` says so); `sfc_syntax::encoding::encode` writes text back in
/// the file's encoding, byte order mark and line endings.
pub fn read_source(path: &Path) -> Result<Decoded, LoadError> {
    let err = |message: String| LoadError { path: path.to_path_buf(), message };
    let bytes = if path.as_os_str() == "-" {
        let mut b = Vec::new();
        std::io::stdin()
            .take(MAX_SOURCE + 1)
            .read_to_end(&mut b)
            .map_err(|e| err(format!("cannot read standard input: {e}")))?;
        b
    } else {
        if path.is_dir() {
            return Err(err(format!("`{}` is a directory", path.display())));
        }
        let f = std::fs::File::open(path).map_err(|e| err(format!("cannot read `{}`: {e}", path.display())))?;
        let mut b = Vec::new();
        f.take(MAX_SOURCE + 1)
            .read_to_end(&mut b)
            .map_err(|e| err(format!("cannot read `{}`: {e}", path.display())))?;
        b
    };
    let shown = if path.as_os_str() == "-" { "standard input".to_string() } else { format!("`{}`", path.display()) };
    if bytes.len() as u64 > MAX_SOURCE {
        return Err(err(format!("{shown} is larger than {} MiB", MAX_SOURCE >> 20)));
    }
    Ok(sfc_syntax::encoding::decode(&bytes))
}

/// Whether a file found in a directory is a chart file: `.st`, `.xml` or `.l5x` (Studio 5000
/// exports), any case.
pub fn is_chart_file(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["st", "xml", "l5x"].iter().any(|x| e.eq_ignore_ascii_case(x)))
}

/// Where to look for chart files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Found {
    /// A file named on the command line (taken as it is, whatever its extension), or found in
    /// a directory.
    File(PathBuf),
    /// A path that could not be read (does not exist, unreadable directory).
    Missing(LoadError),
}

/// The files named by `paths`: files as they are, directories searched recursively for files
/// that `accept` (hidden directories and files skipped, sorted by path), each file once.
/// `-` is kept as it is. A directory without any accepted file is reported as missing.
pub fn collect(paths: &[PathBuf], accept: impl Fn(&Path) -> bool) -> Vec<Found> {
    let mut out = Vec::new();
    let mut seen = std::collections::HashSet::new();
    let mut push = |out: &mut Vec<Found>, p: PathBuf| {
        let key = std::fs::canonicalize(&p).unwrap_or_else(|_| p.clone());
        if seen.insert(key) {
            out.push(Found::File(p));
        }
    };
    for p in paths {
        if p.as_os_str() == "-" || p.is_file() {
            push(&mut out, p.clone());
        } else if p.is_dir() {
            let mut found = Vec::new();
            if let Err(e) = walk(p, &accept, &mut found, 0) {
                out.push(Found::Missing(LoadError {
                    path: p.clone(),
                    message: format!("cannot read the directory `{}`: {e}", p.display()),
                }));
                continue;
            }
            found.sort();
            if found.is_empty() {
                out.push(Found::Missing(LoadError {
                    path: p.clone(),
                    message: format!("no chart files (`*.st`, `*.xml`, `*.l5x`) under `{}`", p.display()),
                }));
            }
            for f in found {
                push(&mut out, f);
            }
        } else {
            let message = match std::fs::metadata(p) {
                Err(e) => format!("cannot read `{}`: {e}", p.display()),
                Ok(_) => format!("`{}` is neither a file nor a directory", p.display()),
            };
            out.push(Found::Missing(LoadError { path: p.clone(), message }));
        }
    }
    out
}

/// Directories nested deeper than this are not searched (a link loop ends here).
const MAX_DEPTH: usize = 64;

fn walk(dir: &Path, accept: &impl Fn(&Path) -> bool, out: &mut Vec<PathBuf>, depth: usize) -> std::io::Result<()> {
    if depth > MAX_DEPTH {
        return Ok(());
    }
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.filter_map(Result::ok).collect();
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let name = e.file_name();
        if name.to_string_lossy().starts_with('.') {
            continue;
        }
        let path = e.path();
        if path.is_dir() {
            walk(&path, accept, out, depth + 1)?;
        } else if path.is_file() && accept(&path) {
            out.push(clean(&path));
        }
    }
    Ok(())
}

/// `./a/b.st` → `a/b.st` (how reports name a file found under `.`).
pub fn clean(path: &Path) -> PathBuf {
    let cleaned: PathBuf = path.components().filter(|c| !matches!(c, std::path::Component::CurDir)).collect();
    if cleaned.as_os_str().is_empty() {
        path.to_path_buf()
    } else {
        cleaned
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sfc-driver-load-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn kinds() {
        assert_eq!(FileKind::of(Path::new("a.XML"), "PROGRAM"), FileKind::PlcOpen);
        assert_eq!(FileKind::of(Path::new("a.st"), "  \n<?xml version='1.0'?>"), FileKind::PlcOpen);
        assert_eq!(FileKind::of(Path::new("-"), "\u{feff}<project/>"), FileKind::PlcOpen);
        assert_eq!(FileKind::of(Path::new("a.st"), "PROGRAM P END_PROGRAM"), FileKind::Iec);
    }

    #[test]
    fn reading() {
        let d = scratch("read");
        std::fs::write(d.join("ok.st"), "PROGRAM P END_PROGRAM").unwrap();
        std::fs::write(d.join("latin.st"), b"(* \xe9 *)").unwrap();
        assert_eq!(read_source(&d.join("ok.st")).unwrap().text, "PROGRAM P END_PROGRAM");
        // Not UTF-8: read as Latin-1 / Windows-1252, and the first such byte is known.
        let latin = read_source(&d.join("latin.st")).unwrap();
        assert_eq!(latin.text, "(* \u{e9} *)");
        assert!(latin.first_non_utf8.is_some());
        let e = read_source(&d.join("none.st")).unwrap_err();
        assert!(e.message.starts_with("cannot read `"), "{e}");
        assert!(read_source(&d).unwrap_err().message.ends_with("is a directory"));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn collecting() {
        let d = scratch("collect");
        for f in ["b.st", "a.xml", "notes.txt", ".hidden/x.st", "sub/c.ST", "empty/readme.md"] {
            let p = d.join(f);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(p, "").unwrap();
        }
        let found = collect(&[d.clone(), d.join("b.st"), d.join("notes.txt"), d.join("nope")], is_chart_file);
        let names: Vec<String> = found
            .iter()
            .map(|f| match f {
                Found::File(p) => p.strip_prefix(&d).unwrap().display().to_string(),
                Found::Missing(e) => format!("missing: {}", e.path.strip_prefix(&d).unwrap().display()),
            })
            .collect();
        assert_eq!(names, ["a.xml", "b.st", "sub/c.ST", "notes.txt", "missing: nope"]);
        let empty = collect(&[d.join("empty")], is_chart_file);
        assert!(matches!(&empty[..], [Found::Missing(e)] if e.message.starts_with("no chart files")));
        let _ = std::fs::remove_dir_all(&d);
    }
}
