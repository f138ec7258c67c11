//! The accept loop: every TCP connection is counted from accept to close, whatever it
//! becomes (a page, a REST request, a WebSocket), so no client can hold descriptors the
//! server does not know about.
//!
//! A connection is **busy** while a request is in flight on it, from its headers until
//! its response's body has been handed over whole, and while the bytes of a response
//! wait for room in its socket; an upgraded one (a WebSocket) is busy until it closes.
//! Otherwise it is **idle**: waiting for its first or next request. Only idle
//! connections are ever closed to make room, and a connection counts until its socket is
//! closed, never less: the caps are the most sockets held, not a number of requests.
//!
//! * **Per address**: one address holds at most `max_connections_per_ip` connections.
//!   At its cap, its own longest-idle connection is closed and the new one takes its
//!   place once it has closed (it waits up to [`MAKING_ROOM`] for that); if none of its
//!   connections is idle, the new one is answered 429 and closed at once. A download
//!   read slowly, or not at all, is busy: it never gives its place to a new connection.
//! * **In all**: at most `max_connections` (by default what the descriptor limit allows,
//!   less a reserve for replay files and the like), the same way: at the cap the
//!   longest-idle connection anywhere makes room, so health checks and admins still get
//!   in while idle sockets are what fills the server, and with none idle the new one is
//!   answered 503. Spectators are refused earlier (see
//!   [`Connections::spectators_welcome`]), so the last places go to requests.
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
use hyper::body::{Body as HttpBody, Bytes, Frame, SizeHint};
use hyper_util::rt::{TokioIo, TokioTimer};
use std::collections::HashMap;
use std::future::Future;
use std::io;
use std::net::{IpAddr, SocketAddr};
use std::pin::{pin, Pin};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::atomic::{AtomicBool, AtomicUsize};
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

/// How long a new connection at a cap waits for the idle connection closed for it to be
/// gone. An idle connection closes at once; one that a request reached in the meantime
/// finishes it first, and the new connection is refused if that takes longer.
pub const MAKING_ROOM: Duration = Duration::from_secs(1);

/// A closing connection's place, handed to the new connection it was closed for.
type Room = tokio::sync::oneshot::Receiver<Conn>;

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
    /// Connections asked to close to make room, by id, and the new connection (of which
    /// address) that gets the place when they have: nobody else can take it meanwhile.
    heirs: HashMap<u64, (IpAddr, tokio::sync::oneshot::Sender<Conn>)>,
    next_id: u64,
}

struct Idle {
    ip: IpAddr,
    since: Instant,
    state: Arc<State>,
}

/// What the accept loop and a connection's task share about it.
#[derive(Default)]
struct State {
    /// Asked to close, to make room.
    close: Notify,
    /// Requests in flight (their response bodies not yet handed over whole); changed
    /// only under the [`Connections`] lock, with the idle set.
    in_flight: AtomicUsize,
    /// A write is waiting for room in the socket: bytes of a response are still to go.
    writing: AtomicBool,
}

impl State {
    /// Nothing in flight and nothing waiting to be written: closing loses nothing.
    fn quiet(&self) -> bool {
        self.in_flight.load(Relaxed) == 0 && !self.writing.load(Relaxed)
    }
}

/// Why a connection was not taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refused {
    /// The connection's address holds its share of places already.
    PerIp,
    /// Every place is taken.
    Full,
}

/// What asking for a place gave.
enum Opened {
    Taken(Conn),
    /// At a cap (which one it says), an idle connection was asked to close: its place
    /// comes once it has.
    MakingRoom(Room, Refused),
    Refused(Refused),
}

impl Connections {
    /// Room for `cap` connections in all and `per_ip_cap` from one address.
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

    /// Counts a new connection from `ip` if there is room for it now, closing nothing;
    /// the place is given back when the [`Conn`] is dropped.
    pub fn open(self: &Arc<Self>, ip: IpAddr) -> Result<Conn, Refused> {
        let mut open = self.open.lock().expect("not poisoned");
        self.take(&mut open, ip)
    }

    /// [`Connections::open`], and at a cap, asks the longest-idle connection that stands
    /// in the way (of `ip` for its cap, of anyone for the total) to close. The new one
    /// gets that one's place once it has closed, never on top of it, and no connection
    /// that arrives meanwhile can take it.
    fn open_or_make_room(self: &Arc<Self>, ip: IpAddr) -> Opened {
        let mut open = self.open.lock().expect("not poisoned");
        match self.take(&mut open, ip) {
            Ok(conn) => Opened::Taken(conn),
            Err(refused) => {
                let of = (refused == Refused::PerIp).then_some(ip);
                match open.close_longest_idle(of) {
                    Some(closing) => {
                        let (heir, room) = tokio::sync::oneshot::channel();
                        open.heirs.insert(closing, (ip, heir));
                        Opened::MakingRoom(room, refused)
                    }
                    None => Opened::Refused(refused),
                }
            }
        }
    }

    /// A place under both caps, if there is one.
    fn take(self: &Arc<Self>, open: &mut Open, ip: IpAddr) -> Result<Conn, Refused> {
        if open.per_ip.get(&ip).copied().unwrap_or(0) >= self.per_ip_cap {
            return Err(Refused::PerIp);
        }
        if open.total >= self.cap {
            return Err(Refused::Full);
        }
        open.total += 1;
        Ok(self.place_for(open, ip))
    }

    /// A new connection's place, counted against `ip` (the total is the caller's).
    fn place_for(self: &Arc<Self>, open: &mut Open, ip: IpAddr) -> Conn {
        *open.per_ip.entry(ip).or_default() += 1;
        open.next_id += 1;
        Conn {
            id: open.next_id,
            ip,
            state: Arc::default(),
            connections: self.clone(),
        }
    }

    /// Closes the longest-idle HTTP connection, to free a descriptor.
    fn close_one_idle(&self) {
        self.open
            .lock()
            .expect("not poisoned")
            .close_longest_idle(None);
    }
}

impl Open {
    /// Asks the longest-idle connection (of `ip`, or of anyone) to close; which, if
    /// there was one. It stops counting as idle at once, so it is asked only once. One
    /// with a response still waiting for room in its socket is not idle, whatever its
    /// requests.
    fn close_longest_idle(&mut self, ip: Option<IpAddr>) -> Option<u64> {
        let oldest = self
            .idle
            .iter()
            .filter(|(_, idle)| ip.is_none_or(|ip| idle.ip == ip))
            .filter(|(_, idle)| !idle.state.writing.load(Relaxed))
            .min_by_key(|(_, idle)| idle.since)
            .map(|(id, _)| *id);
        let id = oldest?;
        self.idle.remove(&id)?.state.close.notify_one();
        Some(id)
    }
}

/// A connection's place in [`Connections`]; dropped when its socket is, which for a
/// WebSocket is when the socket closes, long after its HTTP request.
pub struct Conn {
    id: u64,
    ip: IpAddr,
    state: Arc<State>,
    connections: Arc<Connections>,
}

impl Conn {
    /// Between requests: may be closed to make room.
    fn idle(&self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        self.idle_in(&mut open);
    }

    /// Files this connection as idle from now, in `open` (held locked).
    fn idle_in(&self, open: &mut Open) {
        let idle = Idle {
            ip: self.ip,
            since: Instant::now(),
            state: self.state.clone(),
        };
        open.idle.insert(self.id, idle);
    }

    /// A request is in flight: not to be closed until it and its response are done.
    fn busy(&self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        self.state.in_flight.fetch_add(1, Relaxed);
        open.idle.remove(&self.id);
    }

    /// A request and its response are done; idle once none is in flight.
    fn done(&self) {
        let mut open = self.connections.open.lock().expect("not poisoned");
        if self.state.in_flight.fetch_sub(1, Relaxed) == 1 {
            self.idle_in(&mut open);
        }
    }
}

impl Drop for Conn {
    /// Gives the place back, or hands it to the connection this one was closed for.
    fn drop(&mut self) {
        let cap = self.connections.per_ip_cap;
        let unclaimed = {
            let mut open = self.connections.open.lock().expect("not poisoned");
            open.idle.remove(&self.id);
            // The heir may have reached its own address's cap since (if it is another).
            let heir = open.heirs.remove(&self.id).filter(|(ip, heir)| {
                !heir.is_closed()
                    && (*ip == self.ip || open.per_ip.get(ip).copied().unwrap_or(0) < cap)
            });
            let release = |open: &mut Open, ip: IpAddr| {
                if let Some(n) = open.per_ip.get_mut(&ip) {
                    *n -= 1;
                    if *n == 0 {
                        open.per_ip.remove(&ip);
                    }
                }
            };
            match heir {
                Some((ip, heir)) => {
                    release(&mut open, self.ip);
                    let place = self.connections.place_for(&mut open, ip);
                    // Its heir gave up after all: the place goes back, below (a Conn
                    // dropped under the lock would wait for it for ever).
                    heir.send(place).err()
                }
                None => {
                    open.total -= 1;
                    release(&mut open, self.ip);
                    None
                }
            }
        };
        drop(unclaimed);
    }
}

/// A request in flight on a connection, from its headers until its response's body has
/// been handed over whole (or dropped, the connection gone): the connection is busy for
/// as long as this lives. An upgraded connection stays busy for good.
struct InFlight {
    place: Arc<Conn>,
    upgraded: bool,
}

impl InFlight {
    fn start(place: Arc<Conn>) -> InFlight {
        place.busy();
        InFlight {
            place,
            upgraded: false,
        }
    }
}

impl Drop for InFlight {
    fn drop(&mut self) {
        if !self.upgraded {
            self.place.done();
        }
    }
}

/// A response body that keeps its request [`InFlight`] until the server has taken it
/// whole: a download read slowly is as busy at its last byte as at its first.
struct Tracked {
    body: axum::body::Body,
    _in_flight: InFlight,
}

impl HttpBody for Tracked {
    type Data = Bytes;
    type Error = axum::Error;

    fn poll_frame(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, axum::Error>>> {
        Pin::new(&mut self.body).poll_frame(cx)
    }
    fn is_end_stream(&self) -> bool {
        self.body.is_end_stream()
    }
    fn size_hint(&self) -> SizeHint {
        self.body.size_hint()
    }
}

/// A TCP stream that holds its connection's place for as long as it is open, and
/// fails a write that makes no progress for `write_timeout`: a client that stops
/// reading a download (or any response) gives its descriptor back instead of holding
/// it for as long as it likes. While a write waits for room, the connection is busy.
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
            if self.stalled.take().is_some() {
                self.place.state.writing.store(false, Relaxed);
            }
            return polled;
        }
        let timeout = self.write_timeout;
        let place = &self.place;
        let stalled = self.stalled.get_or_insert_with(|| {
            place.state.writing.store(true, Relaxed);
            Box::pin(tokio::time::sleep(timeout))
        });
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
    /// The places connections are counted in.
    pub connections: Arc<Connections>,
    /// A request whose headers take longer than this is closed (slowloris).
    pub header_timeout: Duration,
    /// A write that makes no progress for this long fails (`send_timeout_ms`).
    pub write_timeout: Duration,
    /// Where refusals and accept errors are counted.
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
    let settings = Arc::new(settings);
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

/// Takes one connection: counts it and serves it, or tells it why not. At a cap with
/// an idle connection to close, the new one waits for that one to be gone, on a task of
/// its own so that the loop goes on accepting.
fn accept(
    stream: TcpStream,
    peer: SocketAddr,
    router: &Router,
    settings: &Arc<Listening>,
    closing: watch::Receiver<bool>,
) {
    match settings.connections.open_or_make_room(peer.ip()) {
        Opened::Taken(place) => {
            serve_connection(stream, peer, place, router.clone(), settings, closing)
        }
        Opened::Refused(refused) => refuse(&stream, refused, &settings.metrics),
        Opened::MakingRoom(room, refused) => {
            let (router, settings) = (router.clone(), settings.clone());
            tokio::spawn(async move {
                match tokio::time::timeout(MAKING_ROOM, room).await {
                    Ok(Ok(place)) => {
                        serve_connection(stream, peer, place, router, &settings, closing)
                    }
                    _ => refuse(&stream, refused, &settings.metrics),
                }
            });
        }
    }
}

/// Serves HTTP on a counted connection until it closes.
fn serve_connection(
    stream: TcpStream,
    peer: SocketAddr,
    place: Conn,
    router: Router,
    settings: &Listening,
    mut closing: watch::Receiver<bool>,
) {
    let place = Arc::new(place);
    let _ = stream.set_nodelay(true);
    place.idle();
    let state = place.state.clone();
    let io = TokioIo::new(Counted {
        stream,
        place: place.clone(),
        write_timeout: settings.write_timeout,
        stalled: None,
    });
    let service = hyper::service::service_fn(move |mut request: hyper::Request<_>| {
        let mut in_flight = InFlight::start(place.clone());
        request
            .extensions_mut()
            .insert(axum::extract::ConnectInfo(peer));
        let served = router.clone().oneshot(request.map(axum::body::Body::new));
        async move {
            let response = served.await?;
            // An upgraded connection is a WebSocket now: never idle, never closed to
            // make room (its owner closes it).
            in_flight.upgraded = response.status() == StatusCode::SWITCHING_PROTOCOLS;
            Ok::<_, std::convert::Infallible>(response.map(|body| Tracked {
                body,
                _in_flight: in_flight,
            }))
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
                _ = state.close.notified(), if !asked => {
                    // Asked to make room. Idle, it is closed now (dropped: a client
                    // that trickles a request's headers is not waited for); if a
                    // request reached it since, that is finished first.
                    if state.quiet() {
                        break;
                    }
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
/// refused client gets no more of the server's time than that. Counted in the metrics.
fn refuse(stream: &TcpStream, refused: Refused, metrics: &Metrics) {
    let counter = match refused {
        Refused::PerIp => &metrics.refused_per_ip,
        Refused::Full => &metrics.refused_full,
    };
    counter.fetch_add(1, Relaxed);
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
    use super::{Connections, Opened, Refused};
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
        assert!(matches!(
            connections.open_or_make_room(ip(1)),
            Opened::Refused(Refused::PerIp)
        ));
        assert!(connections.open(ip(2)).is_ok(), "others are not affected");
        b.done();
        let Opened::MakingRoom(mut room, Refused::PerIp) = connections.open_or_make_room(ip(1))
        else {
            panic!("b is idle: it makes room");
        };
        assert!(notified(&b.state.close));
        // Until b has closed, the new one is not counted: the cap holds, and nobody
        // else gets b's place meanwhile.
        assert_eq!(connections.total(), 2);
        assert!(room.try_recv().is_err(), "b is still open");
        drop(b);
        assert_eq!(connections.open(ip(1)).err(), Some(Refused::PerIp));
        let c = room.try_recv().expect("b's place, once it has closed");
        assert_eq!(connections.total(), 2);
        drop((a, c));
        assert_eq!(connections.total(), 0);
        assert!(connections.open.lock().unwrap().per_ip.is_empty());
    }

    #[test]
    fn a_place_made_for_a_connection_that_gave_up_goes_back() {
        let connections = Arc::new(Connections::new(1, 100));
        let held = connections.open(ip(1)).unwrap();
        held.idle();
        let Opened::MakingRoom(room, Refused::PerIp) = connections.open_or_make_room(ip(1)) else {
            panic!("held is idle");
        };
        drop(room);
        drop(held);
        assert_eq!(connections.total(), 0);
        assert!(connections.open.lock().unwrap().heirs.is_empty());
    }

    #[test]
    fn a_place_made_in_all_moves_to_the_new_address() {
        let connections = Arc::new(Connections::new(1, 2));
        let a = connections.open(ip(1)).unwrap();
        let b = connections.open(ip(2)).unwrap();
        a.idle();
        let Opened::MakingRoom(mut room, Refused::Full) = connections.open_or_make_room(ip(3))
        else {
            panic!("a is idle");
        };
        drop(a);
        let c = room.try_recv().expect("a's place");
        let open = connections.open.lock().unwrap();
        assert_eq!(open.total, 2);
        assert_eq!(open.per_ip.get(&ip(1)), None);
        assert_eq!(open.per_ip.get(&ip(3)), Some(&1));
        drop(open);
        drop((b, c));
        assert_eq!(connections.total(), 0);
    }

    #[test]
    fn a_response_in_flight_or_waiting_for_room_is_never_idle() {
        let connections = Arc::new(Connections::new(1, 100));
        let download = connections.open(ip(1)).unwrap();
        download.idle();
        // A request, then its response's body: busy until the body is done.
        download.busy();
        assert!(matches!(
            connections.open_or_make_room(ip(1)),
            Opened::Refused(Refused::PerIp)
        ));
        download.done();
        // Bytes of the response still wait for room in the socket: not idle either.
        download
            .state
            .writing
            .store(true, std::sync::atomic::Ordering::Relaxed);
        assert!(matches!(
            connections.open_or_make_room(ip(1)),
            Opened::Refused(Refused::PerIp)
        ));
        download
            .state
            .writing
            .store(false, std::sync::atomic::Ordering::Relaxed);
        assert!(matches!(
            connections.open_or_make_room(ip(1)),
            Opened::MakingRoom(_, Refused::PerIp)
        ));
    }

    #[test]
    fn a_full_server_closes_the_longest_idle_connection_for_a_new_one() {
        let connections = Arc::new(Connections::new(100, 3));
        let held: Vec<_> = (1..=3).map(|k| connections.open(ip(k)).unwrap()).collect();
        for c in &held {
            c.busy();
        }
        assert!(matches!(
            connections.open_or_make_room(ip(9)),
            Opened::Refused(Refused::Full)
        ));
        held[2].done();
        std::thread::sleep(std::time::Duration::from_millis(2));
        held[1].done();
        assert!(matches!(
            connections.open_or_make_room(ip(9)),
            Opened::MakingRoom(_, Refused::Full)
        ));
        assert!(notified(&held[2].state.close), "the longest idle");
        assert!(!notified(&held[1].state.close));
        assert_eq!(connections.total(), 3);
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
    fn notified(notify: &tokio::sync::Notify) -> bool {
        use std::future::Future;
        let mut waiting = std::pin::pin!(notify.notified());
        let waker = std::task::Waker::noop();
        waiting
            .as_mut()
            .poll(&mut std::task::Context::from_waker(waker))
            .is_ready()
    }
}
