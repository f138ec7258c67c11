//! The accept loop: every TCP connection is counted from accept to close, whatever it
//! becomes (a page, a REST request, a WebSocket), so no client can hold descriptors the
//! server does not know about.
//!
//! * **Per address**: one address holds at most `max_connections_per_ip` connections.
//!   At its cap, its own longest-idle HTTP connection is closed to make room; if it has
//!   none idle, the new one is answered 429 and closed.
//! * **In all**: at most `max_connections` (by default what the descriptor limit allows,
//!   less a reserve for replay files and the like). At the cap the longest-idle HTTP
//!   connection anywhere is closed to make room, so health checks and admins still get
//!   in while idle sockets are what fills the server; spectators are refused earlier
//!   (see [`Connections::spectators_welcome`]), so the last places go to requests.
//! * **Slow and idle**: a request's headers must arrive within `header_timeout_ms` of
//!   the connection opening or of the previous response, so a client that trickles
//!   headers or opens a connection and says nothing is closed; a write that makes no
//!   progress for `send_timeout_ms` fails, so one that stops reading (a download, say)
//!   is closed too.
//! * **Descriptors run out anyway** (another process, a low limit): accepting fails;
//!   the loop closes the longest-idle connection, pauses briefly instead of spinning on
//!   the error, and logs it once per ten seconds with a count.

use super::metrics::Metrics;
use axum::http::StatusCode;
use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use std::collections::HashMap;
use std::future::Future;
use std::io;
use std::net::{IpAddr, SocketAddr};
use std::pin::{pin, Pin};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::{Duration, Instant};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{watch, Notify};
use tower::ServiceExt;

/// Descriptors kept back from connections: the listener, the standard streams, replay
/// files being written, read and listed, the motion cache, the runtime's own.
const DESCRIPTOR_RESERVE: usize = 64;

/// How long HTTP requests in flight may take to finish once the server stops.
const DRAIN: Duration = Duration::from_secs(2);

/// The connections open now, by client address, and which of them sit idle.
pub struct Connections {
    /// Most connections from one address.
    per_ip_cap: usize,
    /// Most connections in all.
    cap: usize,
    open: Mutex<Open>,
}

#[derive(Default)]
struct Open {
    total: usize,
    per_ip: HashMap<IpAddr, usize>,
    /// HTTP connections with no request in flight, and how to close each.
    idle: HashMap<u64, Idle>,
    next_id: u64,
}

struct Idle {
    ip: IpAddr,
    since: Instant,
    close: Arc<Notify>,
}

/// Why a connection was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    PerIp,
    Full,
}

impl Connections {
    pub fn new(per_ip_cap: usize, cap: usize) -> Connections {
        Connections {
            per_ip_cap,
            cap,
            open: Mutex::default(),
        }
    }

    /// Most connections in all.
    pub fn cap(&self) -> usize {
        self.cap
    }

    /// Connections open now.
    pub fn total(&self) -> usize {
        self.open.lock().expect("not poisoned").total
    }

    /// Whether a new spectator or replay viewer may connect: not in the last eighth of
    /// the connections (at least 16), which are kept for requests, admins and bots.
    pub fn spectators_welcome(&self) -> bool {
        let headroom = (self.cap / 8).max(16).min(self.cap / 2);
        self.total() < self.cap - headroom
    }

    /// Counts a new connection from `ip`, closing an idle one to make room if that is
    /// what it takes; the place is given back when the [`Conn`] is dropped.
    pub fn open(self: &Arc<Self>, ip: IpAddr) -> Result<Conn, Refused> {
        let mut open = self.open.lock().expect("not poisoned");
        let from_ip = open.per_ip.get(&ip).copied().unwrap_or(0);
        if from_ip >= self.per_ip_cap && !open.close_longest_idle(Some(ip)) {
            return Err(Refused::PerIp);
        }
        if open.total >= self.cap && !open.close_longest_idle(None) {
            return Err(Refused::Full);
        }
        open.total += 1;
        *open.per_ip.entry(ip).or_default() += 1;
        open.next_id += 1;
        Ok(Conn {
            id: open.next_id,
            ip,
            close: Arc::new(Notify::new()),
            connections: self.clone(),
        })
    }

    /// Closes the longest-idle HTTP connection, to free a descriptor.
    fn close_one_idle(&self) -> bool {
        self.open
            .lock()
            .expect("not poisoned")
            .close_longest_idle(None)
    }
}

impl Open {
    /// Asks the longest-idle connection (of `ip`, or of anyone) to close; whether there
    /// was one. It stops counting as idle at once, so it is asked only once.
    fn close_longest_idle(&mut self, ip: Option<IpAddr>) -> bool {
        let oldest = self
            .idle
            .iter()
            .filter(|(_, idle)| ip.is_none_or(|ip| idle.ip == ip))
            .min_by_key(|(_, idle)| idle.since)
            .map(|(id, _)| *id);
        match oldest.and_then(|id| self.idle.remove(&id)) {
            Some(idle) => {
                idle.close.notify_one();
                true
            }
            None => false,
        }
    }
}

/// A connection's place in [`Connections`]; dropped when its socket is, which for a
/// WebSocket is when the socket closes, long after its HTTP request.
pub struct Conn {
    id: u64,
    ip: IpAddr,
    close: Arc<Notify>,
    connections: Arc<Connections>,
}

impl Conn {
    /// Between requests: may be closed to make room.
    fn idle(&self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        open.idle.insert(
            self.id,
            Idle {
                ip: self.ip,
                since: Instant::now(),
                close: self.close.clone(),
            },
        );
    }

    /// A request is in flight: not to be closed.
    fn busy(&self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        open.idle.remove(&self.id);
    }
}

impl Drop for Conn {
    fn drop(&mut self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        open.total -= 1;
        open.idle.remove(&self.id);
        if let Some(n) = open.per_ip.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                open.per_ip.remove(&self.ip);
            }
        }
    }
}

/// A TCP stream that holds its connection's place for as long as it is open, and
/// fails a write that makes no progress for `write_timeout`: a client that stops
/// reading a download (or any response) gives its descriptor back instead of holding
/// it for as long as it likes.
pub(crate) struct Counted {
    stream: TcpStream,
    place: Arc<Conn>,
    write_timeout: Duration,
    /// Set while a write waits for room in the socket.
    stalled: Option<Pin<Box<tokio::time::Sleep>>>,
}

impl Counted {
    /// The stream and its place, for a socket that does its own writing with its own
    /// timeout (a spectator's: see `fanout`).
    pub(crate) fn into_parts(self) -> (TcpStream, Arc<Conn>) {
        (self.stream, self.place)
    }

    /// `polled`, unless writes have waited longer than the timeout.
    fn bounded<T>(
        &mut self,
        cx: &mut Context<'_>,
        polled: Poll<io::Result<T>>,
    ) -> Poll<io::Result<T>> {
        if polled.is_ready() {
            self.stalled = None;
            return polled;
        }
        let timeout = self.write_timeout;
        let stalled = self
            .stalled
            .get_or_insert_with(|| Box::pin(tokio::time::sleep(timeout)));
        match stalled.as_mut().poll(cx) {
            Poll::Ready(()) => Poll::Ready(Err(io::Error::new(
                io::ErrorKind::TimedOut,
                "the client took nothing for the write timeout",
            ))),
            Poll::Pending => Poll::Pending,
        }
    }
}

impl AsyncRead for Counted {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_read(cx, buf)
    }
}

impl AsyncWrite for Counted {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        let polled = Pin::new(&mut self.stream).poll_write(cx, buf);
        self.bounded(cx, polled)
    }
    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        let polled = Pin::new(&mut self.stream).poll_flush(cx);
        self.bounded(cx, polled)
    }
    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.stream).poll_shutdown(cx)
    }
    fn poll_write_vectored(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        bufs: &[io::IoSlice<'_>],
    ) -> Poll<io::Result<usize>> {
        let polled = Pin::new(&mut self.stream).poll_write_vectored(cx, bufs);
        self.bounded(cx, polled)
    }
    fn is_write_vectored(&self) -> bool {
        self.stream.is_write_vectored()
    }
}

/// Raises the soft descriptor limit to the hard one (the usual 1,024 is a default, not
/// a decision) and returns how many connections the result leaves room for.
pub fn connection_budget() -> usize {
    let limit = raise_descriptor_limit();
    usize::try_from(limit)
        .unwrap_or(usize::MAX)
        .saturating_sub(DESCRIPTOR_RESERVE)
        .max(16)
}

#[cfg(unix)]
fn raise_descriptor_limit() -> u64 {
    let mut limit = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit and setrlimit only read and write the struct passed.
    unsafe {
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) != 0 {
            return 1024;
        }
        if limit.rlim_cur < limit.rlim_max {
            let raised = libc::rlimit {
                rlim_cur: limit.rlim_max,
                rlim_max: limit.rlim_max,
            };
            if libc::setrlimit(libc::RLIMIT_NOFILE, &raised) == 0 {
                limit = raised;
            }
        }
    }
    limit.rlim_cur
}

#[cfg(not(unix))]
fn raise_descriptor_limit() -> u64 {
    1024
}

/// The accept loop's settings.
pub struct Listening {
    pub connections: Arc<Connections>,
    pub header_timeout: Duration,
    /// A write that makes no progress for this long fails (`send_timeout_ms`).
    pub write_timeout: Duration,
    pub metrics: Arc<Metrics>,
}

/// Serves `router` on `listener` until `shutdown` completes; then takes no new
/// connections, asks open HTTP connections to finish, and waits for them (at most
/// 2 s). WebSockets end with their matches, on the server's own shutdown signal.
pub async fn serve(
    listener: TcpListener,
    router: Router,
    settings: Listening,
    shutdown: impl Future<Output = ()>,
) {
    let (closing_tx, closing) = watch::channel(false);
    let mut shutdown = pin!(shutdown);
    let mut accept_errors = AcceptErrors::default();
    loop {
        tokio::select! {
            _ = &mut shutdown => break,
            accepted = listener.accept() => match accepted {
                Ok((stream, peer)) => {
                    accept(stream, peer, &router, &settings, closing.clone());
                }
                Err(e) => {
                    // Out of descriptors (EMFILE, ENFILE) or memory: the pending
                    // connection stays queued and accept fails again at once, so free a
                    // descriptor and pause rather than spin.
                    settings.metrics.accept_errors.fetch_add(1, Relaxed);
                    accept_errors.log(&e);
                    settings.connections.close_one_idle();
                    tokio::time::sleep(Duration::from_millis(20)).await;
                }
            }
        }
    }
    let _ = closing_tx.send(true);
    // Each connection task holds a receiver: when they are all gone, so are they.
    let _ = tokio::time::timeout(DRAIN, closing_tx.closed()).await;
}

/// Takes one connection: counts it and serves it, or tells it why not.
fn accept(
    stream: TcpStream,
    peer: SocketAddr,
    router: &Router,
    settings: &Listening,
    mut closing: watch::Receiver<bool>,
) {
    let place = match settings.connections.open(peer.ip()) {
        Ok(place) => Arc::new(place),
        Err(refused) => {
            let counter = match refused {
                Refused::PerIp => &settings.metrics.refused_per_ip,
                Refused::Full => &settings.metrics.refused_full,
            };
            counter.fetch_add(1, Relaxed);
            refuse(&stream, refused);
            return;
        }
    };
    let _ = stream.set_nodelay(true);
    place.idle();
    let close = place.close.clone();
    let io = TokioIo::new(Counted {
        stream,
        place: place.clone(),
        write_timeout: settings.write_timeout,
        stalled: None,
    });
    let router = router.clone();
    let service = hyper::service::service_fn(move |mut request: hyper::Request<_>| {
        place.busy();
        request
            .extensions_mut()
            .insert(axum::extract::ConnectInfo(peer));
        let served = router.clone().oneshot(request.map(axum::body::Body::new));
        let place = place.clone();
        async move {
            let response = served.await;
            // An upgraded connection is a WebSocket now: never idle, never closed to
            // make room (its owner closes it).
            let upgraded = response
                .as_ref()
                .is_ok_and(|r| r.status() == StatusCode::SWITCHING_PROTOCOLS);
            if !upgraded {
                place.idle();
            }
            response
        }
    });
    let mut http = hyper::server::conn::http1::Builder::new();
    http.timer(TokioTimer::new())
        .header_read_timeout(settings.header_timeout)
        .keep_alive(true);
    tokio::spawn(async move {
        let mut connection = pin!(http.serve_connection(io, service).with_upgrades());
        let mut asked = false;
        loop {
            tokio::select! {
                _ = connection.as_mut() => break,
                _ = close.notified(), if !asked => {
                    asked = true;
                    connection.as_mut().graceful_shutdown();
                }
                changed = closing.changed(), if !asked => {
                    if changed.is_err() || *closing.borrow() {
                        asked = true;
                        connection.as_mut().graceful_shutdown();
                    }
                }
            }
        }
    });
}

/// Answers a connection that was not taken with a JSON error and closes it. One
/// non-blocking write: a fresh socket's send buffer takes the few hundred bytes, and a
/// refused client gets no more of the server's time than that.
fn refuse(stream: &TcpStream, refused: Refused) {
    let (status, code, message) = match refused {
        Refused::PerIp => (
            StatusCode::TOO_MANY_REQUESTS,
            "too_many_connections",
            "this address has as many connections open as it may (max_connections_per_ip)",
        ),
        Refused::Full => (
            StatusCode::SERVICE_UNAVAILABLE,
            "server_full",
            "the server has as many connections open as it may (max_connections); try again",
        ),
    };
    let body = serde_json::json!({"error": {"code": code, "message": message}}).to_string();
    let response = format!(
        "HTTP/1.1 {} {}\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n\r\n{body}",
        status.as_u16(),
        status.canonical_reason().unwrap_or(""),
        body.len()
    );
    let _ = stream.try_write(response.as_bytes());
}

/// Accept failures, logged once per ten seconds with how many there were.
#[derive(Default)]
struct AcceptErrors {
    since_logged: u64,
    logged: Option<Instant>,
}

impl AcceptErrors {
    fn log(&mut self, e: &io::Error) {
        self.since_logged += 1;
        if self
            .logged
            .is_none_or(|t| t.elapsed() >= Duration::from_secs(10))
        {
            tracing::warn!(error = %e, failures = self.since_logged, "cannot accept connections; closing idle ones");
            self.since_logged = 0;
            self.logged = Some(Instant::now());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{Connections, Refused};
    use std::net::IpAddr;
    use std::sync::Arc;

    fn ip(last: u8) -> IpAddr {
        IpAddr::from([127, 0, 0, last])
    }

    #[test]
    fn an_address_at_its_cap_loses_its_idle_connection_before_it_is_refused() {
        let connections = Arc::new(Connections::new(2, 100));
        let a = connections.open(ip(1)).unwrap();
        let b = connections.open(ip(1)).unwrap();
        a.busy();
        b.busy();
        assert_eq!(connections.open(ip(1)).err(), Some(Refused::PerIp));
        assert!(connections.open(ip(2)).is_ok(), "others are not affected");
        b.idle();
        let closing = b.close.clone();
        let c = connections.open(ip(1)).expect("b's idle place is taken");
        // b was asked to close; until it does, both count.
        assert!(tokio_test_notified(&closing));
        assert_eq!(connections.total(), 3);
        drop((a, b, c));
        assert_eq!(connections.total(), 0);
        assert!(connections.open.lock().unwrap().per_ip.is_empty());
    }

    #[test]
    fn a_full_server_closes_the_longest_idle_connection_for_a_new_one() {
        let connections = Arc::new(Connections::new(100, 3));
        let held: Vec<_> = (1..=3).map(|k| connections.open(ip(k)).unwrap()).collect();
        for c in &held {
            c.busy();
        }
        assert_eq!(connections.open(ip(9)).err(), Some(Refused::Full));
        held[2].idle();
        std::thread::sleep(std::time::Duration::from_millis(2));
        held[1].idle();
        let _new = connections.open(ip(9)).expect("an idle one makes room");
        assert!(tokio_test_notified(&held[2].close), "the longest idle");
        assert!(!tokio_test_notified(&held[1].close));
    }

    #[test]
    fn spectators_are_refused_before_the_last_places() {
        let connections = Arc::new(Connections::new(1000, 64));
        let mut held = Vec::new();
        while connections.spectators_welcome() {
            held.push(connections.open(ip(1)).unwrap());
        }
        assert_eq!(held.len(), 64 - 16, "16 places kept for requests");
        assert!(connections.open(ip(1)).is_ok(), "requests still get in");
    }

    /// Whether `notify` holds a permit (was notified), consuming it.
    fn tokio_test_notified(notify: &tokio::sync::Notify) -> bool {
        use std::future::Future;
        let mut waiting = std::pin::pin!(notify.notified());
        let waker = std::task::Waker::noop();
        waiting
            .as_mut()
            .poll(&mut std::task::Context::from_waker(waker))
            .is_ready()
    }
}
