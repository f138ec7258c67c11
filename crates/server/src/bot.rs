//! The bot socket (`/ws/matches/{id}/play?token=T`): a bot gets its agent's perceptions
//! and sends commands. The token is checked before the upgrade, so a wrong one never gets
//! a socket. The socket says `hello`, then carries what the match sends the agent one
//! way and what the bot says the other. What a message means and what it costs is the
//! match's driver's to decide (answers to perceptions pass free of the rate limit;
//! anything else pays): the socket reads, forwards, and closes when told. Bad input
//! gets an `error` message and the socket stays open; an oversized message closes it
//! with 1009, flooding with 1008 (the driver's decision), a frame that breaks the
//! WebSocket protocol with 1002.

use super::admission::Admitted;
use super::auth;
use super::error::ApiError;
use super::socket::{
    answer_close, classify, ending, limits, refusal, shut, Read, Sender, Sent, POLICY,
};
use super::state::{AppState, MatchEntry, ToMatch};
use super::upgrade::{Socket, Upgrade};
use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use fieldhouse_core::driver::{BotEvent, Close, Conn};
use fieldhouse_core::protocol::{decode, encode, Hello, Role};
use futures_util::StreamExt;
use std::collections::HashMap;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::{mpsc, oneshot};
use tokio_tungstenite::tungstenite::Utf8Bytes;

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

/// `GET /ws/matches/{id}/play`: upgrades a bot whose token controls an agent of the
/// match to its socket; the token is checked first (401 without one, 403 for a wrong
/// one, 410 once the match has ended).
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

async fn bot(socket: Socket, entry: Arc<MatchEntry>, app: Arc<AppState>, k: usize, agent: String) {
    let metrics = app.metrics.clone();
    metrics.bots.fetch_add(1, Relaxed);
    let conn = Conn(app.next_conn.fetch_add(1, Relaxed));
    let (out_tx, mut out_rx) = mpsc::channel::<Utf8Bytes>(16);
    let (close_tx, mut close_rx) = oneshot::channel::<Close>();
    let (mut sink, mut stream) = socket.split();
    let shutdown = app.shutdown.clone();
    let mut send = Sender {
        sink: &mut sink,
        timeout: Duration::from_millis(app.config.send_timeout_ms),
        metrics: &metrics,
    };
    let hello = encode(&Hello {
        agent: Some(&agent),
        ..Hello::new(Role::Bot, &entry.info, limits(&app))
    });
    let joined = send.text(hello.into()).await == Sent::Ok
        && entry
            .control
            .send(ToMatch::Join {
                agent: k,
                conn,
                out: out_tx,
                close: close_tx,
            })
            .await
            .is_ok();
    // The match's end comes through what it publishes, so a bot whose queue is full
    // still gets it.
    let mut published = entry.published.clone();
    // Every write is bounded by the send timeout: a bot that stops reading is closed
    // rather than kept (with its slot) after its match ended or its token reconnected.
    // The match task lets go of both when it closes this connection or ends: then the
    // close, or the end it published, is what is left to wait for.
    let (mut queue_open, mut close_open) = (true, true);
    let closing: Option<(u16, &str)> = if !joined {
        None
    } else {
        loop {
            tokio::select! {
                // What the match queued for this bot goes out before the end or the close
                // it decided after it: the last tick's perception (a catch on the last
                // ball, say) was lost when the end won the race.
                biased;
                outgoing = out_rx.recv(), if queue_open => {
                    let Some(text) = outgoing else {
                        queue_open = false;
                        continue;
                    };
                    if send.text(text).await != Sent::Ok {
                        break None;
                    }
                }
                why = &mut close_rx, if close_open => {
                    // The driver closed this connection (replaced, flooding); anything
                    // queued before goes first.
                    let Ok(why) = why else {
                        close_open = false;
                        continue;
                    };
                    if !flush(&mut send, &mut out_rx).await {
                        break None;
                    }
                    break Some((POLICY, why.reason()));
                }
                changed = published.changed() => {
                    let end = published.borrow_and_update().end.clone();
                    match (changed, end) {
                        (_, Some(end)) => {
                            if !flush(&mut send, &mut out_rx).await || send.text(end).await != Sent::Ok {
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
                    // What to do with a message, and what it costs, is the driver's to
                    // decide: only it knows which commands answer a perception. (Messages
                    // are at most max_message_bytes, so reading a flood costs little.)
                    let said = match read {
                        Read::Closed => break None,
                        Read::Ignore => continue,
                        Read::Text(text) => decode(&text),
                        _ => Err(("binary", "binary frames are not part of the protocol; send JSON text".to_owned())),
                    };
                    let event = BotEvent::Said { agent: k, conn, said };
                    if entry.control.send(ToMatch::Driver(event)).await.is_err() {
                        break None;
                    }
                }
            }
        }
    };
    match closing {
        Some((code, reason)) => shut(&mut sink, &mut stream, code, reason).await,
        // The client closed (or went): its close, if it sent one, is answered.
        None => answer_close(&mut sink).await,
    }
    let _ = entry
        .control
        .send(ToMatch::Driver(BotEvent::Leave { agent: k, conn }))
        .await;
    metrics.bots.fetch_sub(1, Relaxed);
}

/// Sends what is queued for the bot; whether it all went.
async fn flush(send: &mut Sender<'_>, queued: &mut mpsc::Receiver<Utf8Bytes>) -> bool {
    while let Ok(text) = queued.try_recv() {
        if send.text(text).await != Sent::Ok {
            return false;
        }
    }
    true
}
