//! `sfc lsp`: the language server (crate `sfc-lsp`) on standard input and output.

use crate::Status;

#[derive(clap::Args)]
pub struct LspArgs {
    /// Speak the protocol on standard input and output (the default and only transport;
    /// accepted because editors' clients pass it).
    #[arg(long)]
    stdio: bool,
}

pub fn lsp(args: LspArgs) -> u8 {
    let _ = args.stdio;
    if std::io::IsTerminal::is_terminal(&std::io::stdin()) {
        eprintln!(
            "sfc lsp: serving the Language Server Protocol on standard input (an editor starts this; Ctrl-D ends)"
        );
    }
    match sfc_lsp::run_stdio(sfc_lsp::ServerOptions::default()) {
        Ok(()) => Status::Ok.code(),
        Err(e) => {
            crate::term::error(&format!("sfc lsp: {e}"));
            Status::Usage.code()
        }
    }
}
