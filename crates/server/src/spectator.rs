//! The spectator socket (`/ws/matches/{id}`): watches a match's frames. It says `hello`,
//! sends the newest frame at once and then each new one. A spectator that falls behind
//! skips to the newest (counted as dropped), and one whose socket stops accepting data
//! is disconnected, so it never holds up a tick or anyone else. Spectators only listen:
//! what they send is charged to their budget and otherwise ignored, and an oversized
//! message closes the socket with 1009, flooding with 1008.

use super::admission::AdmittedSpectator;
use super::api::ApiError;
use super::budget::{MessageBudget, Verdict};
use super::socket::{
    budget, classify, close, ending, limits, refusal, Read, Sender, Sent, NORMAL, POLICY,
};
use super::state::{AppState, MatchEntry};
use super::upgrade::{Socket, Upgrade};
use axum::extract::{Path, State};
use axum::response::{IntoResponse, Response};
use fieldhouse_core::protocol::{encode, Hello, Role};
use futures_util::stream::SplitStream;
use futures_util::{SinkExt, StreamExt};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;

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
    let hello = encode(&Hello::new(Role::Spectator, &entry.info, limits(&app)));
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
