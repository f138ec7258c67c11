//! The spectator socket (`/ws/matches/{id}`): watches a match's frames. It says `hello`,
//! sends the newest frame at once, and then joins the match's [`Fanout`], which writes
//! each new frame to its socket (see [`super::fanout`]). A spectator that falls behind
//! skips to the newest (counted as dropped), and one whose socket stops accepting data
//! is disconnected, so it never holds up a tick or anyone else. Spectators only listen:
//! what they send is charged to their budget and otherwise ignored, and an oversized
//! message closes the socket with 1009, flooding with 1008, a protocol error with 1002.
//!
//! [`Fanout`]: super::fanout::Fanout

use super::admission::AdmittedSpectator;
use super::api::ApiError;
use super::fanout::{Member, Out, Wire, WireIo};
use super::socket::{
    answer_close, budget, classify, ending, limits, refusal, send_close, Read, NORMAL, POLICY,
};
use super::state::{AppState, MatchEntry};
use super::upgrade::{FrameMeter, RawSocket, Upgrade};
use axum::extract::{Path, State};
use axum::response::{IntoResponse, Response};
use fieldhouse_core::budget::{MessageBudget, Verdict};
use fieldhouse_core::protocol::{encode, Hello, Role};
use futures_util::StreamExt;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio_tungstenite::tungstenite::protocol::Role as WsRole;
use tokio_tungstenite::WebSocketStream;

/// A spectator's socket as its reader sees it.
type Reader = WebSocketStream<FrameMeter<WireIo>>;

/// How long a closing spectator waits for its client's answer to the close.
const CLOSE_WITHIN: Duration = Duration::from_secs(2);

/// `GET /ws/matches/{id}`: a spectator's socket: the `hello`, then the match's newest
/// frame and every frame after it (skipping to the newest when it falls behind), then
/// the `end`.
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
    ws.on_upgrade_raw(&config, move |socket| spectator(socket, entry, app))
}

async fn spectator(socket: RawSocket, entry: Arc<MatchEntry>, app: Arc<AppState>) {
    let metrics = app.metrics.clone();
    metrics.spectators.fetch_add(1, Relaxed);
    entry.spectators.fetch_add(1, Relaxed);
    let wire = Arc::new(Wire::new(socket.stream, socket.place));
    let reader = WebSocketStream::from_raw_socket(
        FrameMeter::new(WireIo::new(wire.clone(), socket.read_first)),
        WsRole::Server,
        Some(socket.settings),
    )
    .await;
    // The reader has a task of its own, woken only when the client sends something; it
    // also writes the close handshake when told to.
    let (said_tx, mut said) = tokio::sync::oneshot::channel();
    let (close_tx, close_rx) = tokio::sync::oneshot::channel();
    let mut listener = tokio::spawn(listen(
        reader,
        wire.clone(),
        budget(&app),
        metrics.clone(),
        said_tx,
        close_rx,
    ));
    let timeout = Duration::from_millis(app.config.send_timeout_ms);
    let shutdown = app.shutdown.clone();
    let published = entry.published.clone();
    let hello = encode(&Hello::new(Role::Spectator, &entry.info, limits(&app)));
    let first = published.borrow().clone();
    let ok = wire.write_text(&hello).is_ok() && wire.write_text(first.frame.as_str()).is_ok();
    if ok {
        metrics.frames_sent.fetch_add(1, Relaxed);
        metrics
            .bytes_out
            .fetch_add((hello.len() + first.frame.len()) as u64, Relaxed);
    }
    // How the server ends the conversation, if it does: a close frame, then the
    // client's answer, which the reader reads.
    let mut closing: Option<(u16, &str)> = None;
    let mut end = first.end.clone();
    if ok && end.is_none() {
        let (out_tx, out) = tokio::sync::oneshot::channel();
        let member = Member::new(wire.clone(), first.seq, out_tx);
        match entry.fanout.join(member, &published, &metrics, timeout) {
            Err(_) => end = published.borrow().end.clone(),
            Ok(()) => tokio::select! {
                out = out => match out {
                    Ok(Out::Ended(last)) => end = last,
                    Ok(Out::TimedOut) => {
                        tracing::info!(id = %entry.info.id, "dropping a spectator that stopped reading");
                    }
                    Ok(Out::Gone) | Err(_) => {}
                },
                read = &mut said => closing = read.ok().flatten(),
            },
        }
        // No frame after this: what follows is the end and the close.
        wire.leave();
        if let Some(end) = &end {
            let _ = wire.write_text(end.as_str());
            closing = Some(ending(&shutdown));
        }
    } else if let (true, Some(end)) = (ok, &end) {
        let _ = wire.write_text(end.as_str());
        closing = Some((NORMAL, "match ended"));
    }
    if let Some(close) = closing {
        let _ = close_tx.send(close);
        let _ = tokio::time::timeout(CLOSE_WITHIN, &mut listener).await;
    }
    listener.abort();
    entry.spectators.fetch_sub(1, Relaxed);
    metrics.spectators.fetch_sub(1, Relaxed);
}

/// Reads a spectator's socket until it closes. Spectators only listen, so what they say
/// is not handled, only charged to their budget; the first thing that ends the
/// conversation (a close, a message over the size limit, flooding) is told through
/// `said` (with the close sent, if the server closes). Closes are written here, as the
/// reader owns the socket's WebSocket state: on the client's misbehaviour, or when the
/// spectator task says so (`close_rx`); reading goes on until the client's answer.
async fn listen(
    mut socket: Reader,
    wire: Arc<Wire>,
    mut budget: MessageBudget,
    metrics: Arc<super::metrics::Metrics>,
    said: tokio::sync::oneshot::Sender<Option<(u16, &'static str)>>,
    mut close_rx: tokio::sync::oneshot::Receiver<(u16, &'static str)>,
) {
    let mut said = Some(said);
    let mut closing = false;
    // The budget's time: this socket's age.
    let opened = tokio::time::Instant::now();
    loop {
        let incoming = tokio::select! {
            order = &mut close_rx, if !closing => {
                closing = true;
                match order {
                    Ok((code, reason)) => {
                        send_close(&mut socket, code, reason).await;
                        continue;
                    }
                    // The spectator task ends without closing: nothing more to read for.
                    Err(_) => return,
                }
            }
            incoming = socket.next() => incoming,
        };
        let read = classify(incoming);
        let verdict = match &read {
            Read::Text(_) | Read::Binary => budget.charge(opened.elapsed()),
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
        if let Some(ending) = ends {
            // A second reason to stop after the first: the client goes on misbehaving
            // after being told, and is read no more.
            let Some(said) = said.take() else { return };
            if let (Some((code, reason)), false) = (ending, closing) {
                closing = true;
                // No frame after the close.
                wire.leave();
                send_close(&mut socket, code, reason).await;
            }
            let _ = said.send(ending);
        }
        if matches!(read, Read::Closed) {
            // No frame after the answering close either: the fan-out may be about to
            // write one.
            wire.leave();
            answer_close(&mut socket).await;
            return;
        }
    }
}
