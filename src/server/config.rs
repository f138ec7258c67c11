//! The server's settings: defaults that suit a laptop, overridable by a TOML file
//! (`serve --config FILE`) and by flags.

use super::admission::valid_origin;
use serde::Deserialize;
use std::net::SocketAddr;
use std::path::Path;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ServerConfig {
    /// Where to listen. Loopback unless told otherwise.
    pub addr: SocketAddr,
    /// Start the built-in demo matches.
    pub demo: bool,
    /// Most matches at once (demos included).
    pub max_matches: usize,
    /// Largest WebSocket message the server reads, bytes; larger closes with 1009.
    pub max_message_bytes: usize,
    /// Messages per second a bot may send, sustained.
    pub bot_messages_per_second: u32,
    /// Messages a bot may send in a burst above the sustained rate.
    pub bot_burst: u32,
    /// A spectator whose socket takes longer than this to accept a frame is dropped, ms.
    pub send_timeout_ms: u64,
    /// A REST request taking longer than this is answered 408, ms.
    pub request_timeout_ms: u64,
    /// Largest REST request body, bytes.
    pub max_body_bytes: usize,
    /// Where every match is recorded as a replay (none: matches are not recorded).
    pub replay_dir: Option<std::path::PathBuf>,
    /// Put the wall-clock time each frame is published, `"sent_us"` (µs since the Unix
    /// epoch), into the frames sent live, so a client on the same host can measure
    /// frame latency (`fieldhouse loadgen` does). Replays keep the frames without it:
    /// a clock reading is no part of what a match computes.
    pub stamp_frames: bool,
    /// Origins (`https://host[:port]`, or `*` for any) whose pages may open WebSockets
    /// here besides the server's own. Clients that send no `Origin` (bots, tools) are
    /// not browsers and are let in; their tokens guard what matters.
    pub allowed_origins: Vec<String>,
    /// Most WebSockets one client address may hold open at once.
    pub max_connections_per_ip: usize,
    /// Run as an Agones game server, talking to the SDK sidecar on this port (`serve
    /// --agones`; not a file setting: it is where the process runs, not how).
    #[serde(skip)]
    pub agones_sdk_port: Option<u16>,
}

impl Default for ServerConfig {
    fn default() -> Self {
        ServerConfig {
            addr: SocketAddr::from(([127, 0, 0, 1], 7878)),
            demo: true,
            max_matches: 64,
            max_message_bytes: 4096,
            bot_messages_per_second: 200,
            bot_burst: 400,
            send_timeout_ms: 5000,
            request_timeout_ms: 10_000,
            max_body_bytes: 64 * 1024,
            replay_dir: None,
            stamp_frames: false,
            allowed_origins: Vec::new(),
            max_connections_per_ip: 256,
            agones_sdk_port: None,
        }
    }
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
    use super::ServerConfig;

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
        assert!(check(|c| c.allowed_origins = vec!["example.com".into()])
            .starts_with("allowed_origins:"));
    }
}
