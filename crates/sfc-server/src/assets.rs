//! The web app (`web/dist`, built by Vite), embedded in the binary. Release builds carry the
//! files; debug builds read them from `web/dist` at run time. When the app was not built, `/`
//! says how to build it.

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

/// A static file of the web app; `/` is `index.html`.
pub async fn serve(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    // Debug builds read from the disk: never let a name climb out of `web/dist`.
    let file = if path.split(['/', '\\']).any(|seg| seg == "..") { None } else { WebApp::get(path) };
    match file {
        Some(file) => {
            // The page must always be fetched again (it names the current bundles); Vite's
            // bundles under `assets/` carry a content hash in their names.
            let cache = if path == "index.html" {
                "no-store"
            } else if path.starts_with("assets/") {
                "max-age=31536000, immutable"
            } else {
                "no-cache"
            };
            (
                [
                    (header::CONTENT_TYPE, file.metadata.mimetype().to_string()),
                    (header::CACHE_CONTROL, cache.to_string()),
                ],
                file.data.into_owned(),
            )
                .into_response()
        }
        None if path == "index.html" => {
            ([(header::CONTENT_TYPE, "text/html; charset=utf-8"), (header::CACHE_CONTROL, "no-store")], NOT_BUILT)
                .into_response()
        }
        None => (StatusCode::NOT_FOUND, [(header::CONTENT_TYPE, "text/plain; charset=utf-8")], "not found\n")
            .into_response(),
    }
}
