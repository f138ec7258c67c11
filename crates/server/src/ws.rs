//! The WebSocket endpoints: spectators (`/ws/matches/{id}`) watch a match's frames; bots
//! (`/ws/matches/{id}/play?token=T`) get their agent's perceptions and send commands.
//!
//! Every socket says `hello` first. A spectator gets the newest frame at once and then
//! each new one; one that falls behind skips to the newest (counted as dropped), and one
//! whose socket stops accepting data is disconnected, so it never holds up a tick or
//! anyone else. Bad input gets an `error` message and the socket stays open; an
//! oversized message closes it with 1009, flooding with 1008. On shutdown every match
//! ends: its sockets get `end` and close with 1001.

use super::admission::{Admitted, AdmittedSpectator};
use super::api::ApiError;
use super::auth;
use super::budget::{MessageBudget, Verdict};
use super::state::{AppState, Control, MatchEntry, ToBot};
use super::upgrade::{FrameFlood, Socket, Upgrade};
use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use fieldhouse_core::protocol::{decode, encode, ClientMessage, ErrorMessage, Hello, Limits};
use futures_util::stream::{SplitSink, SplitStream};
use futures_util::{SinkExt, StreamExt};
use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;
use tokio_tungstenite::tungstenite::protocol::CloseFrame;
use tokio_tungstenite::tungstenite::{self, Message, Utf8Bytes};

/// Close codes (RFC 6455).
pub(super) const GOING_AWAY: u16 = 1001;
pub(super) const POLICY: u16 = 1008;
pub(super) const TOO_BIG: u16 = 1009;
const NORMAL: u16 = 1000;

fn limits(app: &AppState) -> Limits {
    Limits {
        max_message_bytes: app.config.max_message_bytes,
        messages_per_second: app.config.bot_messages_per_second,
    }
}

/// The message budget every socket starts with.
pub(super) fn budget(app: &AppState) -> MessageBudget {
    MessageBudget::new(app.config.bot_messages_per_second, app.config.bot_burst)
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
        code: code.into(),
        reason: Utf8Bytes::from(reason.to_string()),
    }))
}

/// What reading a socket gave, or why it stopped.
pub(super) enum Read {
    Text(Utf8Bytes),
    Binary,
    /// Pings and pongs: the library answers pings, and the frame meter counts both.
    Ignore,
    Closed,
    TooBig,
    /// More control or fragment frames than the frame meter allows.
    Flood,
}

pub(super) fn classify(incoming: Option<Result<Message, tungstenite::Error>>) -> Read {
    match incoming {
        None | Some(Ok(Message::Close(_))) => Read::Closed,
        Some(Ok(Message::Text(t))) => Read::Text(t),
        Some(Ok(Message::Binary(_))) => Read::Binary,
        Some(Ok(_)) => Read::Ignore,
        Some(Err(tungstenite::Error::Capacity(_))) => Read::TooBig,
        Some(Err(tungstenite::Error::Io(e)))
            if e.get_ref().is_some_and(|inner| inner.is::<FrameFlood>()) =>
        {
            Read::Flood
        }
        Some(Err(_)) => Read::Closed,
    }
}

/// How a socket closes because of what its client sent, if it does: 1009 for a message
/// over the size limit, 1008 for flooding. Counted in the metrics.
pub(super) fn refusal(
    read: &Read,
    metrics: &super::metrics::Metrics,
) -> Option<(u16, &'static str)> {
    match read {
        Read::TooBig => {
            metrics.closed_for_size.fetch_add(1, Relaxed);
            Some((TOO_BIG, "message too big"))
        }
        Read::Flood => {
            metrics.closed_for_rate.fetch_add(1, Relaxed);
            Some((POLICY, "too many frames"))
        }
        _ => None,
    }
}

#[derive(Debug, PartialEq, Eq)]
pub(super) enum Sent {
    Ok,
    Failed,
    /// The socket did not take the message in time: the client stopped reading.
    TimedOut,
}

/// Writes to a client's socket, counting bytes, giving up after `timeout`
/// (`send_timeout_ms`): a client that stops reading never holds a task, a slot or a
/// descriptor for longer than that.
pub(super) struct Sender<'a> {
    pub sink: &'a mut SplitSink<Socket, Message>,
    pub timeout: Duration,
    pub metrics: &'a super::metrics::Metrics,
}

impl Sender<'_> {
    pub(crate) async fn text(&mut self, text: Utf8Bytes) -> Sent {
        self.metrics.bytes_out.fetch_add(text.len() as u64, Relaxed);
        // The connection's own write timeout (see `listener`) is the same length and
        // may fire first: either way the client stopped reading.
        let sent = tokio::time::timeout(self.timeout, self.sink.send(Message::Text(text))).await;
        match sent {
            Ok(Ok(())) => Sent::Ok,
            Ok(Err(tungstenite::Error::Io(e))) if e.kind() != std::io::ErrorKind::TimedOut => {
                Sent::Failed
            }
            Ok(Err(tungstenite::Error::Io(_))) | Err(_) => {
                self.metrics.slow_clients_dropped.fetch_add(1, Relaxed);
                Sent::TimedOut
            }
            Ok(Err(_)) => Sent::Failed,
        }
    }

    /// [`Sender::text`] for `?`: anything but [`Sent::Ok`] is the error.
    pub(crate) async fn deliver(&mut self, text: impl Into<Utf8Bytes>) -> Result<(), Sent> {
        match self.text(text.into()).await {
            Sent::Ok => Ok(()),
            failed => Err(failed),
        }
    }
}

/// Sends a close frame, then reads on until the client answers it (or a second passes),
/// so the client gets the close code rather than a connection reset.
pub(super) async fn shut(
    sink: &mut SplitSink<Socket, Message>,
    stream: &mut SplitStream<Socket>,
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
    ws: Upgrade,
    Path(id): Path<String>,
    _: AdmittedSpectator,
    State(app): State<Arc<AppState>>,
) -> Response {
    let Some(entry) = app.get(&id) else {
        return ApiError::not_found(&id).into_response();
    };
    let config = app.config.clone();
    ws.on_upgrade(&config, move |socket| spectator(socket, entry, app))
}

async fn spectator(socket: Socket, entry: Arc<MatchEntry>, app: Arc<AppState>) {
    let metrics = app.metrics.clone();
    metrics.spectators.fetch_add(1, Relaxed);
    entry.spectators.fetch_add(1, Relaxed);
    let (mut sink, stream) = socket.split();
    // The read side has a task of its own, woken only when the client sends something.
    // Reading in the frame loop's `select!` polled the socket for every frame, and
    // each poll cleared a read buffer: a profile at 1,000 spectators showed 12 % of the
    // server's CPU in memset.
    let (said_tx, mut said) = tokio::sync::oneshot::channel();
    let mut listener = tokio::spawn(listen(stream, budget(&app), metrics.clone(), said_tx));
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
                    closing = read.ok().flatten();
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
/// is not handled, only charged to their budget; the first thing that ends the
/// conversation (a close, a message over the size limit, flooding) is told through
/// `said` (with the close to send, if the server closes), and reading goes on until
/// the close, so the client's answer to the server's close frame is taken.
async fn listen(
    mut stream: SplitStream<Socket>,
    mut budget: MessageBudget,
    metrics: Arc<super::metrics::Metrics>,
    said: tokio::sync::oneshot::Sender<Option<(u16, &'static str)>>,
) {
    let mut said = Some(said);
    loop {
        let read = classify(stream.next().await);
        let verdict = match &read {
            Read::Text(_) | Read::Binary => budget.charge(),
            _ => Verdict::Take,
        };
        let ends = match (&read, verdict) {
            (Read::Closed, _) => Some(None),
            (_, Verdict::Flooding) => {
                metrics.closed_for_rate.fetch_add(1, Relaxed);
                Some(Some((POLICY, "too many messages")))
            }
            _ => refusal(&read, &metrics).map(Some),
        };
        if let Some(close) = ends {
            // A second reason to stop after the first: the client goes on misbehaving
            // after being told, and is read no more.
            match said.take() {
                Some(said) => {
                    let _ = said.send(close);
                }
                None => return,
            }
        }
        if matches!(read, Read::Closed) {
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
    ws: Upgrade,
    Path(id): Path<String>,
    Query(query): Query<HashMap<String, String>>,
    _: Admitted,
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
    let config = app.config.clone();
    ws.on_upgrade(&config, move |socket| bot(socket, entry, app, k, agent))
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

async fn bot(socket: Socket, entry: Arc<MatchEntry>, app: Arc<AppState>, k: usize, agent: String) {
    let metrics = app.metrics.clone();
    metrics.bots.fetch_add(1, Relaxed);
    let conn = app.next_conn.fetch_add(1, Relaxed);
    let (out_tx, mut out_rx) = mpsc::channel::<ToBot>(16);
    let (mut sink, mut stream) = socket.split();
    let shutdown = app.shutdown.clone();
    let mut send = Sender {
        sink: &mut sink,
        timeout: Duration::from_millis(app.config.send_timeout_ms),
        metrics: &metrics,
    };
    let hello = encode(&Hello::new("bot", &entry.info, Some(&agent), limits(&app)));
    let joined = send.text(hello.into()).await == Sent::Ok
        && entry
            .control
            .send(Control::BotJoin {
                agent: k,
                conn,
                out: out_tx.clone(),
            })
            .await
            .is_ok();
    let mut budget = budget(&app);
    let mut owed = Owed::default();
    let error = |code: &str, message: &str| {
        metrics.client_errors.fetch_add(1, Relaxed);
        let _ = out_tx.try_send(ToBot::message(encode(&ErrorMessage::new(code, message))));
    };
    // The match's end comes through what it publishes, so a bot whose queue is full
    // still gets it.
    let mut published = entry.published.clone();
    // Every write is bounded by the send timeout: a bot that stops reading is closed
    // rather than kept (with its slot) after its match ended or its token reconnected.
    let closing: Option<(u16, &str)> = if !joined {
        None
    } else {
        loop {
            tokio::select! {
                outgoing = out_rx.recv() => {
                    let Some(ToBot { text, perception, replaced }) = outgoing else { break None };
                    if send.text(text).await != Sent::Ok {
                        break None;
                    }
                    if let Some(tick) = perception {
                        owed.owe(tick);
                    }
                    if replaced {
                        break Some((POLICY, "another connection took over this agent"));
                    }
                }
                changed = published.changed() => {
                    let end = published.borrow_and_update().end.clone();
                    match (changed, end) {
                        (_, Some(end)) => {
                            if send.text(end).await != Sent::Ok {
                                break None;
                            }
                            break Some(ending(&shutdown));
                        }
                        (Err(_), None) => break None,
                        (Ok(()), None) => {}
                    }
                }
                incoming = stream.next() => {
                    let read = classify(incoming);
                    if let Some(close) = refusal(&read, &metrics) {
                        break Some(close);
                    }
                    let message = match read {
                        Read::Closed => break None,
                        Read::Ignore => continue,
                        Read::Text(text) => Some(decode(&text)),
                        _ => None,
                    };
                    // Read first, to see whether it answers a perception: only what is
                    // not owed pays the rate limit. (Messages are at most
                    // max_message_bytes, so reading a flood costs little.)
                    let answers = matches!(
                        &message,
                        Some(Ok(ClientMessage::Command { tick, .. })) if owed.settle(*tick)
                    );
                    if !answers {
                        match budget.charge() {
                            Verdict::Take => {}
                            Verdict::Refuse { warn } => {
                                if warn {
                                    error("rate_limited", "too many messages; slow down or be disconnected");
                                }
                                continue;
                            }
                            Verdict::Flooding => {
                                metrics.closed_for_rate.fetch_add(1, Relaxed);
                                break Some((POLICY, "too many messages"));
                            }
                        }
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
