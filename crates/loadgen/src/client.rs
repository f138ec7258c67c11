//! Spectators: each connects on a task of its own (the HTTP upgrade, written here), and
//! is then read by one of a few threads that poll their share of the sockets (epoll,
//! through mio) and note each message's arrival while the window is open.
//!
//! The load generator shares the machine with the server it measures, so what it spends
//! per received frame is taken from the server: at 5,000 spectators the WebSocket
//! library's client (a task, a timer and a decoded, UTF-8-checked message per frame)
//! took about a core. Here a frame costs its share of one `epoll_wait`, one `read` and
//! a scan of its first bytes: nothing is decoded beyond what identifies a message
//! (a fieldhouse frame's tick and `sent_us`, a hash of a Colyseus patch); pings are
//! answered (Colyseus drops a client that does not), and everything else is skipped.

use std::hash::{Hash, Hasher};
use std::io::{ErrorKind, Read, Write};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{mpsc, Arc};
use std::time::{Duration, SystemTime, UNIX_EPOCH};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::protocol::frame::coding::OpCode;
use tokio_tungstenite::tungstenite::protocol::frame::FrameHeader;

/// Where spectators connect.
#[derive(Debug, Clone)]
pub(crate) enum Target {
    /// A fieldhouse match (or the bare sender), `ws://…/ws/matches/ID`, the `index`th
    /// of the run.
    Fieldhouse { url: String, index: u64 },
    /// A Colyseus room: seats from `POST {http}/matchmake/joinOrCreate/match`, sockets
    /// at `{ws}/{processId}/{roomId}?sessionId=…`.
    Colyseus { http: String, ws: String },
}

/// A message seen in the window.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Arrival {
    /// The same for every spectator's copy of one message: the match's index and the
    /// frame's tick (fieldhouse), a hash of the patch's bytes (Colyseus, whose patches
    /// are the same bytes for everyone and differ from tick to tick).
    pub key: u64,
    pub at_us: u64,
    /// When the server published it (fieldhouse's `sent_us`).
    pub sent_us: Option<u64>,
}

#[derive(Debug, Default)]
pub(crate) struct Log {
    pub arrivals: Vec<Arrival>,
    pub bytes: u64,
}

/// What a round's spectators share while connecting.
#[derive(Debug, Clone)]
pub(crate) struct Shared {
    /// Handshakes allowed in flight.
    pub gate: Arc<tokio::sync::Semaphore>,
    /// Spectators done connecting, whether they made it or not.
    pub settled: Arc<AtomicUsize>,
}

/// Threads reading the spectators' sockets; see [`Readers::start`].
pub(crate) struct Readers {
    inboxes: Vec<(mpsc::Sender<Joined>, Arc<mio::Waker>)>,
    threads: std::sync::Mutex<Vec<std::thread::JoinHandle<Vec<Log>>>>,
    next: AtomicUsize,
    /// Set when the readers are dropped, so a round that fails leaves no thread behind.
    stop: Arc<AtomicBool>,
}

impl Drop for Readers {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// How many threads read the spectators' sockets: `FIELDHOUSE_LOADGEN_READERS`, else
/// one per core.
pub(crate) fn reader_threads() -> usize {
    std::env::var("FIELDHOUSE_LOADGEN_READERS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&n: &usize| (1..=64).contains(&n))
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(2, |n| n.get()))
}

/// A connected spectator on its way to a reader: its socket, what the handshake read
/// past the response's headers, and how to read its messages.
struct Joined {
    stream: std::net::TcpStream,
    leftover: Vec<u8>,
    kind: Kind,
}

#[derive(Debug, Clone, Copy)]
enum Kind {
    Fieldhouse { index: u64 },
    Colyseus,
}

const WAKER: mio::Token = mio::Token(usize::MAX);

/// How often a reader looks at `stop` when its sockets are quiet.
const POLL_EVERY: Duration = Duration::from_millis(100);

impl Readers {
    /// Starts `threads` readers, which log arrivals while `recording` and return their
    /// spectators' logs once `stop` is set.
    pub(crate) fn start(
        threads: usize,
        recording: &Arc<AtomicBool>,
        stop: &Arc<AtomicBool>,
    ) -> anyhow::Result<Readers> {
        let mut inboxes = Vec::new();
        let mut handles = Vec::new();
        for k in 0..threads {
            let poll = mio::Poll::new()?;
            let waker = Arc::new(mio::Waker::new(poll.registry(), WAKER)?);
            let (tx, rx) = mpsc::channel();
            let (recording, stop) = (recording.clone(), stop.clone());
            let thread = std::thread::Builder::new()
                .name(format!("loadgen-reader-{k}"))
                .spawn(move || read_loop(poll, &rx, &recording, &stop))?;
            inboxes.push((tx, waker));
            handles.push(thread);
        }
        Ok(Readers {
            inboxes,
            threads: std::sync::Mutex::new(handles),
            next: AtomicUsize::new(0),
            stop: stop.clone(),
        })
    }

    fn hand_over(&self, joined: Joined) {
        let k = self.next.fetch_add(1, Ordering::Relaxed) % self.inboxes.len();
        let (tx, waker) = &self.inboxes[k];
        if tx.send(joined).is_ok() {
            let _ = waker.wake();
        }
    }

    /// The logs of every spectator handed over, once `stop` (given to
    /// [`Readers::start`]) is set.
    pub(crate) fn logs(&self) -> Vec<Log> {
        for (_, waker) in &self.inboxes {
            let _ = waker.wake();
        }
        let threads = std::mem::take(&mut *self.threads.lock().expect("not poisoned"));
        threads
            .into_iter()
            .filter_map(|t| t.join().ok())
            .flatten()
            .collect()
    }
}

pub(crate) fn now_us() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64)
}

/// Connects one spectator (at most `round.gate` at a time) and hands its socket to a
/// reader; counts it as settled either way.
pub(crate) async fn spectate(target: Target, round: Shared, readers: Arc<Readers>) {
    let connected = {
        let Ok(_permit) = round.gate.acquire().await else {
            round.settled.fetch_add(1, Ordering::SeqCst);
            return;
        };
        connect(&target).await
    };
    match connected {
        Ok(joined) => readers.hand_over(joined),
        Err(e) => tracing::warn!(error = %e, "a spectator could not connect"),
    }
    round.settled.fetch_add(1, Ordering::SeqCst);
}

/// The longest a connection and its handshake may take.
const HANDSHAKE_WITHIN: Duration = Duration::from_secs(30);

async fn connect(target: &Target) -> anyhow::Result<Joined> {
    let (url, kind) = match target {
        Target::Fieldhouse { url, index } => (url.clone(), Kind::Fieldhouse { index: *index }),
        Target::Colyseus { http, ws } => {
            let http = format!("{http}/matchmake/joinOrCreate/match");
            let seat: serde_json::Value = tokio::task::spawn_blocking(move || {
                ureq::post(&http)
                    .set("content-type", "application/json")
                    .send_string("{}")?
                    .into_json::<serde_json::Value>()
                    .map_err(anyhow::Error::from)
            })
            .await??;
            let field = |name: &str| seat[name].as_str().unwrap_or_default().to_owned();
            let url = format!(
                "{ws}/{}/{}?sessionId={}",
                field("processId"),
                field("roomId"),
                field("sessionId")
            );
            (url, Kind::Colyseus)
        }
    };
    let (stream, leftover) = tokio::time::timeout(HANDSHAKE_WITHIN, upgrade(&url))
        .await
        .map_err(|_| anyhow::anyhow!("no handshake within {HANDSHAKE_WITHIN:?}: {url}"))??;
    Ok(Joined {
        stream,
        leftover,
        kind,
    })
}

/// Opens `ws://HOST:PORT/PATH` (RFC 6455 §4.1): the socket, non-blocking, and whatever
/// arrived after the response's headers.
async fn upgrade(url: &str) -> anyhow::Result<(std::net::TcpStream, Vec<u8>)> {
    let rest = url
        .strip_prefix("ws://")
        .ok_or_else(|| anyhow::anyhow!("not a ws:// URL: {url}"))?;
    let (host, path) = rest.split_at(rest.find('/').unwrap_or(rest.len()));
    let path = if path.is_empty() { "/" } else { path };
    let mut stream = tokio::net::TcpStream::connect(host).await?;
    // Any 16 bytes in base64 will do: the client does not check the answer's key.
    stream
        .write_all(
            format!(
                "GET {path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
                 Sec-WebSocket-Version: 13\r\n\r\n"
            )
            .as_bytes(),
        )
        .await?;
    let mut response = Vec::with_capacity(1024);
    let end = loop {
        if let Some(at) = response.windows(4).position(|w| w == b"\r\n\r\n") {
            break at + 4;
        }
        anyhow::ensure!(response.len() < 16 * 1024, "an endless response to {url}");
        if stream.read_buf(&mut response).await? == 0 {
            anyhow::bail!("the server closed the connection during the handshake: {url}");
        }
    };
    let status =
        String::from_utf8_lossy(response.split(|&b| b == b'\r').next().unwrap_or(&[])).into_owned();
    anyhow::ensure!(
        status.split(' ').nth(1) == Some("101"),
        "{url} answered {status:?}"
    );
    let leftover = response.split_off(end);
    Ok((stream.into_std()?, leftover))
}

/// One reader thread: registers the sockets handed to it, reads whichever are ready, and
/// returns their logs once `stop` is set.
fn read_loop(
    mut poll: mio::Poll,
    inbox: &mpsc::Receiver<Joined>,
    recording: &AtomicBool,
    stop: &AtomicBool,
) -> Vec<Log> {
    let mut spectators: Vec<Spectator> = Vec::new();
    let mut events = mio::Events::with_capacity(EVENTS);
    while !stop.load(Ordering::Relaxed) {
        if let Err(e) = poll.poll(&mut events, Some(POLL_EVERY)) {
            if e.kind() != ErrorKind::Interrupted {
                tracing::warn!(error = %e, "a reader cannot poll its sockets");
                break;
            }
        }
        let recording = recording.load(Ordering::Relaxed);
        while let Ok(joined) = inbox.try_recv() {
            let token = mio::Token(spectators.len());
            let mut stream = mio::net::TcpStream::from_std(joined.stream);
            if poll
                .registry()
                .register(&mut stream, token, mio::Interest::READABLE)
                .is_err()
            {
                continue;
            }
            let mut s = Spectator::new(stream, joined.kind);
            let had = joined.leftover.len();
            if had > s.buf.len() {
                s.buf.resize(had.next_power_of_two(), 0);
            }
            s.buf[..had].copy_from_slice(&joined.leftover);
            s.filled = had;
            s.take_frames(now_us(), recording);
            spectators.push(s);
        }
        for event in &events {
            if let Some(s) = spectators.get_mut(event.token().0) {
                if s.open {
                    s.read(recording);
                    if !s.open {
                        let _ = poll.registry().deregister(&mut s.stream);
                    }
                }
            }
        }
    }
    spectators.into_iter().map(|s| s.log).collect()
}

/// Events taken from one poll.
const EVENTS: usize = 1024;

/// The buffer a spectator reads into at first; it grows for a larger message.
const BUFFER_BYTES: usize = 4096;

/// The largest message read (a bigger one closes the spectator).
const MAX_MESSAGE_BYTES: usize = 16 << 20;

/// One spectator's socket, the bytes read and not yet taken as whole frames, and its log.
struct Spectator {
    stream: mio::net::TcpStream,
    kind: Kind,
    buf: Vec<u8>,
    filled: usize,
    open: bool,
    log: Log,
}

impl Spectator {
    fn new(stream: mio::net::TcpStream, kind: Kind) -> Spectator {
        Spectator {
            stream,
            kind,
            buf: vec![0; BUFFER_BYTES],
            filled: 0,
            open: true,
            log: Log::default(),
        }
    }

    /// Reads what the socket holds (edge-triggered: until a read comes back short, which
    /// means it was emptied; new data wakes the poll again) and takes the whole frames.
    fn read(&mut self, recording: bool) {
        let mut at_us = None;
        loop {
            if self.filled == self.buf.len() {
                self.buf.resize(self.buf.len() * 2, 0);
            }
            let room = self.buf.len() - self.filled;
            match self.stream.read(&mut self.buf[self.filled..]) {
                Ok(0) => {
                    self.open = false;
                    return;
                }
                Ok(n) => {
                    self.filled += n;
                    let at = *at_us.get_or_insert_with(now_us);
                    self.take_frames(at, recording);
                    if n < room || !self.open {
                        return;
                    }
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => return,
                Err(e) if e.kind() == ErrorKind::Interrupted => {}
                Err(_) => {
                    self.open = false;
                    return;
                }
            }
        }
    }

    /// Takes every whole frame at the front of the buffer, logging the messages that
    /// count, and keeps the rest for the next read.
    fn take_frames(&mut self, at_us: u64, recording: bool) {
        let mut start = 0;
        while let Some((header, len)) = frame_at(&self.buf[start..self.filled]) {
            if header + len > MAX_MESSAGE_BYTES {
                self.open = false;
                return;
            }
            if self.filled - start < header + len {
                // Room for the whole frame, then wait for the rest.
                let need = header + len;
                if need > self.buf.len() {
                    self.buf.resize(need.next_power_of_two(), 0);
                }
                break;
            }
            let b0 = self.buf[start];
            let payload = start + header..start + header + len;
            self.message(b0 & 0x0f, payload.clone(), at_us, recording);
            start = payload.end;
        }
        self.buf.copy_within(start..self.filled, 0);
        self.filled -= start;
    }

    /// One whole frame: `opcode` and where its payload is in the buffer.
    fn message(
        &mut self,
        opcode: u8,
        payload: std::ops::Range<usize>,
        at_us: u64,
        recording: bool,
    ) {
        const TEXT: u8 = 0x1;
        const BINARY: u8 = 0x2;
        const CLOSE: u8 = 0x8;
        const PING: u8 = 0x9;
        const PONG: u8 = 0xa;
        let bytes = &self.buf[payload];
        let seen = match (self.kind, opcode) {
            (Kind::Fieldhouse { index }, TEXT) => fieldhouse_frame(bytes)
                .map(|(tick, sent_us)| ((index << MATCH_SHIFT) | tick, sent_us)),
            (Kind::Colyseus, BINARY) => match bytes.first().map(|b| b & 31) {
                Some(JOIN_ROOM) => {
                    // The server sends the state only after the client echoes it.
                    let _ = self.stream.write(&client_frame(BINARY, &[JOIN_ROOM]));
                    None
                }
                Some(ROOM_STATE_PATCH) => Some((colyseus_key(bytes), None)),
                _ => None,
            },
            (_, PING) => {
                let _ = self.stream.write(&client_frame(PONG, bytes));
                None
            }
            (_, CLOSE) => {
                self.open = false;
                None
            }
            _ => None,
        };
        if let (Some((key, sent_us)), true) = (seen, recording) {
            self.log.bytes += bytes.len() as u64;
            self.log.arrivals.push(Arrival {
                key,
                at_us,
                sent_us,
            });
        }
    }
}

/// The header's length and the payload's, if `bytes` start with a whole frame header
/// (RFC 6455 §5.2; a server's frames are not masked, but a mask is skipped if present).
fn frame_at(bytes: &[u8]) -> Option<(usize, usize)> {
    let b1 = *bytes.get(1)?;
    let (extended, len) = match b1 & 0x7f {
        126 => (
            2,
            u16::from_be_bytes(bytes.get(2..4)?.try_into().ok()?) as usize,
        ),
        127 => (
            8,
            usize::try_from(u64::from_be_bytes(bytes.get(2..10)?.try_into().ok()?))
                .unwrap_or(usize::MAX / 2),
        ),
        n => (0, n as usize),
    };
    let mask = if b1 & 0x80 != 0 { 4 } else { 0 };
    Some((2 + extended + mask, len))
}

/// A client's frame (masked, as a client's must be; the zero mask leaves the payload as
/// it is) of a short payload: a pong or Colyseus's JOIN_ROOM echo.
fn client_frame(opcode: u8, payload: &[u8]) -> Vec<u8> {
    let payload = &payload[..payload.len().min(125)];
    let mut frame = frame_header(OpCode::from(opcode), Some([0; 4]), payload.len());
    frame.extend_from_slice(payload);
    frame
}

/// A final frame's header, as the WebSocket library writes it (RFC 6455 §5.2), with room
/// for its payload of `len` bytes.
pub(crate) fn frame_header(opcode: OpCode, mask: Option<[u8; 4]>, len: usize) -> Vec<u8> {
    let header = FrameHeader {
        opcode,
        mask,
        ..FrameHeader::default()
    };
    let mut out = Vec::with_capacity(header.len(len as u64) + len);
    header
        .format(len as u64, &mut out)
        .expect("writing to a Vec does not fail");
    out
}

/// The whole number right after the first `label` in `text` (`"tick":` → 42), read
/// without decoding the message.
pub(super) fn number_after(text: &[u8], label: &[u8]) -> Option<u64> {
    let at = find(text, label)? + label.len();
    let digits = text[at..].iter().take_while(|b| b.is_ascii_digit()).count();
    std::str::from_utf8(&text[at..at + digits])
        .ok()?
        .parse()
        .ok()
}

/// Where `needle` (not empty) first occurs in `hay`: a scan for its first byte, then a
/// comparison there (comparing a window at every position cost a `memcmp` call each).
fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    let (&first, rest) = needle.split_first()?;
    let mut from = 0;
    while let Some(k) = hay.get(from..)?.iter().position(|&b| b == first) {
        let at = from + k;
        if hay[at + 1..].starts_with(rest) {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

/// A fieldhouse frame's tick and publish time: `{"type":"frame","sent_us":N,…"tick":T`.
pub(crate) fn fieldhouse_frame(text: &[u8]) -> Option<(u64, Option<u64>)> {
    const HEAD: &[u8] = br#"{"type":"frame","#;
    const SENT: &[u8] = br#""sent_us":"#;
    let rest = text.strip_prefix(HEAD)?;
    let sent_us = rest
        .starts_with(SENT)
        .then(|| number_after(rest, SENT))
        .flatten();
    Some((number_after(rest, br#""tick":"#)?, sent_us))
}

/// A message's key is its match's index shifted this far, then the message within the
/// match (a fieldhouse frame's tick; a hash of a Colyseus patch, whose one room is 0).
pub(crate) const MATCH_SHIFT: u32 = 40;

/// Colyseus protocol codes (`@colyseus/shared-types` Protocol): the low five bits of the
/// first byte; the high bits are modifiers.
const JOIN_ROOM: u8 = 10;
const ROOM_STATE_PATCH: u8 = 15;

/// A state patch's key: a hash of its bytes, in the peer's one room (match 0).
fn colyseus_key(bytes: &[u8]) -> u64 {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    bytes.hash(&mut hasher);
    hasher.finish() & ((1 << MATCH_SHIFT) - 1)
}

/// A WebSocket client over TCP, for the soak and the bots.
pub(super) type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

#[cfg(test)]
mod tests {
    use super::{fieldhouse_frame, frame_at, frame_header, Kind, Spectator};
    use tokio_tungstenite::tungstenite::protocol::frame::coding::OpCode;

    #[test]
    fn a_stamped_frame_gives_its_tick_and_send_time() {
        let frame =
            br#"{"type":"frame","sent_us":1795320000123456,"match":"m","tick":42,"time_s":0.7}"#;
        assert_eq!(
            fieldhouse_frame(frame),
            Some((42, Some(1_795_320_000_123_456)))
        );
        let plain = br#"{"type":"frame","match":"m","tick":42,"time_s":0.7}"#;
        assert_eq!(fieldhouse_frame(plain), Some((42, None)));
        assert_eq!(fieldhouse_frame(br#"{"type":"hello"}"#), None);
    }

    /// A server frame (unmasked) of `payload`.
    fn server_frame(opcode: u8, payload: &[u8]) -> Vec<u8> {
        let mut out = frame_header(OpCode::from(opcode), None, payload.len());
        out.extend_from_slice(payload);
        out
    }

    #[test]
    fn frames_split_anywhere_are_taken_whole_and_large_ones_grow_the_buffer() {
        let frame = |tick: u64| {
            format!(
                r#"{{"type":"frame","sent_us":1000,"match":"m","tick":{tick},"x":"{}"}}"#,
                "y".repeat(400)
            )
        };
        let mut stream = Vec::new();
        stream.extend(server_frame(0x1, br#"{"type":"hello","big":""#));
        stream.extend(server_frame(0x1, &vec![b'h'; 70_000])); // a large hello
        for tick in 1..=20 {
            stream.extend(server_frame(0x1, frame(tick).as_bytes()));
        }
        stream.extend(server_frame(0x9, b"")); // a ping: answered, not logged
        assert_eq!(frame_at(&stream[..1]), None);
        for chunk in [1, 7, 500, 4096, 100_000] {
            // The socket is not read here: a connected pair stands in for it, and the
            // bytes are fed to the buffer as reads would.
            let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
            let client = std::net::TcpStream::connect(listener.local_addr().unwrap()).unwrap();
            let _server = listener.accept().unwrap();
            client.set_nonblocking(true).unwrap();
            let mut s = Spectator::new(
                mio::net::TcpStream::from_std(client),
                Kind::Fieldhouse { index: 3 },
            );
            for piece in stream.chunks(chunk) {
                let mut piece = piece;
                while !piece.is_empty() {
                    if s.filled == s.buf.len() {
                        s.buf.resize(s.buf.len() * 2, 0);
                    }
                    let n = piece.len().min(s.buf.len() - s.filled);
                    s.buf[s.filled..s.filled + n].copy_from_slice(&piece[..n]);
                    s.filled += n;
                    piece = &piece[n..];
                    s.take_frames(7, true);
                }
            }
            assert!(s.open, "chunks of {chunk}");
            assert_eq!(s.filled, 0, "chunks of {chunk}");
            let ticks: Vec<u64> = s.log.arrivals.iter().map(|a| a.key & 0xff).collect();
            assert_eq!(ticks, (1..=20).collect::<Vec<_>>(), "chunks of {chunk}");
            assert!(s
                .log
                .arrivals
                .iter()
                .all(|a| a.key >> super::MATCH_SHIFT == 3));
            assert_eq!(
                s.log.bytes,
                (1..=20).map(|t| frame(t).len() as u64).sum::<u64>()
            );
        }
    }
}
