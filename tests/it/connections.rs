//! Connections from clients that do not play by the rules: headers trickled, sockets
//! opened and left idle, downloads read slowly to hold places, descriptors run short,
//! control frames by the thousand, frames that break the WebSocket protocol, text from
//! clients that should only listen, bots that stop reading, forged Host headers, more
//! requests than the server should run at once. Real binary, loopback only; each
//! test is bounded in time and count.

use crate::common;

use common::server::{connect, next_of, Server, ADMIN};
use futures_util::{SinkExt, StreamExt};
use std::io::{ErrorKind, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tokio_tungstenite::tungstenite::protocol::frame::coding::OpCode;
use tokio_tungstenite::tungstenite::protocol::frame::FrameHeader;
use tokio_tungstenite::tungstenite::Message;

/// A settings file with `toml` in it.
fn settings(name: &str, toml: &str) -> PathBuf {
    let dir = common::server::empty_dir(name);
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("server.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

/// Whether the server has closed `stream` (reads end), without waiting.
fn closed_by_server(stream: &TcpStream) -> bool {
    stream.set_nonblocking(true).unwrap();
    let mut byte = [0u8; 64];
    let closed = loop {
        match (&mut &*stream).read(&mut byte) {
            Ok(0) => break true,
            Ok(_) => continue, // a refusal's response, then the close
            Err(e) if e.kind() == ErrorKind::WouldBlock => break false,
            Err(_) => break true,
        }
    };
    stream.set_nonblocking(false).unwrap();
    closed
}

#[test]
fn trickled_headers_and_silent_connections_are_closed_at_the_header_timeout() {
    let file = settings("header-timeout", "header_timeout_ms = 1000\n");
    let server = Server::start(&["--no-demo", "--config", file.to_str().unwrap()]);
    // A request whose header lines come one every 300 ms: never complete in time.
    let mut trickle = TcpStream::connect(&server.addr).unwrap();
    let opened = Instant::now();
    trickle.write_all(b"GET /healthz HTTP/1.1\r\n").unwrap();
    let mut writer = trickle.try_clone().unwrap();
    let dripping = std::thread::spawn(move || {
        for k in 0..20 {
            // The drip: one header line every 300 ms, slower than the header timeout allows.
            std::thread::sleep(Duration::from_millis(300));
            if writer
                .write_all(format!("X-Drip-{k}: 1\r\n").as_bytes())
                .is_err()
            {
                return;
            }
        }
        let _ = writer.write_all(b"Host: x\r\n\r\n");
    });
    // Connections that say nothing at all.
    let silent: Vec<TcpStream> = (0..20)
        .map(|_| TcpStream::connect(&server.addr).unwrap())
        .collect();
    trickle
        .set_read_timeout(Some(Duration::from_secs(8)))
        .unwrap();
    let mut answer = Vec::new();
    let _ = trickle.read_to_end(&mut answer);
    let after = opened.elapsed();
    let answer = String::from_utf8_lossy(&answer);
    assert!(
        !answer.contains("200 OK"),
        "a trickled request was served: {answer}"
    );
    assert!(
        after < Duration::from_secs(3),
        "closed after {after:?}, not at the 1 s header timeout"
    );
    dripping.join().unwrap();
    // They were opened with the trickle, so they are due now; they get as long as it had.
    common::until_blocking(
        Duration::from_secs(3),
        "silent connections outlive the header timeout",
        || silent.iter().all(closed_by_server),
    );
    // A prompt client is unaffected.
    assert_eq!(server.get("/readyz")["ready"], true);
}

#[test]
fn every_connection_counts_against_its_address_not_only_websockets() {
    let server = Server::start(&["--no-demo", "--max-connections-per-ip", "10"]);
    // Thirty idle connections from one address: it never holds more than ten, because
    // at its cap its longest-idle one is closed for the next.
    let idle: Vec<TcpStream> = (0..30)
        .map(|_| TcpStream::connect(&server.addr).unwrap())
        .collect();
    // Well within the header timeout (10 s), which would close them all anyway.
    common::until_blocking(
        Duration::from_secs(2),
        "one address kept more than 10 of its 30 idle connections",
        || idle.iter().filter(|s| !closed_by_server(s)).count() <= 10,
    );
    // Requests still get in (an idle connection makes room).
    assert_eq!(server.get("/readyz")["ready"], true);
    drop(idle);
    // Ten busy connections (WebSockets) fill the cap: the next connection is refused
    // with 429, whatever it asks for.
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(async {
        let (id, _) = server.create(serde_json::json!({"sport": "cricket"}));
        let url = server.ws(&format!("/ws/matches/{id}"));
        let deadline = Instant::now() + Duration::from_secs(5);
        let mut held = Vec::new();
        while held.len() < 10 {
            match tokio_tungstenite::connect_async(&url).await {
                Ok((socket, _)) => held.push(socket),
                // The idle connections above may not all be gone yet.
                Err(_) if Instant::now() < deadline => {
                    tokio::time::sleep(Duration::from_millis(50)).await
                }
                Err(e) => panic!("the cap is 10, {} open: {e}", held.len()),
            }
        }
        match ureq::get(&server.http("/healthz")).call() {
            Err(ureq::Error::Status(429, response)) => {
                let body: serde_json::Value = response.into_json().unwrap();
                assert_eq!(body["error"]["code"], "too_many_connections");
            }
            other => panic!("an 11th connection: {other:?}"),
        }
    });
}

/// Connects from `source` (any 127.0.0.0/8 address is this machine).
async fn connect_from(source: [u8; 4], addr: &str) -> std::io::Result<tokio::net::TcpStream> {
    let socket = tokio::net::TcpSocket::new_v4()?;
    socket.bind((std::net::Ipv4Addr::from(source), 0).into())?;
    socket.connect(addr.parse().unwrap()).await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn with_descriptors_short_health_checks_and_admins_still_get_in() {
    // 160 descriptors: room for 96 connections. Many addresses, so the per-address cap
    // (256) is not what stops them.
    let server = Server::launch(
        &["sh", "-c", "ulimit -n 160 && exec \"$0\" \"$@\""],
        "info",
        &["--no-demo"],
    );
    let (id, tokens) = server.create(common::server::fielder_with_bot("realtime", 1000));
    let mut idle = Vec::new();
    for k in 0..400 {
        let source = [127, 0, 0, 2 + (k % 8) as u8];
        if let Ok(stream) = connect_from(source, &server.addr).await {
            idle.push(stream);
        }
    }
    // Not a wait for a state the test needs: everything below must hold whatever the
    // server has made of the flood so far (it may refuse at its cap or run out of
    // descriptors, depending on timing). The pause lets the flood reach the accept loop,
    // so the health check meets the worst of it rather than an empty backlog.
    tokio::time::sleep(Duration::from_millis(200)).await;
    let started = Instant::now();
    assert_eq!(
        tokio::task::spawn_blocking({
            let url = server.http("/healthz");
            move || ureq::get(&url).call().unwrap().into_string().unwrap()
        })
        .await
        .unwrap(),
        "ok"
    );
    assert!(started.elapsed() < Duration::from_secs(2));
    // An admin can still create and delete matches.
    let (second, _) = tokio::task::spawn_blocking({
        let url = server.http("/api/matches");
        move || {
            let doc: serde_json::Value = ureq::post(&url)
                .set("Authorization", &format!("Bearer {ADMIN}"))
                .send_json(serde_json::json!({"sport": "cricket"}))
                .unwrap()
                .into_json()
                .unwrap();
            (doc["id"].as_str().unwrap().to_string(), ())
        }
    })
    .await
    .unwrap();
    // Spectators are shed first; a bot still gets its agent.
    let spectator = tokio_tungstenite::connect_async(server.ws(&format!("/ws/matches/{id}"))).await;
    match spectator {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status(), 503),
        other => panic!("a spectator near the limit: {:?}", other.map(|_| ())),
    }
    let token = tokens["cf"].as_str().unwrap();
    let mut bot = connect(&server.ws(&format!("/ws/matches/{id}/play?token={token}"))).await;
    assert_eq!(next_of(&mut bot, "hello").await["role"], "bot");
    assert!(!second.is_empty());
    drop(idle);
    let log = server.log.lock().unwrap().join("\n");
    let complaints = log.matches("cannot accept").count();
    assert!(
        complaints <= 3,
        "{complaints} accept-error lines: the log is flooded\n{log}"
    );
}

/// A WebSocket opened by hand, so the test can write any frame it likes.
async fn raw_socket(server: &Server, path: &str) -> tokio::net::TcpStream {
    let mut stream = tokio::net::TcpStream::connect(&server.addr).await.unwrap();
    let request = format!(
        "GET {path} HTTP/1.1\r\nHost: {}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
         Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
        server.addr
    );
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut head = Vec::new();
    while !head.ends_with(b"\r\n\r\n") {
        let mut byte = [0u8];
        stream.read_exact(&mut byte).await.unwrap();
        head.push(byte[0]);
    }
    assert!(
        head.starts_with(b"HTTP/1.1 101"),
        "{}",
        String::from_utf8_lossy(&head)
    );
    stream
}

/// A masked client frame.
fn frame(fin: bool, opcode: u8, payload: &[u8]) -> Vec<u8> {
    raw_frame((u8::from(fin) << 7) | opcode, true, payload)
}

/// Reads server frames until a close; its code (None: the connection ended without one).
async fn close_code(stream: &mut tokio::net::TcpStream) -> Option<u16> {
    let reading = async {
        loop {
            let mut head = [0u8; 2];
            stream.read_exact(&mut head).await.ok()?;
            let length = match head[1] & 0x7f {
                126 => u64::from(stream.read_u16().await.ok()?),
                127 => stream.read_u64().await.ok()?,
                n => u64::from(n),
            };
            let mut payload = vec![0u8; length as usize];
            stream.read_exact(&mut payload).await.ok()?;
            if head[0] & 0x0f == 0x8 {
                return payload.get(..2).map(|c| u16::from_be_bytes([c[0], c[1]]));
            }
        }
    };
    tokio::time::timeout(Duration::from_secs(10), reading)
        .await
        .expect("the server answers within 10 s")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn control_and_fragment_frame_floods_are_closed_with_1008() {
    let server = Server::start(&[]);
    let floods: [(&str, Vec<u8>); 3] = [
        ("pings", frame(true, 0x9, b"hi").repeat(5000)),
        ("pongs", frame(true, 0xa, b"").repeat(5000)),
        ("an endless message of empty continuation frames", {
            let mut bytes = frame(false, 0x1, b"{");
            bytes.extend(frame(false, 0x0, b"").repeat(5000));
            bytes
        }),
    ];
    for (what, bytes) in floods {
        let mut socket = raw_socket(&server, "/ws/matches/demo-baseball").await;
        // The server may close before it has read them all.
        let _ = socket.write_all(&bytes).await;
        assert_eq!(close_code(&mut socket).await, Some(1008), "{what}");
    }
    // A ping now and then is answered, and the socket stays open.
    let mut polite = connect(&server.ws("/ws/matches/demo-baseball")).await;
    for _ in 0..5 {
        polite
            .send(Message::Ping(b"still there?".to_vec().into()))
            .await
            .unwrap();
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let mut pongs = 0;
    while pongs < 5 {
        match tokio::time::timeout(Duration::from_secs(5), polite.next()).await {
            Ok(Some(Ok(Message::Pong(_)))) => pongs += 1,
            Ok(Some(Ok(Message::Close(c)))) => panic!("a polite client was closed: {c:?}"),
            Ok(Some(Ok(_))) => {}
            other => panic!("{other:?}"),
        }
    }
    assert!(server.metric("fieldhouse_closed_flooding_total") >= 3.0);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn spectators_and_replay_viewers_that_flood_text_are_closed_with_1008() {
    let dir = common::server::empty_dir("flooding-viewers");
    let server = Server::start(&["--replay-dir", dir.to_str().unwrap()]);
    let replays = server.get("/api/replays");
    let replay = replays["replays"][0]["id"]
        .as_str()
        .expect("a demo is recorded");
    for path in [
        "/ws/matches/demo-cricket".to_string(),
        format!("/ws/replays/{replay}"),
    ] {
        let mut socket = connect(&server.ws(&path)).await;
        let chatter = r#"{"type":"control","action":"pause"}"#;
        let mut sent = 0;
        let closed = loop {
            if sent < 5000 && socket.send(Message::Text(chatter.into())).await.is_ok() {
                sent += 1;
                continue;
            }
            match tokio::time::timeout(Duration::from_secs(10), socket.next()).await {
                Ok(Some(Ok(Message::Close(Some(frame))))) => break u16::from(frame.code),
                Ok(Some(Ok(_))) => {}
                other => panic!("{path}: {other:?}"),
            }
        };
        assert_eq!(closed, 1008, "{path}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_bot_that_stops_reading_is_closed_within_the_send_timeout() {
    let file = settings("bot-write-timeout", "send_timeout_ms = 1000\n");
    let server = Server::start(&["--no-demo", "--config", file.to_str().unwrap()]);
    // Lock-step with a 1 ms deadline: perceptions as fast as the match can make them.
    let (id, tokens) = server.create(common::server::fielder_with_bot("lockstep", 1));
    let url = server.ws(&format!(
        "/ws/matches/{id}/play?token={}",
        tokens["cf"].as_str().unwrap()
    ));
    // A small receive window, so the server's writes back up soon.
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket.set_recv_buffer_size(2048).unwrap();
    let stream = socket.connect(server.addr.parse().unwrap()).await.unwrap();
    let request = url.as_str().into_client_request().unwrap();
    let (stalled, _) = tokio_tungstenite::client_async(request, stream)
        .await
        .unwrap();
    // It never reads again. Wait until the server's writes to it stop (no byte out for
    // half a second): its socket is full and the server's write to it is waiting.
    let (mut written, mut since) = (-1.0, Instant::now());
    common::until(
        Duration::from_secs(30),
        "the server kept writing to a bot that reads nothing",
        || {
            let now = server.metric("fieldhouse_bytes_out_total");
            if now != written {
                (written, since) = (now, Instant::now());
            }
            since.elapsed() >= Duration::from_millis(500)
        },
    )
    .await;
    // Its owner reconnects with the same token and reads; the stalled connection must
    // not keep a place (before, it stayed connected for as long as its client lived).
    let mut fresh = connect(&url).await;
    assert_eq!(next_of(&mut fresh, "hello").await["role"], "bot");
    common::until(
        Duration::from_secs(5),
        "a bot that stopped reading is still connected after its token reconnected",
        || server.metric("fieldhouse_connections{role=\"bot\"}") <= 1.0,
    )
    .await;
    assert!(server.metric("fieldhouse_slow_clients_dropped_total") >= 1.0);
    drop(stalled);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_forged_host_cannot_pass_for_the_servers_own_origin() {
    let server = Server::start(&["--allow-host", "play.example"]);
    let port = server.addr.rsplit(':').next().unwrap().to_string();
    let open = |host: String| {
        let url = server.ws("/ws/matches/demo-baseball");
        async move {
            let mut request = url.into_client_request().unwrap();
            let headers = request.headers_mut();
            headers.insert("host", host.parse().unwrap());
            headers.insert("origin", format!("http://{host}").parse().unwrap());
            match tokio_tungstenite::connect_async(request).await {
                Ok(_) => 101,
                Err(tokio_tungstenite::tungstenite::Error::Http(r)) => r.status().as_u16(),
                Err(e) => panic!("{e}"),
            }
        }
    };
    // A page whose name the attacker pointed at this machine: Origin and Host agree.
    assert_eq!(open(format!("evil.example:{port}")).await, 403);
    assert_eq!(open(format!("localhost:{port}")).await, 101);
    assert_eq!(open(format!("play.example:{port}")).await, 101);
    assert!(server.metric("fieldhouse_sockets_refused_total{reason=\"origin\"}") >= 1.0);
}

/// At a limit of one request in flight, a request that holds the slot (the admin's POST
/// whose body has not arrived: its handler is waiting for it) makes every other API request
/// an immediate 503 "overloaded", not a wait; probes are outside the limit; and once the
/// slot is let go the API answers again. (Holding the slot on purpose, rather than
/// racing many clients, keeps the test exact on a loaded machine.)
#[test]
fn requests_beyond_the_concurrency_limit_are_shed_not_queued() {
    let file = settings("shedding", "max_concurrent_requests = 1\n");
    let server = Server::start(&["--no-demo", "--config", file.to_str().unwrap()]);
    let url = server.http("/api/matches");
    // The admin's POST whose body never comes: it holds the slot from the moment its
    // handler starts reading the body.
    let hold = || {
        let mut holder = TcpStream::connect(&server.addr).unwrap();
        write!(
            holder,
            "POST /api/matches HTTP/1.1\r\nHost: {}\r\nAuthorization: Bearer {ADMIN}\r\nContent-Type: application/json\r\nContent-Length: 64\r\n\r\n",
            server.addr
        )
        .unwrap();
        holder
    };
    let mut holder = hold();
    let status = || match ureq::get(&url).call() {
        Ok(r) => r.status(),
        Err(ureq::Error::Status(code, r)) => {
            let body: serde_json::Value = r.into_json().unwrap();
            assert_eq!(body["error"]["code"], "overloaded");
            code
        }
        Err(e) => panic!("{e}"),
    };
    // The held request reaches its handler within moments; from then on every request
    // is shed at once. If it arrived while one of these was in flight, it was itself
    // shed (it has an answer): hold the slot again.
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut shed_from = 0;
    while status() != 503 {
        assert!(
            Instant::now() < deadline,
            "a request holding the only slot sheds the others"
        );
        holder.set_nonblocking(true).unwrap();
        let answered = holder.read(&mut [0u8; 64]).is_ok();
        holder.set_nonblocking(false).unwrap();
        if answered {
            holder = hold();
        }
        shed_from += 1;
        std::thread::sleep(Duration::from_millis(10));
    }
    for _ in 0..10 {
        assert_eq!(status(), 503);
        // Health checks are not part of the limit.
        assert_eq!(server.get("/readyz")["ready"], true);
    }
    assert!(
        server.metric("fieldhouse_requests_shed_total") >= 11.0,
        "{shed_from}"
    );
    // Let the slot go: the API answers again.
    drop(holder);
    let answered = (0..200).any(|_| {
        let s = status();
        if s != 200 {
            std::thread::sleep(Duration::from_millis(10));
        }
        s == 200
    });
    assert!(answered, "the API stays shut after the slot is let go");
}

/// Whether the server has closed its end of `client`'s connection, as the kernel's
/// table of TCP sockets says (the server's socket has left ESTABLISHED), without
/// reading what the server sent.
/// Requests without the admin token are refused from their headers, before their body
/// is read: anonymous POSTs that never send their body (more of them than the API has
/// request slots) are each answered 401 at once, and the admin's own POST still creates
/// its match rather than meeting 503 "overloaded".
#[test]
fn anonymous_slow_bodies_cannot_deny_match_creation() {
    let file = settings("slow-bodies", "max_concurrent_requests = 4\n");
    let server = Server::start(&["--no-demo", "--config", file.to_str().unwrap()]);
    let anonymous: Vec<TcpStream> = (0..12)
        .map(|_| {
            let mut stream = TcpStream::connect(&server.addr).unwrap();
            write!(
                stream,
                "POST /api/matches HTTP/1.1\r\nHost: {}\r\nContent-Type: application/json\r\nContent-Length: 4096\r\n\r\n{{",
                server.addr
            )
            .unwrap();
            stream
        })
        .collect();
    for mut stream in anonymous {
        stream
            .set_read_timeout(Some(Duration::from_secs(5)))
            .unwrap();
        let mut head = [0u8; 12];
        stream
            .read_exact(&mut head)
            .expect("an anonymous POST is answered without its body");
        assert_eq!(&head, b"HTTP/1.1 401", "{}", String::from_utf8_lossy(&head));
    }
    let (id, _) = server.create(common::server::fielder_with_bot("lockstep", 200));
    assert!(!id.is_empty());
}

fn server_side_closed(server: &Server, client: &TcpStream) -> bool {
    let hex = |addr: std::net::SocketAddr| match addr {
        std::net::SocketAddr::V4(a) => {
            format!(
                "{:08X}:{:04X}",
                u32::from_ne_bytes(a.ip().octets()),
                a.port()
            )
        }
        std::net::SocketAddr::V6(_) => panic!("the tests listen on IPv4 loopback"),
    };
    let (local, remote) = (
        hex(server.addr.parse().unwrap()),
        hex(client.local_addr().unwrap()),
    );
    let table = std::fs::read_to_string("/proc/net/tcp").unwrap();
    // Rows: slot, local address, remote address, state (01 is ESTABLISHED), ...
    !table.lines().any(|row| {
        let fields: Vec<&str> = row.split_whitespace().collect();
        fields.get(1..4) == Some(&[local.as_str(), remote.as_str(), "01"][..])
    })
}

#[test]
fn a_download_whose_client_stops_reading_is_closed_at_the_send_timeout() {
    let file = settings("stalled-download", "send_timeout_ms = 1000\n");
    let dir = common::server::empty_dir("stalled-download-replays");
    std::fs::create_dir_all(&dir).unwrap();
    // The download streams bytes; whether they are a replay does not matter here.
    let size = 32 << 20;
    std::fs::write(dir.join("large.jsonl"), vec![b'x'; size]).unwrap();
    let server = Server::start(&[
        "--no-demo",
        "--config",
        file.to_str().unwrap(),
        "--replay-dir",
        dir.to_str().unwrap(),
    ]);
    let mut client = TcpStream::connect(&server.addr).unwrap();
    write!(
        client,
        "GET /api/replays/large HTTP/1.1\r\nHost: {}\r\n\r\n",
        server.addr
    )
    .unwrap();
    assert!(
        !server_side_closed(&server, &client),
        "the server's end of the download is not in /proc/net/tcp"
    );
    // Read nothing: the socket buffers fill, the server's writes stall, and at the send
    // timeout (1 s) it gives up and closes its end.
    common::until_blocking(
        Duration::from_secs(10),
        "the server kept a download whose client reads nothing",
        || server_side_closed(&server, &client),
    );
    client
        .set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let mut received = Vec::new();
    let ended = client.read_to_end(&mut received);
    assert!(ended.is_ok(), "the server closed the connection: {ended:?}");
    assert!(
        received.len() < size,
        "the whole file came through ({} bytes): the stalled download was kept",
        received.len()
    );
}

/// The server's TCP sockets (not its listener) whose client address `peer` accepts:
/// its descriptors, matched by inode to the kernel's table of TCP sockets. What the
/// server really holds, whatever its own accounting says.
fn sockets_held(server: &Server, peer: impl Fn(std::net::Ipv4Addr) -> bool) -> usize {
    let fds = format!("/proc/{}/fd", server.child.id());
    let inodes: std::collections::HashSet<String> = std::fs::read_dir(&fds)
        .unwrap()
        .filter_map(|fd| {
            let link = std::fs::read_link(fd.ok()?.path()).ok()?;
            let link = link.to_str()?;
            Some(
                link.strip_prefix("socket:[")?
                    .strip_suffix(']')?
                    .to_string(),
            )
        })
        .collect();
    let table = std::fs::read_to_string("/proc/net/tcp").unwrap();
    // Rows: slot, local address, remote address, state (0A is LISTEN), ..., inode (10th).
    table
        .lines()
        .skip(1)
        .filter(|row| {
            let fields: Vec<&str> = row.split_whitespace().collect();
            let remote = fields[2].split(':').next().unwrap();
            let remote =
                std::net::Ipv4Addr::from(u32::from_str_radix(remote, 16).unwrap().to_ne_bytes());
            fields[3] != "0A" && inodes.contains(fields[9]) && peer(remote)
        })
        .count()
}

/// Asks for a download of replay `id` from `source` (a client with a small receive
/// buffer) and reads its status code, and no more unless it is refused: a client that
/// reads the body slowly, or never. A refused connection is read to its end, so the
/// server has closed it when this returns.
async fn download_from(source: [u8; 4], server: &Server, id: &str) -> (u16, tokio::net::TcpStream) {
    let socket = tokio::net::TcpSocket::new_v4().unwrap();
    socket.set_recv_buffer_size(4096).unwrap();
    socket
        .bind((std::net::Ipv4Addr::from(source), 0).into())
        .unwrap();
    let mut stream = socket.connect(server.addr.parse().unwrap()).await.unwrap();
    let request = format!(
        "GET /api/replays/{id} HTTP/1.1\r\nHost: {}\r\n\r\n",
        server.addr
    );
    // A refused connection may be closed before the request is written.
    let _ = stream.write_all(request.as_bytes()).await;
    let mut head = [0u8; 12];
    tokio::time::timeout(Duration::from_secs(10), stream.read_exact(&mut head))
        .await
        .expect("an answer within 10 s")
        .expect("a status line");
    let status: u16 = std::str::from_utf8(&head[9..12]).unwrap().parse().unwrap();
    if status != 200 {
        let mut rest = Vec::new();
        let _ = tokio::time::timeout(Duration::from_secs(10), stream.read_to_end(&mut rest))
            .await
            .expect("a refused connection is closed");
    }
    (status, stream)
}

/// A download is busy until its body has gone, however slowly its client reads: it is
/// never closed to make room for another connection, and new connections at a cap are
/// refused (429 for an address at its cap, 503 for a full server) rather than counted on
/// top of it. Before, a download counted as idle once its headers were out, so each new
/// connection "closed" one (a graceful shutdown that let its body go on) and was counted
/// as well: one address held 320 connections at a cap of 20.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn slow_downloads_hold_their_places_and_the_caps_hold() {
    // Downloads that read nothing are not dropped at the send timeout within the test.
    let file = settings(
        "slow-downloads",
        "send_timeout_ms = 60000\nmax_connections = 32\n",
    );
    let dir = common::server::empty_dir("slow-downloads-replays");
    std::fs::create_dir_all(&dir).unwrap();
    // 64 MB (sparse) that no socket buffer holds: the body is in flight until its
    // client has read it.
    std::fs::File::create(dir.join("large.jsonl"))
        .unwrap()
        .set_len(64 << 20)
        .unwrap();
    let server = Server::start(&[
        "--no-demo",
        "--config",
        file.to_str().unwrap(),
        "--replay-dir",
        dir.to_str().unwrap(),
        "--max-connections-per-ip",
        "20",
    ]);
    let attacker = [127, 0, 0, 2];
    let from = |a: [u8; 4]| move |ip: std::net::Ipv4Addr| ip.octets() == a;
    let mut held = Vec::new();
    for _ in 0..20 {
        let (status, stream) = download_from(attacker, &server, "large").await;
        assert_eq!(status, 200);
        held.push(stream);
    }
    // 300 more from the same address, each asking for the download too.
    let (mut answers, mut most) = (std::collections::BTreeMap::new(), 0);
    for k in 0..300 {
        let (status, stream) = download_from(attacker, &server, "large").await;
        *answers.entry(status).or_insert(0) += 1;
        if status == 200 {
            held.push(stream);
        }
        if k % 10 == 9 {
            // A refused socket the client saw closed can outlive its EOF in the server's
            // descriptor table for a moment (the FIN goes before the descriptor does):
            // over the cap, look again until it is gone or two seconds have passed.
            let mut held_now = sockets_held(&server, from(attacker));
            for _ in 0..20 {
                if held_now <= 20 {
                    break;
                }
                tokio::time::sleep(Duration::from_millis(100)).await;
                held_now = sockets_held(&server, from(attacker));
            }
            most = most.max(held_now);
        }
    }
    assert!(
        most <= 20,
        "the server held {most} connections from one address at a cap of 20 (answers: {answers:?})"
    );
    assert_eq!(
        answers[&429], 300,
        "every connection over the cap is refused"
    );
    assert_eq!(sockets_held(&server, from(attacker)), 20);
    assert_eq!(
        server.metric("fieldhouse_sockets_refused_total{reason=\"per_ip\"}"),
        300.0
    );
    // The total cap the same way: 12 more downloads from another address fill the 32
    // places; 100 connections from a third are refused 503 and the server holds 32.
    for _ in 0..12 {
        let (status, stream) = download_from([127, 0, 0, 3], &server, "large").await;
        assert_eq!(status, 200);
        held.push(stream);
    }
    let (mut full, mut most) = (0, 0);
    for k in 0..100 {
        match download_from([127, 0, 0, 4], &server, "large").await {
            (503, _) => full += 1,
            (200, stream) => held.push(stream),
            (other, _) => panic!("a connection over the total cap got {other}"),
        }
        if k % 10 == 9 {
            most = most.max(sockets_held(&server, |_| true));
        }
    }
    assert!(
        most <= 32,
        "the server held {most} connections at a cap of 32 ({full} of 100 refused)"
    );
    assert_eq!(full, 100);
    // Let the downloads go: their places come back, and the refusals were counted.
    drop(held);
    common::until(
        Duration::from_secs(10),
        "the closed downloads' places come back",
        || sockets_held(&server, |_| true) == 0,
    )
    .await;
    assert_eq!(
        server.metric("fieldhouse_sockets_refused_total{reason=\"full\"}"),
        100.0
    );
}

/// A client frame of any first byte (FIN, reserved bits, opcode), masked or not, any
/// length: the header as the WebSocket library writes it, however wrong the frame is.
fn raw_frame(first: u8, masked: bool, payload: &[u8]) -> Vec<u8> {
    let mask = masked.then_some([7, 7, 7, 7]);
    let header = FrameHeader {
        is_final: first & 0x80 != 0,
        rsv1: first & 0x40 != 0,
        rsv2: first & 0x20 != 0,
        rsv3: first & 0x10 != 0,
        opcode: OpCode::from(first & 0x0f),
        mask,
    };
    let mut out = Vec::new();
    header.format(payload.len() as u64, &mut out).unwrap();
    match mask {
        Some(mask) => out.extend(payload.iter().enumerate().map(|(k, b)| b ^ mask[k % 4])),
        None => out.extend(payload),
    }
    out
}

/// Frames that break RFC 6455 get a close frame with 1002 (protocol error) on every
/// socket kind, text that is not UTF-8 gets 1007, and a message over the size limit
/// still gets 1009. Before, a protocol error ended the socket without a close frame.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn protocol_errors_are_closed_with_1002_on_every_socket_kind() {
    let dir = common::server::empty_dir("protocol-errors");
    let server = Server::start(&["--replay-dir", dir.to_str().unwrap()]);
    let replays = server.get("/api/replays");
    let replay = replays["replays"][0]["id"]
        .as_str()
        .expect("a demo is recorded")
        .to_string();
    let (id, tokens) = server.create(common::server::fielder_with_bot("realtime", 1000));
    let play = format!(
        "/ws/matches/{id}/play?token={}",
        tokens["cf"].as_str().unwrap()
    );
    let close = |code: u16, reason: &[u8]| {
        let mut payload = code.to_be_bytes().to_vec();
        payload.extend(reason);
        payload
    };
    let violations: Vec<(&str, Vec<u8>, u16)> = vec![
        (
            "a reserved bit set (RSV1)",
            raw_frame(0x80 | 0x40 | 0x1, true, b"{}"),
            1002,
        ),
        (
            "reserved bits set (RSV2, RSV3)",
            raw_frame(0x80 | 0x30 | 0x2, true, b"x"),
            1002,
        ),
        ("an unmasked frame", raw_frame(0x81, false, b"{}"), 1002),
        (
            "a reserved data opcode (3)",
            raw_frame(0x83, true, b"x"),
            1002,
        ),
        (
            "a reserved control opcode (0xB)",
            raw_frame(0x8b, true, b""),
            1002,
        ),
        (
            "a continuation frame first",
            raw_frame(0x80, true, b"x"),
            1002,
        ),
        (
            "a new message inside a fragmented one",
            {
                let mut bytes = raw_frame(0x01, true, b"{");
                bytes.extend(raw_frame(0x81, true, b"}"));
                bytes
            },
            1002,
        ),
        ("a fragmented ping", raw_frame(0x09, true, b"hi"), 1002),
        (
            "a ping of 126 bytes",
            raw_frame(0x89, true, &[b'p'; 126]),
            1002,
        ),
        (
            "a close with a one-byte body",
            raw_frame(0x88, true, &[3]),
            1002,
        ),
        (
            "a close with code 1005 (never sent)",
            raw_frame(0x88, true, &close(1005, b"")),
            1002,
        ),
        (
            "a close with code 999",
            raw_frame(0x88, true, &close(999, b"")),
            1002,
        ),
        (
            "a close with reserved code 2000",
            raw_frame(0x88, true, &close(2000, b"")),
            1002,
        ),
        (
            "a close with code 5000",
            raw_frame(0x88, true, &close(5000, b"")),
            1002,
        ),
        (
            "text that is not UTF-8",
            raw_frame(0x81, true, &[b'{', 0xff, 0xfe, b'}']),
            1007,
        ),
        (
            "a close whose reason is not UTF-8",
            raw_frame(0x88, true, &close(1000, &[0xc3, 0x28])),
            1007,
        ),
        (
            "a message over the size limit",
            raw_frame(0x81, true, &vec![b' '; 5000]),
            1009,
        ),
        // Not an error: a close the server answers with its own, as RFC 6455 asks.
        (
            "a close with 1000",
            raw_frame(0x88, true, &close(1000, b"bye")),
            1000,
        ),
    ];
    for path in [
        "/ws/matches/demo-baseball".to_string(),
        play.clone(),
        format!("/ws/replays/{replay}"),
    ] {
        for (what, bytes, code) in &violations {
            let mut socket = raw_socket(&server, &path).await;
            // The server may close before it has read them all.
            let _ = socket.write_all(bytes).await;
            assert_eq!(
                close_code(&mut socket).await,
                Some(*code),
                "{what} on {path}"
            );
        }
    }
    // 14 protocol errors and 2 bad texts on each of the three sockets.
    assert_eq!(
        server.metric("fieldhouse_closed_protocol_error_total"),
        3.0 * 16.0
    );
}
