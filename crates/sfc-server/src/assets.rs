//! The web app (`web/dist`, built by Vite), embedded in the binary. Release builds carry the
//! files; debug builds read them from `web/dist` at run time, or from the directory in
//! `SFC_WEB_DIST` (the browser tests serve the test build, `web/dist-test`, the only build with
//! the test hook `window.__sfc`). When the app was not built, `/` says how to build it.

use axum::http::{header, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use rust_embed::RustEmbed;

#[derive(RustEmbed)]
#[folder = "../../web/dist"] // relative to this crate
#[allow_missing = true]
struct WebApp;

/// Shown at `/` when the binary was built without the web app.
const NOT_BUILT: &str = r#"<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>SFC Editor</title></head>
<body style="font-family: sans-serif; max-width: 40em; margin: 3em auto">
<h1>SFC Editor: the web app was not built</h1>
<p>This <code>sfc</code> binary was compiled before the browser app existed in <code>web/dist</code>.
Build the app, then build <code>sfc</code> again:</p>
<pre>cd web &amp;&amp; npm ci &amp;&amp; npm run build &amp;&amp; cd ..
cargo build --release</pre>
<p>The HTTP API under <code>/api/</code> works without it.</p>
</body></html>
"#;

/// The bytes and MIME type of a file of the app (`path` has no `..`).
fn get(path: &str) -> Option<(Vec<u8>, String)> {
    #[cfg(debug_assertions)]
    if let Some(dir) = std::env::var_os("SFC_WEB_DIST").filter(|d| !d.is_empty()) {
        let data = std::fs::read(std::path::Path::new(&dir).join(path)).ok()?;
        let mime = match path.rsplit('.').next() {
            Some("html") => "text/html",
            Some("js") => "text/javascript",
            Some("css") => "text/css",
            Some("svg") => "image/svg+xml",
            Some("json") => "application/json",
            Some("png") => "image/png",
            Some("woff2") => "font/woff2",
            _ => "application/octet-stream",
        };
        return Some((data, mime.to_string()));
    }
    WebApp::get(path).map(|f| (f.data.into_owned(), f.metadata.mimetype().to_string()))
}

/// A static file of the web app; `/` is `index.html`.
pub async fn serve(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    // Debug builds read from the disk: never let a name climb out of `web/dist`.
    let file = if path.split(['/', '\\']).any(|seg| seg == "..") { None } else { get(path) };
    match file {
        Some((data, mime)) => {
            // The page must always be fetched again (it names the current bundles); Vite's
            // bundles under `assets/` carry a content hash in their names.
            let cache = if path == "index.html" {
                "no-store"
            } else if path.starts_with("assets/") {
                "max-age=31536000, immutable"
            } else {
                "no-cache"
            };
            ([(header::CONTENT_TYPE, mime), (header::CACHE_CONTROL, cache.to_string())], data).into_response()
        }
        None if path == "index.html" => {
            ([(header::CONTENT_TYPE, "text/html; charset=utf-8"), (header::CACHE_CONTROL, "no-store")], NOT_BUILT)
                .into_response()
        }
        None => (StatusCode::NOT_FOUND, [(header::CONTENT_TYPE, "text/plain; charset=utf-8")], "not found\n")
            .into_response(),
    }
}
