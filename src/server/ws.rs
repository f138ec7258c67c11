//! The WebSocket endpoints: spectators (`/ws/matches/{id}`) watch a match's frames; bots
//! (`/ws/matches/{id}/play?token=T`) get their agent's perceptions and send commands.
//!
//! Every socket says `hello` first. A spectator gets the newest frame at once and then
//! each new one; one that falls behind skips to the newest (counted as dropped), and one
//! whose socket stops accepting data is disconnected, so it never holds up a tick or
//! anyone else. Bad input gets an `error` message and the socket stays open; an
//! oversized message closes it with 1009, flooding with 1008. On shutdown every match
//! ends: its sockets get `end` and close with 1001.

use super::admission::Admitted;
use super::api::ApiError;
use super::auth;
use super::state::{AppState, Control, MatchEntry, ToBot};
use crate::protocol::{decode, encode, ClientMessage, ErrorMessage, Hello, Limits};
use axum::extract::ws::{CloseFrame, Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use futures_util::stream::{SplitSink, SplitStream};
use futures_util::{SinkExt, StreamExt};
use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tokio::sync::mpsc;

/// Close codes (RFC 6455).
pub(super) const GOING_AWAY: u16 = 1001;
const POLICY: u16 = 1008;
pub(super) const TOO_BIG: u16 = 1009;
const NORMAL: u16 = 1000;

/// Sockets buffer little: frames are small and a slow reader should skip, not queue.
const SOCKET_BUFFER_BYTES: usize = 8 * 1024;

fn limits(app: &AppState) -> Limits {
    Limits {
        max_message_bytes: app.config.max_message_bytes,
        messages_per_second: app.config.bot_messages_per_second,
    }
}

pub(super) fn upgrade(ws: WebSocketUpgrade, app: &AppState) -> WebSocketUpgrade {
    ws.max_message_size(app.config.max_message_bytes)
        .max_frame_size(app.config.max_message_bytes)
        .read_buffer_size(SOCKET_BUFFER_BYTES)
        .write_buffer_size(SOCKET_BUFFER_BYTES)
}

/// How a socket closes after its match's `end`: 1001 when the server is shutting down
/// (every match ends then), else 1000.
fn ending(shutdown: &tokio::sync::watch::Receiver<bool>) -> (u16, &'static str) {
    if *shutdown.borrow() {
        (GOING_AWAY, "server shutting down")
    } else {
        (NORMAL, "match ended")
    }
}

fn close(code: u16, reason: &str) -> Message {
    Message::Close(Some(CloseFrame {
        code,
        reason: Utf8Bytes::from(reason.to_string()),
    }))
}

/// Why reading a socket stopped, if it did.
pub(super) enum Read {
    Text(Utf8Bytes),
    Binary,
    Ignore,
    Closed,
    TooBig,
}

pub(super) fn classify(incoming: Option<Result<Message, axum::Error>>) -> Read {
    match incoming {
        None | Some(Ok(Message::Close(_))) => Read::Closed,
        Some(Ok(Message::Text(t))) => Read::Text(t),
        Some(Ok(Message::Binary(_))) => Read::Binary,
        Some(Ok(_)) => Read::Ignore, // ping and pong are answered by the library
        Some(Err(e)) => {
            let too_big = e
                .into_inner()
                .downcast_ref::<tokio_tungstenite::tungstenite::Error>()
                .is_some_and(|e| matches!(e, tokio_tungstenite::tungstenite::Error::Capacity(_)));
            if too_big {
                Read::TooBig
            } else {
                Read::Closed
            }
        }
    }
}

#[derive(Debug, PartialEq, Eq)]
enum Sent {
    Ok,
    Failed,
    /// The socket did not take the message in time: the client stopped reading.
    TimedOut,
}

/// Writes to a spectator's socket, counting bytes, giving up after `timeout`.
struct Sender<'a> {
    sink: &'a mut SplitSink<WebSocket, Message>,
    timeout: Duration,
    metrics: &'a super::metrics::Metrics,
}

impl Sender<'_> {
    async fn text(&mut self, text: Utf8Bytes) -> Sent {
        self.metrics.bytes_out.fetch_add(text.len() as u64, Relaxed);
        match tokio::time::timeout(self.timeout, self.sink.send(Message::Text(text))).await {
            Ok(Ok(())) => Sent::Ok,
            Ok(Err(_)) => Sent::Failed,
            Err(_) => Sent::TimedOut,
        }
    }
}

/// Sends a close frame, then reads on until the client answers it (or a second passes),
/// so the client gets the close code rather than a connection reset.
pub(super) async fn shut(
    sink: &mut SplitSink<WebSocket, Message>,
    stream: &mut SplitStream<WebSocket>,
    code: u16,
    reason: &str,
) {
    let _ = tokio::time::timeout(Duration::from_secs(1), sink.send(close(code, reason))).await;
    let _ = tokio::time::timeout(Duration::from_secs(1), async {
        while let Some(Ok(message)) = stream.next().await {
            if matches!(message, Message::Close(_)) {
                break;
            }
        }
    })
    .await;
}

pub async fn spectate(
    ws: WebSocketUpgrade,
    Path(id): Path<String>,
    admitted: Admitted,
    State(app): State<Arc<AppState>>,
) -> Response {
    let Some(entry) = app.get(&id) else {
        return ApiError::not_found(&id).into_response();
    };
    upgrade(ws, &app).on_upgrade(move |socket| async move {
        spectator(socket, entry, app).await;
        drop(admitted);
    })
}

async fn spectator(socket: WebSocket, entry: Arc<MatchEntry>, app: Arc<AppState>) {
    let metrics = app.metrics.clone();
    metrics.spectators.fetch_add(1, Relaxed);
    entry.spectators.fetch_add(1, Relaxed);
    let (mut sink, stream) = socket.split();
    // The read side has a task of its own, woken only when the client sends something.
    // Reading in the frame loop's `select!` polled the socket for every frame, and
    // each poll cleared a read buffer: a profile at 1,000 spectators showed 12 % of the
    // server's CPU in memset.
    let (said_tx, mut said) = tokio::sync::oneshot::channel();
    let mut listener = tokio::spawn(listen(stream, said_tx));
    let timeout = Duration::from_millis(app.config.send_timeout_ms);
    let shutdown = app.shutdown.clone();
    let mut published = entry.published.clone();
    let hello = encode(&Hello::new("spectator", &entry.info, None, limits(&app)));
    let first = published.borrow_and_update().clone();
    let mut last_seq = first.seq;
    let mut send = Sender {
        sink: &mut sink,
        timeout,
        metrics: &metrics,
    };
    let ok = send.text(hello.into()).await == Sent::Ok && send.text(first.frame).await == Sent::Ok;
    if ok {
        metrics.frames_sent.fetch_add(1, Relaxed);
    }
    // How the server ends the conversation, if it does: a close frame, then the
    // client's answer, which the listener reads (for at most a second).
    let mut closing: Option<(u16, &str)> = None;
    if let (true, Some(end)) = (ok, &first.end) {
        send.text(end.clone()).await;
        closing = Some((NORMAL, "match ended"));
    }
    if ok && closing.is_none() {
        loop {
            tokio::select! {
                changed = published.changed() => {
                    if changed.is_err() {
                        break;
                    }
                    let p = published.borrow_and_update().clone();
                    if p.seq > last_seq {
                        app.metrics.frames_dropped.fetch_add(p.seq - last_seq - 1, Relaxed);
                        last_seq = p.seq;
                        match send.text(p.frame).await {
                            Sent::Ok => { metrics.frames_sent.fetch_add(1, Relaxed); }
                            Sent::Failed => break,
                            Sent::TimedOut => {
                                metrics.slow_clients_dropped.fetch_add(1, Relaxed);
                                tracing::info!(id = %entry.info.id, "dropping a spectator that stopped reading");
                                break;
                            }
                        }
                    }
                    if let Some(end) = p.end {
                        send.text(end).await;
                        closing = Some(ending(&shutdown));
                        break;
                    }
                }
                read = &mut said => {
                    if let Ok(Read::TooBig) = read {
                        metrics.closed_for_size.fetch_add(1, Relaxed);
                        closing = Some((TOO_BIG, "message too big"));
                    }
                    break;
                }
            }
        }
    }
    if let Some((code, reason)) = closing {
        let _ = tokio::time::timeout(Duration::from_secs(1), sink.send(close(code, reason))).await;
        let _ = tokio::time::timeout(Duration::from_secs(1), &mut listener).await;
    }
    listener.abort();
    entry.spectators.fetch_sub(1, Relaxed);
    metrics.spectators.fetch_sub(1, Relaxed);
}

/// Reads a spectator's socket until it closes. Spectators only listen, so what they say
/// is not read; the first thing that ends the conversation (a close, or a message over
/// the size limit) is told through `said`, and reading goes on until the close, so the
/// client's answer to the server's close frame is taken.
async fn listen(mut stream: SplitStream<WebSocket>, said: tokio::sync::oneshot::Sender<Read>) {
    let mut said = Some(said);
    loop {
        let read = classify(stream.next().await);
        let closed = matches!(read, Read::Closed);
        if matches!(read, Read::Closed | Read::TooBig) {
            if let Some(said) = said.take() {
                let _ = said.send(read);
            }
        }
        if closed {
            return;
        }
    }
}

/// The bot token of a request: `?token=T`, `Authorization: Bearer T` or
/// `X-Fieldhouse-Token: T`.
fn token_of<'a>(query: &'a HashMap<String, String>, headers: &'a HeaderMap) -> Option<&'a str> {
    query.get("token").map(String::as_str).or_else(|| {
        headers
            .get("authorization")
            .and_then(|v| v.to_str().ok())
            .and_then(auth::bearer)
            .or_else(|| {
                headers
                    .get("x-fieldhouse-token")
                    .and_then(|v| v.to_str().ok())
            })
    })
}

pub async fn play(
    ws: WebSocketUpgrade,
    Path(id): Path<String>,
    Query(query): Query<HashMap<String, String>>,
    admitted: Admitted,
    headers: HeaderMap,
    State(app): State<Arc<AppState>>,
) -> Response {
    let Some(entry) = app.get(&id) else {
        return ApiError::not_found(&id).into_response();
    };
    // The token is checked before the upgrade: a wrong one never gets a socket.
    let Some(token) = token_of(&query, &headers) else {
        return ApiError::unauthorized(
            "a bot token is required: ?token=T or Authorization: Bearer T",
        )
        .into_response();
    };
    // Compare against every token so the time taken does not say which agent matched.
    let mut found = None;
    for (k, agent, expected) in &entry.tokens {
        if auth::same(token, expected) {
            found = Some((*k, agent.clone()));
        }
    }
    let Some((k, agent)) = found else {
        return ApiError::forbidden("this token controls no agent of this match").into_response();
    };
    if entry.ended.load(Relaxed) {
        return ApiError::gone(&id).into_response();
    }
    upgrade(ws, &app).on_upgrade(move |socket| async move {
        bot(socket, entry, app, k, agent).await;
        drop(admitted);
    })
}

/// A token bucket: `rate` messages a second, `burst` at once.
struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    last: Instant,
    /// Messages refused with no quiet second between them: flooding, once there are
    /// more than a burst of them.
    strikes: u32,
    last_refused: Instant,
}

impl Bucket {
    fn take(&mut self) -> bool {
        let now = Instant::now();
        self.tokens = (self.tokens + (now - self.last).as_secs_f64() * self.rate).min(self.burst);
        self.last = now;
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            return true;
        }
        if now - self.last_refused > Duration::from_secs(1) {
            self.strikes = 0;
        }
        self.strikes += 1;
        self.last_refused = now;
        false
    }
}

/// The perceptions a bot has been sent and not yet answered, by tick: its answer to
/// each is owed, so it passes free of the rate limit, once. A lock-step bot answers
/// every perception at once, and a match may send them faster than any fixed rate;
/// charging those answers disconnected bots that did exactly what the protocol asks.
/// Only the newest [`Owed::MAX`] are remembered: an answer to an older one is charged.
#[derive(Default)]
struct Owed(VecDeque<u64>);

impl Owed {
    const MAX: usize = 64;

    fn owe(&mut self, tick: u64) {
        if self.0.len() == Self::MAX {
            self.0.pop_front();
        }
        self.0.push_back(tick);
    }

    /// Whether a command for `tick` answers an unanswered perception; it is answered
    /// from now on.
    fn settle(&mut self, tick: u64) -> bool {
        let found = self.0.iter().position(|&t| t == tick);
        found.map(|k| self.0.remove(k)).is_some()
    }
}

async fn bot(
    socket: WebSocket,
    entry: Arc<MatchEntry>,
    app: Arc<AppState>,
    k: usize,
    agent: String,
) {
    let metrics = app.metrics.clone();
    metrics.bots.fetch_add(1, Relaxed);
    let conn = app.next_conn.fetch_add(1, Relaxed);
    let (out_tx, mut out_rx) = mpsc::channel::<ToBot>(16);
    let (mut sink, mut stream) = socket.split();
    let shutdown = app.shutdown.clone();
    let hello = encode(&Hello::new("bot", &entry.info, Some(&agent), limits(&app)));
    let joined = sink.send(Message::Text(hello.into())).await.is_ok()
        && entry
            .control
            .send(Control::BotJoin {
                agent: k,
                conn,
                out: out_tx.clone(),
            })
            .await
            .is_ok();
    let mut bucket = Bucket {
        tokens: f64::from(app.config.bot_burst),
        rate: f64::from(app.config.bot_messages_per_second),
        burst: f64::from(app.config.bot_burst),
        last: Instant::now(),
        strikes: 0,
        last_refused: Instant::now(),
    };
    let error = |code: &str, message: &str| {
        metrics.client_errors.fetch_add(1, Relaxed);
        let _ = out_tx.try_send(ToBot::message(encode(&ErrorMessage::new(code, message))));
    };
    // The match's end comes through what it publishes, so a bot whose queue is full
    // still gets it.
    let mut published = entry.published.clone();
    let mut owed = Owed::default();
    let closing: Option<(u16, &str)> = if !joined {
        None
    } else {
        loop {
            tokio::select! {
                outgoing = out_rx.recv() => {
                    let Some(ToBot { text, perception }) = outgoing else { break None };
                    if let Some(tick) = perception {
                        owed.owe(tick);
                    }
                    let replaced = text.as_str().contains("\"code\":\"replaced\"");
                    metrics.bytes_out.fetch_add(text.len() as u64, Relaxed);
                    if sink.send(Message::Text(text)).await.is_err() {
                        break None;
                    }
                    if replaced {
                        break Some((POLICY, "another connection took over this agent"));
                    }
                }
                changed = published.changed() => {
                    let end = published.borrow_and_update().end.clone();
                    match (changed, end) {
                        (_, Some(end)) => {
                            metrics.bytes_out.fetch_add(end.len() as u64, Relaxed);
                            let _ = sink.send(Message::Text(end)).await;
                            break Some(ending(&shutdown));
                        }
                        (Err(_), None) => break None,
                        (Ok(()), None) => {}
                    }
                }
                incoming = stream.next() => match classify(incoming) {
                    Read::Closed => break None,
                    Read::TooBig => {
                        metrics.closed_for_size.fetch_add(1, Relaxed);
                        break Some((TOO_BIG, "message too big"));
                    }
                    Read::Ignore => {}
                    read => {
                        // Read first, to see whether it answers a perception: only what
                        // is not owed pays the rate limit. (Messages are at most
                        // max_message_bytes, so reading a flood costs little.)
                        let message = match &read {
                            Read::Text(text) => Some(decode(text)),
                            _ => None,
                        };
                        let answers = matches!(
                            &message,
                            Some(Ok(ClientMessage::Command { tick, .. })) if owed.settle(*tick)
                        );
                        if !answers && !bucket.take() {
                            if bucket.strikes > app.config.bot_burst {
                                metrics.closed_for_rate.fetch_add(1, Relaxed);
                                break Some((POLICY, "too many messages"));
                            }
                            if bucket.strikes == 1 {
                                error("rate_limited", "too many messages; slow down or be disconnected");
                            }
                            continue;
                        }
                        match message {
                            None => error("binary", "binary frames are not part of the protocol; send JSON text"),
                            Some(Ok(ClientMessage::Command { tick, action })) => {
                                let command = Control::Command { agent: k, conn, tick, action };
                                if entry.control.send(command).await.is_err() {
                                    break None;
                                }
                            }
                            Some(Err((code, message))) => error(code, &message),
                        }
                    }
                },
            }
        }
    };
    if let Some((code, reason)) = closing {
        shut(&mut sink, &mut stream, code, reason).await;
    }
    let _ = entry
        .control
        .send(Control::BotLeave { agent: k, conn })
        .await;
    metrics.bots.fetch_sub(1, Relaxed);
}

#[cfg(test)]
mod tests {
    use super::Owed;

    #[test]
    fn each_perception_is_owed_one_answer_and_only_the_newest_are_remembered() {
        let mut owed = Owed::default();
        owed.owe(6);
        owed.owe(12);
        assert!(owed.settle(12));
        assert!(
            !owed.settle(12),
            "a second answer to the same perception pays"
        );
        assert!(
            !owed.settle(18),
            "nor does an answer to a perception never sent"
        );
        assert!(owed.settle(6), "answers may come out of order");
        for tick in 0..(Owed::MAX as u64 + 10) {
            owed.owe(tick);
        }
        assert!(
            !owed.settle(9),
            "forgotten: older than the newest {}",
            Owed::MAX
        );
        assert!(owed.settle(10));
        assert_eq!(owed.0.len(), Owed::MAX - 1);
    }
}
