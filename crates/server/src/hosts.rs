//! What a Host and an Origin header may name: the syntax the configuration's
//! `allowed_hosts` and `allowed_origins` entries are checked against, and the split of a
//! Host header into name and port that admission compares. A leaf, so that the
//! configuration can check its entries without depending on admission.

use std::net::IpAddr;

/// `name[:port]`, with IPv6 addresses in brackets (`[::1]:7878`); the brackets are
/// dropped from the name.
pub(crate) fn split_host(host: &str) -> (&str, Option<u16>) {
    if let Some(rest) = host.strip_prefix('[') {
        let (name, after) = rest.split_once(']').unwrap_or((rest, ""));
        return (name, after.strip_prefix(':').and_then(|p| p.parse().ok()));
    }
    match host.rsplit_once(':') {
        Some((name, port)) => (name, port.parse().ok()),
        None => (host, None),
    }
}

/// Checks an `allowed_hosts` entry: a host name or IP address (IPv6 in brackets), with
/// an optional port.
pub fn valid_host(entry: &str) -> bool {
    let (name, port) = split_host(entry);
    let port_written = match entry.strip_prefix('[') {
        Some(rest) => rest.contains("]:"),
        None => entry.contains(':'),
    };
    let name_ok = name.parse::<IpAddr>().is_ok()
        || (!name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '.'));
    name_ok && (!port_written || port.is_some())
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
