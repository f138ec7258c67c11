//! Who may open a WebSocket, decided before the upgrade: the origin policy, and a cap
//! on each address's open connections.
//!
//! Browsers let any page open a WebSocket to any server, sending the page's `Origin`;
//! unlike `fetch`, no CORS check stops it. So the server checks the origin itself: a
//! page it served (same origin) and the origins an operator allows may connect. Bots
//! and tools send no `Origin` and are not browsers, so the check does not concern them;
//! their tokens do.
//!
//! One address may hold at most `max_connections_per_ip` sockets (spectators, bots and
//! replay viewers together), so one client cannot take every file descriptor.

use super::api::ApiError;
use super::state::AppState;
use axum::extract::{ConnectInfo, FromRequestParts};
use axum::http::request::Parts;
use axum::http::{HeaderMap, StatusCode};
use std::collections::HashMap;
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::{Arc, Mutex};

/// Open WebSocket connections per client address.
#[derive(Default)]
pub struct Connections {
    open: Mutex<HashMap<IpAddr, usize>>,
}

/// A connection's place in [`Connections`], given back when it is dropped: when its
/// socket closes, or when the upgrade never completes.
pub struct Admitted {
    app: Arc<AppState>,
    ip: IpAddr,
}

impl Drop for Admitted {
    fn drop(&mut self) {
        let mut open = self.app.connections.open.lock().expect("not poisoned");
        if let Some(n) = open.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                open.remove(&self.ip);
            }
        }
    }
}

/// Every socket route takes an `Admitted` among its arguments, so the checks run before
/// the handler and its upgrade; the handler keeps it for the socket's life.
impl FromRequestParts<Arc<AppState>> for Admitted {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut Parts,
        app: &Arc<AppState>,
    ) -> Result<Admitted, ApiError> {
        let peer = parts
            .extensions
            .get::<ConnectInfo<SocketAddr>>()
            .map(|ConnectInfo(peer)| peer.ip())
            .ok_or_else(|| {
                ApiError::new(
                    StatusCode::INTERNAL_SERVER_ERROR,
                    "internal",
                    "the server was started without peer addresses",
                )
            })?;
        admit(app, peer, &parts.headers)
    }
}

/// Lets a WebSocket request in, or says why not: 403 for an origin the policy does
/// not allow, 429 for an address at its connection cap.
fn admit(app: &Arc<AppState>, ip: IpAddr, headers: &HeaderMap) -> Result<Admitted, ApiError> {
    if let Err(origin) = check_origin(&app.config.allowed_origins, headers) {
        app.metrics.refused_origin.fetch_add(1, Relaxed);
        return Err(ApiError::forbidden(&format!(
            "origin {origin} may not open sockets here (allowed_origins)"
        )));
    }
    let mut open = app.connections.open.lock().expect("not poisoned");
    let n = open.entry(ip).or_default();
    if *n >= app.config.max_connections_per_ip {
        app.metrics.refused_per_ip.fetch_add(1, Relaxed);
        return Err(ApiError::new(
            StatusCode::TOO_MANY_REQUESTS,
            "too_many_connections",
            format!(
                "this address already has {n} open sockets (max_connections_per_ip)",
                n = *n
            ),
        ));
    }
    *n += 1;
    Ok(Admitted {
        app: app.clone(),
        ip,
    })
}

/// No `Origin` (not a browser), the server's own origin, or one of `allowed` (`*`
/// allows every origin). Else the refused origin, for the error.
fn check_origin(allowed: &[String], headers: &HeaderMap) -> Result<(), String> {
    let Some(origin) = headers.get("origin") else {
        return Ok(());
    };
    let origin = origin.to_str().unwrap_or("(not text)");
    let host = headers.get("host").and_then(|h| h.to_str().ok());
    let authority = origin
        .strip_prefix("http://")
        .or_else(|| origin.strip_prefix("https://"));
    let same_origin = authority.is_some_and(|a| host.is_some_and(|h| a.eq_ignore_ascii_case(h)));
    if same_origin
        || allowed
            .iter()
            .any(|o| o == "*" || o.eq_ignore_ascii_case(origin))
    {
        Ok(())
    } else {
        Err(origin.to_string())
    }
}

/// Checks an `allowed_origins` entry: `*`, or a scheme and host with an optional
/// port and nothing after (`https://example.com:8443`), as browsers send it.
pub fn valid_origin(entry: &str) -> bool {
    if entry == "*" {
        return true;
    }
    let Some(rest) = entry
        .strip_prefix("http://")
        .or_else(|| entry.strip_prefix("https://"))
    else {
        return false;
    };
    !rest.is_empty() && !rest.contains(['/', '?', '#', ' ']) && !rest.ends_with(':')
}

#[cfg(test)]
mod tests {
    use super::{check_origin, valid_origin};
    use axum::http::HeaderMap;

    fn headers(origin: Option<&str>, host: &str) -> HeaderMap {
        let mut h = HeaderMap::new();
        h.insert("host", host.parse().unwrap());
        if let Some(o) = origin {
            h.insert("origin", o.parse().unwrap());
        }
        h
    }

    #[test]
    fn same_origin_and_no_origin_pass_and_others_need_allowing() {
        let none: Vec<String> = Vec::new();
        assert!(check_origin(&none, &headers(None, "127.0.0.1:7878")).is_ok());
        assert!(check_origin(
            &none,
            &headers(Some("http://127.0.0.1:7878"), "127.0.0.1:7878")
        )
        .is_ok());
        assert!(check_origin(
            &none,
            &headers(Some("https://Play.example"), "play.example")
        )
        .is_ok());
        let evil = headers(Some("http://evil.example"), "127.0.0.1:7878");
        assert_eq!(
            check_origin(&none, &evil),
            Err("http://evil.example".into())
        );
        // A different port is a different origin.
        assert!(check_origin(
            &none,
            &headers(Some("http://127.0.0.1:9999"), "127.0.0.1:7878")
        )
        .is_err());
        assert!(check_origin(&["http://evil.example".into()], &evil).is_ok());
        assert!(check_origin(&["*".into()], &evil).is_ok());
        assert!(check_origin(&["http://other.example".into()], &evil).is_err());
    }

    #[test]
    fn allowed_origins_are_scheme_and_host_only() {
        for ok in [
            "*",
            "http://a.example",
            "https://a.example:8443",
            "http://[::1]:7878",
        ] {
            assert!(valid_origin(ok), "{ok}");
        }
        for bad in [
            "a.example",
            "http://",
            "https://a.example/",
            "ftp://a",
            "http://a:",
            "http://a?x",
        ] {
            assert!(!valid_origin(bad), "{bad}");
        }
    }
}
