//! Puts the git commit the binary is built from into `SFC_BUILD_COMMIT` (`sfc --version`).
//! Packagers may set `SFC_BUILD_COMMIT` themselves; a source archive without `.git` builds
//! with "no git commit" instead.

use std::process::Command;

fn git(args: &[&str]) -> Option<String> {
    let out = Command::new("git").args(args).current_dir(env!("CARGO_MANIFEST_DIR")).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn main() {
    println!("cargo:rerun-if-env-changed=SFC_BUILD_COMMIT");
    if let Ok(given) = std::env::var("SFC_BUILD_COMMIT") {
        println!("cargo:rustc-env=SFC_BUILD_COMMIT={given}");
        return;
    }
    let commit = git(&["rev-parse", "--short=12", "HEAD"]);
    let describe = match &commit {
        Some(c) => {
            let date = git(&["log", "-1", "--format=%cs", "HEAD"]).unwrap_or_default();
            format!("{c} {date}").trim().to_string()
        }
        None => "no git commit".to_string(),
    };
    println!("cargo:rustc-env=SFC_BUILD_COMMIT={describe}");
    // Rebuild when HEAD moves (a commit, a checkout); the paths work in worktrees too.
    for path in ["HEAD", "packed-refs"] {
        if let Some(p) = git(&["rev-parse", "--git-path", path]) {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(p);
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
    if let Some(head_ref) = git(&["symbolic-ref", "-q", "HEAD"]) {
        if let Some(p) = git(&["rev-parse", "--git-path", &head_ref]) {
            let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(p);
            println!("cargo:rerun-if-changed={}", p.display());
        }
    }
}
