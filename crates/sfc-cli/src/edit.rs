//! `sfc edit [FILE…]`: serve the SFC Editor on 127.0.0.1, print its URL and open a browser.
//! Host mode (`--fb … --result PATH`, seed 001 chapter 12) edits one chart for a host
//! application, which reads the built transition table from `PATH`.

use clap::ValueEnum;
use sfc_server::{EditOptions, HostBlock, HostMode};
use std::io::Write;
use std::path::PathBuf;

#[derive(Clone, Copy, ValueEnum)]
pub enum FbArg {
    Atmt,
    Eatmt,
}

#[derive(clap::Args)]
#[command(after_help = "The editor's settings (language, recent charts, watch lists) are kept in \
    $SFC_CONFIG_DIR/editor.json when SFC_CONFIG_DIR is set, else in the user's config directory: \
    $XDG_CONFIG_HOME/sfc/editor.json or ~/.config/sfc/editor.json (%APPDATA%\\sfc\\editor.json on Windows).")]
pub struct EditArgs {
    /// Charts (`.st`, `.xml`) and directories to edit; the editor may read and write files under
    /// these directories and the files' directories (default: the current directory).
    files: Vec<PathBuf>,
    /// Port on 127.0.0.1 (default: any free port).
    #[arg(long)]
    port: Option<u16>,
    /// Only print the URL; do not open a browser.
    #[arg(long)]
    no_open: bool,
    /// Host mode: build for this REX block; needs one FILE (created if missing) and --result.
    #[arg(long, value_enum, requires = "result")]
    fb: Option<FbArg>,
    /// Host mode: state limit (default 16 for atmt, 256 for eatmt).
    #[arg(long, value_name = "N", requires = "fb")]
    nstep: Option<u32>,
    /// Host mode: rule limit (default 64 for atmt, 1024 for eatmt).
    #[arg(long, value_name = "N", requires = "fb")]
    ntr: Option<u32>,
    /// Host mode: file the one-line transition table is written to after each successful build.
    #[arg(long, value_name = "PATH", requires = "fb")]
    result: Option<PathBuf>,
}

/// Whether a browser can be shown: a graphical session on Unix, always on macOS and Windows.
fn has_display() -> bool {
    cfg!(any(target_os = "macos", windows))
        || ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// A page that forwards the browser to `url`, written where only this user can read it
/// (a fresh directory of mode 0700, the file 0600), so the browser is started on the file's
/// path and the token never appears in any process's arguments (where every local user could
/// read it). Returns the directory, removed when the editor stops.
fn launch_page(url: &str) -> std::io::Result<(PathBuf, PathBuf)> {
    let base = std::env::temp_dir();
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    for k in 0..100u32 {
        let dir = base.join(format!("sfc-edit-{}-{nanos:x}-{k}", std::process::id()));
        let mut builder = std::fs::DirBuilder::new();
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        match builder.create(&dir) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
        let file = dir.join("open.html");
        let mut options = std::fs::OpenOptions::new();
        options.write(true).create_new(true);
        #[cfg(unix)]
        std::os::unix::fs::OpenOptionsExt::mode(&mut options, 0o600);
        let mut f = options.open(&file)?;
        let escaped = url.replace('&', "&amp;").replace('"', "&quot;").replace('<', "&lt;");
        write!(
            f,
            "<!doctype html>\n<html><head><meta charset=\"utf-8\"><meta http-equiv=\"refresh\" content=\"0;url={escaped}\">\
             <title>SFC Editor</title></head><body><p><a href=\"{escaped}\">Open the SFC Editor</a></p></body></html>\n"
        )?;
        return Ok((dir, file));
    }
    Err(std::io::Error::other("no fresh directory for the browser's launch page"))
}

/// Starts the system's browser on the local file `page`; a failure only means the user opens
/// the printed URL by hand.
fn open_browser(page: &std::path::Path) {
    let url = page;
    let mut cmd = if cfg!(target_os = "macos") {
        std::process::Command::new("open")
    } else if cfg!(windows) {
        let mut c = std::process::Command::new("cmd");
        c.args(["/C", "start", ""]);
        c
    } else {
        std::process::Command::new("xdg-open")
    };
    cmd.arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    if let Ok(mut child) = cmd.spawn() {
        // Reap it when it ends, so it does not linger as a zombie while the editor runs.
        std::thread::spawn(move || child.wait());
    }
}

pub fn edit(a: EditArgs) -> u8 {
    let host = match (a.fb, a.result) {
        (Some(fb), Some(result)) => {
            if a.files.len() != 1 {
                eprintln!("error: host mode (--fb) edits exactly one chart: give one FILE");
                return 2;
            }
            let fb = match fb {
                FbArg::Atmt => HostBlock::Atmt,
                FbArg::Eatmt => HostBlock::Eatmt,
            };
            Some(HostMode { fb, nstep: a.nstep, ntr: a.ntr, result })
        }
        // clap enforces that --fb and --result come together.
        _ => None,
    };
    let opts = EditOptions { files: a.files, port: a.port, host };
    let open = !a.no_open && has_display();
    let mut launch_dir: Option<PathBuf> = None;
    let result = sfc_server::serve(opts, |url| {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "SFC Editor: {url}");
        let _ = out.flush();
        if open {
            match launch_page(url) {
                Ok((dir, page)) => {
                    open_browser(&page);
                    launch_dir = Some(dir);
                }
                Err(e) => eprintln!("note: the browser was not opened ({e}); open the URL above"),
            }
        }
    });
    if let Some(dir) = launch_dir {
        let _ = std::fs::remove_dir_all(dir);
    }
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            2
        }
    }
}
