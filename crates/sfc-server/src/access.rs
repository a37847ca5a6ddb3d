//! Who may talk to the server: requests must name the server by its loopback address (a page
//! of another site that rebinds its DNS name to 127.0.0.1 still sends its own name), and API
//! calls must carry the per-run token, which only the page opened from the printed URL knows.

use crate::api::ApiError;
use crate::AppState;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};

/// The header the page sends the token in.
pub const TOKEN_HEADER: &str = "x-sfc-token";

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

fn token_ok(headers: &HeaderMap, token: &str) -> bool {
    headers.get(TOKEN_HEADER).is_some_and(|v| same_secret(v.as_bytes(), token.as_bytes()))
}

/// The check every request passes: the `Host` (and an absolute URI's authority) must be the
/// server's own; `/api/` also needs the token. Adds the headers every answer carries.
pub async fn guard(State(state): State<AppState>, req: Request, next: Next) -> Response {
    let port = state.port();
    let host_ok =
        req.headers().get(header::HOST).and_then(|h| h.to_str().ok()).is_some_and(|h| is_own_authority(h, port))
            && req.uri().authority().is_none_or(|a| is_own_authority(a.as_str(), port));
    let api = req.uri().path().starts_with("/api/") || req.uri().path() == "/api";
    let mut response = if !host_ok {
        ApiError::new(StatusCode::FORBIDDEN, "the Host header must be 127.0.0.1:PORT or localhost:PORT").into_response()
    } else if api && !token_ok(req.headers(), state.token()) {
        ApiError::new(StatusCode::FORBIDDEN, "missing or wrong X-Sfc-Token").into_response()
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
