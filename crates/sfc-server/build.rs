//! Rebuilds the crate when the web app appears or changes, so the binary serves the current
//! `web/dist`: release builds embed its files; debug builds read them at run time, but only
//! from a folder that existed when the crate was compiled (rust-embed resolves it then).

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let web = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web");
    let dist = web.join("dist");
    let release = std::env::var("PROFILE").as_deref() == Ok("release");
    if !dist.is_dir() {
        // Watch `web/` itself, so building the app later is noticed.
        println!("cargo:rerun-if-changed={}", web.display());
    } else if release {
        println!("cargo:rerun-if-changed={}", dist.display());
    }
}
