//! The SFC Editor's server: the HTTP API of `docs/editor.md` and the web app built from `web/`,
//! embedded in the binary. Loopback only, a per-run token, and file access confined to the
//! directories it was started with.
