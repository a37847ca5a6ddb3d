//! Who may talk to the server: requests must name the server by its loopback address (a page
//! of another site that rebinds its DNS name to 127.0.0.1 still sends its own name), and API
//! calls must carry the per-run token, which only the page opened from the printed URL knows.
//!
//! The page gets the token once: the printed URL `/?token=T` answers with a redirect to `/`
//! that sets the token as an `HttpOnly`, `SameSite=Strict` cookie, so the address bar, the
//! history and the page's scripts no longer hold it. API calls then carry the cookie and the
//! header `X-Sfc-Page: 1` (a header another origin cannot send without a CORS preflight, which
//! this server never grants). Scripts and tests may send the token in `X-Sfc-Token` instead.

use crate::api::ApiError;
use crate::AppState;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// The header a script sends the token in.
pub const TOKEN_HEADER: &str = "x-sfc-token";
/// The header the page sends with its cookie.
pub const PAGE_HEADER: &str = "x-sfc-page";

/// The cookie that holds the token for the page; named after the port, since cookies are not
/// kept apart by port and two editors may run at once.
pub fn cookie_name(port: u16) -> String {
    format!("sfc_token_{port}")
}

/// A new token: 32 random hex digits.
pub fn new_token() -> Result<String, String> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| format!("cannot get random bytes for the token: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Whether `authority` is `127.0.0.1:PORT` or `localhost:PORT`.
fn is_own_authority(authority: &str, port: u16) -> bool {
    let Some((host, p)) = authority.rsplit_once(':') else { return false };
    p == port.to_string() && (host == "127.0.0.1" || host.eq_ignore_ascii_case("localhost"))
}

/// Compares without stopping at the first difference, so timing does not reveal the token.
fn same_secret(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// The value of cookie `name` in the request's `Cookie` headers.
fn cookie<'a>(headers: &'a HeaderMap, name: &str) -> Option<&'a str> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .filter_map(|kv| kv.trim().split_once('='))
        .find(|(k, _)| *k == name)
        .map(|(_, v)| v.trim())
}

/// The token in `X-Sfc-Token`, or in the page's cookie together with `X-Sfc-Page`.
fn token_ok(headers: &HeaderMap, token: &str, port: u16) -> bool {
    if headers.get(TOKEN_HEADER).is_some_and(|v| same_secret(v.as_bytes(), token.as_bytes())) {
        return true;
    }
    headers.contains_key(PAGE_HEADER)
        && cookie(headers, &cookie_name(port)).is_some_and(|v| same_secret(v.as_bytes(), token.as_bytes()))
}

/// The `token` of the query string, if any.
fn query_token(query: Option<&str>) -> Option<&str> {
    query?.split('&').filter_map(|kv| kv.split_once('=')).find(|(k, _)| *k == "token").map(|(_, v)| v)
}

/// The answer to the printed URL: with the right token, a redirect to `/` that sets the cookie.
fn exchange(token_given: &str, state: &AppState) -> Response {
    if !same_secret(token_given.as_bytes(), state.token().as_bytes()) {
        return (
            StatusCode::FORBIDDEN,
            [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
            "This link is not the one `sfc edit` printed for this run.\n",
        )
            .into_response();
    }
    let cookie = format!("{}={}; HttpOnly; SameSite=Strict; Path=/", cookie_name(state.port()), state.token());
    let mut r = (StatusCode::SEE_OTHER, [(header::LOCATION, "/")]).into_response();
    if let Ok(v) = HeaderValue::from_str(&cookie) {
        r.headers_mut().insert(header::SET_COOKIE, v);
    }
    r.headers_mut().insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

/// The check every request passes: the `Host` (and an absolute URI's authority) must be the
/// server's own; `/api/` also needs the token. Adds the headers every answer carries.
pub async fn guard(State(state): State<AppState>, req: Request, next: Next) -> Response {
    let port = state.port();
    // Exactly one Host header: with two, which one a check or a proxy reads differs.
    let host_ok = req.headers().get_all(header::HOST).iter().count() == 1
        && req.headers().get(header::HOST).and_then(|h| h.to_str().ok()).is_some_and(|h| is_own_authority(h, port))
        && req.uri().authority().is_none_or(|a| is_own_authority(a.as_str(), port));
    let api = req.uri().path().starts_with("/api/") || req.uri().path() == "/api";
    let page = matches!(req.uri().path(), "/" | "/index.html");
    let mut response = if !host_ok {
        ApiError::new(StatusCode::FORBIDDEN, "the Host header must be 127.0.0.1:PORT or localhost:PORT").into_response()
    } else if api && !token_ok(req.headers(), state.token(), port) {
        ApiError::new(
            StatusCode::FORBIDDEN,
            "missing or wrong token: open the URL `sfc edit` printed (or send X-Sfc-Token)",
        )
        .into_response()
    } else if let (true, Some(given)) = (page, query_token(req.uri().query())) {
        exchange(given, &state)
    } else {
        next.run(req).await
    };
    let headers = response.headers_mut();
    headers.insert(header::X_CONTENT_TYPE_OPTIONS, HeaderValue::from_static("nosniff"));
    headers.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    if api {
        headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    }
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn authorities() {
        assert!(is_own_authority("127.0.0.1:8080", 8080));
        assert!(is_own_authority("LocalHost:8080", 8080));
        assert!(!is_own_authority("127.0.0.1:8081", 8080));
        assert!(!is_own_authority("127.0.0.1", 8080));
        assert!(!is_own_authority("evil.example:8080", 8080));
        assert!(!is_own_authority("127.0.0.1.evil.example:8080", 8080));
        assert!(!is_own_authority("[::1]:8080", 8080));
    }

    #[test]
    fn cookies_and_query() {
        let mut h = HeaderMap::new();
        h.insert(header::COOKIE, HeaderValue::from_static("a=1; sfc_token_80=abc ; b=2"));
        assert_eq!(cookie(&h, "sfc_token_80"), Some("abc"));
        assert_eq!(cookie(&h, "sfc_token_81"), None);
        assert!(!token_ok(&h, "abc", 80), "a cookie alone is not enough");
        h.insert(PAGE_HEADER, HeaderValue::from_static("1"));
        assert!(token_ok(&h, "abc", 80));
        assert!(!token_ok(&h, "abd", 80));
        assert!(!token_ok(&h, "abc", 81));
        assert_eq!(query_token(Some("x=1&token=ff")), Some("ff"));
        assert_eq!(query_token(Some("tokens=ff")), None);
        assert_eq!(query_token(None), None);
    }

    #[test]
    fn tokens_are_32_hex_digits_and_differ() {
        let a = new_token().unwrap();
        let b = new_token().unwrap();
        assert_eq!(a.len(), 32);
        assert!(a.chars().all(|c| c.is_ascii_hexdigit() && !c.is_ascii_uppercase()));
        assert_ne!(a, b);
        assert!(same_secret(a.as_bytes(), a.as_bytes()));
        assert!(!same_secret(a.as_bytes(), b.as_bytes()));
        assert!(!same_secret(a.as_bytes(), &a.as_bytes()[1..]));
    }
}
