//! Who may open a WebSocket, decided before the upgrade: the origin policy, and room
//! for spectators.
//!
//! Browsers let any page open a WebSocket to any server, sending the page's `Origin`;
//! unlike `fetch`, no CORS check stops it. So the server checks the origin itself: a
//! page it served (same origin) and the origins an operator allows may connect. Bots
//! and tools send no `Origin` and are not browsers, so the check does not concern them;
//! their tokens do.
//!
//! "Same origin" means the `Origin` names the `Host` the request was sent to *and* that
//! host is one of the server's own: a loopback name, the address it listens on, or one
//! in `allowed_hosts`. Without the second half a DNS-rebinding page (its name pointed at
//! 127.0.0.1 after it loaded) would pass, since its `Origin` and `Host` agree.
//!
//! Connections are counted and capped where they are accepted (see `listener`);
//! here spectators and replay viewers are refused while the server is near its cap, so
//! the last places go to requests, admins and bots.

use super::error::ApiError;
use super::hosts::split_host;
use super::state::AppState;
use axum::extract::FromRequestParts;
use axum::http::request::Parts;
use axum::http::{HeaderMap, StatusCode};
use std::net::{IpAddr, SocketAddr};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;

/// A WebSocket request whose origin may connect (bots).
pub struct Admitted;

/// A spectator's or replay viewer's WebSocket request: its origin may connect and the
/// server has room for it.
pub struct AdmittedSpectator;

impl FromRequestParts<Arc<AppState>> for Admitted {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut Parts,
        app: &Arc<AppState>,
    ) -> Result<Admitted, ApiError> {
        let config = &app.config;
        let ours = |host: &str| host_is_ours(host, config.addr, &config.allowed_hosts);
        if let Err(origin) = check_origin(&config.allowed_origins, ours, &parts.headers) {
            app.metrics.refused_origin.fetch_add(1, Relaxed);
            return Err(ApiError::forbidden(&format!(
                "origin {origin} may not open sockets here (allowed_origins, allowed_hosts)"
            )));
        }
        Ok(Admitted)
    }
}

impl FromRequestParts<Arc<AppState>> for AdmittedSpectator {
    type Rejection = ApiError;

    async fn from_request_parts(
        parts: &mut Parts,
        app: &Arc<AppState>,
    ) -> Result<AdmittedSpectator, ApiError> {
        Admitted::from_request_parts(parts, app).await?;
        if !app.connections.spectators_welcome() {
            app.metrics.refused_busy.fetch_add(1, Relaxed);
            return Err(ApiError::new(
                StatusCode::SERVICE_UNAVAILABLE,
                "server_busy",
                "the server is near its connection limit and takes no more spectators now; try again later",
            ));
        }
        Ok(AdmittedSpectator)
    }
}

/// No `Origin` (not a browser), the server's own origin, or one of `allowed` (`*`
/// allows every origin). Else the refused origin, for the error. `ours` says whether a
/// `Host` is one of the server's own.
fn check_origin(
    allowed: &[String],
    ours: impl Fn(&str) -> bool,
    headers: &HeaderMap,
) -> Result<(), String> {
    let Some(origin) = headers.get("origin") else {
        return Ok(());
    };
    let origin = origin.to_str().unwrap_or("(not text)");
    let host = headers
        .get("host")
        .and_then(|h| h.to_str().ok())
        .filter(|h| ours(h));
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

/// Whether a `Host` header names this server: a loopback name or address (any port:
/// no one else's page can be served from them), the address it listens on, or an entry
/// of `allowed_hosts` (`name` for any port, `name:port` for one).
fn host_is_ours(host: &str, listening: SocketAddr, allowed_hosts: &[String]) -> bool {
    let (name, port) = split_host(host);
    let loopback = name.eq_ignore_ascii_case("localhost")
        || name.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback());
    let listen_address = !listening.ip().is_unspecified()
        && name.parse::<IpAddr>().ok() == Some(listening.ip())
        && port == Some(listening.port());
    loopback
        || listen_address
        || allowed_hosts.iter().any(|entry| {
            let (entry_name, entry_port) = split_host(entry);
            entry_name.eq_ignore_ascii_case(name) && (entry_port.is_none() || entry_port == port)
        })
}

#[cfg(test)]
mod tests {
    use super::{check_origin, host_is_ours};
    use crate::hosts::{valid_host, valid_origin};
    use axum::http::HeaderMap;
    use std::net::SocketAddr;

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
        let check_origin =
            |allowed: &[String], headers: &HeaderMap| check_origin(allowed, |_| true, headers);
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

    #[test]
    fn a_forged_host_is_not_the_servers_own() {
        let listening: SocketAddr = "0.0.0.0:7878".parse().unwrap();
        let none: Vec<String> = Vec::new();
        let ours = |h: &str| host_is_ours(h, listening, &none);
        // The DNS-rebinding shape: the page's origin and the Host agree, but the name
        // is the attacker's.
        let rebound = headers(Some("http://evil.example:7878"), "evil.example:7878");
        assert_eq!(
            check_origin(&none, ours, &rebound),
            Err("http://evil.example:7878".into())
        );
        for own in [
            "localhost:7878",
            "127.0.0.1:8080",
            "[::1]:7878",
            "LOCALHOST:1",
        ] {
            let page = headers(Some(&format!("http://{own}")), own);
            assert!(check_origin(&none, ours, &page).is_ok(), "{own}");
        }
        let named = vec!["play.example".to_string(), "tv.example:8443".to_string()];
        let ours = |h: &str| host_is_ours(h, listening, &named);
        let page = headers(Some("https://play.example:9000"), "play.example:9000");
        assert!(check_origin(&none, ours, &page).is_ok());
        let page = headers(Some("https://tv.example:8443"), "tv.example:8443");
        assert!(check_origin(&none, ours, &page).is_ok());
        let page = headers(Some("https://tv.example:9"), "tv.example:9");
        assert!(check_origin(&none, ours, &page).is_err(), "another port");
        // A specific listen address is the server's own, at its port.
        let at: SocketAddr = "10.0.0.5:7878".parse().unwrap();
        assert!(host_is_ours("10.0.0.5:7878", at, &none));
        assert!(!host_is_ours("10.0.0.5:80", at, &none));
    }

    #[test]
    fn allowed_hosts_are_names_or_addresses_with_an_optional_port() {
        for ok in [
            "play.example",
            "play.example:8443",
            "10.0.0.5",
            "[::1]:7878",
            "[::1]",
        ] {
            assert!(valid_host(ok), "{ok}");
        }
        for bad in [
            "",
            "http://play.example",
            "play.example/",
            "a b",
            "play.example:port",
            ":80",
        ] {
            assert!(!valid_host(bad), "{bad}");
        }
    }
}
