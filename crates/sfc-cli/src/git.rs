//! `sfc git setup`: a repository's git compares charts by meaning. It writes the lines of
//! `.gitattributes` that give `*.st`, `*.xml` and `*.l5x` the diff driver `sfc`, and configures
//! that driver in the repository's own config: `sfc diff --git-external` as git's external diff
//! (`git diff`, `git show`, `git log -p`), and `sfc build --target text` as its textconv (used
//! with `--no-ext-diff`: the charts as canonical text, PLCopen XML included). `*.st` and `*.xml`
//! also get the merge driver `sfc`: `sfc merge %O %A %B -o %A --path %P`.

use crate::term;
use crate::Status;
use std::path::{Path, PathBuf};
use std::process::Command;

#[derive(clap::Args)]
pub struct GitArgs {
    #[command(subcommand)]
    command: GitCommand,
}

#[derive(clap::Subcommand)]
enum GitCommand {
    /// Configure the repository's git to diff charts by meaning (`.gitattributes` and the
    /// repository's git config).
    Setup(SetupArgs),
}

#[derive(clap::Args)]
struct SetupArgs {
    /// A directory of the repository (default: the current directory).
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
}

/// The lines `.gitattributes` gets.
const ATTRIBUTES: [&str; 4] = ["*.st diff=sfc merge=sfc", "*.xml diff=sfc merge=sfc", "*.l5x diff=sfc", "*.L5X diff=sfc"];
/// Lines an earlier `sfc git setup` wrote, replaced by the ones above.
const EARLIER: [(&str, &str); 2] = [("*.st diff=sfc", "*.st diff=sfc merge=sfc"), ("*.xml diff=sfc", "*.xml diff=sfc merge=sfc")];

pub fn git(a: GitArgs) -> u8 {
    match a.command {
        GitCommand::Setup(s) => match setup(s.dir.as_deref().unwrap_or(Path::new("."))) {
            Ok(()) => Status::Ok.code(),
            Err(m) => {
                term::error(&m);
                Status::Usage.code()
            }
        },
    }
}

fn run_git(dir: &Path, args: &[&str]) -> Result<String, String> {
    let o = Command::new("git")
        .current_dir(dir)
        .args(args)
        .output()
        .map_err(|e| format!("cannot run git: {e}"))?;
    if !o.status.success() {
        return Err(format!("git {}: {}", args.join(" "), String::from_utf8_lossy(&o.stderr).trim()));
    }
    Ok(String::from_utf8_lossy(&o.stdout).trim().to_string())
}

fn setup(dir: &Path) -> Result<(), String> {
    let root = run_git(dir, &["rev-parse", "--show-toplevel"])
        .map_err(|_| format!("`{}` is not in a git repository", dir.display()))?;
    let root = PathBuf::from(root);
    // This binary, by its full path, so that git finds the same sfc whatever its PATH.
    let exe = std::env::current_exe().map_err(|e| format!("cannot tell where sfc is: {e}"))?;
    let exe = exe.display().to_string().replace('\\', "/");
    let quoted = if exe.contains(' ') { format!("\"{exe}\"") } else { exe };
    run_git(&root, &["config", "diff.sfc.command", &format!("{quoted} diff --git-external")])?;
    run_git(&root, &["config", "diff.sfc.textconv", &format!("{quoted} build --target text")])?;
    run_git(&root, &["config", "diff.sfc.binary", "false"])?;
    run_git(&root, &["config", "merge.sfc.name", "sfc: charts merged by element"])?;
    run_git(&root, &["config", "merge.sfc.driver", &format!("{quoted} merge %O %A %B -o %A --path %P")])?;
    let path = root.join(".gitattributes");
    let read = std::fs::read_to_string(&path).unwrap_or_default();
    // An earlier setup's lines get the merge driver in place.
    let upgraded: String = read
        .split_inclusive('\n')
        .map(|l| match EARLIER.iter().find(|(old, _)| l.trim() == *old) {
            Some((_, new)) => format!("{new}\n"),
            None => l.to_string(),
        })
        .collect();
    let before = upgraded.clone();
    let present: Vec<&str> = before.lines().map(str::trim).collect();
    let missing: Vec<&str> = ATTRIBUTES.iter().copied().filter(|l| !present.contains(l)).collect();
    if !missing.is_empty() || upgraded != read {
        let mut text = before.clone();
        if !text.is_empty() && !text.ends_with('\n') {
            text.push('\n');
        }
        text.push_str("# sfc: charts compared by meaning (`sfc git setup`, docs/diff.md)\n");
        for l in &missing {
            text.push_str(l);
            text.push('\n');
        }
        sfc_driver::write_atomically(&path, text.as_bytes()).map_err(|e| format!("cannot write `{}`: {e}", path.display()))?;
    }
    println!("git in {} diffs charts by meaning:", root.display());
    println!("  git config diff.sfc.command: sfc diff --git-external (git diff, git show, git log -p)");
    println!("  git config diff.sfc.textconv: sfc build --target text (with --no-ext-diff)");
    println!("  git config merge.sfc.driver: sfc merge (git merge, rebase, cherry-pick of *.st and *.xml)");
    if missing.is_empty() {
        println!("  .gitattributes already gives *.st, *.xml and *.l5x the drivers");
    } else {
        println!("  .gitattributes: added {}", missing.join(", "));
    }
    Ok(())
}
