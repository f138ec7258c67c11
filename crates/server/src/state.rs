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

/// A match as the rest of the server sees it: what it is, how to reach its task, and
/// what its task publishes. The match itself (world, seats, end) is its task's driver's.
pub struct MatchEntry {
    /// Its id, name, sport, agents and rates, as `hello` and the API give them.
    pub info: MatchInfo,
    /// How it is paced.
    pub mode: Mode,
    /// The scenario it was made from, as the API shows it.
    pub scenario: Scenario,
    /// Its newest frame and, once it has ended, its `end`, for spectators, bots and the
    /// API.
    pub published: watch::Receiver<super::fanout::Published>,
    /// Where bot sockets and the API reach its task.
    pub control: mpsc::Sender<ToMatch>,
    /// Bot tokens: (agent index, agent id, token).
    pub tokens: Vec<(usize, String, String)>,
    /// How many spectators watch it now.
    pub spectators: AtomicU64,
    /// The tick it is at, as its task last said.
    pub tick: AtomicU64,
    /// Whether it has ended (its `end` is published).
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

/// What every request handler, socket and match task of one server shares.
pub struct AppState {
    /// Where match tasks run: a runtime apart from the sockets' (see `serve`).
    pub ticking: tokio::runtime::Handle,
    /// The server's settings.
    pub config: ServerConfig,
    /// The token the API's writes need.
    pub admin_token: crate::auth::AdminToken,
    /// The motion capabilities basketball matches are built with.
    pub caps: Arc<Capabilities>,
    /// The counters and histograms `/metrics` shows.
    pub metrics: Arc<Metrics>,
    /// The matches, running and recently ended, by id.
    pub matches: RwLock<BTreeMap<String, Arc<MatchEntry>>>,
    /// Becomes true when the server starts shutting down.
    pub shutdown: watch::Receiver<bool>,
    /// The next bot connection's number ([`fieldhouse_core::driver::Conn`]).
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
    /// The match with id `id`, if the table has it.
    pub fn get(&self, id: &str) -> Option<Arc<MatchEntry>> {
        self.matches.read().expect("not poisoned").get(id).cloned()
    }
}
