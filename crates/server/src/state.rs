//! What the server shares between requests: the matches and their handles, the motion
//! capabilities, the admin token, the metrics.

use super::config::ServerConfig;
use super::metrics::Metrics;
use fieldhouse_core::basketball::Capabilities;
use fieldhouse_core::driver::Event;
use fieldhouse_core::protocol::MatchInfo;
use fieldhouse_core::sim::{Mode, Scenario};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64};
use std::sync::{Arc, Mutex, OnceLock, RwLock};
use std::time::Instant;
use tokio::sync::{mpsc, watch};
use tokio_tungstenite::tungstenite::Utf8Bytes;

/// What a match task sends a bot's socket. A perception carries its tick: the bot owes
/// one answer to it, and that answer is never charged to its rate limit. The last
/// message of a connection another one took over says so, and the socket closes after it.
#[derive(Debug)]
pub struct ToBot {
    pub text: Utf8Bytes,
    pub perception: Option<u64>,
    pub replaced: bool,
}

impl ToBot {
    pub fn message(text: String) -> ToBot {
        ToBot {
            text: Utf8Bytes::from(text),
            perception: None,
            replaced: false,
        }
    }
    pub fn perception(tick: u64, text: String) -> ToBot {
        ToBot {
            perception: Some(tick),
            ..ToBot::message(text)
        }
    }
    pub fn replaced(text: String) -> ToBot {
        ToBot {
            replaced: true,
            ..ToBot::message(text)
        }
    }
}

/// What sockets and the API tell a match task: what its driver is to handle, and a
/// bot's arrival, which also brings the queue the task sends that bot's messages to.
pub enum Control {
    /// A bot connected to agent `agent` on connection `conn`; its messages go to `out`.
    BotJoin {
        agent: usize,
        conn: u64,
        out: mpsc::Sender<ToBot>,
    },
    /// Anything else, passed to the match's driver as it is.
    Driver(Event),
    /// Makes the match task panic, standing for a bug, to test that a panic ends the
    /// match cleanly.
    #[cfg(test)]
    Panic,
}

pub struct MatchEntry {
    pub info: MatchInfo,
    pub mode: Mode,
    pub scenario: Scenario,
    pub published: watch::Receiver<super::fanout::Published>,
    pub control: mpsc::Sender<Control>,
    /// Bot tokens: (agent index, agent id, token).
    pub tokens: Vec<(usize, String, String)>,
    pub spectators: AtomicU64,
    pub tick: AtomicU64,
    pub ended: AtomicBool,
    /// When it ended: an ended match is listed for `ended_match_ttl_s` after this,
    /// then swept from the table.
    pub ended_at: OnceLock<Instant>,
    /// Who controls each agent now (`true`: a bot).
    pub controlled: Mutex<Vec<bool>>,
    /// The id of the replay file it is recording into now, if the server records
    /// matches: a match that rotates its replay into segments names the newest, which
    /// retention keeps while it is written (the first may be long gone).
    pub replay: Arc<Mutex<Option<String>>>,
    /// Why recording stopped, if it did.
    pub replay_error: Mutex<Option<String>>,
    /// Its spectators, to whom its frames are written.
    pub fanout: super::fanout::Fanout,
}

pub struct AppState {
    /// Where match tasks run: a runtime apart from the sockets' (see `serve`).
    pub ticking: tokio::runtime::Handle,
    pub config: ServerConfig,
    pub admin_token: crate::auth::AdminToken,
    pub caps: Arc<Capabilities>,
    pub metrics: Arc<Metrics>,
    pub matches: RwLock<BTreeMap<String, Arc<MatchEntry>>>,
    pub shutdown: watch::Receiver<bool>,
    pub next_conn: AtomicU64,
    /// Where matches are recorded, if anywhere.
    pub replay_dir: Option<std::path::PathBuf>,
    /// The replays being written and the indexes being watched.
    pub replays: super::replay_dir::Replays,
    /// Told when a recording finishes, so retention looks at the directory then too.
    pub replay_written: tokio::sync::Notify,
    /// Open connections, per client address and in all.
    pub connections: Arc<super::listener::Connections>,
}

impl AppState {
    pub fn get(&self, id: &str) -> Option<Arc<MatchEntry>> {
        self.matches.read().expect("not poisoned").get(id).cloned()
    }
}
