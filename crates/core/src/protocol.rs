//! The WebSocket protocol, version 2: every message is a JSON object with a `"type"`.
//! Each type has a JSON Schema in `proto/<type>.schema.json`, and `PROTOCOL.md` explains
//! them for bot authors. Fields are only ever added; a breaking change bumps [`VERSION`].
//!
//! Server to client: `hello` (first, always), `frame` (spectators), `perception`
//! (bots), `end`, `error`. Client to server: `command` (bots).

use crate::sim::Action;
use crate::strict_json::{self, Refused};
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The protocol's name, sent in every `hello` so a client knows what it is talking to.
pub const PROTOCOL: &str = "fieldhouse";
/// The protocol's version: within it fields are only added; a breaking change bumps it.
pub const VERSION: u32 = 2;

/// Everything static about a match, as `hello` and `GET /api/matches/{id}` show it.
#[derive(Debug, Clone, Serialize)]
pub struct MatchInfo {
    /// The match's id, as in its URLs.
    pub id: String,
    /// The scenario's name, if it gave one.
    pub name: Option<String>,
    /// `baseball`, `cricket` or `basketball`.
    pub sport: &'static str,
    /// `realtime`, `fast` or `lockstep`: how ticks are paced.
    pub mode: &'static str,
    /// The seed of every random draw in the match: the same seed, the same match.
    pub seed: u64,
    /// Simulation ticks per second of match time, Hz.
    pub tick_hz: f64,
    /// Frames sent to spectators per second of match time, Hz.
    pub frame_hz: f64,
    /// Bots get a `perception` every this many ticks, and answer with a `command`.
    pub perception_every_ticks: u64,
    /// The field as a client draws it; its shape depends on the sport (PROTOCOL.md).
    pub field: Value,
    /// Each agent's static description: id, team, strategy (and a fielder's home).
    pub agents: Vec<Value>,
    /// Where the motion data came from, named without any path of the server's
    /// ([`crate::motion::MotionSource`]'s `Display`).
    pub motion_source: String,
}

/// Limits a client must respect, announced in `hello`.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Limits {
    /// Largest message the server reads; a larger one closes the socket with 1009.
    pub max_message_bytes: usize,
    /// Sustained messages per second a bot may send beyond one answer per perception
    /// (those are never counted); flooding closes with 1008.
    pub messages_per_second: u32,
}

/// The first message on every socket: the protocol, the client's role, the match and
/// the limits.
#[derive(Debug, Clone, Serialize)]
pub struct Hello<'a> {
    /// Always `hello`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Always [`PROTOCOL`].
    pub protocol: &'static str,
    /// Always [`VERSION`].
    pub version: u32,
    /// `spectator` or `bot`.
    pub role: &'static str,
    /// Everything static about the match.
    #[serde(rename = "match")]
    pub match_info: &'a MatchInfo,
    /// The agent a bot controls.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agent: Option<&'a str>,
    /// What the client must respect.
    pub limits: Limits,
}

impl<'a> Hello<'a> {
    /// A `hello` of this protocol and version.
    pub fn new(
        role: &'static str,
        match_info: &'a MatchInfo,
        agent: Option<&'a str>,
        limits: Limits,
    ) -> Self {
        Hello {
            kind: "hello",
            protocol: PROTOCOL,
            version: VERSION,
            role,
            match_info,
            agent,
            limits,
        }
    }
}

/// The world at one tick, with the events since the previous frame.
#[derive(Debug, Clone, Serialize)]
pub struct Frame<'a> {
    /// Always `frame`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// The match's id.
    #[serde(rename = "match")]
    pub match_id: &'a str,
    /// The tick this frame shows.
    pub tick: u64,
    /// Match time, s: `tick / tick_hz`, to the millisecond.
    pub time_s: f64,
    /// The ball now; its shape depends on the sport (PROTOCOL.md).
    pub ball: &'a Value,
    /// Every agent now, in the order of `hello`'s `agents`.
    pub agents: &'a [Value],
    /// The score so far.
    pub score: &'a Value,
    /// What happened since the previous frame (launches, catches, passes, shots…).
    pub events: &'a [Value],
}

/// The last message of a match's sockets: why it ended, and its result.
#[derive(Debug, Clone, Serialize)]
pub struct End<'a> {
    /// Always `end`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// The match's id.
    #[serde(rename = "match")]
    pub match_id: &'a str,
    /// The tick the match ended on.
    pub tick: u64,
    /// `finished`, `deleted`, `shutdown` or `error` (the server failed running it).
    pub reason: &'a str,
    /// The final score.
    pub result: &'a Value,
}

/// What a bot's agent perceives at a tick; the bot answers with a `command` for it.
#[derive(Debug, Clone, Serialize)]
pub struct Perception<'a> {
    /// Always `perception`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// The tick perceived, which the bot's `command` names.
    pub tick: u64,
    /// Match time, s: `tick / tick_hz`.
    pub time_s: f64,
    /// The id of the agent perceiving.
    pub agent: &'a str,
    /// What the agent perceives; its shape depends on the sport (PROTOCOL.md).
    pub perception: &'a Value,
}

/// An error about a client's message; the connection stays open.
#[derive(Debug, Clone, Serialize)]
pub struct ErrorMessage<'a> {
    /// Always `error`.
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// What kind of error, for programs: `malformed_json`, `bad_message`, `rate_limited`…
    pub code: &'a str,
    /// What is wrong, for people.
    pub message: &'a str,
}

impl<'a> ErrorMessage<'a> {
    /// An `error` with this code and message.
    pub fn new(code: &'a str, message: &'a str) -> Self {
        ErrorMessage {
            kind: "error",
            code,
            message,
        }
    }
}

/// What a bot sends.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMessage {
    /// The action for its agent, answering the perception of `tick`.
    Command {
        /// The tick of the perception this answers.
        tick: u64,
        /// What the agent is to do.
        action: Action,
    },
}

/// Reads a client's message, or says what is wrong with it: `(code, message)` with code
/// `malformed_json` (not JSON at all) or `bad_message` (JSON, but not a message we know,
/// including one that names a key twice). Only objects are messages: serde would
/// otherwise also read a struct from an array.
pub fn decode(text: &str) -> Result<ClientMessage, (&'static str, String)> {
    let value = strict_json::parse(text.as_bytes()).map_err(|e| match e {
        Refused::Malformed(m) => ("malformed_json", m),
        duplicate @ Refused::DuplicateKey { .. } => ("bad_message", duplicate.to_string()),
    })?;
    let is_object = |v: &Value| v.is_object();
    if !is_object(&value) || value.get("action").is_some_and(|a| !is_object(a)) {
        return Err((
            "bad_message",
            "a message and its action are JSON objects".into(),
        ));
    }
    serde_json::from_value(value).map_err(|e| ("bad_message", e.to_string()))
}

/// Serialises a message (they always serialise: their fields are plain data).
pub fn encode(message: &impl Serialize) -> String {
    serde_json::to_string(message).expect("protocol messages serialise")
}

#[cfg(test)]
mod tests {
    use super::decode;

    #[test]
    fn a_message_naming_a_key_twice_is_refused_at_any_depth() {
        assert!(decode(r#"{"type":"command","tick":3,"action":{"kind":"stand"}}"#).is_ok());
        for twice in [
            r#"{"type":"command","tick":3,"tick":99,"action":{"kind":"stand"}}"#,
            r#"{"type":"command","tick":3,"action":{"kind":"stand","kind":"shoot"}}"#,
        ] {
            let (code, message) = decode(twice).unwrap_err();
            assert_eq!(code, "bad_message", "{twice}");
            assert!(message.contains("duplicate key"), "{message}");
        }
        assert_eq!(decode(r#"{"type":"#).unwrap_err().0, "malformed_json");
    }
}
