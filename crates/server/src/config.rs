//! The server's settings: defaults that suit a laptop, overridable by a TOML file
//! (`serve --config FILE`) and by flags.

use super::hosts::{valid_host, valid_origin};
use serde::{Deserialize, Deserializer};
use std::net::{IpAddr, SocketAddr, ToSocketAddrs};
use std::path::Path;

const GIB: u64 = 1024 * 1024 * 1024;

/// The port `serve` listens on when the address names none.
pub const DEFAULT_PORT: u16 = 7878;

/// What an address to listen on looks like, for every message about a wrong one.
const ADDR_FORM: &str = "expected HOST:PORT, e.g. 127.0.0.1:7878, where HOST is an IP address \
    or a host name (localhost); a HOST alone listens on port 7878";

/// How `serve` runs: its address, limits, timeouts, replay directory and demos, from the
/// command line, the environment and the TOML file (unknown keys refused); every field
/// has a default.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServerConfig {
    /// Where to listen. Loopback unless told otherwise. In the file it is written as on
    /// the command line (see [`listen_addr`]).
    #[serde(deserialize_with = "listen_addr_setting")]
    pub addr: SocketAddr,
    /// Start the built-in demo matches.
    pub demo: bool,
    /// Most matches at once (demos included).
    pub max_matches: usize,
    /// Largest WebSocket message the server reads, bytes; larger closes with 1009.
    pub max_message_bytes: usize,
    /// Messages per second a client may send on any socket (bot, spectator, replay
    /// viewer), sustained; a bot's one answer to each perception is free.
    pub bot_messages_per_second: u32,
    /// Messages a client may send in a burst above the sustained rate; refused a burst
    /// more, it is closed with 1008.
    pub bot_burst: u32,
    /// A client (spectator, bot, replay viewer) whose socket takes longer than this to
    /// accept a message is dropped, ms.
    pub send_timeout_ms: u64,
    /// A REST request taking longer than this is answered 408, ms.
    pub request_timeout_ms: u64,
    /// Largest REST request body, bytes.
    pub max_body_bytes: usize,
    /// Where every match is recorded as a replay (none: matches are not recorded).
    pub replay_dir: Option<std::path::PathBuf>,
    /// Retention: the replays in `replay_dir` may take this many bytes in all; past it
    /// the oldest are deleted (never one being written).
    pub replay_retention_bytes: u64,
    /// Retention: replays older than this many days are deleted (0: no age limit).
    pub replay_retention_days: u32,
    /// The most one match's replay may write; past it the recording ends with the
    /// footer reason `size_limit` (the match goes on). Matches that rotate are exempt.
    pub replay_max_match_bytes: u64,
    /// Real-time matches without bot slots (the demos, which never end) rotate their
    /// replay into files of about this size.
    pub replay_segment_bytes: u64,
    /// Put the wall-clock time each frame is published, `"sent_us"` (µs since the Unix
    /// epoch), into the frames sent live, so a client on the same host can measure
    /// frame latency (`fieldhouse loadgen` does). Replays keep the frames without it:
    /// a clock reading is no part of what a match computes.
    pub stamp_frames: bool,
    /// Origins (`https://host[:port]`, or `*` for any) whose pages may open WebSockets
    /// here besides the server's own. Clients that send no `Origin` (bots, tools) are
    /// not browsers and are let in; their tokens guard what matters.
    pub allowed_origins: Vec<String>,
    /// Host names (or addresses) this server is reached by besides loopback and its
    /// listen address, `name` or `name:port`: a page served under one of them may open
    /// WebSockets as the server's own. Anything else claiming to be the server's own
    /// origin is a DNS-rebinding page.
    pub allowed_hosts: Vec<String>,
    /// Most connections (HTTP and WebSocket) one client address may hold open at once.
    pub max_connections_per_ip: usize,
    /// Most connections in all; none: what the descriptor limit allows, less a reserve.
    pub max_connections: Option<usize>,
    /// A request's headers must arrive within this of the connection opening (or of
    /// the previous response on a kept-alive connection), ms; else it is closed.
    pub header_timeout_ms: u64,
    /// Most REST requests in flight at once; more are answered 503 at once.
    pub max_concurrent_requests: usize,
    /// How long an ended match stays listed, s (at most `max_matches` ended matches
    /// are kept, the most recently ended).
    pub ended_match_ttl_s: u64,
    /// Run as an Agones game server, talking to the SDK sidecar on this port (`serve
    /// --agones`; not a file setting: it is where the process runs, not how).
    #[serde(skip)]
    pub agones_sdk_port: Option<u16>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            addr: SocketAddr::from(([127, 0, 0, 1], DEFAULT_PORT)),
            demo: true,
            max_matches: 64,
            max_message_bytes: 4096,
            bot_messages_per_second: 200,
            bot_burst: 400,
            send_timeout_ms: 5000,
            request_timeout_ms: 10_000,
            max_body_bytes: 64 * 1024,
            replay_dir: None,
            replay_retention_bytes: 2 * GIB,
            replay_retention_days: 7,
            replay_max_match_bytes: GIB,
            replay_segment_bytes: 64 * 1024 * 1024,
            stamp_frames: false,
            allowed_origins: Vec::new(),
            allowed_hosts: Vec::new(),
            max_connections_per_ip: 256,
            max_connections: None,
            header_timeout_ms: 10_000,
            max_concurrent_requests: 256,
            ended_match_ttl_s: 600,
            agones_sdk_port: None,
        }
    }
}

/// An address to listen on, as people write it: `HOST:PORT` where HOST is an IP address
/// (`127.0.0.1:7878`, `[::1]:7878`, `0.0.0.0:7878`) or a host name that resolves
/// (`localhost:7878`), or a HOST alone, meaning port [`DEFAULT_PORT`]. A name that
/// resolves to several addresses listens on a loopback one if it has one (so
/// `localhost` never opens the server to the network), else on its first IPv4
/// address, else on its first. Anything else is refused with what is expected.
pub fn listen_addr(text: &str) -> Result<SocketAddr, String> {
    let text = text.trim();
    if let Ok(addr) = text.parse::<SocketAddr>() {
        return Ok(addr);
    }
    // An IP address alone, IPv6 with or without brackets.
    let bare = text
        .strip_prefix('[')
        .and_then(|t| t.strip_suffix(']'))
        .unwrap_or(text);
    if let Ok(ip) = bare.parse::<IpAddr>() {
        return Ok(SocketAddr::new(ip, DEFAULT_PORT));
    }
    // Only what a host, an IP address and a port are written with: a URL, a path or a
    // stray space is refused here rather than mistaken for a strange host name.
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | ':' | '[' | ']');
    if text.is_empty() || !text.chars().all(allowed) {
        return Err(format!("not an address to listen on; {ADDR_FORM}"));
    }
    let (host, port) = match text.rsplit_once(':') {
        Some((host, port)) => {
            let port = port.parse::<u16>().map_err(|_| {
                format!("the port \"{port}\" is not a number from 0 to 65535; {ADDR_FORM}")
            })?;
            (host, port)
        }
        None => (text, DEFAULT_PORT),
    };
    // What is left must be a host name (an IPv6 address with a port needs brackets).
    let name = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '.';
    if host.is_empty() || !host.chars().all(name) {
        return Err(format!(
            "\"{host}\" is neither an IP address nor a host name (an IPv6 address with a \
             port is written in brackets: [::1]:7878); {ADDR_FORM}"
        ));
    }
    let resolved: Vec<SocketAddr> = (host, port)
        .to_socket_addrs()
        .map_err(|e| format!("cannot resolve the host name \"{host}\" ({e}); {ADDR_FORM}"))?
        .collect();
    resolved
        .iter()
        .find(|a| a.ip().is_loopback())
        .or_else(|| resolved.iter().find(|a| a.is_ipv4()))
        .or(resolved.first())
        .copied()
        .ok_or_else(|| format!("the host name \"{host}\" has no address; {ADDR_FORM}"))
}

/// `addr` in the settings file, read as [`listen_addr`] reads the flag.
fn listen_addr_setting<'de, D: Deserializer<'de>>(d: D) -> Result<SocketAddr, D::Error> {
    let text = String::deserialize(d)?;
    listen_addr(&text).map_err(|e| serde::de::Error::custom(format!("\"{text}\": {e}")))
}

impl ServerConfig {
    /// Reads a TOML file; an error names the file and the field at fault.
    pub fn load(path: &Path) -> Result<ServerConfig, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let de = toml::Deserializer::new(&text);
        let config: ServerConfig = serde_path_to_error::deserialize(de)
            .map_err(|e| format!("{}: {}: {}", path.display(), e.path(), e.inner().message()))?;
        config
            .check()
            .map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(config)
    }

    /// Checks values the types allow but the server cannot use; the error names the
    /// field.
    pub fn check(&self) -> Result<(), String> {
        let at_least = |field: &str, value: u64, min: u64| {
            if value < min {
                Err(format!("{field}: must be at least {min}, not {value}"))
            } else {
                Ok(())
            }
        };
        at_least("max_message_bytes", self.max_message_bytes as u64, 256)?;
        at_least(
            "bot_messages_per_second",
            self.bot_messages_per_second.into(),
            1,
        )?;
        at_least("max_matches", self.max_matches as u64, 1)?;
        at_least(
            "max_connections_per_ip",
            self.max_connections_per_ip as u64,
            1,
        )?;
        at_least("header_timeout_ms", self.header_timeout_ms, 100)?;
        at_least(
            "max_concurrent_requests",
            self.max_concurrent_requests as u64,
            1,
        )?;
        if let Some(n) = self.max_connections {
            at_least("max_connections", n as u64, 32)?;
        }
        if let Some(bad) = self.allowed_hosts.iter().find(|h| !valid_host(h)) {
            return Err(format!(
                "allowed_hosts: \"{bad}\" is not a host; write a name or address with an optional port (play.example, play.example:8443, [::1]:7878)"
            ));
        }
        // Smaller than a few dozen frames, a file would be mostly header and footer.
        at_least(
            "replay_max_match_bytes",
            self.replay_max_match_bytes,
            16 * 1024,
        )?;
        at_least("replay_segment_bytes", self.replay_segment_bytes, 16 * 1024)?;
        if let Some(bad) = self.allowed_origins.iter().find(|o| !valid_origin(o)) {
            return Err(format!(
                "allowed_origins: \"{bad}\" is not an origin; write scheme://host[:port] (https://example.com) or *"
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{listen_addr, ServerConfig};
    use std::net::SocketAddr;

    #[test]
    fn addresses_are_read_as_people_write_them() {
        let at = |s: &str| listen_addr(s).unwrap();
        assert_eq!(
            at("127.0.0.1:7892"),
            SocketAddr::from(([127, 0, 0, 1], 7892))
        );
        assert_eq!(at("127.0.0.1"), SocketAddr::from(([127, 0, 0, 1], 7878)));
        assert_eq!(at("0.0.0.0:0"), SocketAddr::from(([0, 0, 0, 0], 0)));
        assert_eq!(at("[::1]:80"), "[::1]:80".parse().unwrap());
        assert_eq!(at("::1"), "[::1]:7878".parse().unwrap());
        assert_eq!(at("[::1]"), "[::1]:7878".parse().unwrap());
        let local = at("localhost:7892");
        assert!(local.ip().is_loopback(), "{local}");
        assert_eq!(local.port(), 7892);
        assert_eq!(at("localhost").port(), 7878);
        for wrong in [
            "",
            "localhost:port",
            "127.0.0.1:99999",
            "http://127.0.0.1:7878",
            "127.0.0.1:7878/",
            "fe80::1:7878x",
        ] {
            let message = listen_addr(wrong).unwrap_err();
            assert!(
                message.contains("HOST:PORT, e.g. 127.0.0.1:7878"),
                "{wrong:?}: {message}"
            );
        }
    }

    #[test]
    fn the_defaults_listen_on_loopback_and_pass_their_own_check() {
        let config = ServerConfig::default();
        assert!(config.addr.ip().is_loopback());
        assert_eq!(config.check(), Ok(()));
        assert!(
            config.allowed_origins.is_empty(),
            "only the server's own pages"
        );
    }

    #[test]
    fn a_bad_setting_is_named() {
        let check = |edit: fn(&mut ServerConfig)| {
            let mut config = ServerConfig::default();
            edit(&mut config);
            config.check().unwrap_err()
        };
        assert!(check(|c| c.max_connections_per_ip = 0).starts_with("max_connections_per_ip:"));
        assert!(check(|c| c.max_message_bytes = 10).starts_with("max_message_bytes:"));
        assert!(check(|c| c.replay_segment_bytes = 1000).starts_with("replay_segment_bytes:"));
        assert!(check(|c| c.allowed_origins = vec!["example.com".into()])
            .starts_with("allowed_origins:"));
    }
}
