//! What the server shares between requests: the matches and their handles, the motion
//! capabilities, the admin token, the metrics.

use super::config::ServerConfig;
use super::metrics::Metrics;
use fieldhouse_core::basketball::Capabilities;
use fieldhouse_core::driver::{BotEvent, Close, Conn};
use fieldhouse_core::protocol::MatchInfo;
use fieldhouse_core::sim::{Mode, Scenario};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicU64};
use std::sync::{Arc, Mutex, OnceLock, RwLock};
use tokio::sync::{mpsc, oneshot, watch};
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::Utf8Bytes;

/// What sockets and the API tell a match task: what its driver is to handle, a bot's
/// arrival, which also brings where the task reaches that connection, and a stop.
pub enum ToMatch {
    /// A bot connected to agent `agent` on connection `conn`; its messages go to `out`,
    /// and `close` closes it.
    Join {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The connection.
        conn: Conn,
        /// The socket's queue of messages to send.
        out: mpsc::Sender<Utf8Bytes>,
        /// Closes the socket, after what is queued.
        close: oneshot::Sender<Close>,
    },
    /// Anything else a bot connection did, passed to the match's driver as it is.
    Driver(BotEvent),
    /// The API deleted the match.
    Stop,
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
    pub control: mpsc::Sender<ToMatch>,
    /// Bot tokens: (agent index, agent id, token).
    pub tokens: Vec<(usize, String, String)>,
    pub spectators: AtomicU64,
    pub tick: AtomicU64,
    pub ended: AtomicBool,
    /// When it ended: an ended match is listed for `ended_match_ttl_s` after this,
    /// then swept from the table.
    pub ended_at: OnceLock<Instant>,
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
