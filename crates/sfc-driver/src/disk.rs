//! Writing chart files: writes that never leave a partial file (the command line's and the
//! editor's, one implementation), and the guard that keeps an output off its input.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Distinguishes the temporary files of concurrent writes within this process.
static TEMP_SERIAL: AtomicU64 = AtomicU64::new(0);

/// The temporary file a write of `path` goes through: hidden, in the same directory (so the
/// rename is atomic), and unique to this process and write.
fn temp_path(path: &Path) -> PathBuf {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let serial = TEMP_SERIAL.fetch_add(1, Ordering::Relaxed);
    dir.join(format!(".{name}.sfc-tmp-{}-{serial}", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary file in the same directory, synced, then
/// renames it (and syncs the directory, so the rename survives a power cut): readers see the old
/// content or the new one, never a partial file. An existing file keeps its permissions. On
/// failure the temporary file is removed and `path` is untouched.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = temp_path(path);
    let result = (|| {
        let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        if let Ok(meta) = std::fs::metadata(path) {
            std::fs::set_permissions(&tmp, meta.permissions())?;
        }
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
        return result;
    }
    #[cfg(unix)]
    if let Some(dir) = tmp.parent() {
        // Best effort: some file systems refuse to sync a directory; the data is written anyway.
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
    }
    result
}

/// Whether `a` and `b` name the same existing file (through links, `..` or another spelling);
/// `-` (standard input or output) is never a file.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if a.as_os_str() == "-" || b.as_os_str() == "-" {
        return false;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sfc-driver-disk-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> =
            std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        v.sort();
        v
    }

    #[test]
    fn write_replaces_content_and_leaves_no_temporary_file() {
        let d = scratch("replace");
        let f = d.join("chart.st");
        std::fs::write(&f, "old content that is longer than the new one\n").unwrap();
        write_atomically(&f, b"new\n").unwrap();
        assert_eq!(std::fs::read(&f).unwrap(), b"new\n");
        assert_eq!(entries(&d), ["chart.st"]);
        write_atomically(&d.join("fresh.st"), b"x").unwrap();
        assert_eq!(entries(&d), ["chart.st", "fresh.st"]);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[cfg(unix)]
    #[test]
    fn write_keeps_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let d = scratch("perm");
        let f = d.join("chart.st");
        std::fs::write(&f, "a").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomically(&f, b"b").unwrap();
        assert_eq!(std::fs::metadata(&f).unwrap().permissions().mode() & 0o777, 0o640);
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn same_file_sees_through_spellings() {
        let d = scratch("same");
        let f = d.join("chart.st");
        std::fs::write(&f, "x").unwrap();
        std::fs::create_dir_all(d.join("sub")).unwrap();
        assert!(same_file(&f, &d.join("sub/../chart.st")));
        assert!(!same_file(&f, &d.join("other.st")), "a file that does not exist is not the same");
        assert!(!same_file(Path::new("-"), Path::new("-")));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&f, d.join("link.st")).unwrap();
            assert!(same_file(&f, &d.join("link.st")));
        }
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn failed_write_leaves_nothing() {
        let d = scratch("fail");
        // The target is a non-empty directory: the rename fails after the temporary file exists.
        let target = d.join("chart.st");
        std::fs::create_dir_all(target.join("inside")).unwrap();
        assert!(write_atomically(&target, b"text").is_err());
        assert_eq!(entries(&d), ["chart.st"]);
        assert!(target.is_dir());
        let _ = std::fs::remove_dir_all(&d);
    }
}
