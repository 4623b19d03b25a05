//! Who may talk to the server. On loopback (the default) the machine's own browsers may, and the
//! `Host` header must name a loopback address (a web page elsewhere cannot reach the server by
//! rebinding a name of its own to 127.0.0.1). Any other address needs the token: printed at start or
//! read from `--token-file`, presented once as `?token=` (the server answers with a cookie and the
//! address without it) or on every request as `Authorization: Bearer TOKEN`; every request is
//! checked. Requests that change state (`POST`) must come from the server's own pages: a browser's
//! `Origin` (or `Sec-Fetch-Site`) must say so.

use std::net::SocketAddr;

use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Redirect, Response};

/// The cookie that carries the token after the first visit.
pub const COOKIE: &str = "canopener_token";

/// The access rules of one server.
#[derive(Debug, Clone)]
pub struct Access {
    /// The token every request must carry; `None` on loopback without `--token-file`.
    token: Option<String>,
    /// Whether the server listens on loopback only (then `Host` must be a loopback name).
    loopback: bool,
}

/// Why the token could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum TokenError {
    /// The token file could not be read.
    #[error("--token-file {path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// The token is too short to guess-proof the server.
    #[error(
        "--token-file {path}: the token has {length} characters; give at least 16 (letters, digits, - or _)"
    )]
    Weak {
        /// The file.
        path: String,
        /// Its length.
        length: usize,
    },
    /// No randomness to make a token from.
    #[error("cannot make a token: {0}")]
    Random(String),
}

impl Access {
    /// The rules for a server on `listen`, with the token of `token_file` (trimmed) when given, else a
    /// fresh random one when `listen` is not loopback.
    pub fn new(listen: SocketAddr, token_file: Option<&std::path::Path>) -> Result<Access, TokenError> {
        let loopback = listen.ip().is_loopback();
        let token = match token_file {
            Some(path) => {
                let shown = path.display().to_string();
                let bytes = crate::backend::read_file(path).map_err(|source| TokenError::Read {
                    path: shown.clone(),
                    source,
                })?;
                let token = String::from_utf8_lossy(&bytes).trim().to_owned();
                let valid = token
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
                if token.chars().count() < 16 || !valid {
                    return Err(TokenError::Weak {
                        path: shown,
                        length: token.chars().count(),
                    });
                }
                Some(token)
            }
            None if loopback => None,
            None => Some(random_token()?),
        };
        Ok(Access { token, loopback })
    }

    /// The token, when one is required.
    pub fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// Whether `headers` and the query carry the token (always, when none is required).
    fn admits(&self, headers: &HeaderMap, query_token: Option<&str>) -> bool {
        let Some(token) = &self.token else {
            return true;
        };
        let bearer = headers
            .get(header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "));
        let cookie = headers
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(';'))
            .filter_map(|pair| pair.trim().strip_prefix(COOKIE)?.strip_prefix('='));
        bearer
            .into_iter()
            .chain(cookie)
            .chain(query_token)
            .any(|given| same(given, token))
    }
}

/// 128 random bits as 32 hex digits.
fn random_token() -> Result<String, TokenError> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| TokenError::Random(e.to_string()))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// Compares in time independent of where the strings differ.
fn same(given: &str, token: &str) -> bool {
    given.len() == token.len()
        && given
            .bytes()
            .zip(token.bytes())
            .fold(0u8, |acc, (a, b)| acc | (a ^ b))
            == 0
}

/// The host part of a `Host` header or an origin's authority (`[::1]:8080` → `::1`).
fn host_name(authority: &str) -> &str {
    if let Some(rest) = authority.strip_prefix('[') {
        return rest.split(']').next().unwrap_or(rest);
    }
    authority.rsplit_once(':').map_or(authority, |(host, _)| host)
}

fn is_loopback_name(host: &str) -> bool {
    host.eq_ignore_ascii_case("localhost")
        || host.parse::<std::net::IpAddr>().is_ok_and(|ip| ip.is_loopback())
}

/// A refusal as the pages and scripts read it: a status and one plain sentence.
fn refuse(status: StatusCode, message: &str) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        message.to_owned(),
    )
        .into_response()
}

/// The middleware that applies [`Access`] to every request.
pub async fn check(State(access): State<Access>, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let host = headers
        .get(header::HOST)
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
        .to_owned();
    if access.loopback && access.token.is_none() && !is_loopback_name(host_name(&host)) {
        return refuse(
            StatusCode::MISDIRECTED_REQUEST,
            "this server answers only to localhost, 127.0.0.1 or [::1]: open it by one of those names",
        );
    }
    let query_token = request
        .uri()
        .query()
        .and_then(|q| q.split('&').find_map(|pair| pair.strip_prefix("token=")))
        .map(str::to_owned);
    if !access.admits(headers, query_token.as_deref()) {
        return refuse(
            StatusCode::UNAUTHORIZED,
            "this server needs its token: open the address `canopener serve` printed at start \
             (…/?token=…), or send `Authorization: Bearer TOKEN`",
        );
    }
    let changes_state = !matches!(*request.method(), Method::GET | Method::HEAD | Method::OPTIONS);
    if changes_state && !same_origin(headers, &host) {
        return refuse(
            StatusCode::FORBIDDEN,
            "refused: this request changes the server's state and came from another site's page",
        );
    }
    // The token in the address goes into a cookie, and the address the browser shows loses it.
    if let (Some(token), Some(_)) = (&access.token, &query_token)
        && request.method() == Method::GET
    {
        let rest: Vec<&str> = request
            .uri()
            .query()
            .unwrap_or_default()
            .split('&')
            .filter(|pair| !pair.is_empty() && !pair.starts_with("token="))
            .collect();
        let mut target = request.uri().path().to_owned();
        if !rest.is_empty() {
            target = format!("{target}?{}", rest.join("&"));
        }
        let mut response = Redirect::to(&target).into_response();
        let cookie = format!("{COOKIE}={token}; HttpOnly; SameSite=Strict; Path=/");
        if let Ok(value) = HeaderValue::from_str(&cookie) {
            response.headers_mut().insert(header::SET_COOKIE, value);
        }
        return response;
    }
    next.run(request).await
}

/// Whether a state-changing request comes from this server's own pages: its `Origin` names the host
/// it was sent to, or (without `Origin`) `Sec-Fetch-Site` says same-origin. A request with neither
/// is not from a browser's page (a script, curl): it carries the token where one is needed.
fn same_origin(headers: &HeaderMap, host: &str) -> bool {
    if let Some(origin) = headers.get(header::ORIGIN).and_then(|v| v.to_str().ok()) {
        let authority = origin
            .strip_prefix("http://")
            .or_else(|| origin.strip_prefix("https://"));
        return authority.is_some_and(|a| a.eq_ignore_ascii_case(host));
    }
    match headers.get("sec-fetch-site").and_then(|v| v.to_str().ok()) {
        Some(site) => site == "same-origin" || site == "none",
        None => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(pairs: &[(&'static str, &str)]) -> HeaderMap {
        let mut map = HeaderMap::new();
        for (name, value) in pairs {
            map.append(*name, HeaderValue::from_str(value).unwrap());
        }
        map
    }

    #[test]
    fn loopback_needs_no_token_and_any_other_address_gets_a_random_one() {
        let local = Access::new("127.0.0.1:8080".parse().unwrap(), None).unwrap();
        assert_eq!(local.token(), None);
        assert!(local.admits(&HeaderMap::new(), None));
        let open = Access::new("0.0.0.0:8080".parse().unwrap(), None).unwrap();
        let token = open.token().unwrap().to_owned();
        assert_eq!(token.len(), 32);
        let other = Access::new("0.0.0.0:8080".parse().unwrap(), None).unwrap();
        assert_ne!(other.token(), Some(token.as_str()), "tokens are random");
        assert!(!open.admits(&HeaderMap::new(), None));
        assert!(!open.admits(&HeaderMap::new(), Some("wrong")));
        assert!(open.admits(&HeaderMap::new(), Some(&token)));
        let bearer = format!("Bearer {token}");
        assert!(open.admits(&headers(&[("authorization", &bearer)]), None));
        let cookie = format!("theme=dark; {COOKIE}={token}");
        assert!(open.admits(&headers(&[("cookie", &cookie)]), None));
        assert!(!open.admits(&headers(&[("cookie", "canopener_token=nope")]), None));
    }

    #[test]
    fn state_changes_must_come_from_the_servers_own_pages() {
        let host = "127.0.0.1:8080";
        assert!(same_origin(
            &headers(&[("origin", "http://127.0.0.1:8080")]),
            host
        ));
        assert!(!same_origin(&headers(&[("origin", "http://evil.example")]), host));
        assert!(!same_origin(&headers(&[("origin", "null")]), host));
        assert!(!same_origin(&headers(&[("sec-fetch-site", "cross-site")]), host));
        assert!(same_origin(&headers(&[("sec-fetch-site", "same-origin")]), host));
        assert!(same_origin(&HeaderMap::new(), host), "a script without a browser");
    }

    #[test]
    fn host_names_are_read_with_and_without_ports() {
        assert_eq!(host_name("localhost:8080"), "localhost");
        assert_eq!(host_name("[::1]:8080"), "::1");
        assert_eq!(host_name("127.0.0.1"), "127.0.0.1");
        assert!(is_loopback_name("::1") && is_loopback_name("LOCALHOST"));
        assert!(!is_loopback_name("canopener.example"));
    }

    #[test]
    fn constant_time_comparison_compares() {
        assert!(same("abc", "abc"));
        assert!(!same("abc", "abd") && !same("abc", "abcd"));
    }
}
