//! The WebSocket protocol, version 3: every message is a JSON object with a `"type"`,
//! and every message is a Rust type here. `PROTOCOL.md` explains them for bot authors;
//! the JSON Schemas in `proto/` are generated from these types ([`crate::schemas`]).
//! Fields are only ever added; a breaking change bumps [`VERSION`].
//!
//! Server to client: [`Hello`] (first, always), [`Frame`] (spectators), [`Perception`]
//! (bots), [`End`], [`ErrorMessage`]. Client to server: [`ClientMessage`] (bots'
//! `command`s) and [`ViewerMessage`] (replay viewers' `control`s).
//!
//! # Layout
//!
//! * this file: the messages, and [`decode`] / [`encode`] / [`write_frame`];
//! * [`fly`] and [`hoops`]: what a message holds for each sport (the sport-specific
//!   parts are untagged enums of the two: a client tells them apart by `hello`'s
//!   `match.sport`);
//! * `quantise`: frames are written with their floats rounded to a millimetre.

pub mod fly;
pub mod hoops;
#[cfg(test)]
mod key_order_tests;
mod quantise;

use crate::strict_json::{self, Refused};
use crate::tags;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use serde_json::Value;

/// The protocol's name, sent in every `hello` so a client knows what it is talking to.
pub const PROTOCOL: &str = "fieldhouse";
/// The protocol's version: within it fields are only added; a breaking change bumps it,
/// and so does any change of the frames' bytes, since replays record the version their
/// frames were written in and are verified byte for byte ([`FrameShape`]).
///
/// 3: basketball players carry their pose's blend across cuts (`blend`) and, when it
/// differs from `behaviour`, the graph their `node` is of (`graph`).
pub const VERSION: u32 = 3;

/// The oldest version whose frames this build still writes (to verify a replay recorded
/// in it).
pub const OLDEST_VERSION: u32 = 2;

/// Frames as a version of the protocol wrote them. Replays recorded in an older version
/// are verified by re-simulating and writing the frames as that version did: the world
/// is the same, only the fields a later version added are left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameShape(u32);

impl FrameShape {
    /// Frames as this build sends them.
    pub const CURRENT: FrameShape = FrameShape(VERSION);

    /// Frames as protocol `version` wrote them, if this build can still write them.
    pub fn of_version(version: u32) -> Result<FrameShape, String> {
        if (OLDEST_VERSION..=VERSION).contains(&version) {
            Ok(FrameShape(version))
        } else {
            Err(format!(
                "frames of protocol version {version}: this build writes versions \
                 {OLDEST_VERSION} to {VERSION}"
            ))
        }
    }

    /// The version.
    pub fn version(self) -> u32 {
        self.0
    }

    /// Leaves out of `agents` what this version's frames did not have.
    pub fn shape(self, agents: &mut [Agent<'_>]) {
        if self.0 < 3 {
            for agent in agents {
                if let Agent::Player(p) = agent {
                    p.blend = None;
                    p.graph = None;
                }
            }
        }
    }
}

/// Everything static about a match, as `hello` and `GET /api/matches/{id}` show it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct MatchInfo {
    /// The match's id, as in its URLs.
    pub id: String,
    /// The scenario's name, if it gave one.
    pub name: Option<String>,
    /// `baseball`, `cricket` or `basketball`: which shapes `field`, `agents` and the
    /// frames' `ball`, `agents` and `score` take.
    #[schemars(extend("enum" = ["baseball", "cricket", "basketball"]))]
    pub sport: &'static str,
    /// `realtime`, `fast` or `lockstep`: how ticks are paced (see the scenario's `mode`).
    #[schemars(extend("enum" = ["realtime", "fast", "lockstep"]))]
    pub mode: &'static str,
    /// The seed of every random draw in the match: the same seed, the same match.
    pub seed: u64,
    /// Simulation ticks per second of match time, Hz.
    pub tick_hz: f64,
    /// Frames sent to spectators per second of match time, Hz.
    pub frame_hz: f64,
    /// Bots get a `perception` every this many ticks, and answer with a `command`.
    #[schemars(range(min = 1))]
    pub perception_every_ticks: u64,
    /// The field as a client draws it.
    pub field: Field,
    /// Each agent's static description, in the order of every frame's `agents`.
    pub agents: Vec<AgentInfo>,
    /// Where the motion data came from, in words and without any path of the server's
    /// ([`crate::motion::MotionSource`]'s `Display`); for baseball and cricket, whose
    /// fielders use none, [`crate::sim::NO_MOTION`].
    pub motion_source: String,
}

/// The field of a match, by sport.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Field {
    /// Baseball.
    Baseball(fly::BaseballField),
    /// Cricket.
    Cricket(fly::CricketField),
    /// Basketball.
    Basketball(hoops::Field),
}

/// An agent's static description, by sport.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum AgentInfo {
    /// A fielder (baseball, cricket).
    Fielder(fly::FielderInfo),
    /// A basketball player.
    Player(hoops::PlayerInfo),
}

/// Limits a client must respect, announced in `hello`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Limits {
    /// Largest message the server reads, bytes; a larger one closes the socket with
    /// 1009.
    pub max_message_bytes: usize,
    /// Sustained messages per second a bot may send beyond one answer per perception
    /// (those are never counted); flooding closes with 1008.
    pub messages_per_second: u32,
}

/// Who a connection is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    /// `/ws/matches/{id}`: watches a match.
    Spectator,
    /// `/ws/matches/{id}/play`: controls an agent.
    Bot,
    /// `/ws/replays/{id}`: a recorded match played back, which takes `control` messages.
    Replay,
}

/// Server to client: the first message on every socket, spectator, bot or replay
/// viewer. It names the protocol and version, the role, everything static about the
/// match (the same `match` object `GET /api/matches/{id}` shows; for a replay, the one
/// recorded in the file's header), the agent a bot controls, what a replay holds, and
/// the limits a client must respect. Fields may be added in later releases of version
/// 3; ignore those you do not know.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(title = "hello")]
pub struct Hello<'a, M: Serialize = MatchInfo> {
    /// Always `hello`.
    #[serde(rename = "type")]
    pub kind: tags::Hello,
    /// Always `fieldhouse`.
    pub protocol: tags::Fieldhouse,
    /// Protocol version. A breaking change bumps it; within a version fields are only
    /// added.
    #[schemars(extend("const" = 3))]
    pub version: u32,
    /// Who this connection is.
    pub role: Role,
    /// Everything static about the match.
    #[serde(rename = "match")]
    pub match_info: &'a M,
    /// Bots only: the id of the agent this connection controls.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub agent: Option<&'a str>,
    /// Replay viewers only: what the replay file holds. Its frames follow, paced as
    /// recorded; then an `end`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replay: Option<ReplayInfo<'a>>,
    /// What the client must respect.
    pub limits: Limits,
}

impl<'a, M: Serialize> Hello<'a, M> {
    /// A `hello` of this protocol and version.
    pub fn new(role: Role, match_info: &'a M, limits: Limits) -> Self {
        Hello {
            kind: tags::Hello,
            protocol: tags::Fieldhouse,
            version: VERSION,
            role,
            match_info,
            agent: None,
            replay: None,
            limits,
        }
    }
}

/// What a replay file holds, as its viewers' `hello` says.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct ReplayInfo<'a> {
    /// Whether the file ends with its footer (the match was over when it was written).
    pub complete: bool,
    /// The tick of its first frame; null without frames.
    pub first_tick: Option<u64>,
    /// How many frames it holds, as its footer says; null for a file without one (the
    /// match is still running, or the file was cut), whose frames are counted only by
    /// reading them all.
    pub frames: Option<u64>,
    /// The replay's id (its file name without `.jsonl.zst`, or `.jsonl` for a format 1
    /// file), as in `GET /api/replays`.
    pub id: &'a str,
    /// The tick of its last frame; null without frames.
    pub last_tick: Option<u64>,
    /// The protocol version its frames were written in (2 for a file that does not say):
    /// a replay recorded before version 3 has frames without version 3's fields.
    pub protocol: u32,
}

/// Server to client (spectators and replay viewers; a replay's frames are the recorded
/// ones, byte for byte): the whole world at one tick, with the events since the previous
/// frame. Sent frame_hz times per simulated second; a spectator that falls behind skips
/// to the newest frame (the skipped frames' events are lost to it). The shapes of
/// `ball`, `agents`, `score` and the events depend on the sport. Objects may gain fields
/// in later releases of version 3, and new event kinds may appear; ignore what you do not
/// know. Numbers are rounded to a millimetre, a milliradian, a millisecond.
///
/// A server started with `--stamp-frames` adds `"sent_us"` (when the frame was
/// published, µs since the Unix epoch) right after `type`, for measuring latency on the
/// same host; replay files never have it.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(title = "frame")]
pub struct Frame<'a> {
    /// Always `frame`.
    #[serde(rename = "type")]
    pub kind: tags::Frame,
    /// The match's id.
    #[serde(rename = "match")]
    pub match_id: &'a str,
    /// The tick this frame shows.
    pub tick: u64,
    /// Match time, s: `tick / tick_hz`.
    pub time_s: f64,
    /// The ball now.
    pub ball: Ball<'a>,
    /// Every agent now, in the order of `hello`'s `match.agents`.
    pub agents: Vec<Agent<'a>>,
    /// The score so far.
    pub score: Score,
    /// What happened since the previous frame, in order.
    pub events: &'a [Event],
}

/// The ball in a frame, by sport.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Ball<'a> {
    /// Baseball, cricket.
    Fly(fly::Ball),
    /// Basketball.
    Hoops(hoops::Ball<'a>),
}

/// An agent in a frame, by sport.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Agent<'a> {
    /// A fielder (baseball, cricket).
    Fielder(fly::Fielder<'a>),
    /// A basketball player.
    Player(hoops::Player<'a>),
}

/// The score, by sport: a frame's `score`, an `end`'s `result`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Score {
    /// Baseball, cricket: balls.
    Fly(fly::Score),
    /// Basketball: points.
    Hoops(hoops::Score),
}

/// Something that happened, by sport (`kind` names it).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Event {
    /// Baseball, cricket.
    Fly(fly::Event),
    /// Basketball.
    Hoops(hoops::Event),
}

/// Server to client (spectators, bots and replay viewers): the match is over. On a live
/// match it is the last message: the server then closes the socket with code 1000, or
/// 1001 when the server is shutting down (reason `shutdown`); spectators get the final
/// frame just before it. On a replay (`/ws/replays/{id}`) it follows the last frame each
/// time playback reaches it, and the socket stays open, paused, for more `control`
/// messages.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(title = "end")]
pub struct End<'a, R: Serialize = Score> {
    /// Always `end`.
    #[serde(rename = "type")]
    pub kind: tags::End,
    /// The match's id.
    #[serde(rename = "match")]
    pub match_id: &'a str,
    /// The last tick played (a replay: the tick of its last frame).
    pub tick: u64,
    /// `finished`: duration_s, options.possessions (basketball) or the last of
    /// options.launches (baseball, cricket) reached; `deleted`: DELETE
    /// /api/matches/{id}; `shutdown`: the server is stopping; `error`: the server failed
    /// while running the match (a bug, logged; the result may be null). A replay gives
    /// the reason its file's footer recorded, or `incomplete` when the file has no
    /// footer (the match was still running, or the process died), `size_limit` or
    /// `rotated` when the server stopped recording it in that file.
    #[schemars(extend("enum" = ["finished", "deleted", "shutdown", "error", "incomplete", "size_limit", "rotated"]))]
    pub reason: &'a str,
    /// The final score: the frames' `score` object for the sport; null when it is not
    /// known.
    pub result: Option<&'a R>,
}

/// Server to client (bots only): what the bot's agent perceives at `tick`, sent every
/// perception_every_ticks ticks (see hello) while the bot is connected. Answer it with
/// a `command` carrying the same `tick`. A fielder (baseball, cricket) sees its own body
/// and the ball only as an eye sees it; a basketball player sees the whole court.
/// Numbers are not rounded. Objects may gain fields in later releases of version 3;
/// ignore what you do not know.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(title = "perception")]
pub struct Perception<'a> {
    /// Always `perception`.
    #[serde(rename = "type")]
    pub kind: tags::Perception,
    /// The tick perceived, which the bot's `command` names.
    pub tick: u64,
    /// Match time, s: `tick / tick_hz`.
    pub time_s: f64,
    /// The agent this connection controls.
    pub agent: &'a str,
    /// What it perceives.
    pub perception: Sensed<'a>,
}

/// What an agent perceives, by sport.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
pub enum Sensed<'a> {
    /// A fielder (baseball, cricket).
    Fielder(fly::Sensed),
    /// A basketball player.
    Player(hoops::Sensed<'a>),
}

/// Server to client (bots and replay viewers): something was wrong with a message the
/// client sent, or with what it asked. The connection stays open. Codes for bots:
/// `malformed_json` (not JSON, or a number too large for a double), `bad_message` (JSON,
/// but not a valid command: unknown type, unknown or missing field, wrong type, a key
/// given twice), `binary` (a binary frame), `rate_limited` (messages are being dropped
/// for exceeding the rate), `rejected` (a valid command the agent cannot carry out:
/// wrong sport, no ball, target out of range, ...), `stale_tick` (the command's tick is
/// more than 4 perception periods old), `future_tick` (more than one period ahead),
/// `replaced` (another connection with this agent's token took over; this one gets
/// nothing more). For replay viewers every refused `control` message gets
/// `bad_control`. New codes may be added; treat an unknown one as a generic error.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(title = "error")]
pub struct ErrorMessage<'a> {
    /// Always `error`.
    #[serde(rename = "type")]
    pub kind: tags::Error,
    /// What kind of error, for programs (see above).
    #[schemars(regex(pattern = "^[a-z][a-z_]*$"))]
    pub code: &'a str,
    /// What is wrong, for people.
    pub message: &'a str,
}

impl<'a> ErrorMessage<'a> {
    /// An `error` with this code and message.
    pub fn new(code: &'a str, message: &'a str) -> Self {
        ErrorMessage {
            kind: tags::Error,
            code,
            message,
        }
    }
}

/// Client to server (bots only): the action for the bot's agent, answering the
/// perception of `tick`. The server parses it strictly: an unknown field anywhere, a key
/// given twice at any depth, a missing field, a wrong type or a wrong array length is
/// answered with an `error` of code `bad_message` (invalid JSON: `malformed_json`) and
/// the command is ignored. A well-formed command can still be refused for what it asks
/// (`rejected`, `stale_tick`, `future_tick`). Fielders (baseball, cricket) accept
/// accelerate, run_to and stand; basketball players accept move_to, pass, shoot and
/// stand. Write `tick` as an integer literal: the server does not accept `5.0` for 5.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
#[schemars(title = "command")]
pub enum ClientMessage {
    /// The action for its agent, answering the perception of `tick`.
    Command {
        /// The tick of the perception this answers. More than 4 perception periods
        /// (4 × perception_every_ticks) behind the match: `stale_tick`; more than one
        /// period ahead: `future_tick`.
        tick: u64,
        /// What the agent is to do.
        action: Action,
    },
}

/// What a bot asks of its agent.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Fielder: accelerate along `[ax, az]`, m/s² (clamped to the body's limits).
    Accelerate {
        /// `[ax, az]`, m/s², on the ground plane.
        accel: [f64; 2],
    },
    /// Fielder: run to `[x, z]` and stop there.
    RunTo {
        /// `[x, z]`, m, within 250 m of the batter.
        target: [f64; 2],
    },
    /// Basketball: move toward `[x, z]` (dribbling if holding the ball) until within
    /// 0.75 m of it.
    MoveTo {
        /// `[x, z]`, m, on the court (within 1 m of it).
        target: [f64; 2],
    },
    /// Basketball: pass to the teammate with this id.
    Pass {
        /// The receiver's agent id.
        to: String,
    },
    /// Basketball: shoot from here.
    Shoot {},
    /// Stop: a fielder decelerates to rest, a player stands.
    Stand {},
}

impl Action {
    /// The action's `kind`.
    pub fn name(&self) -> &'static str {
        match self {
            Action::Accelerate { .. } => "accelerate",
            Action::RunTo { .. } => "run_to",
            Action::MoveTo { .. } => "move_to",
            Action::Pass { .. } => "pass",
            Action::Shoot {} => "shoot",
            Action::Stand {} => "stand",
        }
    }
}

/// Client to server (replay viewers only, on `/ws/replays/{id}`): controls the playback
/// of a recorded match. The server parses it strictly: an unknown type or action, an
/// unknown or missing field, or a wrong type is answered with an `error` of code
/// `bad_control` (so is text that is not JSON) and the message is ignored; so is a speed
/// outside 0.25 to 8 and a seek past the last frame. Playback starts at once, at speed
/// 1: frames are sent at the recorded pace; after the last frame comes an `end`, and the
/// socket stays open, paused. Write `tick` as an integer literal.
#[derive(Debug, Clone, PartialEq, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
#[schemars(title = "control")]
pub enum ViewerMessage {
    /// A playback control.
    Control(Control),
}

/// What a replay viewer asks.
#[derive(Debug, Clone, PartialEq, Deserialize, JsonSchema)]
#[serde(tag = "action", rename_all = "snake_case", deny_unknown_fields)]
pub enum Control {
    /// Resume playback from the next frame, which is sent at once. After the `end`,
    /// playback has nothing left to play: seek first.
    Play {},
    /// Stop sending frames until `play`.
    Pause {},
    /// Play at this multiple of the recorded pace, 0.25 to 8.
    Speed {
        /// The multiple.
        speed: f64,
    },
    /// Go to the first frame at or after `tick`, send it at once, and keep the state of
    /// playing or paused.
    Seek {
        /// The tick to go to.
        tick: u64,
        /// Also send, at once and before it, the frames of up to this many seconds
        /// before `tick` (0 to [`MAX_LEAD_IN_S`]): what led there, so a viewer can show
        /// the flight so far or the latest decision, not only the moment it landed on.
        #[serde(default)]
        lead_in_s: Option<f64>,
    },
}

/// The longest lead-in a `seek` may ask for, s: a fly ball's whole flight (the longest
/// catchable ones stay up about 7 s) with room to spare, and at 30 frames a second at
/// most 450 frames sent at once.
pub const MAX_LEAD_IN_S: f64 = 15.0;

/// Reads a message the way clients' messages are read: strictly (a key given twice at
/// any depth is refused, and only objects are messages: serde would otherwise also read
/// a struct from an array). Errors are `(code, message)` with code `malformed_json` (not
/// JSON at all) or `bad_message` (JSON, but not a message we know).
fn read_strictly<T: serde::de::DeserializeOwned>(
    text: &str,
    nested: Option<&str>,
) -> Result<T, (&'static str, String)> {
    let value = strict_json::parse(text.as_bytes()).map_err(|e| match e {
        Refused::Malformed(m) => ("malformed_json", m),
        duplicate @ Refused::DuplicateKey { .. } => ("bad_message", duplicate.to_string()),
    })?;
    let is_object = |v: &Value| v.is_object();
    if !is_object(&value) || nested.is_some_and(|n| value.get(n).is_some_and(|v| !is_object(v))) {
        return Err((
            "bad_message",
            match nested {
                Some(n) => format!("a message and its {n} are JSON objects"),
                None => "a message is a JSON object".into(),
            },
        ));
    }
    serde_json::from_value(value).map_err(|e| ("bad_message", e.to_string()))
}

/// Reads a bot's message, or says what is wrong with it: `(code, message)` with code
/// `malformed_json` (not JSON at all) or `bad_message` (JSON, but not a command,
/// including one that names a key twice).
pub fn decode(text: &str) -> Result<ClientMessage, (&'static str, String)> {
    read_strictly(text, Some("action"))
}

/// Reads a replay viewer's message, or says what is wrong with it.
pub fn decode_control(text: &str) -> Result<ViewerMessage, String> {
    read_strictly(text, None).map_err(|(_, message)| message)
}

/// Serialises a message (they always serialise: their fields are plain data).
pub fn encode(message: &impl Serialize) -> String {
    serde_json::to_string(message).expect("protocol messages serialise")
}

/// Appends a frame to `out`, its numbers rounded to a millimetre (see `quantise`).
/// What is appended is UTF-8 JSON on one line.
pub fn write_frame(out: &mut Vec<u8>, frame: &Frame<'_>) {
    quantise::write(out, frame);
}

#[cfg(test)]
mod tests {
    use super::{decode, decode_control, Control, ViewerMessage};

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

    #[test]
    fn a_viewer_control_is_read_strictly() {
        assert_eq!(
            decode_control(r#"{"type":"control","action":"seek","tick":5}"#),
            Ok(ViewerMessage::Control(Control::Seek {
                tick: 5,
                lead_in_s: None
            }))
        );
        for bad in [
            r#"[{"type":"control","action":"play"}]"#,
            r#"{"type":"control","action":"play","extra":1}"#,
            r#"{"type":"control","action":"seek","tick":5.0}"#,
            r#"{"type":"control","action":"play","action":"pause"}"#,
        ] {
            assert!(decode_control(bad).is_err(), "{bad}");
        }
    }
}
