//! A `fieldhouse serve` for integration tests, and the WebSocket helpers that talk to
//! it: the real binary on a free loopback port, messages checked against proto/.

use futures_util::StreamExt;
use serde_json::{json, Value};
use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio_tungstenite::tungstenite::Message;

pub(crate) const ADMIN: &str = "test-admin-token-0123456789";

/// A `fieldhouse serve` on a free loopback port, killed when dropped.
pub(crate) struct Server {
    pub child: Child,
    pub addr: String,
    /// Everything the server has written to stderr so far, a line each.
    pub log: Arc<Mutex<Vec<String>>>,
}

impl Server {
    pub(crate) fn start(extra: &[&str]) -> Server {
        Server::launch(&[], "info", extra)
    }

    /// A server started by `wrapper` (a command line that runs the one after it, like
    /// `unshare -m sh -c '...; exec "$0" "$@"'`), logging at `log` level.
    pub(crate) fn launch(wrapper: &[&str], log: &str, extra: &[&str]) -> Server {
        let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("server-cache");
        let binary = env!("CARGO_BIN_EXE_fieldhouse");
        let mut command = match wrapper.split_first() {
            Some((program, args)) => {
                let mut c = Command::new(program);
                c.args(args).arg(binary);
                c
            }
            None => Command::new(binary),
        };
        let mut child = command
            .args(["serve", "--addr", "127.0.0.1:0"])
            .arg("--cache-dir")
            .arg(&cache)
            .args(extra)
            .env("FIELDHOUSE_ADMIN_TOKEN", ADMIN)
            .env("FIELDHOUSE_LOG", log)
            .env_remove("FIELDHOUSE_ADDR")
            .env_remove("FIELDHOUSE_MOCAP_DIR")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the binary starts");
        let stderr = BufReader::new(child.stderr.take().unwrap());
        let (tx, rx) = std::sync::mpsc::channel();
        let log = Arc::new(Mutex::new(Vec::new()));
        let lines = log.clone();
        std::thread::spawn(move || {
            let mut tx = Some(tx);
            for line in stderr.lines().map_while(Result::ok) {
                lines.lock().unwrap().push(line.clone());
                if let Some(at) = line.find("http://") {
                    let addr: String = line[at + 7..].chars().take_while(|c| *c != '/').collect();
                    if let Some(tx) = tx.take() {
                        let _ = tx.send(addr);
                    }
                }
            }
        });
        let addr = rx
            .recv_timeout(Duration::from_secs(120))
            .expect("the server says where it listens");
        Server { child, addr, log }
    }

    pub(crate) fn http(&self, path: &str) -> String {
        format!("http://{}{path}", self.addr)
    }

    pub(crate) fn ws(&self, path: &str) -> String {
        format!("ws://{}{path}", self.addr)
    }

    pub(crate) fn get(&self, path: &str) -> Value {
        ureq::get(&self.http(path))
            .call()
            .unwrap()
            .into_json()
            .unwrap()
    }

    /// Creates a match; returns its id and bot tokens.
    pub(crate) fn create(&self, scenario: Value) -> (String, Value) {
        self.create_at("/api/matches", scenario)
    }

    /// [`Server::create`] through `path` (`/api/matches` with a query).
    pub(crate) fn create_at(&self, path: &str, scenario: Value) -> (String, Value) {
        let doc: Value = ureq::post(&self.http(path))
            .set("Authorization", &format!("Bearer {ADMIN}"))
            .send_json(scenario)
            .expect("created")
            .into_json()
            .unwrap();
        (
            doc["id"].as_str().unwrap().to_string(),
            doc["bot_tokens"].clone(),
        )
    }

    /// A match whose fielder "cf" is a bot slot, and a bot connected to it (its
    /// `hello` not yet read): the match id, the bot token and the socket.
    pub(crate) async fn play_cf(&self, mode: &str, deadline_ms: u64) -> (String, String, Socket) {
        let (id, tokens) = self.create(fielder_with_bot(mode, deadline_ms));
        let token = tokens["cf"].as_str().unwrap().to_string();
        let bot = connect(&self.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
        (id, token, bot)
    }

    /// A sample from `/metrics`: `name` with its labels, as written there
    /// (`fieldhouse_connections{role="bot"}`).
    pub(crate) fn metric(&self, name: &str) -> f64 {
        let text = ureq::get(&self.http("/metrics"))
            .call()
            .unwrap()
            .into_string()
            .unwrap();
        text.lines()
            .find_map(|l| l.strip_prefix(name)?.trim().parse().ok())
            .unwrap_or_else(|| panic!("{name} in /metrics:\n{text}"))
    }

    pub(crate) fn tick(&self, id: &str) -> u64 {
        self.get(&format!("/api/matches/{id}"))["tick"]
            .as_u64()
            .unwrap()
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The schema of a message type, from proto/.
pub(crate) fn schema(kind: &str) -> jsonschema::Validator {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("proto/{kind}.schema.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).expect("a valid schema")
}

pub(crate) fn assert_valid(message: &Value) {
    let kind = message["type"].as_str().expect("every message has a type");
    let validator = schema(kind);
    let errors: Vec<String> = validator
        .iter_errors(message)
        .map(|e| format!("{e} at {}", e.instance_path))
        .collect();
    assert!(
        errors.is_empty(),
        "{kind} does not match its schema: {errors:?}\n{message}"
    );
}

pub(crate) type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

pub(crate) async fn connect(url: &str) -> Socket {
    tokio_tungstenite::connect_async(url)
        .await
        .expect("the socket opens")
        .0
}

/// The next text message as JSON (within 10 s).
pub(crate) async fn next(socket: &mut Socket) -> Value {
    loop {
        let message = tokio::time::timeout(Duration::from_secs(10), socket.next())
            .await
            .expect("a message within 10 s")
            .expect("the socket is open")
            .expect("no error");
        if let Message::Text(t) = message {
            return serde_json::from_str(&t).expect("JSON");
        }
    }
}

/// The next message of a type, skipping others.
pub(crate) async fn next_of(socket: &mut Socket, kind: &str) -> Value {
    loop {
        let m = next(socket).await;
        if m["type"] == kind {
            return m;
        }
    }
}

pub(crate) fn fielder_with_bot(mode: &str, deadline_ms: u64) -> Value {
    json!({
        "sport": "baseball",
        "mode": mode,
        "lockstep_deadline_ms": deadline_ms,
        "agents": [
            {"id": "cf", "strategy": "chapman", "position": [60.0, 60.0], "bot": true},
            {"id": "rf", "strategy": "lot-optical", "position": [20.0, 80.0]}
        ],
        "options": {"pause_s": 30.0}
    })
}

/// A directory under the test target directory, gone before the test starts.
pub(crate) fn empty_dir(name: &str) -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}
