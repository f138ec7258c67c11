//! `fieldhouse loadgen` as a user runs it: it starts the real server on loopback, fills
//! it with spectators, and reports. Only what must hold whatever the machine's speed is
//! checked (timings belong in BENCHMARKS.md): every spectator connects, frames arrive
//! and the figures are consistent.

use crate::common;

use common::fieldhouse;

#[test]
fn loadgen_reports_a_small_round_and_the_bare_senders_beside_it() {
    // The server loadgen starts inherits the cost-map cache the server tests use, so it
    // starts without building maps.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args("loadgen --spectators 20 --matches 2 --seconds 1 --settle 0.5 --json".split(' '))
        .env_remove("FIELDHOUSE_MOCAP_DIR")
        .env(
            "FIELDHOUSE_CACHE_DIR",
            std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("server-cache"),
        )
        .env_remove("FIELDHOUSE_LOG")
        .output()
        .expect("the binary runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rounds: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let servers: Vec<_> = rounds
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["server"].as_str().unwrap())
        .collect();
    assert_eq!(servers, ["fieldhouse", "bare"], "{rounds}");
    for round in rounds.as_array().unwrap() {
        assert_eq!(round["matches"], 2);
        assert_eq!(round["connected"], 20);
        // About 30 frames a second reach each of them in the one-second window.
        let delivered = round["delivered"].as_u64().unwrap();
        assert!(delivered >= 20 * 10, "{round}");
        let share = round["delivered_share"].as_f64().unwrap();
        assert!(share > 0.5 && share <= 1.1, "{round}");
        // Frames are stamped, so latency is measured; a fly-ball frame is small.
        // Latencies come from differences that saturate at zero: a real one on loopback
        // is above zero and well under a second, and the median is at most the 99th
        // percentile.
        let latency = &round["latency_ms"];
        let (p50, p99) = (
            latency["p50"].as_f64().unwrap(),
            latency["p99"].as_f64().unwrap(),
        );
        assert!(p50 > 0.0 && p50 <= p99 && p99 < 1000.0, "{round}");
        assert!(
            round["bytes_per_message"].as_f64().unwrap() < 1024.0,
            "{round}"
        );
        assert!(round["server_rss_mb"].as_f64().unwrap() > 1.0);
    }
    let (ours, bare) = (&rounds[0], &rounds[1]);
    assert!(ours["tick_overruns"].as_u64().is_some(), "{ours}");
    assert!(bare["tick_overruns"].is_null(), "{bare}");
    // fieldhouse's CPU per frame is reported against the bare sender's; 20 spectators
    // for a second may cost the bare sender less than /proc's 10 ms tick, and then
    // there is no ratio to give.
    let floor = bare["server_cpu_us_per_message"].as_f64().unwrap();
    if floor > 0.0 {
        assert_eq!(bare["cpu_vs_bare"].as_f64(), Some(1.0), "{bare}");
        let ratio = ours["server_cpu_us_per_message"].as_f64().unwrap() / floor;
        assert!(
            (ours["cpu_vs_bare"].as_f64().unwrap() - ratio).abs() < 1e-9,
            "{rounds}"
        );
    } else {
        assert!(
            ours["cpu_vs_bare"].is_null() && bare["cpu_vs_bare"].is_null(),
            "{rounds}"
        );
    }
    // The bare sender's frames are the size of fieldhouse's in the same run.
    let (a, b) = (
        ours["bytes_per_message"].as_f64().unwrap(),
        bare["bytes_per_message"].as_f64().unwrap(),
    );
    assert!((a - b).abs() <= 1.0, "{a} against {b}");
}

/// The bare sender on its own, as loadgen starts it: it says where it listens, answers
/// a WebSocket handshake, sends stamped frames with a rising tick 30 times a second, and
/// exits when its standard input closes.
#[test]
fn the_bare_sender_answers_a_handshake_and_sends_stamped_frames() {
    use futures_util::StreamExt;
    use std::io::BufRead;
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_fieldhouse"))
        .args(["bare-sender", "--addr", "127.0.0.1:0", "--exit-with-stdin"])
        .args(["--payload-bytes", "600"])
        .env("FIELDHOUSE_LOG", "info")
        .stdin(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the binary runs");
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let url = stderr
        .lines()
        .map_while(Result::ok)
        .find_map(|line| {
            let at = line.find("ws://")?;
            Some(line[at..].split_whitespace().next()?.to_string())
        })
        .expect("it says where it listens");
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    let frames: Vec<serde_json::Value> = runtime.block_on(async {
        let (mut socket, response) = tokio_tungstenite::connect_async(format!("{url}bare/0"))
            .await
            .expect("a WebSocket handshake");
        assert_eq!(response.status(), 101);
        let mut frames = Vec::new();
        while frames.len() < 5 {
            let message = tokio::time::timeout(std::time::Duration::from_secs(5), socket.next())
                .await
                .expect("a frame within 5 s")
                .expect("the socket is open")
                .expect("a message");
            let text = message.into_text().expect("a text message");
            assert_eq!(text.len(), 600, "padded to the size asked for");
            frames.push(serde_json::from_str(text.as_str()).expect("JSON"));
        }
        frames
    });
    for pair in frames.windows(2) {
        assert_eq!(pair[0]["type"], "frame");
        let ticks = (pair[0]["tick"].as_u64(), pair[1]["tick"].as_u64());
        assert!(ticks.1 > ticks.0, "{ticks:?}");
        let sent = (pair[0]["sent_us"].as_u64(), pair[1]["sent_us"].as_u64());
        assert!(
            sent.1 > sent.0 && sent.0 > Some(1_700_000_000_000_000),
            "{sent:?}"
        );
    }
    drop(child.stdin.take());
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        assert!(
            started.elapsed() < std::time::Duration::from_secs(10),
            "the bare sender outlived its standard input"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

#[test]
fn loadgen_refuses_bad_arguments_and_a_missing_peer() {
    for args in [
        "loadgen --spectators 0",
        "loadgen --spectators 1,x",
        "loadgen --seconds -1",
        "loadgen --seconds 0.5",
        "loadgen --settle 61",
        "loadgen --peer nobody",
    ] {
        let out = fieldhouse(args);
        assert_eq!(out.status.code(), Some(2), "{args}");
        assert!(out.stdout.is_empty(), "{args}");
    }
}

#[test]
fn a_peer_that_cannot_start_fails_before_any_round_with_the_install_command() {
    let root = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("peers");
    let _ = std::fs::remove_dir_all(&root);
    let peers = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/peers");
    // The tracked files without node_modules: what a fresh clone has.
    let fresh = root.join("fresh");
    std::fs::create_dir_all(&fresh).unwrap();
    for file in ["package.json", "package-lock.json", "colyseus-server.mjs"] {
        std::fs::copy(peers.join(file), fresh.join(file)).unwrap();
    }
    // Installed, but the server script is gone.
    let scriptless = root.join("scriptless");
    std::fs::create_dir_all(scriptless.join("node_modules/@colyseus/core")).unwrap();
    std::fs::create_dir_all(scriptless.join("node_modules/.bin")).unwrap();
    std::fs::copy(peers.join("package.json"), scriptless.join("package.json")).unwrap();
    std::fs::write(
        scriptless.join("node_modules/@colyseus/core/package.json"),
        "{}",
    )
    .unwrap();
    std::fs::write(scriptless.join("node_modules/.bin/node"), "").unwrap();
    let nowhere = root.join("nowhere");
    for (dir, expected) in [
        (&nowhere, format!("npm ci --prefix {}", nowhere.display())),
        (&fresh, format!("npm ci --prefix {}", fresh.display())),
        (&scriptless, "colyseus-server.mjs".to_string()),
    ] {
        let started = std::time::Instant::now();
        let err = common::failure(&format!(
            "loadgen --spectators 1 --seconds 1 --settle 0 --peer colyseus --peer-dir {}",
            dir.display()
        ));
        assert!(err.contains(&expected), "{expected:?} not in {err}");
        // No server was started and no spectator connected: fieldhouse's round would
        // have taken seconds and logged them.
        assert!(!err.contains("connecting"), "a round ran first: {err}");
        assert!(
            started.elapsed() < std::time::Duration::from_secs(5),
            "{:?}",
            started.elapsed()
        );
    }
}

/// `npm ci` installs only from a lock that lists every package the tree needs, optional
/// builds for other systems included; a lock that lacks one is refused by `npm ci` and
/// rewritten by `npm install` (it was, on every machine). Checked here without a network:
/// every dependency of every package in bench/peers/package-lock.json resolves, as Node
/// resolves it, to an entry of the lock.
#[test]
fn the_peers_lock_file_lists_every_package_so_npm_ci_accepts_it() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/peers/package-lock.json");
    let lock: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let packages = lock["packages"].as_object().unwrap();
    let mut missing = Vec::new();
    for (at, package) in packages {
        for kind in ["dependencies", "optionalDependencies"] {
            for name in package[kind]
                .as_object()
                .into_iter()
                .flatten()
                .map(|(n, _)| n)
            {
                // From the package's own node_modules up to the root's.
                let mut base = at.as_str();
                let found = loop {
                    let candidate = if base.is_empty() {
                        format!("node_modules/{name}")
                    } else {
                        format!("{base}/node_modules/{name}")
                    };
                    if packages.contains_key(&candidate) {
                        break true;
                    }
                    if base.is_empty() {
                        break false;
                    }
                    base = base.rsplit_once("/node_modules/").map_or("", |(up, _)| up);
                };
                if !found {
                    missing.push(format!("{name} (needed by {at:?})"));
                }
            }
        }
    }
    assert!(missing.is_empty(), "not in the lock: {missing:?}");
}

#[test]
fn loadgen_bots_answer_every_perception_and_report_the_turnaround() {
    let out =
        fieldhouse("loadgen --bots 6 --matches 2 --spectators 4 --seconds 1 --settle 0 --json");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let round: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(round["bots"], 6);
    assert_eq!(round["connected"], 6);
    // Lock-step matches go at their bots' pace: far more than 60 ticks a second, and
    // every bot answered many of them.
    let commands = round["commands"].as_u64().unwrap();
    assert!(commands >= 6 * 60, "{round}");
    assert!(
        round["ticks_per_s_median"].as_f64().unwrap() > 60.0,
        "{round}"
    );
    let t = &round["turnaround_ms"];
    assert!(
        t["p50"].as_f64().unwrap() > 0.0 && t["p50"].as_f64() <= t["p99"].as_f64(),
        "{round}"
    );
    // The spectators watched the bots' matches in the same window: lock-step frames come
    // at the bots' pace (one every two ticks), far faster than 30 a second.
    let watched = &round["spectators"];
    assert_eq!(watched["connected"], 4, "{round}");
    assert_eq!(watched["matches"], 2, "{round}");
    let share = watched["delivered_share"].as_f64().unwrap();
    assert!(share > 0.0 && share <= 1.0, "{round}");
    assert!(
        watched["rate_median_hz"].as_f64().unwrap() > 30.0,
        "{round}"
    );
    let err = common::failure("loadgen --bots 6 --matches 2 --spectators 10,20");
    assert!(
        err.contains("--spectators with --bots is one count"),
        "{err}"
    );
    // More bots than two matches can seat is refused.
    let err = common::failure("loadgen --bots 70 --matches 2");
    assert!(err.contains("each match holds 1 to 32 bots"), "{err}");
    assert_eq!(fieldhouse("loadgen --bots 0").status.code(), Some(2));
}
