//! Confinement of file access to what the editor was given: the files named on the command line,
//! and the directories named there (its roots).
//!
//! A path from the page is accepted only when it is absolute, has no `..`, and its canonical
//! form (symbolic links resolved along the part that exists) is one of the named files or lies
//! under a root without passing through a hidden directory (a name starting with `.`, such as
//! `.git` or `.ssh`). The part that does not exist yet (a new file) cannot contain links, so it
//! cannot lead elsewhere. A named file does not open its directory: `sfc edit ~/a.st` serves
//! `~/a.st` and nothing else.

use std::path::{Component, Path, PathBuf};

/// Why a path was refused.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Refusal {
    /// Not an absolute path (the API speaks in absolute paths): a malformed request.
    Malformed(String),
    /// Outside the roots, through `..`, a link, or plainly.
    Outside(String),
}

/// The canonical form of `path`, resolved along its existing part.
fn canonical_prefix(path: &Path) -> Result<PathBuf, Refusal> {
    let outside = |why: String| Refusal::Outside(why);
    // The longest existing ancestor (a dangling link counts as existing, and is refused below).
    let existing = path
        .ancestors()
        .find(|a| std::fs::symlink_metadata(a).is_ok())
        .ok_or_else(|| outside(format!("`{}` is not under the editor's directories", path.display())))?;
    let canonical = std::fs::canonicalize(existing).map_err(|e| {
        outside(format!("`{}` cannot be resolved ({e}); a dangling link is not followed", existing.display()))
    })?;
    let rest = path.strip_prefix(existing).unwrap_or(Path::new(""));
    Ok(if rest.as_os_str().is_empty() { canonical } else { canonical.join(rest) })
}

/// The canonical path of `raw` when it is one of `files` or lies under one of `roots` (all
/// canonical) without passing through a hidden directory.
pub fn confine(roots: &[PathBuf], files: &[PathBuf], raw: &str) -> Result<PathBuf, Refusal> {
    if raw.is_empty() || raw.contains('\0') {
        return Err(Refusal::Malformed("the path is empty or holds a NUL character".to_string()));
    }
    let path = Path::new(raw);
    if !path.is_absolute() {
        return Err(Refusal::Malformed(format!("`{raw}` is not an absolute path")));
    }
    if path.components().any(|c| c == Component::ParentDir) {
        return Err(Refusal::Outside(format!("`{raw}`: `..` is not allowed in paths")));
    }
    let resolved = canonical_prefix(path)?;
    if files.contains(&resolved) {
        return Ok(resolved);
    }
    let Some(root) = roots.iter().find(|r| resolved.starts_with(r)) else {
        return Err(Refusal::Outside(if roots.is_empty() {
            format!("`{raw}` was not named on the command line (the editor serves only the files it was started with)")
        } else {
            format!("`{raw}` is not under the editor's directories")
        }));
    };
    let inside = resolved.strip_prefix(root).unwrap_or(Path::new(""));
    let mut parts = inside.components().peekable();
    while let Some(c) = parts.next() {
        let hidden = c.as_os_str().to_str().is_none_or(|n| n.starts_with('.'));
        if hidden && parts.peek().is_some() {
            return Err(Refusal::Outside(format!(
                "`{raw}` is inside a hidden directory, which the editor does not serve"
            )));
        }
        if hidden {
            return Err(Refusal::Outside(format!("`{raw}` is a hidden file, which the editor does not serve")));
        }
    }
    Ok(resolved)
}

/// The roots for the paths given on the command line: each directory named (the current
/// directory when nothing is named), and the files named (a file may not exist yet, its
/// directory must). A file's directory is not a root. Returns the canonical roots (without
/// duplicates) and the canonical files.
pub fn roots_of(paths: &[PathBuf], cwd: &Path) -> Result<(Vec<PathBuf>, Vec<PathBuf>), String> {
    let mut roots: Vec<PathBuf> = Vec::new();
    let mut files = Vec::new();
    let cannot = |p: &Path, e: std::io::Error| format!("cannot use `{}`: {e}", p.display());
    if paths.is_empty() {
        roots.push(std::fs::canonicalize(cwd).map_err(|e| cannot(cwd, e))?);
    }
    for p in paths {
        let abs = if p.is_absolute() { p.clone() } else { cwd.join(p) };
        if abs.is_dir() {
            roots.push(std::fs::canonicalize(&abs).map_err(|e| cannot(p, e))?);
            continue;
        }
        // A file: its canonical path when it exists (so a link names its target's directory),
        // else the canonical parent joined with the name.
        let file = match std::fs::canonicalize(&abs) {
            Ok(f) => f,
            Err(_) => {
                let name = abs.file_name().ok_or_else(|| format!("cannot use `{}`: not a file name", p.display()))?;
                let parent = abs.parent().unwrap_or(Path::new("/"));
                let parent = std::fs::canonicalize(parent)
                    .map_err(|e| format!("cannot use `{}`: its directory `{}`: {e}", p.display(), parent.display()))?;
                parent.join(name)
            }
        };
        if !files.contains(&file) {
            files.push(file);
        }
    }
    let mut unique: Vec<PathBuf> = Vec::new();
    for r in roots {
        if !unique.contains(&r) {
            unique.push(r);
        }
    }
    Ok((unique, files))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sfc-server-confine-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::canonicalize(&d).unwrap()
    }

    #[test]
    fn inside_paths_are_accepted_existing_or_not() {
        let d = scratch("inside");
        std::fs::create_dir_all(d.join("sub")).unwrap();
        std::fs::write(d.join("sub/a.st"), "").unwrap();
        let roots = [d.clone()];
        let s = |p: &Path| p.to_str().unwrap().to_string();
        assert_eq!(confine(&roots, &[], &s(&d.join("sub/a.st"))), Ok(d.join("sub/a.st")));
        assert_eq!(confine(&roots, &[], &s(&d.join("sub/new.st"))), Ok(d.join("sub/new.st")));
        assert_eq!(confine(&roots, &[], &s(&d.join("new/deeper.st"))), Ok(d.join("new/deeper.st")));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn refusals() {
        let d = scratch("refuse");
        let roots = [d.join("root")];
        std::fs::create_dir_all(&roots[0]).unwrap();
        std::fs::write(d.join("secret.st"), "").unwrap();
        let s = |p: PathBuf| p.to_str().unwrap().to_string();
        assert!(matches!(confine(&roots, &[], "relative/a.st"), Err(Refusal::Malformed(_))));
        assert!(matches!(confine(&roots, &[], ""), Err(Refusal::Malformed(_))));
        assert!(matches!(confine(&roots, &[], &s(d.join("secret.st"))), Err(Refusal::Outside(_))));
        assert!(matches!(confine(&roots, &[], &s(d.join("root/../secret.st"))), Err(Refusal::Outside(_))));
        assert!(matches!(confine(&roots, &[], "/etc/passwd"), Err(Refusal::Outside(_))));
        // A root's name as a prefix of another directory's name is not inside it.
        std::fs::create_dir_all(d.join("rootless")).unwrap();
        assert!(matches!(confine(&roots, &[], &s(d.join("rootless/a.st"))), Err(Refusal::Outside(_))));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&d, roots[0].join("up")).unwrap();
            std::os::unix::fs::symlink(d.join("secret.st"), roots[0].join("link.st")).unwrap();
            std::os::unix::fs::symlink(d.join("missing.st"), roots[0].join("dangling.st")).unwrap();
            assert!(matches!(confine(&roots, &[], &s(roots[0].join("up/secret.st"))), Err(Refusal::Outside(_))));
            assert!(matches!(confine(&roots, &[], &s(roots[0].join("up/new.st"))), Err(Refusal::Outside(_))));
            assert!(matches!(confine(&roots, &[], &s(roots[0].join("link.st"))), Err(Refusal::Outside(_))));
            assert!(matches!(confine(&roots, &[], &s(roots[0].join("dangling.st"))), Err(Refusal::Outside(_))));
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn named_files_alone_and_no_hidden_directories() {
        let d = scratch("named");
        std::fs::create_dir_all(d.join(".git")).unwrap();
        std::fs::write(d.join("a.st"), "").unwrap();
        std::fs::write(d.join("b.st"), "").unwrap();
        let s = |p: PathBuf| p.to_str().unwrap().to_string();
        // A named file: that file, not its neighbours.
        let files = [d.join("a.st")];
        assert_eq!(confine(&[], &files, &s(d.join("a.st"))), Ok(d.join("a.st")));
        assert!(matches!(confine(&[], &files, &s(d.join("b.st"))), Err(Refusal::Outside(_))));
        assert!(matches!(confine(&[], &files, &s(d.join("new.st"))), Err(Refusal::Outside(_))));
        // A named directory: its charts, but nothing inside hidden directories.
        let roots = [d.clone()];
        assert_eq!(confine(&roots, &[], &s(d.join("b.st"))), Ok(d.join("b.st")));
        assert!(matches!(confine(&roots, &[], &s(d.join(".git/x.st"))), Err(Refusal::Outside(_))));
        assert!(matches!(confine(&roots, &[], &s(d.join(".hidden.st"))), Err(Refusal::Outside(_))));
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn roots_from_arguments() {
        let d = scratch("args");
        std::fs::create_dir_all(d.join("dir")).unwrap();
        std::fs::write(d.join("a.st"), "").unwrap();
        let (roots, files) =
            roots_of(&[PathBuf::from("dir"), PathBuf::from("a.st"), PathBuf::from("new.st")], &d).unwrap();
        assert_eq!(roots, [d.join("dir")]);
        assert_eq!(files, [d.join("a.st"), d.join("new.st")]);
        let (roots, files) = roots_of(&[PathBuf::from("a.st")], &d).unwrap();
        assert_eq!((roots.len(), files), (0, vec![d.join("a.st")]));
        let (roots, files) = roots_of(&[], &d).unwrap();
        assert_eq!((roots, files.len()), (vec![d.clone()], 0));
        assert!(roots_of(&[PathBuf::from("nowhere/x.st")], &d).is_err());
        let _ = std::fs::remove_dir_all(&d);
    }
}
