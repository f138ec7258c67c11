//! The bot socket (`/ws/matches/{id}/play?token=T`): a bot gets its agent's perceptions
//! and sends commands. The token is checked before the upgrade, so a wrong one never gets
//! a socket. The socket says `hello`, then carries what the match sends the agent one
//! way and commands the other. Answers to perceptions are owed (`Owed`) and pass free
//! of the rate limit; anything else pays. Bad input gets an `error` message and the
//! socket stays open; an oversized message closes it with 1009, flooding with 1008, a
//! frame that breaks the WebSocket protocol with 1002.

use super::admission::Admitted;
use super::auth;
use super::budget::Verdict;
use super::error::ApiError;
use super::socket::{
    answer_close, budget, classify, ending, limits, refusal, shut, Read, Sender, Sent, POLICY,
};
use super::state::{AppState, Control, MatchEntry, ToBot};
use super::upgrade::{Socket, Upgrade};
use axum::extract::{Path, Query, State};
use axum::http::HeaderMap;
use axum::response::{IntoResponse, Response};
use fieldhouse_core::driver::Event;
use fieldhouse_core::protocol::{decode, encode, ClientMessage, ErrorMessage, Hello, Role};
use futures_util::StreamExt;
use std::collections::{HashMap, VecDeque};
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;
use std::time::Duration;
use tokio::sync::mpsc;

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
    let hello = encode(&Hello {
        agent: Some(&agent),
        ..Hello::new(Role::Bot, &entry.info, limits(&app))
    });
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
                // What the match queued for this bot goes out before the end it published
                // after it: the last tick's perception (a catch on the last ball, say)
                // was lost when the end won the race.
                biased;
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
                            // Anything queued before the end still goes first.
                            let mut sent = Sent::Ok;
                            while let (Sent::Ok, Ok(queued)) = (&sent, out_rx.try_recv()) {
                                sent = send.text(queued.text).await;
                            }
                            if sent != Sent::Ok || send.text(end).await != Sent::Ok {
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
                            let command = Control::Driver(Event::Command { agent: k, conn, tick, action });
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
    match closing {
        Some((code, reason)) => shut(&mut sink, &mut stream, code, reason).await,
        // The client closed (or went): its close, if it sent one, is answered.
        None => answer_close(&mut sink).await,
    }
    let _ = entry
        .control
        .send(Control::Driver(Event::BotLeave { agent: k, conn }))
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
