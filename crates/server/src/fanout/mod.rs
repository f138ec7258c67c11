//! A match's frames to its spectators, written straight to their sockets.
//!
//! Each frame is framed once per shard (a WebSocket text frame: header and payload in
//! one buffer) and written to every spectator's TCP socket with one non-blocking write,
//! by a task per shard of the audience: as many shards as the sockets' runtime has
//! workers, so the writes of a large audience go on every core. No spectator has a task
//! woken per frame, and no spectator's frame is copied or allocated: at 1,000 spectators
//! a task per spectator woken by the match's watch channel (a wake, a poll, a split
//! socket's lock, the WebSocket library's copy into its buffer, a timer) cost as much
//! user-space CPU again as the write itself, beside the kernel's part.
//!
//! * A socket that cannot take a frame **skips** it (counted as dropped), as before: a
//!   write the kernel takes only part of keeps its tail, which goes first at the next
//!   frame; if the tail does not go, that frame is skipped too. A spectator never holds
//!   up a match or another spectator.
//! * A socket that takes **nothing for `send_timeout_ms`** is dropped (a slow client).
//! * A shard that falls behind skips to the newest frame for all its spectators.
//! * Everything else a spectator's socket does is the spectator task's (the `hello`,
//!   the newest frame at once, the `end`) or its reader's (client messages, pings'
//!   pongs, the close handshake); their writes go through the same [`Wire`], whole
//!   frames at a time, so they never land inside a frame.

mod wire;

pub use wire::{text_frame, Wire, WireIo};

use super::metrics::Metrics;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};
use tokio::sync::{oneshot, watch};
use tokio_tungstenite::tungstenite::Utf8Bytes;
use wire::Offered;

/// The newest frame of a match (encoded once; every spectator gets the same bytes), and
/// its `end` once it has ended.
#[derive(Debug, Clone)]
pub struct Published {
    /// Frames published so far: a spectator that sees a gap skipped frames.
    pub seq: u64,
    /// The newest frame's JSON text.
    pub frame: Utf8Bytes,
    /// The match's `end` message's JSON text, once it has ended.
    pub end: Option<Utf8Bytes>,
}

/// Members a shard writes to before letting other tasks on its worker run.
const WRITES_BETWEEN_YIELDS: usize = 256;

/// Why the fan-out let a spectator go.
#[derive(Debug)]
pub enum Out {
    /// The match ended; its `end`, if it was published.
    Ended(Option<Utf8Bytes>),
    /// The socket failed (the client went away).
    Gone,
    /// The socket took nothing for the send timeout.
    TimedOut,
}

/// A spectator in a shard: its wire, the last frame it was offered, when its socket last
/// took anything, and where to say why it was let go.
pub struct Member {
    wire: Arc<Wire>,
    last_seq: u64,
    progress: Instant,
    out: oneshot::Sender<Out>,
}

impl Member {
    /// A spectator that has had frame `seq`; told on `out` when it is let go.
    pub fn new(wire: Arc<Wire>, seq: u64, out: oneshot::Sender<Out>) -> Member {
        Member {
            wire,
            last_seq: seq,
            progress: Instant::now(),
            out,
        }
    }
}

/// A shard's newcomers, taken by its task at the next frame; `None` once the task has
/// finished (the match is over).
type Newcomers = Arc<Mutex<Option<Vec<Member>>>>;

/// A match's audience in shards, each written by a task of its own; started by the first
/// spectator to join.
#[derive(Default)]
pub struct Fanout {
    /// Each shard's newcomers.
    shards: OnceLock<Vec<Newcomers>>,
    next: AtomicUsize,
}

impl Fanout {
    /// Adds a spectator to a shard (starting the shards' tasks on this runtime if this
    /// is the first); it gets every frame after `member.last_seq`. Gives the member
    /// back if the match is over.
    pub fn join(
        &self,
        member: Member,
        published: &watch::Receiver<Published>,
        metrics: &Arc<Metrics>,
        send_timeout: Duration,
    ) -> Result<(), Member> {
        let shards = self.shards.get_or_init(|| {
            let workers = tokio::runtime::Handle::current().metrics().num_workers();
            (0..workers.max(1))
                .map(|_| {
                    let shard = Arc::new(Mutex::new(Some(Vec::new())));
                    tokio::spawn(run(
                        shard.clone(),
                        published.clone(),
                        metrics.clone(),
                        send_timeout,
                    ));
                    shard
                })
                .collect()
        });
        let k = self.next.fetch_add(1, Relaxed) % shards.len();
        match shards[k].lock().expect("not poisoned").as_mut() {
            Some(newcomers) => {
                newcomers.push(member);
                Ok(())
            }
            None => Err(member),
        }
    }
}

/// What happened to a member at one frame.
enum Fate {
    Keep,
    Out(Out),
}

/// Counts for one frame, added to the metrics once.
#[derive(Default)]
struct Tally {
    sent: u64,
    dropped: u64,
    bytes: u64,
    slow: u64,
}

/// A shard's task: at each frame published, its newcomers join, and every member is
/// offered the frame; when the match ends, every member (and any newcomer after) is told.
async fn run(
    newcomers: Newcomers,
    mut published: watch::Receiver<Published>,
    metrics: Arc<Metrics>,
    send_timeout: Duration,
) {
    let mut members: Vec<Member> = Vec::new();
    loop {
        let changed = published.changed().await;
        let p = published.borrow_and_update().clone();
        let over = changed.is_err() || p.end.is_some();
        {
            let mut arrived = newcomers.lock().expect("not poisoned");
            let list = if over {
                arrived.take()
            } else {
                arrived.as_mut().map(std::mem::take)
            };
            members.extend(list.into_iter().flatten());
        }
        let frame = text_frame(p.frame.as_bytes());
        let mut tally = Tally::default();
        let now = Instant::now();
        let mut k = 0;
        let mut since_yield = 0;
        while k < members.len() {
            since_yield += 1;
            if since_yield == WRITES_BETWEEN_YIELDS {
                since_yield = 0;
                tokio::task::yield_now().await;
            }
            match offer(
                &mut members[k],
                p.seq,
                &frame,
                p.frame.len(),
                now,
                send_timeout,
                &mut tally,
            ) {
                Fate::Keep => k += 1,
                Fate::Out(why) => {
                    let _ = members.swap_remove(k).out.send(why);
                }
            }
        }
        metrics.frames_sent.fetch_add(tally.sent, Relaxed);
        metrics.frames_dropped.fetch_add(tally.dropped, Relaxed);
        metrics.bytes_out.fetch_add(tally.bytes, Relaxed);
        metrics.slow_clients_dropped.fetch_add(tally.slow, Relaxed);
        if over {
            for m in members {
                let _ = m.out.send(Out::Ended(p.end.clone()));
            }
            return;
        }
    }
}

/// Offers frame `seq` to one member.
fn offer(
    m: &mut Member,
    seq: u64,
    frame: &[u8],
    payload_len: usize,
    now: Instant,
    send_timeout: Duration,
    tally: &mut Tally,
) -> Fate {
    if m.wire.has_left() {
        // Its spectator task has gone (the client closed, or broke the rules).
        return Fate::Out(Out::Gone);
    }
    if seq <= m.last_seq {
        return Fate::Keep;
    }
    tally.dropped += seq - m.last_seq - 1;
    m.last_seq = seq;
    match m.wire.offer(frame) {
        Ok(Offered::Left) => Fate::Out(Out::Gone),
        Ok(Offered::Sent) => {
            m.progress = now;
            tally.sent += 1;
            tally.bytes += payload_len as u64;
            Fate::Keep
        }
        Ok(Offered::Skipped { progress }) => {
            tally.dropped += 1;
            if progress {
                m.progress = now;
            }
            if now.saturating_duration_since(m.progress) >= send_timeout {
                tally.slow += 1;
                Fate::Out(Out::TimedOut)
            } else {
                Fate::Keep
            }
        }
        Err(_) => Fate::Out(Out::Gone),
    }
}

#[cfg(test)]
mod tests {
    use super::{offer, text_frame, Fate, Member, Out, Tally, Wire};
    use crate::listener::Connections;
    use std::sync::Arc;
    use std::time::{Duration, Instant};

    /// A server-side socket whose client reads nothing (a small receive buffer, so it
    /// fills soon), as a wire, and the client.
    async fn stalled_pair() -> (Arc<Wire>, tokio::net::TcpStream) {
        let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
        let client = tokio::net::TcpSocket::new_v4().unwrap();
        client.set_recv_buffer_size(2048).unwrap();
        let client = client
            .connect(listener.local_addr().unwrap())
            .await
            .unwrap();
        let (server, peer) = listener.accept().await.unwrap();
        // As a spectator's socket is once its handshake is written.
        server.writable().await.unwrap();
        let connections = Arc::new(Connections::new(8, 8));
        let place = Arc::new(connections.open(peer.ip()).unwrap());
        (Arc::new(Wire::new(server, place)), client)
    }

    #[tokio::test]
    async fn a_full_socket_skips_frames_keeps_the_stream_whole_and_is_let_go_at_the_timeout() {
        let (wire, client) = stalled_pair().await;
        let (out, _told) = tokio::sync::oneshot::channel();
        let mut member = Member::new(wire.clone(), 0, out);
        let payload = [b'x'; 1000];
        let frame = text_frame(&payload);
        let timeout = Duration::from_secs(5);
        let mut tally = Tally::default();
        let mut seq = 0;
        while tally.dropped == 0 {
            seq += 1;
            assert!(seq < 100_000, "the socket never filled");
            let fate = offer(
                &mut member,
                seq,
                &frame,
                1000,
                Instant::now(),
                timeout,
                &mut tally,
            );
            assert!(matches!(fate, Fate::Keep));
        }
        assert_eq!(tally.sent, seq - 1);
        // At most the tail of one frame waits: nothing queues behind a full socket.
        assert!(wire.pending_len() < frame.len());
        // Skipping until the timeout, then let go, counted as slow.
        let later = Instant::now() + timeout;
        let fate = offer(
            &mut member,
            seq + 2,
            &frame,
            1000,
            later,
            timeout,
            &mut tally,
        );
        assert!(matches!(fate, Fate::Out(Out::TimedOut)));
        assert_eq!((tally.dropped, tally.slow), (3, 1));
        // What reached the client is whole frames, then at most the start of one.
        let mut client = client.into_std().unwrap();
        client.set_nonblocking(true).unwrap();
        let mut got = Vec::new();
        let mut chunk = [0u8; 65536];
        while let Ok(n) = std::io::Read::read(&mut client, &mut chunk) {
            if n == 0 {
                break;
            }
            got.extend_from_slice(&chunk[..n]);
        }
        let whole = got.len() / frame.len();
        assert!(whole > 0);
        for k in 0..whole {
            assert_eq!(&got[k * frame.len()..(k + 1) * frame.len()], &frame[..]);
        }
        assert_eq!(
            &got[whole * frame.len()..],
            &frame[..got.len() % frame.len()]
        );
    }

    #[tokio::test]
    async fn a_spectator_that_left_or_a_client_that_closed_is_let_go() {
        let (wire, _client) = stalled_pair().await;
        let frame = text_frame(b"{}");
        let mut tally = Tally::default();
        let (out, _told) = tokio::sync::oneshot::channel();
        let mut member = Member::new(wire.clone(), 0, out);
        wire.leave();
        let fate = offer(
            &mut member,
            1,
            &frame,
            2,
            Instant::now(),
            Duration::from_secs(5),
            &mut tally,
        );
        assert!(matches!(fate, Fate::Out(Out::Gone)));
        let (wire, client) = stalled_pair().await;
        let (out, _told) = tokio::sync::oneshot::channel();
        let mut member = Member::new(wire, 0, out);
        drop(client);
        let mut seq = 0;
        let gone = loop {
            seq += 1;
            let fate = offer(
                &mut member,
                seq,
                &frame,
                2,
                Instant::now(),
                Duration::from_secs(5),
                &mut tally,
            );
            if let Fate::Out(why) = fate {
                break why;
            }
            assert!(seq < 1000, "writes to a closed connection kept succeeding");
            tokio::time::sleep(Duration::from_millis(5)).await;
        };
        assert!(matches!(gone, Out::Gone), "{gone:?}");
    }
}
