//! The replay directory under attack and under load, against the real binary on
//! loopback: what is in the directory besides replays (links, devices, FIFOs, endless
//! lines), what large replays cost (downloads, viewers, seeks, slow readers), how the
//! directory is kept bounded (retention, rotation), and that writing replays never
//! holds up a tick.

use crate::common;

use common::server::*;
use fieldhouse::replay::{Encoding, Recorder};
use futures_util::{SinkExt, StreamExt};
use serde_json::{json, Value};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::Message;

/// A field of the server's `/proc/PID/status`, in kB (VmRSS, VmHWM).
fn memory_kb(server: &Server, field: &str) -> u64 {
    let status = std::fs::read_to_string(format!("/proc/{}/status", server.child.id())).unwrap();
    status
        .lines()
        .find_map(|l| {
            l.strip_prefix(field)?
                .trim()
                .strip_suffix("kB")?
                .trim()
                .parse()
                .ok()
        })
        .unwrap()
}

/// Bytes the server has read, from files and sockets (`rchar` in `/proc/PID/io`).
fn bytes_read(server: &Server) -> u64 {
    let io = std::fs::read_to_string(format!("/proc/{}/io", server.child.id())).unwrap();
    io.lines()
        .find_map(|l| l.strip_prefix("rchar:")?.trim().parse().ok())
        .unwrap()
}

/// CPU time the server has used, in clock ticks (user + system).
fn cpu_ticks(server: &Server) -> u64 {
    let stat = std::fs::read_to_string(format!("/proc/{}/stat", server.child.id())).unwrap();
    let after_name = &stat[stat.rfind(')').unwrap() + 2..];
    let fields: Vec<&str> = after_name.split_whitespace().collect();
    fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap()
}

/// The header of the replays tests make.
fn made_header() -> Value {
    json!({
        "record": "header", "format": 1, "fieldhouse": "0.1.0",
        "match": {"id": "made", "name": "made by a test", "sport": "baseball"},
        "scenario": {"sport": "baseball", "mode": "fast", "duration_s": 10000.0},
        "seed": 1, "motion": "none", "started_unix_ms": 0,
    })
}

/// Frame `k` of the replays tests make: tick `2 k`, padded to about `bytes`.
fn made_frame(k: u64, bytes: usize) -> String {
    let pad = "x".repeat(bytes.saturating_sub(60));
    format!(
        r#"{{"type":"frame","match":"made","tick":{},"pad":"{pad}"}}"#,
        2 * k
    )
}

/// Writes a format 2 replay (as the server records) of `frames` frames as
/// [`write_replay`] makes them, with a footer.
fn write_compressed_replay(path: &Path, frames: u64, frame_bytes: usize) {
    let file = std::fs::File::create_new(path).unwrap();
    let out = std::io::BufWriter::new(file);
    let mut recorder = Recorder::new(out, &made_header(), Encoding::Zstd).unwrap();
    for k in 0..frames {
        recorder.frame(&made_frame(k, frame_bytes)).unwrap();
    }
    let last = 2 * frames.saturating_sub(1);
    recorder.finish(last, "finished", &json!({})).unwrap();
}

/// Writes a format 1 replay (as written before format 2) of `frames` frames (ticks 0,
/// 2, 4, ...), each padded to about `frame_bytes`, with a footer if `complete`. Quick:
/// a hundred megabytes in a second.
fn write_replay(path: &Path, frames: u64, frame_bytes: usize, complete: bool) {
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    writeln!(out, "{}", made_header()).unwrap();
    for k in 0..frames {
        writeln!(out, "{}", made_frame(k, frame_bytes)).unwrap();
    }
    if complete {
        let footer = json!({"record": "footer", "tick": 2 * frames.saturating_sub(1), "frames": frames, "hash": "-", "reason": "finished", "result": {}});
        writeln!(out, "{footer}").unwrap();
    }
    out.flush().unwrap();
}

/// The names in `dir`, sorted.
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The tick of the last whole frame written to `file`.
fn last_tick_in(file: &Path) -> Option<u64> {
    let bytes = std::fs::read(file).unwrap();
    let (text, _) = fieldhouse::replay::decode(&bytes).unwrap();
    String::from_utf8_lossy(&text)
        .lines()
        .rfind(|l| l.starts_with(r#"{"type":"frame""#))
        .and_then(|l| serde_json::from_str::<Value>(l).ok()?["tick"].as_u64())
}

fn status_of(server: &Server, path: &str) -> u16 {
    match ureq::get(&server.http(path))
        .timeout(Duration::from_secs(5))
        .call()
    {
        Ok(r) => r.status(),
        Err(ureq::Error::Status(code, _)) => code,
        Err(e) => panic!("{path}: {e}"),
    }
}

/// The first thing `found` finds in the listing, asked again and again for 30 s.
async fn until_listed<T>(server: &Server, found: impl Fn(&[Value]) -> Option<T>) -> T {
    let mut listing = Vec::new();
    common::found_within(Duration::from_secs(30), || {
        listing = listed(server);
        found(&listing)
    })
    .await
    .unwrap_or_else(|| panic!("not listed in 30 s: {listing:?}"))
}

fn listed(server: &Server) -> Vec<Value> {
    let started = Instant::now();
    let list = ureq::get(&server.http("/api/replays"))
        .timeout(Duration::from_secs(5))
        .call()
        .expect("the listing answers")
        .into_json::<Value>()
        .unwrap();
    assert!(
        started.elapsed() < Duration::from_secs(3),
        "listing took {:?}",
        started.elapsed()
    );
    list["replays"].as_array().unwrap().clone()
}

fn ids(replays: &[Value]) -> Vec<&str> {
    replays.iter().map(|r| r["id"].as_str().unwrap()).collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn links_devices_and_fifos_in_the_replay_directory_are_neither_served_nor_listed() {
    let dir = empty_dir("hostile-replay-dir");
    std::fs::create_dir_all(&dir).unwrap();
    let outside = empty_dir("hostile-replay-outside");
    std::fs::create_dir_all(&outside).unwrap();
    let secret = outside.join("secret.txt");
    std::fs::write(&secret, "ADMIN_TOKEN=do-not-serve-me\n").unwrap();
    write_replay(&dir.join("real.jsonl"), 10, 200, true);
    let link =
        |target: &Path, name: &str| std::os::unix::fs::symlink(target, dir.join(name)).unwrap();
    link(&secret, "secret.jsonl");
    link(Path::new("/etc/passwd"), "passwd.jsonl");
    link(Path::new("/proc/self/environ"), "environ.jsonl");
    link(Path::new("/dev/zero"), "zero.jsonl");
    link(&dir.join("real.jsonl"), "alias.jsonl");
    std::fs::hard_link(&secret, dir.join("hard.jsonl")).unwrap();
    let made = Command::new("mkfifo")
        .arg(dir.join("fifo.jsonl"))
        .status()
        .unwrap();
    assert!(made.success());
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    // The lobby polls the listing: it answers at once, with the real replay only.
    for _ in 0..3 {
        assert_eq!(ids(&listed(&server)), ["real"]);
    }
    for name in [
        "secret", "passwd", "environ", "zero", "alias", "hard", "fifo",
    ] {
        assert_eq!(
            status_of(&server, &format!("/api/replays/{name}")),
            404,
            "{name}"
        );
        let refused =
            tokio_tungstenite::connect_async(server.ws(&format!("/ws/replays/{name}"))).await;
        match refused {
            Err(tokio_tungstenite::tungstenite::Error::Http(r)) => {
                assert_eq!(r.status(), 404, "{name}")
            }
            other => panic!("{name}: {:?}", other.map(|_| "opened")),
        }
    }
    // Nothing was read through a link, and the server is still up.
    let body = ureq::get(&server.http("/api/replays/secret"))
        .call()
        .map_or_else(
            |e| match e {
                ureq::Error::Status(_, r) => r.into_string().unwrap(),
                e => panic!("{e}"),
            },
            |r| r.into_string().unwrap(),
        );
    assert!(
        !body.contains("do-not-serve-me") && !body.contains(dir.to_str().unwrap()),
        "{body}"
    );
    assert_eq!(status_of(&server, "/healthz"), 200);
    assert_eq!(status_of(&server, "/api/replays/real"), 200);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_header_line_without_end_is_listed_as_unreadable_quickly_and_in_little_memory() {
    let dir = empty_dir("endless-header");
    std::fs::create_dir_all(&dir).unwrap();
    // 50 MB and no newline.
    let mut endless = std::fs::File::create(dir.join("endless.jsonl")).unwrap();
    let block = vec![b'{'; 1 << 20];
    for _ in 0..50 {
        endless.write_all(&block).unwrap();
    }
    drop(endless);
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let before = memory_kb(&server, "VmHWM:");
    let replays = listed(&server);
    assert_eq!(ids(&replays), ["endless"]);
    assert!(replays[0]["error"].is_string(), "{replays:?}");
    // The lobby asks every 2 s: a file unchanged since is not read again.
    let read_before = bytes_read(&server);
    for _ in 0..5 {
        assert_eq!(listed(&server), replays);
    }
    let read = bytes_read(&server) - read_before;
    assert!(read < 100_000, "5 more listings read {read} bytes");
    // Viewing it is refused before the upgrade, also without reading it all.
    let refused = tokio_tungstenite::connect_async(server.ws("/ws/replays/endless")).await;
    match refused {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status(), 422),
        other => panic!("{:?}", other.map(|_| "opened")),
    }
    let grew = memory_kb(&server, "VmHWM:").saturating_sub(before);
    assert!(
        grew < 10_000,
        "the peak memory grew {grew} kB reading a 50 MB line"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn downloads_serve_exactly_the_range_asked() {
    let dir = empty_dir("ranged-downloads");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("ranged.jsonl");
    write_replay(&file, 2000, 500, true);
    let bytes = std::fs::read(&file).unwrap();
    let len = bytes.len();
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let get = |range: Option<&str>| {
        let mut request = ureq::get(&server.http("/api/replays/ranged"));
        if let Some(range) = range {
            request = request.set("Range", range);
        }
        match request.call() {
            Ok(r) | Err(ureq::Error::Status(_, r)) => r,
            Err(e) => panic!("{e}"),
        }
    };
    let whole = get(None);
    assert_eq!(whole.status(), 200);
    assert_eq!(whole.header("accept-ranges"), Some("bytes"));
    assert_eq!(
        whole.header("content-length"),
        Some(len.to_string().as_str())
    );
    let mut body = Vec::new();
    whole.into_reader().read_to_end(&mut body).unwrap();
    assert!(body == bytes, "the whole file, byte for byte");
    for (range, start, end) in [
        ("bytes=0-99", 0, 99),
        ("bytes=1000-", 1000, len - 1),
        ("bytes=-500", len - 500, len - 1),
        ("bytes=123456-123457", 123_456, 123_457),
        (
            &format!("bytes={}-{}", len - 10, len + 1000) as &str,
            len - 10,
            len - 1,
        ),
    ] {
        let part = get(Some(range));
        assert_eq!(part.status(), 206, "{range}");
        assert_eq!(
            part.header("content-range").map(str::to_string),
            Some(format!("bytes {start}-{end}/{len}")),
            "{range}"
        );
        let mut body = Vec::new();
        part.into_reader().read_to_end(&mut body).unwrap();
        assert!(body == bytes[start..=end], "{range}: the bytes asked");
    }
    let past = get(Some(&format!("bytes={len}-")));
    assert_eq!(past.status(), 416);
    assert_eq!(
        past.header("content-range").map(str::to_string),
        Some(format!("bytes */{len}"))
    );
}

/// Starts a download and reads only its first bytes: a client on a slow link.
fn slow_download(server: &Server, id: &str) -> std::net::TcpStream {
    let mut socket = std::net::TcpStream::connect(&server.addr).unwrap();
    write!(
        socket,
        "GET /api/replays/{id} HTTP/1.1\r\nHost: test\r\n\r\n"
    )
    .unwrap();
    let mut first = [0; 4096];
    socket.read_exact(&mut first).unwrap();
    assert!(first.starts_with(b"HTTP/1.1 200"));
    socket
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn viewers_and_slow_downloads_of_a_big_replay_cost_a_fraction_of_its_size() {
    let dir = empty_dir("big-replay");
    std::fs::create_dir_all(&dir).unwrap();
    // About 80 MB.
    write_replay(&dir.join("big.jsonl"), 80_000, 1000, true);
    let size_kb = std::fs::metadata(dir.join("big.jsonl")).unwrap().len() / 1000;
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let before = memory_kb(&server, "VmRSS:");
    let mut viewers = Vec::new();
    for _ in 0..8 {
        let mut viewer = connect(&server.ws("/ws/replays/big")).await;
        let hello = next(&mut viewer).await;
        assert_eq!(hello["replay"]["frames"], 80_000);
        assert_eq!(next_of(&mut viewer, "frame").await["tick"], 0);
        viewers.push(viewer);
    }
    let downloads: Vec<_> = (0..8).map(|_| slow_download(&server, "big")).collect();
    // Time for every slow download to be under way and holding what it holds: memory is
    // read while they are stalled, not before they start.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let grew = memory_kb(&server, "VmRSS:").saturating_sub(before);
    eprintln!("8 viewers and 8 slow downloads of a {size_kb} kB replay: resident memory grew {grew} kB (from {before} kB)");
    assert!(
        grew < size_kb / 4,
        "memory grew {grew} kB for a {size_kb} kB replay"
    );
    // A seek flood is answered from the index, not by scanning the frames.
    let cpu = cpu_ticks(&server);
    let (mut sink, mut stream) = viewers.swap_remove(0).split();
    // As many as the viewer's message budget takes at once (`bot_burst`, 400); more
    // would be refused, and a flood closed (connections::spectators_and_replay_…).
    let seeks = 400u64;
    // Even ticks, which the replay has, in an order that jumps about.
    let tick = |k: u64| 2 * ((k * 7919) % 80_000);
    let answers = tokio::spawn(async move {
        let mut answered = 0;
        while answered < seeks {
            let message = tokio::time::timeout(Duration::from_secs(10), stream.next())
                .await
                .expect("answers keep coming")
                .expect("the socket is open")
                .unwrap();
            let Message::Text(text) = message else {
                continue;
            };
            let f: Value = serde_json::from_str(&text).unwrap();
            if f["tick"].as_u64() == Some(tick(answered)) {
                answered += 1;
            }
        }
    });
    for k in 0..seeks {
        let seek = json!({"type": "control", "action": "seek", "tick": tick(k)});
        sink.send(Message::Text(seek.to_string().into()))
            .await
            .unwrap();
    }
    answers.await.unwrap();
    let used = cpu_ticks(&server) - cpu;
    eprintln!("{seeks} seeks in an 80,000-frame replay: {used} CPU ticks (1/100 s)");
    assert!(used < 100, "{seeks} seeks took {used} CPU ticks");
    drop(downloads);
}

/// Writes a format 2 replay of `chunks` chunks, each some 2 MiB of the tiniest frame
/// there is, at one tick, packed into a few hundred bytes: how a 100 kB file once held
/// 37.5 million frames (and their index 931 MB).
fn write_frame_dense_replay(path: &Path, chunks: usize) {
    let mut bytes = zstd::bulk::compress(format!("{}\n", made_header()).as_bytes(), 1).unwrap();
    let line = "{\"type\":\"frame\",\"tick\":1}\n";
    let dense = line.repeat((2 << 20) / line.len() - 1);
    let chunk = zstd::bulk::compress(dense.as_bytes(), 1).unwrap();
    for _ in 0..chunks {
        bytes.extend_from_slice(&chunk);
    }
    std::fs::write(path, bytes).unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frame_dense_replays_cost_their_bytes_not_their_frames() {
    let dir = empty_dir("dense-replay");
    std::fs::create_dir_all(&dir).unwrap();
    write_frame_dense_replay(&dir.join("dense.jsonl.zst"), 300);
    let size_kb = std::fs::metadata(dir.join("dense.jsonl.zst"))
        .unwrap()
        .len()
        / 1000;
    write_compressed_replay(&dir.join("plain.jsonl.zst"), 500, 300);
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let before = memory_kb(&server, "VmRSS:");
    // Viewers come and go, each opening the file afresh (the index goes with the last
    // viewer), and seek about in it; a viewer of another replay comes meanwhile.
    for round in 0..6 {
        let mut viewer = connect(&server.ws("/ws/replays/dense")).await;
        let hello = next(&mut viewer).await;
        assert_eq!(hello["replay"]["complete"], false, "{hello}");
        assert_eq!(hello["replay"]["first_tick"], 1, "{hello}");
        assert_eq!(next_of(&mut viewer, "frame").await["tick"], 1);
        let seek = json!({"type": "control", "action": "seek", "tick": 1, "lead_in_s": 15});
        viewer
            .send(Message::Text(seek.to_string().into()))
            .await
            .unwrap();
        assert_eq!(next_of(&mut viewer, "frame").await["tick"], 1);
        let mut other = connect(&server.ws("/ws/replays/plain")).await;
        assert_eq!(
            next(&mut other).await["replay"]["frames"],
            500,
            "round {round}"
        );
        assert_eq!(next_of(&mut other, "frame").await["tick"], 0);
    }
    let peak = memory_kb(&server, "VmHWM:").saturating_sub(before);
    eprintln!("6 viewers in turn of a {size_kb} kB frame-dense replay: peak resident memory {peak} kB over {before} kB");
    // Each viewer decodes a block of at most 4 MiB and its frames' places; the index
    // is a few kilobytes. An index per frame would take some 580 MB here; what the
    // bound leaves beyond the blocks is the allocator's (its arenas grow with the
    // threads that run at once: 31 MB measured idle, 41 MB with the machine busy).
    assert!(peak < 64_000, "peak memory grew {peak} kB");
}

/// A match created with `?record=false` leaves nothing in the replay directory (a
/// learner's episodes by the thousand made a nameless file each); one without the
/// query is recorded as before; a query that says anything else is refused.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn matches_are_recorded_unless_created_with_record_false() {
    let dir = empty_dir("record-false");
    std::fs::create_dir_all(&dir).unwrap();
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let scenario = common::server::fielder_with_bot("realtime", 1000);
    let (unrecorded, _) = server.create_at("/api/matches?record=false", scenario.clone());
    let (recorded, _) = server.create_at("/api/matches?record=true", scenario.clone());
    let (by_default, _) = server.create(scenario.clone());
    let files = || names_in(&dir);
    common::until(
        Duration::from_secs(10),
        "the recorded matches' files",
        || {
            let names = files();
            names.iter().any(|n| n.starts_with(&recorded))
                && names.iter().any(|n| n.starts_with(&by_default))
        },
    )
    .await;
    assert!(
        !files().iter().any(|n| n.starts_with(&unrecorded)),
        "{:?}",
        files()
    );
    let shown = server.get(&format!("/api/matches/{unrecorded}"));
    assert_eq!(shown["replay"], Value::Null, "{shown}");
    assert!(server.get(&format!("/api/matches/{recorded}"))["replay"].is_string());
    for query in ["record=no", "record=", "recrod=false"] {
        let refused = ureq::post(&server.http(&format!("/api/matches?{query}")))
            .set("Authorization", &format!("Bearer {ADMIN}"))
            .send_json(scenario.clone())
            .unwrap_err();
        let ureq::Error::Status(400, answer) = refused else {
            panic!("{query}: {refused}")
        };
        let body: Value = answer.into_json().unwrap();
        assert_eq!(body["error"]["code"], "bad_query", "{query}: {body}");
    }
}

/// A server whose settings file says `settings`.
fn server_with(name: &str, settings: &str, flags: &[&str]) -> (Server, PathBuf) {
    let dir = empty_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("server.toml");
    std::fs::write(&config, settings).unwrap();
    let replays = dir.join("replays");
    std::fs::create_dir_all(&replays).unwrap();
    let mut args = vec![
        "--config",
        config.to_str().unwrap(),
        "--replay-dir",
        replays.to_str().unwrap(),
    ];
    args.extend(flags);
    (Server::start(&args), replays)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_viewer_that_stops_reading_is_closed_within_the_send_timeout() {
    let (server, dir) = server_with("unread-viewer", "send_timeout_ms = 300\n", &["--no-demo"]);
    // Big frames at 8×: the socket's buffers fill within a second.
    write_replay(&dir.join("wide.jsonl"), 400, 64 * 1024, true);
    let mut viewer = connect(&server.ws("/ws/replays/wide")).await;
    next(&mut viewer).await;
    let speed = json!({"type": "control", "action": "speed", "speed": 8.0});
    viewer
        .send(Message::Text(speed.to_string().into()))
        .await
        .unwrap();
    // And now it reads no more.
    common::until(
        Duration::from_secs(8),
        "a viewer that stopped reading was kept",
        || server.metric("fieldhouse_slow_clients_dropped_total") >= 1.0,
    )
    .await;
    let log = server.log.lock().unwrap().join("\n");
    assert!(log.contains("replay viewer that stopped reading"), "{log}");
}

/// A crafted replay whose frames are a lifetime apart (tick 0, then u64::MAX, at one tick
/// a second) is played with the gap capped: its viewer's socket stays open and answers,
/// where the wait's arithmetic used to panic the viewer's task and drop the socket.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_a_lifetime_apart_do_not_break_their_viewer() {
    let (server, dir) = server_with("lifetime-gap", "", &["--no-demo"]);
    let mut header = made_header();
    header["scenario"]["tick_hz"] = json!(1.0);
    header["scenario"]["frame_hz"] = json!(1.0);
    let frame = |tick: u64| format!(r#"{{"type":"frame","match":"made","tick":{tick}}}"#);
    std::fs::write(
        dir.join("gap.jsonl"),
        format!("{header}\n{}\n{}\n", frame(0), frame(u64::MAX)),
    )
    .unwrap();
    let mut viewer = connect(&server.ws("/ws/replays/gap")).await;
    let mut first = next(&mut viewer).await;
    while first["type"] != "frame" {
        first = next(&mut viewer).await;
    }
    assert_eq!(first["tick"], 0);
    viewer.send(Message::Ping(vec![7].into())).await.unwrap();
    let answered = tokio::time::timeout(Duration::from_secs(5), async {
        while let Some(Ok(message)) = viewer.next().await {
            if let Message::Pong(p) = message {
                return p.to_vec() == vec![7];
            }
        }
        false
    })
    .await;
    assert_eq!(answered, Ok(true), "the viewer's socket was dropped");
    let log = server.log.lock().unwrap().join("\n");
    assert!(!log.contains("panicked"), "{log}");
}

/// Seeks are cheap messages and their lead-ins many frames: a viewer's lead-in frames are
/// bounded by a budget of their own (1,000 at once, 100 a second), so thirty seeks with
/// the longest lead-in (15 s: 450 frames each here) bring about a thousand frames, not
/// 13,500.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn seek_lead_ins_are_bounded_per_viewer() {
    let (server, dir) = server_with("lead-ins", "", &["--no-demo"]);
    write_replay(&dir.join("long.jsonl"), 20_000, 200, true);
    let mut viewer = connect(&server.ws("/ws/replays/long")).await;
    next(&mut viewer).await;
    let control = |c: Value| Message::Text(c.to_string().into());
    viewer
        .send(control(json!({"type": "control", "action": "pause"})))
        .await
        .unwrap();
    let started = Instant::now();
    for k in 0..30u64 {
        let seek = json!({"type": "control", "action": "seek", "tick": 30_000 + 100 * k, "lead_in_s": 15.0});
        viewer.send(control(seek)).await.unwrap();
    }
    let mut frames = 0u64;
    while let Ok(Some(Ok(message))) =
        tokio::time::timeout(Duration::from_millis(1500), viewer.next()).await
    {
        if let Message::Text(t) = message {
            frames += u64::from(t.contains(r#""type":"frame""#));
        }
    }
    let allowed = 1000.0 + 100.0 * started.elapsed().as_secs_f64() + 30.0;
    assert!(
        (frames as f64) <= allowed,
        "{frames} frames for 30 seeks (at most {allowed:.0})"
    );
    assert!(
        frames >= 1000,
        "the first lead-in is whole: {frames} frames"
    );
}

/// Sets a file's modification time to `days_ago` days ago.
fn age(path: &Path, days_ago: u64) {
    let then = std::time::SystemTime::now() - Duration::from_secs(days_ago * 86_400);
    std::fs::File::options()
        .write(true)
        .open(path)
        .unwrap()
        .set_modified(then)
        .unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn retention_deletes_the_oldest_replays_and_never_the_one_being_written() {
    let dir = empty_dir("retention");
    std::fs::create_dir_all(&dir).unwrap();
    let outside = empty_dir("retention-outside");
    std::fs::create_dir_all(&outside).unwrap();
    for (k, days) in [(1, 30u64), (2, 3), (3, 2), (4, 1)] {
        let path = dir.join(format!("old-{k}.jsonl"));
        write_replay(&path, 100, 1000, true);
        age(&path, days);
    }
    // A link to a file elsewhere, older than anything: neither it nor what it names goes.
    let precious = outside.join("precious.jsonl");
    write_replay(&precious, 10, 100, true);
    age(&precious, 100);
    std::os::unix::fs::symlink(&precious, dir.join("link.jsonl")).unwrap();
    // 250 kB and 10 days: at start old-1 goes for its age, old-2 for the size.
    let server = Server::start(&[
        "--no-demo",
        "--replay-dir",
        dir.to_str().unwrap(),
        "--replay-retention-bytes",
        "250000",
        "--replay-keep-days",
        "10",
    ]);
    let present = || names_in(&dir);
    let mut names = Vec::new();
    common::found_within(Duration::from_secs(10), || {
        names = present();
        (!names.contains(&"old-2.jsonl".to_string())).then_some(())
    })
    .await
    .unwrap_or_else(|| panic!("old-2.jsonl was never deleted: {names:?}"));
    assert_eq!(present(), ["link.jsonl", "old-3.jsonl", "old-4.jsonl"]);
    // A real-time match records; a fast one finishes, which sweeps again: everything
    // but the recording goes, since the recording alone is over the limit soon.
    let (live, _) = server.create(json!({"sport": "baseball", "mode": "realtime"}));
    common::until(
        Duration::from_secs(5),
        "the real-time match never started its recording",
        || present().iter().any(|n| n.starts_with(&live)),
    )
    .await;
    // Ten minutes of cricket: 1.5 MB compressed, over the limit by itself.
    let (fast, _) = server.create(json!({"sport": "cricket", "mode": "fast", "duration_s": 600.0}));
    common::found_within(Duration::from_secs(20), || {
        names = present();
        let only_live = names.len() == 2 && names.iter().any(|n| n.starts_with(&live));
        (only_live && !names.iter().any(|n| n.starts_with(&fast))).then_some(())
    })
    .await
    .unwrap_or_else(|| panic!("retention never left only the recording: {names:?}"));
    assert!(precious.exists(), "a link's target is never deleted");
    // The count and the log line follow each deletion: on a busy machine, a moment
    // later.
    common::until(
        Duration::from_secs(5),
        "the deletions were never counted and logged",
        || {
            server.metric("fieldhouse_replays_deleted_total") >= 5.0
                && server
                    .log
                    .lock()
                    .unwrap()
                    .iter()
                    .any(|l| l.contains("deleted an old replay"))
        },
    )
    .await;
    // The recording goes on.
    let recording = present()
        .into_iter()
        .find(|n| n.starts_with(&live))
        .unwrap();
    let size = |name: &str| std::fs::metadata(dir.join(name)).map_or(0, |m| m.len());
    let before = size(&recording);
    common::until(Duration::from_secs(5), "the live recording grows", || {
        size(&recording) > before
    })
    .await;
    // Its viewers each see what was written when they came (the later one's index
    // scanned on from the earlier one's).
    let live_replay = recording.strip_suffix(".jsonl.zst").unwrap();
    let mut early = connect(&server.ws(&format!("/ws/replays/{live_replay}"))).await;
    let seen_early = next(&mut early).await["replay"].clone();
    // The writer writes whole chunks: one that lands after the early viewer came.
    let early_last = seen_early["last_tick"]
        .as_u64()
        .expect("a viewer is told the last tick");
    common::until(
        Duration::from_secs(10),
        "no chunk was written after the early viewer came",
        || last_tick_in(&dir.join(&recording)).is_some_and(|t| t > early_last),
    )
    .await;
    let mut late = connect(&server.ws(&format!("/ws/replays/{live_replay}"))).await;
    let seen_late = next(&mut late).await["replay"].clone();
    assert_eq!(seen_late["complete"], false);
    assert!(
        seen_late["last_tick"].as_u64().unwrap() > early_last,
        "{seen_early} {seen_late}"
    );
    assert_eq!(seen_late["first_tick"], 0);
}

/// A server whose process may hold at most `descriptors` files and sockets at once (soft
/// and hard limit: the server raises its soft limit to the hard one).
fn server_with_descriptors(descriptors: u32, flags: &[&str]) -> Server {
    let limit = format!("ulimit -n {descriptors} && exec \"$0\" \"$@\"");
    Server::launch(&["sh", "-c", &limit], "info", flags)
}

/// Writes `count` small replays into `dir`, named `r000`, `r001`, ..., alternately format
/// 2 and format 1, each a second newer than the one before (`r000` the oldest, modified
/// `count` seconds ago); returns their names, oldest first.
fn write_many_replays(dir: &Path, count: u64) -> Vec<String> {
    // One of each format, copied: a recorder syncs each file it finishes, which for
    // hundreds of files takes most of a minute.
    let made = dir.join("made");
    std::fs::create_dir_all(&made).unwrap();
    write_compressed_replay(&made.join("two.jsonl.zst"), 3, 100);
    write_replay(&made.join("one.jsonl"), 3, 100, true);
    let two = std::fs::read(made.join("two.jsonl.zst")).unwrap();
    let one = std::fs::read(made.join("one.jsonl")).unwrap();
    std::fs::remove_dir_all(&made).unwrap();
    let now = std::time::SystemTime::now();
    (0..count)
        .map(|k| {
            let (name, bytes) = match k % 2 {
                0 => (format!("r{k:03}.jsonl.zst"), &two),
                _ => (format!("r{k:03}.jsonl"), &one),
            };
            let mut file = std::fs::File::create_new(dir.join(&name)).unwrap();
            file.write_all(bytes).unwrap();
            file.set_modified(now - Duration::from_secs(count - k))
                .unwrap();
            name
        })
        .collect()
}

/// Every page of the listing, `limit` replays a page, following `next` until there is
/// none; each page answered within 5 s.
fn pages(server: &Server, limit: usize) -> Vec<Vec<Value>> {
    let mut pages = Vec::new();
    let mut after: Option<String> = None;
    loop {
        let path = match &after {
            Some(cursor) => format!("/api/replays?limit={limit}&after={cursor}"),
            None => format!("/api/replays?limit={limit}"),
        };
        let page: Value = ureq::get(&server.http(&path))
            .timeout(Duration::from_secs(5))
            .call()
            .unwrap_or_else(|e| panic!("{path}: {e}"))
            .into_json()
            .unwrap();
        pages.push(page["replays"].as_array().unwrap().clone());
        match page["next"].as_str() {
            Some(cursor) => after = Some(cursor.to_string()),
            None => return pages,
        }
        assert!(pages.len() <= 1000, "the listing never ends");
    }
}

/// Descriptors the server's process holds now.
fn descriptors(server: &Server) -> usize {
    std::fs::read_dir(format!("/proc/{}/fd", server.child.id()))
        .unwrap()
        .count()
}

/// More replays than the server may hold descriptors (600 files, a limit of 256): the
/// listing pages through every one, newest first, none missing and none in error, with
/// one file open at a time; listings at once each get every page.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn more_replays_than_descriptors_are_all_listed_a_page_at_a_time_newest_first() {
    let dir = empty_dir("many-replays");
    std::fs::create_dir_all(&dir).unwrap();
    let written = write_many_replays(&dir, 600);
    let newest_first: Vec<&str> = written
        .iter()
        .rev()
        .map(|n| n.split('.').next().unwrap())
        .collect();
    let server =
        server_with_descriptors(256, &["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    // The first listing reads every file's header and footer: one file at a time, so
    // the process holds hardly more descriptors than when idle.
    let idle = descriptors(&server);
    let stop = Arc::new(AtomicBool::new(false));
    let most = std::thread::spawn({
        let (pid, stop) = (server.child.id(), stop.clone());
        move || {
            let mut most = 0;
            while !stop.load(Ordering::Relaxed) {
                if let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) {
                    most = most.max(fds.count());
                }
            }
            most
        }
    });
    let started = Instant::now();
    let all = pages(&server, 1000);
    let took = started.elapsed();
    stop.store(true, Ordering::Relaxed);
    let most = most.join().unwrap();
    eprintln!(
        "600 replays listed in {took:?} (first read), {idle} descriptors idle, at most {most} while listing"
    );
    // A few over idle (which itself moves by a few as the server settles after its
    // start), where holding every file open reached the limit.
    assert!(
        most <= idle.max(16) + 8,
        "{idle} descriptors idle, {most} while listing"
    );
    assert_eq!(all.len(), 1, "600 replays fit one page of 1000");
    assert_eq!(ids(&all[0]), newest_first);
    // A page at a time: 100 by default, the last page without a `next`.
    let paged = pages(&server, 100);
    assert_eq!(paged.iter().map(Vec::len).collect::<Vec<_>>(), [100; 6]);
    let paged: Vec<Value> = paged.into_iter().flatten().collect();
    assert_eq!(ids(&paged), newest_first);
    for entry in &paged {
        assert!(entry.get("error").is_none(), "{entry}");
        assert_eq!(entry["complete"], true, "{entry}");
        assert_eq!(entry["match"], "made", "{entry}");
    }
    let default_page = server.get("/api/replays");
    assert_eq!(default_page["replays"].as_array().unwrap().len(), 100);
    assert_eq!(default_page["total"], 600);
    assert!(default_page["next"].is_string(), "{}", default_page["next"]);
    // Eight clients page through at once, each in pages of 37: every request answered,
    // every replay listed.
    let lists: Vec<_> = (0..8)
        .map(|_| {
            let lister = Lister {
                addr: server.addr.clone(),
            };
            std::thread::spawn(move || lister.ids(37))
        })
        .collect();
    for list in lists {
        assert_eq!(list.join().unwrap(), newest_first);
    }
    // Bad pages are refused, saying why.
    for query in [
        "limit=0",
        "limit=1001",
        "limit=x",
        "after=nonsense",
        "after=12.bad%2Fid",
    ] {
        let response = get(&server, &format!("/api/replays?{query}"));
        assert_eq!(response.status(), 400, "{query}");
        let body: Value = response.into_json().unwrap();
        assert_eq!(body["error"]["code"], "bad_query", "{query}: {body}");
    }
}

/// A listing client of its own, for threads.
struct Lister {
    addr: String,
}

impl Lister {
    /// Every replay's id, a page of `limit` at a time.
    fn ids(&self, limit: usize) -> Vec<String> {
        let mut ids = Vec::new();
        let mut after = String::new();
        loop {
            let url = format!("http://{}/api/replays?limit={limit}{after}", self.addr);
            let page: Value = ureq::get(&url)
                .timeout(Duration::from_secs(10))
                .call()
                .unwrap_or_else(|e| panic!("{url}: {e}"))
                .into_json()
                .unwrap();
            for entry in page["replays"].as_array().unwrap() {
                assert!(entry.get("error").is_none(), "{entry}");
                ids.push(entry["id"].as_str().unwrap().to_string());
            }
            match page["next"].as_str() {
                Some(cursor) => after = format!("&after={cursor}"),
                None => return ids,
            }
        }
    }
}

/// Retention weighs every replay, however few descriptors the server has: 600 files at
/// a limit of 256, kept to a budget of about a sixth of them, lose exactly the oldest.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn retention_keeps_its_budget_with_more_replays_than_descriptors() {
    let dir = empty_dir("many-replays-retention");
    std::fs::create_dir_all(&dir).unwrap();
    let written = write_many_replays(&dir, 600);
    let size = |name: &String| std::fs::metadata(dir.join(name)).unwrap().len();
    let all: u64 = written.iter().map(size).sum();
    let budget = all / 6;
    // What retention keeps: the newest that fit the budget together.
    let mut kept = Vec::new();
    let mut total = 0;
    for name in written.iter().rev() {
        if total + size(name) > budget {
            break;
        }
        total += size(name);
        kept.push(name.clone());
    }
    kept.sort();
    let budget_flag = budget.to_string();
    let server = server_with_descriptors(
        256,
        &[
            "--no-demo",
            "--replay-dir",
            dir.to_str().unwrap(),
            "--replay-retention-bytes",
            &budget_flag,
        ],
    );
    let present = || names_in(&dir);
    let mut names = Vec::new();
    common::found_within(Duration::from_secs(10), || {
        names = present();
        (names == kept).then_some(())
    })
    .await
    .unwrap_or_else(|| {
        panic!(
            "retention kept {} files (wanted the newest {}): {:?}",
            names.len(),
            kept.len(),
            &names[..names.len().min(10)]
        )
    });
    assert_eq!(
        server.metric("fieldhouse_replays_deleted_total") as usize,
        600 - kept.len()
    );
}

/// Sweeps asked for by recordings that finish in a burst (a match created and deleted,
/// again and again) are coalesced: at most one a second.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn retention_sweeps_at_most_once_a_second_however_many_recordings_finish() {
    let (server, _dir) = server_with("sweep-burst", "", &["--no-demo"]);
    common::until(Duration::from_secs(5), "no sweep at start", || {
        server.metric("fieldhouse_replay_sweeps_total") >= 1.0
    })
    .await;
    let before = server.metric("fieldhouse_replay_sweeps_total");
    let started = Instant::now();
    for _ in 0..60 {
        let (id, _) = server.create(json!({"sport": "cricket", "mode": "realtime"}));
        ureq::delete(&server.http(&format!("/api/matches/{id}")))
            .set("Authorization", &format!("Bearer {ADMIN}"))
            .call()
            .unwrap();
    }
    // The last recording's sweep comes within a second of it.
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let sweeps = server.metric("fieldhouse_replay_sweeps_total") - before;
    let seconds = started.elapsed().as_secs_f64();
    eprintln!("60 recordings finished in {seconds:.1} s: {sweeps} sweeps");
    assert!(sweeps >= 1.0, "no sweep after the recordings");
    assert!(
        sweeps <= seconds.ceil() + 1.0,
        "{sweeps} sweeps in {seconds:.1} s"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_never_ending_match_rotates_its_replay_into_segments_that_verify() {
    let (server, dir) = server_with(
        "rotation",
        "replay_segment_bytes = 16384\nreplay_max_match_bytes = 16384\n",
        &["--no-demo"],
    );
    // No bot slots, real time: it rotates (the total limit is for other matches).
    let (id, _) = server.create(json!({"sport": "baseball", "mode": "realtime", "seed": 7}));
    let segments = until_listed(&server, |listing| {
        let mut segments: Vec<Value> = listing
            .iter()
            .filter(|r| r["match"] == id.as_str())
            .cloned()
            .collect();
        // Listed newest first: the first segment last.
        segments.sort_by_key(|s| s["segment"].as_u64());
        (segments.len() >= 3).then_some(segments)
    })
    .await;
    let first_ticks: Vec<u64> = segments
        .iter()
        .map(|s| s["first_tick"].as_u64().unwrap())
        .collect();
    assert_eq!(first_ticks[0], 0);
    assert!(first_ticks[1] > 0, "{segments:?}");
    assert_eq!(segments[1]["segment"], 1);
    assert_eq!(segments[0]["reason"], "rotated");
    for segment in &segments[..2] {
        assert!(
            segment["bytes"].as_u64().unwrap() < 16_384 + 8_192,
            "{segment}"
        );
        common::assert_verifies(
            &dir.join(format!("{}.jsonl.zst", segment["id"].as_str().unwrap())),
        );
    }
    // A later segment plays from its own first tick.
    let second = segments[1]["id"].as_str().unwrap();
    let mut viewer = connect(&server.ws(&format!("/ws/replays/{second}"))).await;
    let hello = next(&mut viewer).await;
    assert_eq!(hello["replay"]["first_tick"].as_u64(), Some(first_ticks[1]));
    assert_eq!(hello["replay"]["complete"], true);
    let shown = server.get(&format!("/api/matches/{id}"));
    assert!(shown["replay_error"].is_null());
    // The match names the segment it is writing now, not its first (which retention
    // may already have deleted): a later one than the two finished above.
    let now = shown["replay"].as_str().unwrap();
    let listed: Vec<&str> = segments.iter().map(|s| s["id"].as_str().unwrap()).collect();
    assert!(!listed[..2].contains(&now), "{now} among {listed:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_fast_match_stops_recording_at_its_size_limit_and_its_replay_verifies() {
    let (server, dir) = server_with(
        "size-limit",
        "replay_max_match_bytes = 200000\n",
        &["--no-demo"],
    );
    let (id, _) = server.create(json!({"sport": "cricket", "mode": "fast", "duration_s": 600.0}));
    let replay = until_listed(&server, |listing| {
        listing
            .iter()
            .find(|r| r["match"] == id.as_str() && r["complete"] == true)
            .cloned()
    })
    .await;
    assert_eq!(replay["reason"], "size_limit");
    assert!(
        replay["bytes"].as_u64().unwrap() <= 200_000 + 4096,
        "{replay}"
    );
    // The match hears why at its next frame, and shows it.
    let mut shown = Value::Null;
    common::found_within(Duration::from_secs(5), || {
        shown = server.get(&format!("/api/matches/{id}"));
        let why = shown["replay_error"].as_str().unwrap_or_default();
        why.contains("replay_max_match_bytes").then_some(())
    })
    .await
    .unwrap_or_else(|| panic!("the match never showed its size limit: {shown}"));
    common::assert_verifies(&dir.join(format!("{}.jsonl.zst", replay["id"].as_str().unwrap())));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn other_matches_keep_ticking_while_a_large_replay_closes() {
    // A fast match writes 25–60 MB of frames a second, 3–7 MB compressed: 20 MB (about
    // 170 MB of frames) is under the default 1 GiB limit.
    let dir = empty_dir("closing-big-replay");
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let (live, _) = server.create(json!({"sport": "baseball", "mode": "realtime"}));
    let mut spectator = connect(&server.ws(&format!("/ws/matches/{live}"))).await;
    next(&mut spectator).await;
    let (fast, _) =
        server.create(json!({"sport": "cricket", "mode": "fast", "duration_s": 100000.0}));
    // Let it write a large replay, then delete it: its replay is flushed, synced and
    // closed while the real-time match must go on at 30 frames a second.
    let written = || -> u64 {
        std::fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .filter(|e| e.file_name().to_string_lossy().starts_with(&fast))
            .filter_map(|e| e.metadata().ok())
            .map(|m| m.len())
            .sum()
    };
    common::until(
        Duration::from_secs(30),
        "the fast match never wrote 20 MB of replay",
        || written() >= 20_000_000,
    )
    .await;
    let timing = Arc::new(AtomicBool::new(false));
    let gaps = tokio::spawn({
        let timing = timing.clone();
        async move {
            let (mut last, mut worst) = (Instant::now(), Duration::ZERO);
            let until = Instant::now() + Duration::from_secs(3);
            while Instant::now() < until {
                next_of(&mut spectator, "frame").await;
                worst = worst.max(last.elapsed());
                last = Instant::now();
                timing.store(true, Ordering::Relaxed);
            }
            worst
        }
    });
    common::until(
        Duration::from_secs(5),
        "the live frames were never timed",
        || timing.load(Ordering::Relaxed),
    )
    .await;
    let deleting = Instant::now();
    ureq::delete(&server.http(&format!("/api/matches/{fast}")))
        .set("Authorization", &format!("Bearer {ADMIN}"))
        .call()
        .unwrap();
    let worst = gaps.await.unwrap();
    // Frames come every 33 ms, and the fast match takes turns on the same thread, so
    // gaps of some 40 ms are normal; syncing the replay on that thread stopped them for
    // 200–300 ms (2.9 s for a 2 GB replay).
    let bytes: u64 = listed(&server)
        .iter()
        .filter(|r| r["match"] == fast.as_str())
        .map(|r| r["bytes"].as_u64().unwrap())
        .sum();
    eprintln!(
        "a {} MB replay closed {:?} after its delete; the worst gap between live frames was {worst:?}",
        bytes / 1_000_000,
        deleting.elapsed()
    );
    assert!(
        worst < Duration::from_millis(150),
        "live frames stopped for {worst:?}"
    );
    drop(server);
    let _ = std::fs::remove_dir_all(&dir);
}

/// GETs `path`: the response, whatever its status.
fn get(server: &Server, path: &str) -> ureq::Response {
    match ureq::get(&server.http(path)).call() {
        Ok(r) | Err(ureq::Error::Status(_, r)) => r,
        Err(e) => panic!("{path}: {e}"),
    }
}

/// The frame a viewer is sent after it seeks to `tick` (frames sent before the seek
/// may still be on the way: they are skipped).
async fn seek(viewer: &mut Socket, tick: u64) -> u64 {
    let seek = json!({"type": "control", "action": "seek", "tick": tick});
    viewer
        .send(Message::Text(seek.to_string().into()))
        .await
        .unwrap();
    loop {
        let at = next_of(viewer, "frame").await["tick"].as_u64().unwrap();
        if (tick..tick + 2).contains(&at) {
            return at;
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn replays_of_both_formats_are_listed_played_sought_and_downloaded_as_stored() {
    let dir = empty_dir("both-formats");
    std::fs::create_dir_all(&dir).unwrap();
    // Format 2, as the server records, and format 1, written before format 2 existed.
    write_compressed_replay(&dir.join("new.jsonl.zst"), 5000, 500);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/replay-format1.jsonl");
    std::fs::copy(&fixture, dir.join("old.jsonl")).unwrap();
    // One id with both names: the format 2 file is the replay.
    write_compressed_replay(&dir.join("both.jsonl.zst"), 10, 200);
    write_replay(&dir.join("both.jsonl"), 20, 200, true);
    // A name that says the other format: what the file holds is what counts.
    write_replay(&dir.join("misnamed.jsonl.zst"), 30, 200, true);
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let listing = listed(&server);
    let mut listed_ids = ids(&listing);
    listed_ids.sort_unstable();
    assert_eq!(listed_ids, ["both", "misnamed", "new", "old"]);
    let cases = [
        // id, stored as, served as, media type, frames, first tick
        (
            "both",
            "both.jsonl.zst",
            "both.jsonl.zst",
            "application/zstd",
            10,
            0,
        ),
        (
            "misnamed",
            "misnamed.jsonl.zst",
            "misnamed.jsonl",
            "application/x-ndjson",
            30,
            0,
        ),
        (
            "new",
            "new.jsonl.zst",
            "new.jsonl.zst",
            "application/zstd",
            5000,
            0,
        ),
        (
            "old",
            "old.jsonl",
            "old.jsonl",
            "application/x-ndjson",
            91,
            0,
        ),
    ];
    for (id, stored, served, media, frames, first) in cases {
        let entry = listing.iter().find(|e| e["id"] == id).unwrap();
        assert_eq!(entry["file"], served, "{entry}");
        assert_eq!(entry["complete"], true, "{entry}");
        let bytes = std::fs::read(dir.join(stored)).unwrap();
        assert_eq!(entry["bytes"], bytes.len(), "{entry}");
        // Downloaded as stored, named and typed for what it holds.
        let response = get(&server, &format!("/api/replays/{id}"));
        assert_eq!(response.status(), 200);
        assert_eq!(response.header("content-type"), Some(media), "{id}");
        assert_eq!(
            response.header("content-disposition").map(str::to_string),
            Some(format!("attachment; filename=\"{served}\"")),
            "{id}"
        );
        let mut body = Vec::new();
        response.into_reader().read_to_end(&mut body).unwrap();
        assert!(body == bytes, "{id}: the file as stored");
        // Played from its first frame.
        let mut viewer = connect(&server.ws(&format!("/ws/replays/{id}"))).await;
        let hello = next(&mut viewer).await;
        assert_eq!(hello["replay"]["frames"], frames, "{id}: {hello}");
        assert_eq!(hello["replay"]["complete"], true, "{id}: {hello}");
        assert_eq!(next_of(&mut viewer, "frame").await["tick"], first, "{id}");
    }
    // Seeking in a compressed replay lands where asked, forwards and back, each frame
    // read from its chunk.
    let mut viewer = connect(&server.ws("/ws/replays/new")).await;
    next(&mut viewer).await;
    for tick in [6000, 9998, 2, 5000, 120] {
        assert_eq!(seek(&mut viewer, tick).await, tick);
    }
    let mut old = connect(&server.ws("/ws/replays/old")).await;
    next(&mut old).await;
    assert_eq!(seek(&mut old, 100).await, 100);
    // A range of a compressed replay is its bytes, as of any file.
    let part = ureq::get(&server.http("/api/replays/new"))
        .set("Range", "bytes=0-3")
        .call()
        .unwrap();
    assert_eq!(part.status(), 206);
    let mut magic = Vec::new();
    part.into_reader().read_to_end(&mut magic).unwrap();
    assert_eq!(magic, [0x28, 0xb5, 0x2f, 0xfd]);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recording_being_written_is_watched_as_its_chunks_land() {
    let dir = empty_dir("live-chunks");
    std::fs::create_dir_all(&dir).unwrap();
    let server = Server::start(&["--no-demo", "--replay-dir", dir.to_str().unwrap()]);
    let (live, _) = server.create(json!({"sport": "baseball", "mode": "realtime"}));
    let replay = until_listed(&server, |listing| {
        let r = listing.iter().find(|r| r["match"] == live.as_str())?;
        Some(r["id"].as_str().unwrap().to_string())
    })
    .await;
    // A new viewer sees the frames of the chunks written when it came: none at first
    // (the first chunk lands when full, 60 frames in 2 s, or when its first frame has
    // waited 2 s), then more, chunk by chunk. Its hello says the last tick written (the
    // count of frames is known only once the footer is).
    let mut seen: Vec<u64> = Vec::new();
    let started = Instant::now();
    while seen.len() < 2 {
        assert!(
            started.elapsed() < Duration::from_secs(20),
            "last ticks seen by viewers as the recording went: {seen:?}"
        );
        let mut viewer = connect(&server.ws(&format!("/ws/replays/{replay}"))).await;
        let hello = next(&mut viewer).await;
        assert_eq!(hello["replay"]["complete"], false);
        assert_eq!(hello["replay"]["frames"], Value::Null);
        if let Some(last) = hello["replay"]["last_tick"].as_u64() {
            if seen.last() != Some(&last) {
                assert!(seen.last() < Some(&last), "{seen:?} then {last}");
                seen.push(last);
            }
            // It plays what has landed, from the start.
            let first = next_of(&mut viewer, "frame").await;
            assert_eq!(first["tick"], 0);
            assert_eq!(first["match"], live.as_str());
        }
        // The recording lands a chunk at a time: the next viewer comes a little later,
        // when more of it may have landed.
        tokio::time::sleep(Duration::from_millis(300)).await;
    }
    eprintln!("last ticks seen by viewers as the recording went: {seen:?}");
    // Each landing is whole chunks: about 60 frames, two ticks apart.
    let steps: Vec<u64> = seen.windows(2).map(|w| w[1] - w[0]).collect();
    assert!(steps.iter().all(|&s| s >= 40), "{seen:?}");
}
