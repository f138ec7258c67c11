//! Operations: `serve --agones` against a fake Agones SDK sidecar (a small HTTP server
//! on loopback that records what the game server tells it: Agones' REST SDK, POST
//! /ready, /health, /shutdown), and the container files in docker/ against the binary
//! they run. (No Docker engine runs here, so the images themselves are not built.)

use crate::common;

use common::server::*;
use serde_json::json;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpListener;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The fake sidecar: every request's path, with when it came.
struct Sidecar {
    port: u16,
    calls: Arc<Mutex<Vec<(Instant, String)>>>,
}

impl Sidecar {
    fn start() -> Sidecar {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = listener.local_addr().unwrap().port();
        let calls = Arc::new(Mutex::new(Vec::new()));
        let seen = calls.clone();
        std::thread::spawn(move || {
            for stream in listener.incoming().map_while(Result::ok) {
                let seen = seen.clone();
                std::thread::spawn(move || {
                    let mut reader = BufReader::new(stream.try_clone().unwrap());
                    let mut stream = stream;
                    // Requests one after another on a kept-alive connection.
                    loop {
                        let mut request_line = String::new();
                        if reader.read_line(&mut request_line).unwrap_or(0) == 0 {
                            return;
                        }
                        let mut length = 0;
                        loop {
                            let mut header = String::new();
                            reader.read_line(&mut header).unwrap();
                            if header.trim().is_empty() {
                                break;
                            }
                            if let Some((name, value)) = header.split_once(':') {
                                if name.eq_ignore_ascii_case("content-length") {
                                    length = value.trim().parse().unwrap();
                                }
                            }
                        }
                        let mut body = vec![0; length];
                        reader.read_exact(&mut body).unwrap();
                        let mut parts = request_line.split_whitespace();
                        let call = format!("{} {}", parts.next().unwrap(), parts.next().unwrap());
                        seen.lock().unwrap().push((Instant::now(), call));
                        let _ = stream.write_all(
                            b"HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: 2\r\n\r\n{}",
                        );
                    }
                });
            }
        });
        Sidecar { port, calls }
    }

    fn calls(&self) -> Vec<(Instant, String)> {
        self.calls.lock().unwrap().clone()
    }

    /// Waits up to `within` for a call to `path`.
    fn wait_for(&self, path: &str, within: Duration) -> Instant {
        let deadline = Instant::now() + within;
        loop {
            if let Some((at, _)) = self.calls().into_iter().find(|(_, c)| c == path) {
                return at;
            }
            assert!(
                Instant::now() < deadline,
                "no {path} within {within:?}: {:?}",
                self.calls()
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

#[test]
fn ready_health_and_shutdown_reach_the_sidecar_and_the_server_exits_after_its_match() {
    let sidecar = Sidecar::start();
    let port = sidecar.port.to_string();
    let mut server = Server::start(&["--no-demo", "--agones", "--agones-sdk-port", &port]);
    sidecar.wait_for("POST /ready", Duration::from_secs(10));
    // The match an allocator would create: it plays 6 s and ends.
    let (id, _) = server.create(json!({"sport": "cricket", "duration_s": 6.0}));
    assert_eq!(
        server.get(&format!("/api/matches/{id}"))["status"],
        "running"
    );
    let shutdown = sidecar.wait_for("POST /shutdown", Duration::from_secs(30));
    let status = server.child.wait().expect("the server exits");
    assert!(status.success(), "{status}");
    let calls = sidecar.calls();
    // Ready first; then Health at most 2.5 s apart (Agones' default period is 5 s),
    // from Ready until the Shutdown.
    assert_eq!(calls[0].1, "POST /ready", "{calls:?}");
    let mut beats: Vec<Instant> = calls
        .iter()
        .filter(|(_, c)| c == "POST /health")
        .map(|(t, _)| *t)
        .collect();
    beats.insert(0, calls[0].0);
    beats.push(shutdown);
    assert!(beats.len() >= 4, "{calls:?}");
    for pair in beats.windows(2) {
        assert!(
            pair[1] - pair[0] < Duration::from_millis(2500),
            "a gap of {:?}",
            pair[1] - pair[0]
        );
    }
    // Not before its match ended: it played all its 6 s (360 ticks) and finished,
    // as the server's log says (read to its end, the process having exited).
    let deadline = Instant::now() + Duration::from_secs(5);
    let ended = loop {
        let log = server.log.lock().unwrap().clone();
        if let Some(line) = log.iter().find(|l| l.contains("match ended")) {
            break line.clone();
        }
        assert!(Instant::now() < deadline, "no end in the log: {log:?}");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert!(
        ended.contains("finished") && ended.contains("tick=360"),
        "shut down before its match ended: {ended}"
    );
    assert_eq!(
        calls.iter().filter(|(_, c)| c == "POST /shutdown").count(),
        1
    );
}

#[test]
fn sigterm_also_asks_the_sidecar_for_shutdown() {
    let sidecar = Sidecar::start();
    let port = sidecar.port.to_string();
    let mut server = Server::start(&["--agones", "--agones-sdk-port", &port]);
    sidecar.wait_for("POST /ready", Duration::from_secs(10));
    let pid = server.child.id().to_string();
    assert!(std::process::Command::new("kill")
        .args(["-TERM", &pid])
        .status()
        .unwrap()
        .success());
    sidecar.wait_for("POST /shutdown", Duration::from_secs(10));
    assert!(server.child.wait().unwrap().success());
}

/// The `args: [...]` lists of a manifest.
fn args_lists(yaml: &str) -> Vec<Vec<String>> {
    yaml.lines()
        .filter_map(|l| l.trim().strip_prefix("args: "))
        .map(|list| serde_json::from_str(list).expect("args are a JSON-style list"))
        .collect()
}

#[test]
fn the_container_files_use_flags_and_settings_the_binary_has() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let read = |p: &str| std::fs::read_to_string(root.join(p)).unwrap();
    let help = String::from_utf8(common::fieldhouse("serve --help").stdout).unwrap();
    // Every environment setting the Dockerfile and compose file give is one `serve` reads.
    let dockerfile = read("docker/Dockerfile");
    let compose = read("docker/compose.yaml");
    for var in [
        "FIELDHOUSE_ADDR",
        "FIELDHOUSE_REPLAY_DIR",
        "FIELDHOUSE_CACHE_DIR",
        "FIELDHOUSE_MOCAP_DIR",
    ] {
        assert!(
            help.contains(&format!("env: {var}")),
            "serve --help does not read {var}"
        );
    }
    assert!(
        dockerfile.contains("FIELDHOUSE_ADDR=0.0.0.0:7878") && dockerfile.contains("EXPOSE 7878")
    );
    // The image builds from what it copies: the build script packs data/mocap into the
    // binary, and the page and schemas are included from web/ and proto/.
    let copied: Vec<&str> = dockerfile
        .lines()
        .filter_map(|l| l.strip_prefix("COPY "))
        .filter(|l| !l.starts_with("--from"))
        .flat_map(|l| l.split_whitespace())
        .collect();
    for input in [
        "Cargo.toml",
        "Cargo.lock",
        // The workspace's library crates (the core's build script packs data/).
        "crates",
        "data",
        "src",
        "web",
        "proto",
    ] {
        assert!(
            copied.contains(&input),
            "the Dockerfile does not copy {input}"
        );
        assert!(
            root.join(input).exists(),
            "{input} is not in the repository"
        );
    }
    assert!(
        compose.contains("FIELDHOUSE_ADMIN_TOKEN")
            && compose.contains("/var/lib/fieldhouse/replays")
    );
    // The manifests' command lines parse (clap refuses an unknown flag before --help).
    for manifest in ["docker/agones/fleet.yaml", "docker/agones/gameserver.yaml"] {
        let lists = args_lists(&read(manifest));
        assert!(!lists.is_empty(), "{manifest}");
        for args in lists {
            assert!(
                args.contains(&"--agones".to_string()),
                "{manifest}: {args:?}"
            );
            let out = common::fieldhouse(&format!("{} --help", args.join(" ")));
            assert!(
                out.status.success(),
                "{manifest}: {args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        assert!(read(manifest).contains("containerPort: 7878"));
    }
}
