//! Hostile clients and failing disks against the real binary: who may open sockets
//! (origin policy, connections per address), what reaches the logs, and a replay
//! directory that fills up or disappears under a running match. RELIABILITY.md lists
//! each case with the test that covers it.

use crate::common;

use common::server::*;
use futures_util::StreamExt;
use serde_json::Value;
use std::net::SocketAddr;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::Error as WsError;

/// Waits until match `id` is past tick `before` (at most 5 s).
async fn ticks_past(server: &Server, id: &str, before: u64) {
    common::until(
        Duration::from_secs(5),
        &format!("{id} stopped ticking at {before}"),
        || server.tick(id) > before,
    )
    .await;
}

/// Opens a WebSocket sending `origin`, if any: the socket, or the HTTP status of the
/// refusal.
async fn open(url: &str, origin: Option<&str>) -> Result<Socket, u16> {
    let mut request = url.into_client_request().unwrap();
    if let Some(origin) = origin {
        request
            .headers_mut()
            .insert("origin", origin.parse().unwrap());
    }
    match tokio_tungstenite::connect_async(request).await {
        Ok((socket, _)) => Ok(socket),
        Err(WsError::Http(response)) => Err(response.status().as_u16()),
        Err(e) => panic!("{url}: {e}"),
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pages_from_other_origins_are_refused_unless_allowed() {
    let server = Server::start(&["--allow-origin", "https://friend.example"]);
    let url = server.ws("/ws/matches/demo-baseball");
    let own = format!("http://{}", server.addr);
    // Not a browser, the server's own page, an allowed origin: let in.
    for origin in [None, Some(own.as_str()), Some("https://friend.example")] {
        let mut socket = open(&url, origin)
            .await
            .unwrap_or_else(|status| panic!("origin {origin:?} was refused with {status}"));
        assert_eq!(next(&mut socket).await["type"], "hello");
    }
    // Any other page: refused before the upgrade, on every socket route.
    for path in [
        "/ws/matches/demo-baseball",
        "/ws/matches/demo-baseball/play?token=x",
        "/ws/replays/x",
    ] {
        let refused = open(&server.ws(path), Some("https://evil.example")).await;
        assert_eq!(refused.err(), Some(403), "{path}");
    }
    // Another port on the same host is another origin.
    let other_port = format!("http://{}:1", server.addr.split(':').next().unwrap());
    assert_eq!(open(&url, Some(&other_port)).await.err(), Some(403));
    assert_eq!(
        server.metric("fieldhouse_sockets_refused_total{reason=\"origin\"}"),
        4.0
    );
    // The matches went on.
    let before = server.tick("demo-baseball");
    ticks_past(&server, "demo-baseball", before).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn one_address_holds_at_most_its_share_of_sockets() {
    let server = Server::start(&["--max-connections-per-ip", "3"]);
    let url = server.ws("/ws/matches/demo-cricket");
    let mut held = Vec::new();
    for _ in 0..3 {
        let mut socket = open(&url, None).await.expect("within the cap");
        next_of(&mut socket, "frame").await;
        held.push(socket);
    }
    assert_eq!(open(&url, None).await.err(), Some(429));
    assert_eq!(
        open(&server.ws("/ws/replays/x"), None).await.err(),
        Some(429),
        "replay viewers count too"
    );
    // The sockets held are unharmed, and closing one frees its place.
    for socket in &mut held {
        next_of(socket, "frame").await;
    }
    held.pop().unwrap().close(None).await.unwrap();
    let deadline = Instant::now() + Duration::from_secs(5);
    let mut again = loop {
        match open(&url, None).await {
            Ok(socket) => break socket,
            Err(429) if Instant::now() < deadline => {
                tokio::time::sleep(Duration::from_millis(50)).await
            }
            Err(status) => panic!("a freed place was not given back: {status}"),
        }
    };
    next_of(&mut again, "frame").await;
    // Every connection counts, plain HTTP too: an address cannot hold descriptors
    // the cap does not see.
    match ureq::get(&server.http("/healthz")).call() {
        Err(ureq::Error::Status(429, _)) => {}
        other => panic!("an HTTP request over the cap: {other:?}"),
    }
    drop((held, again));
    let deadline = Instant::now() + Duration::from_secs(5);
    while ureq::get(&server.http("/healthz")).call().is_err() {
        assert!(
            Instant::now() < deadline,
            "closed sockets free their places"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert!(server.metric("fieldhouse_sockets_refused_total{reason=\"per_ip\"}") >= 3.0);
}

#[test]
fn bad_limits_are_refused_naming_the_setting() {
    let bad_origin = common::bad_input("serve --no-demo --allow-origin friend.example");
    assert!(
        bad_origin.contains("allowed_origins") && bad_origin.contains("friend.example"),
        "{bad_origin}"
    );
    let zero = common::bad_input("serve --no-demo --max-connections-per-ip 0");
    assert!(zero.contains("max_connections_per_ip"), "{zero}");
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("bad-limits");
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("server.toml");
    std::fs::write(
        &config,
        "allowed_origins = [\"https://ok.example\", \"https://x.example/path\"]\n",
    )
    .unwrap();
    let err = common::bad_input(&format!("serve --config {}", config.display()));
    assert!(
        err.contains("server.toml") && err.contains("allowed_origins"),
        "{err}"
    );
}

/// `fieldhouse serve ARGS` with the test servers' cache and `env` set (and
/// no FIELDHOUSE_ADMIN_TOKEN or FIELDHOUSE_ADDR unless `env` sets them): the address it
/// listens on, once it says so (then it is stopped), or everything it wrote to stderr
/// if it exits first.
fn serve_until_listening(args: &[&str], env: &[(&str, &str)]) -> Result<SocketAddr, String> {
    use std::io::{BufRead, BufReader};
    let cache = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("server-cache");
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"));
    command
        .arg("serve")
        .args(args)
        .arg("--cache-dir")
        .arg(&cache)
        .env_remove("FIELDHOUSE_ADMIN_TOKEN")
        .env_remove("FIELDHOUSE_ADDR")
        .env_remove("FIELDHOUSE_LOG")
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped());
    for (name, value) in env {
        command.env(name, value);
    }
    let mut child = command.spawn().expect("the binary starts");
    let mut stderr = String::new();
    for line in BufReader::new(child.stderr.take().unwrap()).lines() {
        let line = line.unwrap();
        if let Some(at) = line.find("http://") {
            let addr: String = line[at + 7..].chars().take_while(|c| *c != '/').collect();
            let _ = child.kill();
            let _ = child.wait();
            return Ok(addr.parse().expect("a socket address"));
        }
        stderr += &line;
        stderr.push('\n');
    }
    assert!(
        !child.wait().unwrap().success(),
        "serve exited cleanly without listening"
    );
    Err(stderr)
}

#[test]
fn serve_checks_its_port_and_settings_before_loading_motion() {
    // A busy port: refused at once, naming the address and what to do, before motion is
    // loaded and before an admin token is printed that could never be used.
    let busy = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = busy.local_addr().unwrap().to_string();
    let started = Instant::now();
    let err = serve_until_listening(&["--no-demo", "--addr", &addr], &[]).unwrap_err();
    assert!(err.contains(&format!("cannot listen on {addr}")), "{err}");
    assert!(err.contains("in use") && err.contains("--addr"), "{err}");
    assert!(
        !err.contains("motion loaded"),
        "motion was loaded first:\n{err}"
    );
    assert!(
        !err.contains("admin token"),
        "a token was printed first:\n{err}"
    );
    assert!(
        started.elapsed() < Duration::from_secs(10),
        "{:?}",
        started.elapsed()
    );
    // An admin token too short to be a secret: the same.
    let err = serve_until_listening(
        &["--no-demo", "--addr", "127.0.0.1:0"],
        &[("FIELDHOUSE_ADMIN_TOKEN", "short")],
    )
    .unwrap_err();
    assert!(
        err.contains("FIELDHOUSE_ADMIN_TOKEN must be at least 16"),
        "{err}"
    );
    assert!(
        !err.contains("motion loaded"),
        "motion was loaded first:\n{err}"
    );
}

/// Runs `serve` with `--addr VALUE` that must be refused as a usage error; its stderr.
fn refused_addr(value: &str) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["serve", "--no-demo", "--addr", value])
        .env_remove("FIELDHOUSE_ADDR")
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(2),
        "--addr {value:?} was not refused"
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn addresses_are_read_as_people_write_them() {
    // A host name that resolves, from the flag, the environment or the file; localhost
    // stays on loopback.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("addr-forms");
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("server.toml");
    std::fs::write(&config, "addr = \"localhost:0\"\n").unwrap();
    let config_arg = config.to_str().unwrap();
    for (args, env) in [
        (vec!["--no-demo", "--addr", "localhost:0"], vec![]),
        (vec!["--no-demo"], vec![("FIELDHOUSE_ADDR", "localhost:0")]),
        (vec!["--no-demo", "--config", config_arg], vec![]),
    ] {
        let addr = serve_until_listening(&args, &env)
            .unwrap_or_else(|err| panic!("{args:?} {env:?} did not listen: {err}"));
        assert!(addr.ip().is_loopback(), "{args:?} {env:?}: {addr}");
    }
    // A host alone means port 7878. (Held here, if free, so that the server fails at
    // once naming it instead of serving on a port other tests might want.)
    let _held = std::net::TcpListener::bind("127.0.0.1:7878");
    let err = serve_until_listening(&["--no-demo", "--addr", "127.0.0.1"], &[]).unwrap_err();
    assert!(err.contains("cannot listen on 127.0.0.1:7878"), "{err}");
    // Anything else: refused before anything starts, saying what is expected.
    for wrong in [
        "localhost:port",
        "127.0.0.1:99999",
        "http://127.0.0.1:7878",
        "127.0.0.1 7878",
        "",
    ] {
        let err = refused_addr(wrong);
        assert!(
            err.contains("HOST:PORT, e.g. 127.0.0.1:7878"),
            "{wrong:?}: {err}"
        );
    }
    std::fs::write(&config, "addr = \"localhost:port\"\n").unwrap();
    let err = common::failure(&format!("serve --config {}", config.display()));
    assert!(
        err.contains("server.toml: addr:") && err.contains("HOST:PORT, e.g. 127.0.0.1:7878"),
        "{err}"
    );
}

#[test]
fn no_error_repeats_its_cause() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("error-chains");
    std::fs::create_dir_all(dir.join("a-directory")).unwrap();
    std::fs::write(dir.join("a-file"), "not a directory").unwrap();
    let missing = dir.join("missing");
    let (missing, a_dir, a_file) = (
        missing.display(),
        dir.join("a-directory").display().to_string(),
        dir.join("a-file").display().to_string(),
    );
    let closed = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap();
    for command in [
        format!("replay info {missing}.jsonl"),
        format!("replay export {missing}.jsonl"),
        format!("run {missing}.toml"),
        format!("serve --config {a_dir}"),
        format!("serve --config {missing}.toml"),
        format!("motion-graph --behaviour run --mocap {missing}"),
        format!("costmap --behaviour run --mocap {a_file}"),
        format!("bot --url ws://{closed}/ws/matches/x/play --token t"),
    ] {
        let err = common::failure(&command);
        let message = err
            .lines()
            .find_map(|l| l.strip_prefix("error: "))
            .unwrap_or_else(|| panic!("{command}: no error line in {err}"));
        assert!(
            message.matches("(os error").count() <= 1,
            "{command}: {message}"
        );
        let segments: Vec<&str> = message.split(": ").collect();
        for (i, segment) in segments.iter().enumerate() {
            assert!(
                !segments[i + 1..].contains(segment),
                "{command}: \"{segment}\" repeats in {message}"
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn no_token_reaches_the_logs_even_at_trace_level() {
    let server = Server::launch(&[], "trace", &["--no-demo"]);
    let (id, token, mut bot) = server.play_cf("realtime", 1000).await;
    next_of(&mut bot, "perception").await;
    // A wrong token, and the admin token, go through the logs' reach as well.
    let refused = open(
        &server.ws(&format!(
            "/ws/matches/{id}/play?token=0123456789abcdef0123456789abcdef"
        )),
        None,
    )
    .await;
    assert_eq!(refused.err(), Some(403));
    ureq::delete(&server.http(&format!("/api/matches/{id}")))
        .set("Authorization", &format!("Bearer {ADMIN}"))
        .call()
        .unwrap();
    next_of(&mut bot, "end").await;
    // The server closes the bot's socket after the end; then everything up to the
    // match's end is logged once it says so.
    while let Ok(Some(Ok(_))) = tokio::time::timeout(Duration::from_secs(5), bot.next()).await {}
    let deadline = Instant::now() + Duration::from_secs(5);
    let log = loop {
        let log = server.log.lock().unwrap().join("\n");
        if log.contains("match ended") {
            break log;
        }
        assert!(Instant::now() < deadline, "the end is not logged:\n{log}");
        tokio::time::sleep(Duration::from_millis(20)).await;
    };
    assert!(log.contains("/ws/matches/"), "requests are logged:\n{log}");
    for secret in [token.as_str(), ADMIN, "0123456789abcdef0123456789abcdef"] {
        assert!(!log.contains(secret), "a token reached the log");
    }
}

/// `serve` with its replay directory on a tmpfs of `kib` KiB in a mount namespace of
/// its own (the test runs as root, as CI does; `unshare` is util-linux's).
fn server_on_a_small_disk(dir: &std::path::Path, kib: u32) -> Server {
    std::fs::create_dir_all(dir).unwrap();
    let mount = format!(
        "mount -t tmpfs -o size={kib}k tmpfs '{}' && exec \"$0\" \"$@\"",
        dir.display()
    );
    let dir = dir.to_str().unwrap();
    Server::launch(
        &["unshare", "-m", "sh", "-c", &mount],
        "info",
        &["--replay-dir", dir],
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_replay_disk_stops_the_recording_not_the_match() {
    // Three demo matches write about 45 KB of frames a second: 64 KiB fills at once.
    let server = server_on_a_small_disk(&empty_dir("full-disk"), 64);
    let mut spectator = open(&server.ws("/ws/matches/demo-baseball"), None)
        .await
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    let failed = loop {
        let matches = server.get("/api/matches")["matches"].clone();
        let failed: Vec<Value> = matches
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| !m["replay_error"].is_null())
            .cloned()
            .collect();
        if !failed.is_empty() {
            break failed;
        }
        assert!(
            Instant::now() < deadline,
            "no replay error reported: {matches}"
        );
        tokio::time::sleep(Duration::from_millis(200)).await;
    };
    let why = failed[0]["replay_error"].as_str().unwrap();
    assert!(
        why.contains("No space left") || why.contains("os error 28"),
        "{why}"
    );
    assert!(server.metric("fieldhouse_replay_errors_total") >= 1.0);
    let log = server.log.lock().unwrap().join("\n");
    assert!(
        log.contains("replay recording stopped") || log.contains("cannot record"),
        "{log}"
    );
    // Every match still ticks and still streams.
    let id = failed[0]["id"].as_str().unwrap();
    let before = server.tick(id);
    let frame = next_of(&mut spectator, "frame").await;
    let later = next_of(&mut spectator, "frame").await;
    assert!(later["tick"].as_u64().unwrap() > frame["tick"].as_u64().unwrap());
    ticks_past(&server, id, before).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_directory_that_vanishes_leaves_new_matches_unrecorded_but_running() {
    let dir = empty_dir("vanishing-replays");
    let _ = std::fs::remove_file(&dir); // left by an earlier run
    std::fs::create_dir_all(&dir).unwrap();
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    // An operator's mistake: the directory is replaced by a file. (Root ignores
    // permission bits, so a read-only directory would not stop this test's writes.)
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::write(&dir, "not a directory").unwrap();
    let (id, _) = server.create(serde_json::json!({"sport": "cricket"}));
    let shown = server.get(&format!("/api/matches/{id}"));
    let why = shown["replay_error"]
        .as_str()
        .expect("the API shows the error");
    assert!(why.starts_with("cannot create"), "{why}");
    assert!(shown["replay"].is_null());
    assert_eq!(server.metric("fieldhouse_replay_errors_total"), 1.0);
    let before = server.tick(&id);
    ticks_past(&server, &id, before).await;
}

/// Its own step of `scripts/test` (`cargo nextest run --run-ignored only`): the soak loads
/// both cores for half a minute, which would slow every test running beside it.
#[test]
#[ignore = "the soak is its own step in scripts/test: cargo nextest run --run-ignored only"]
fn a_short_soak_leaves_nothing_behind() {
    let report = common::json("soak --minutes 0.5 --json");
    assert_eq!(report["failures"], 0, "{report:#}");
    // A bot's command for a tick already past is refused as stale now and then on a
    // busy machine; any other error is a fault.
    for (code, _) in report["bot_errors"].as_object().unwrap() {
        assert_eq!(code, "stale_tick", "{report:#}");
    }
    assert!(
        report["matches_created"].as_u64().unwrap() >= 8,
        "{report:#}"
    );
    assert_eq!(report["matches_created"], report["matches_deleted"]);
    assert!(
        report["bot_sessions"].as_u64().unwrap() >= 16,
        "bots came back: {report:#}"
    );
    assert!(report["frames_received"].as_u64().unwrap() > 1000);
    let (start, end) = (&report["samples"][0], &report["end"]);
    assert_eq!(end["matches"], 0);
    assert_eq!(end["sockets"], 0);
    // Every socket and file the churn opened is closed again.
    assert!(
        end["fds"].as_u64().unwrap() <= start["fds"].as_u64().unwrap() + 2,
        "{report:#}"
    );
    assert_eq!(
        end["threads"]
            .as_u64()
            .expect("the soak reports its threads"),
        start["threads"]
            .as_u64()
            .expect("the soak reports its threads")
    );
}

#[test]
fn soak_arguments_are_checked() {
    let err = common::failure("soak --minutes 0");
    assert!(err.contains("outside 0.5 to 120 minutes"), "{err}");
}
