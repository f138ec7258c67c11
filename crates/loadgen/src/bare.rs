//! The bare sender (`fieldhouse bare-sender`, a hidden subcommand that `loadgen` starts
//! in a process of its own): the least a server must do to put the same frame bytes on
//! the same number of WebSocket connections at the same rate as `fieldhouse serve`, so
//! that fieldhouse's CPU per delivered frame can be read against a floor measured on the
//! same machine in the same run.
//!
//! What it does:
//!
//! * **Accepts** TCP connections on one thread and answers each WebSocket upgrade
//!   (`GET` with `Sec-WebSocket-Key`, any path) with `101 Switching Protocols`; nothing
//!   else of HTTP. The socket is then set non-blocking with `TCP_NODELAY`, as
//!   fieldhouse's are, and handed to the sender.
//! * **Sends**, on one thread per core (each with its share of the sockets, as a
//!   server's runtime spreads them over its workers), `frame_hz` times a second: one
//!   prebuilt, unmasked WebSocket text frame, the same bytes for every socket. Its payload is a real
//!   fieldhouse baseball frame (`Session::frame` of the default scenario) in which only
//!   the fields the load generator reads are patched each tick into fixed-width slots:
//!   `sent_us` (the publish time, as `serve --stamp-frames` writes it) and `tick`. It is
//!   padded with trailing spaces to `--payload-bytes`, which `loadgen` sets to the mean
//!   size of the frames fieldhouse sent in the same run, so the payload is the size of
//!   a live frame. Each socket gets one `write` per tick.
//! * **Skips** a frame for a socket whose kernel buffer is full, as fieldhouse skips a
//!   spectator to the newest frame: a write the kernel took only part of keeps its
//!   unwritten tail (the stream must stay whole), which is written first at the next
//!   tick; if even that does not go, the socket misses that tick's frame too. A socket
//!   whose write fails is closed.
//!
//! What it does not do: no simulation and no JSON encoding (the template is encoded once
//! at start), no `hello`, no reading after the handshake (so no pings, pongs, closes or
//! message budgets: a client's close is noticed when a write fails), no metrics, no
//! timeouts, no limits on connections, no per-socket task or buffer beyond a partly
//! written frame's tail. It is not a server anyone should run; it is what writing the
//! bytes costs on this machine.

use crate::client::now_us;
use anyhow::Context;
use std::io::{ErrorKind, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::mpsc;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::handshake::derive_accept_key;
use tokio_tungstenite::tungstenite::protocol::frame::coding::{Data, OpCode};

/// The match id in the bare sender's frames: as long as a fieldhouse match id (12 hex
/// digits), so the frame is the same size.
const MATCH_ID: &str = "bare00000000";

/// The match the frame comes from: the default baseball scenario, 60 ticks and 30
/// frames a second; the template is the median-length frame of its first
/// `TEMPLATE_FRAMES`.
const TICK_HZ: f64 = 60.0;
const FRAME_HZ: f64 = 30.0;
const TEMPLATE_FRAMES: usize = 600;

/// Width of the `tick` slot: digits, then spaces (JSON allows white space after a
/// number). Six digits is over four hours of a 60 Hz match.
const TICK_WIDTH: usize = 6;

/// Width of the `sent_us` slot: µs since the Unix epoch have 16 digits until 2286.
const SENT_WIDTH: usize = 16;

/// The longest an upgrade request may take to arrive, and its largest size.
const HANDSHAKE_WITHIN: Duration = Duration::from_secs(2);
const MAX_REQUEST_BYTES: usize = 8 * 1024;

/// One WebSocket frame, ready to write, with the places its per-tick fields go.
#[derive(Debug, Clone)]
pub struct Template {
    bytes: Vec<u8>,
    header_len: usize,
    sent_at: usize,
    tick_at: usize,
}

impl Template {
    /// A real fieldhouse frame of the default baseball match (the shortest of its first
    /// `TEMPLATE_FRAMES`), padded with trailing spaces to `payload_bytes` if that is
    /// longer (the size of the frames fieldhouse sent in the same run); else the median
    /// of those frames.
    pub fn baseball(payload_bytes: Option<usize>) -> anyhow::Result<Template> {
        use fieldhouse_core::session::Session;
        use fieldhouse_core::sim::{Scenario, World};
        let scenario = Scenario::from_value(serde_json::json!({"sport": "baseball"}))
            .map_err(|e| anyhow::anyhow!("the default baseball scenario: {e}"))?;
        let world = World::new(&scenario, None)
            .map_err(|e| anyhow::anyhow!("the default baseball world: {e}"))?;
        let mut session = Session::new(world, MATCH_ID.into(), TICK_HZ, FRAME_HZ);
        let mut frames = vec![session.frame()];
        while frames.len() < TEMPLATE_FRAMES && !session.world.finished() {
            frames.extend(session.step());
        }
        frames.sort_by_key(String::len);
        let mut template = match payload_bytes {
            Some(_) => Template::from_frame(&frames[0])?,
            None => Template::from_frame(&frames[frames.len() / 2])?,
        };
        if let Some(want) = payload_bytes {
            template.pad_to(want);
        }
        Ok(template)
    }

    /// Trailing spaces (white space JSON allows) until the payload is `len` bytes, if it
    /// is shorter.
    fn pad_to(&mut self, len: usize) {
        let payload = self.payload().len();
        if len > payload {
            let mut text = self.payload().to_vec();
            text.resize(len, b' ');
            let header = frame_header(text.len());
            let shift = header.len() as isize - self.header_len as isize;
            self.bytes = header.clone();
            self.bytes.extend_from_slice(&text);
            self.sent_at = (self.sent_at as isize + shift) as usize;
            self.tick_at = (self.tick_at as isize + shift) as usize;
            self.header_len = header.len();
        }
    }

    /// The frame `text` (`{"type":"frame",…,"tick":T,…}`) with a `sent_us` slot as its
    /// second field (where `serve --stamp-frames` puts it) and its tick in a slot.
    pub fn from_frame(text: &str) -> anyhow::Result<Template> {
        const HEAD: &str = r#"{"type":"frame","#;
        const SENT: &str = r#""sent_us":"#;
        const TICK: &str = r#""tick":"#;
        let rest = text.strip_prefix(HEAD).context("not a fieldhouse frame")?;
        let mut payload = format!("{HEAD}{SENT}{:SENT_WIDTH$},{rest}", 0);
        let sent_at = HEAD.len() + SENT.len();
        let tick_at = payload.find(TICK).context("a frame without a tick")? + TICK.len();
        let digits = payload[tick_at..]
            .bytes()
            .take_while(u8::is_ascii_digit)
            .count();
        payload.replace_range(tick_at..tick_at + digits, &format!("{:TICK_WIDTH$}", 0));
        let header = frame_header(payload.len());
        let mut bytes = header.clone();
        bytes.extend_from_slice(payload.as_bytes());
        Ok(Template {
            bytes,
            header_len: header.len(),
            sent_at: header.len() + sent_at,
            tick_at: header.len() + tick_at,
        })
    }

    /// Writes `tick` and `sent_us` into their slots, left-aligned, padded with spaces.
    pub fn patch(&mut self, tick: u64, sent_us: u64) {
        put(
            &mut self.bytes[self.tick_at..self.tick_at + TICK_WIDTH],
            tick,
        );
        put(
            &mut self.bytes[self.sent_at..self.sent_at + SENT_WIDTH],
            sent_us,
        );
    }

    /// The whole WebSocket frame.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    /// The payload (the frame's text).
    pub fn payload(&self) -> &[u8] {
        &self.bytes[self.header_len..]
    }
}

/// `n` in decimal at the start of `slot`, the rest spaces (digits that do not fit are
/// cut, which a 16-digit time and a six-digit tick never need).
fn put(slot: &mut [u8], mut n: u64) {
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    let digits = &digits[k..];
    let used = digits.len().min(slot.len());
    slot[..used].copy_from_slice(&digits[..used]);
    slot[used..].fill(b' ');
}

/// An unmasked server frame's header: FIN, text, the payload's length (RFC 6455 §5.2).
fn frame_header(len: usize) -> Vec<u8> {
    crate::client::frame_header(OpCode::Data(Data::Text), None, len)
}

/// Serves on `listener` until the process is killed: accepts on this thread, sends on
/// `threads` others (each its share of the sockets), `frame_hz` frames a second (see
/// the module's doc).
pub fn serve(
    listener: TcpListener,
    template: Template,
    frame_hz: f64,
    threads: usize,
) -> anyhow::Result<()> {
    let period = Duration::from_secs_f64(1.0 / frame_hz);
    let ticks_per_frame = (TICK_HZ / frame_hz).round().max(1.0) as u64;
    let start = Instant::now();
    let mut senders = Vec::new();
    for k in 0..threads.max(1) {
        let (joined, arrivals) = mpsc::channel::<TcpStream>();
        let mut template = template.clone();
        std::thread::Builder::new()
            .name(format!("bare-sender-{k}"))
            .spawn(move || send(&arrivals, &mut template, start, period, ticks_per_frame))
            .context("starting a sender thread")?;
        senders.push(joined);
    }
    for (k, stream) in listener.incoming().enumerate() {
        let Ok(mut stream) = stream else { continue };
        if upgrade(&mut stream).is_ok()
            && stream.set_nonblocking(true).is_ok()
            && senders[k % senders.len()].send(stream).is_err()
        {
            break;
        }
    }
    Ok(())
}

/// Answers one WebSocket upgrade request on `stream` (blocking, bounded in time and
/// size); an error if it was not one.
fn upgrade(stream: &mut TcpStream) -> std::io::Result<()> {
    stream.set_read_timeout(Some(HANDSHAKE_WITHIN))?;
    stream.set_nodelay(true)?;
    let mut request = Vec::with_capacity(1024);
    let mut chunk = [0u8; 1024];
    while !request.windows(4).any(|w| w == b"\r\n\r\n") {
        let n = stream.read(&mut chunk)?;
        if n == 0 || request.len() + n > MAX_REQUEST_BYTES {
            return Err(ErrorKind::InvalidData.into());
        }
        request.extend_from_slice(&chunk[..n]);
    }
    let text = String::from_utf8_lossy(&request);
    let key = text.lines().find_map(|line| {
        let (name, value) = line.split_once(':')?;
        name.trim()
            .eq_ignore_ascii_case("sec-websocket-key")
            .then(|| value.trim().to_string())
    });
    let Some(key) = key else {
        let _ = stream.write_all(
            b"HTTP/1.1 400 Bad Request\r\ncontent-length: 0\r\nconnection: close\r\n\r\n",
        );
        return Err(ErrorKind::InvalidData.into());
    };
    let accept = derive_accept_key(key.as_bytes());
    write!(
        stream,
        "HTTP/1.1 101 Switching Protocols\r\nConnection: upgrade\r\nUpgrade: websocket\r\n\
         Sec-WebSocket-Accept: {accept}\r\n\r\n"
    )?;
    Ok(())
}

/// A connected client: its socket and the unwritten tail of a frame the kernel took
/// only part of.
struct Client {
    stream: TcpStream,
    tail: Vec<u8>,
}

impl Client {
    /// Writes what is left of the last frame, then `frame` if that went; false if the
    /// socket failed (the client is gone).
    fn offer(&mut self, frame: &[u8]) -> bool {
        if !self.tail.is_empty() {
            match self.stream.write(&self.tail) {
                Ok(n) => {
                    self.tail.drain(..n);
                }
                Err(e) if e.kind() == ErrorKind::WouldBlock => {}
                Err(_) => return false,
            }
            if !self.tail.is_empty() {
                return true; // still full: this frame is skipped
            }
        }
        match self.stream.write(frame) {
            Ok(n) if n < frame.len() => {
                self.tail.extend_from_slice(&frame[n..]);
                true
            }
            Ok(_) => true,
            Err(e) => e.kind() == ErrorKind::WouldBlock, // full: skipped
        }
    }
}

/// A sender thread: at `start` and every `period` after, the template patched with the
/// tick and the time, offered to each of its clients. The tick is the frame's number
/// since `start` (times `ticks_per_frame`), the same on every thread; a thread that
/// falls behind skips to the current frame (frames missed are missed, as a late
/// tick's would be).
fn send(
    arrivals: &mpsc::Receiver<TcpStream>,
    template: &mut Template,
    start: Instant,
    period: Duration,
    ticks_per_frame: u64,
) {
    let mut clients: Vec<Client> = Vec::new();
    let period_ns = period.as_nanos().max(1);
    let mut frame = 0u64;
    loop {
        let due = start + Duration::from_nanos((period_ns * u128::from(frame)) as u64);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        let current = ((Instant::now() - start).as_nanos() / period_ns) as u64;
        frame = frame.max(current);
        loop {
            match arrivals.try_recv() {
                Ok(stream) => clients.push(Client {
                    stream,
                    tail: Vec::new(),
                }),
                Err(mpsc::TryRecvError::Empty) => break,
                Err(mpsc::TryRecvError::Disconnected) => return,
            }
        }
        template.patch(frame * ticks_per_frame, now_us());
        let bytes = template.bytes();
        clients.retain_mut(|c| c.offer(bytes));
        frame += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::Template;

    #[test]
    fn the_template_is_a_real_frame_with_its_tick_and_time_patched_in_place() {
        let mut t = Template::baseball(None).unwrap();
        let len = t.bytes().len();
        t.patch(1234, 1_795_320_000_123_456);
        assert_eq!(t.bytes().len(), len, "fixed size");
        let frame: serde_json::Value = serde_json::from_slice(t.payload()).unwrap();
        assert_eq!(frame["type"], "frame");
        assert_eq!(frame["tick"], 1234);
        assert_eq!(frame["sent_us"], 1_795_320_000_123_456u64);
        assert_eq!(frame["match"], super::MATCH_ID);
        assert!(frame["agents"].as_array().is_some_and(|a| a.len() == 3));
        // The WebSocket header: FIN + text, unmasked, a 16-bit length for 126..65535.
        let payload = t.payload().len();
        assert_eq!(t.bytes()[0], 0x81);
        assert_eq!(t.bytes()[1], 126);
        assert_eq!(
            u16::from_be_bytes([t.bytes()[2], t.bytes()[3]]) as usize,
            payload
        );
        // A stamped fieldhouse frame's size: 400 to 700 bytes.
        assert!((400..700).contains(&payload), "{payload}");
        // Padded to a size, it is still a frame the load generator reads.
        let mut padded = Template::baseball(Some(600)).unwrap();
        padded.patch(1234, 1_795_320_000_123_456);
        assert_eq!(padded.payload().len(), 600);
        let frame: serde_json::Value = serde_json::from_slice(padded.payload()).unwrap();
        assert_eq!(frame["tick"], 1234);
        assert_eq!(padded.bytes()[0], 0x81);
        // The load generator reads it like a fieldhouse frame.
        let text = std::str::from_utf8(t.payload()).unwrap();
        assert_eq!(
            crate::client::fieldhouse_frame(text.as_bytes()),
            Some((1234, Some(1_795_320_000_123_456)))
        );
    }
}
