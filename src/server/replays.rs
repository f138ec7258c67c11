//! Replays the server recorded: listed and downloaded over REST, and played over a
//! WebSocket with the live protocol (`hello`, `frame`s, `end`) plus the client's
//! `control` messages: play, pause, speed (0.25× to 8×), seek to a tick.

use super::admission::AdmittedSpectator;
use super::api::ApiError;
use super::budget::Verdict;
use super::state::AppState;
use super::upgrade::{Socket, Upgrade};
use super::ws::{budget, classify, refusal, shut, Read, GOING_AWAY, POLICY};
use crate::protocol::{encode, End, ErrorMessage};
use crate::replay::{self, Replay};
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use futures_util::{SinkExt, StreamExt};
use serde::Deserialize;
use serde_json::{json, Value};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::{Message, Utf8Bytes};

/// The file of replay `id`, if the id is one: letters, digits, `-` and `_` only, so no
/// id reaches outside the replay directory.
fn file_of(app: &AppState, id: &str) -> Result<PathBuf, ApiError> {
    let dir = app.replay_dir.as_ref().ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            "no_replays",
            "this server does not record replays (serve --replay-dir DIR)",
        )
    })?;
    let valid = !id.is_empty()
        && id.len() <= 128
        && id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    if !valid {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            "bad_id",
            format!("\"{id}\" is not a replay id"),
        ));
    }
    let path = dir.join(format!("{id}.jsonl"));
    if !path.is_file() {
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no replay \"{id}\""),
        ));
    }
    Ok(path)
}

pub async fn list(State(app): State<Arc<AppState>>) -> Result<Json<Value>, ApiError> {
    let Some(dir) = app.replay_dir.clone() else {
        return Ok(Json(json!({"replays": []})));
    };
    let replays = tokio::task::spawn_blocking(move || {
        let mut out = Vec::new();
        for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.extension().and_then(|e| e.to_str()) != Some("jsonl") {
                continue;
            }
            let Some(id) = path.file_stem().map(|s| s.to_string_lossy().into_owned()) else {
                continue;
            };
            let bytes = entry.metadata().map_or(0, |m| m.len());
            match replay::peek(&path) {
                Ok((header, footer)) => out.push(json!({
                    "id": id,
                    "bytes": bytes,
                    "match": header["match"]["id"],
                    "name": header["match"]["name"],
                    "sport": header["match"]["sport"],
                    "started_unix_ms": header["started_unix_ms"],
                    "complete": footer.is_some(),
                    "result": footer.as_ref().map(|f| f["result"].clone()),
                })),
                Err(e) => out.push(json!({"id": id, "bytes": bytes, "error": e})),
            }
        }
        out.sort_by(|a, b| a["id"].as_str().cmp(&b["id"].as_str()));
        out
    })
    .await
    .unwrap_or_default();
    Ok(Json(json!({"replays": replays})))
}

pub async fn download(
    Path(id): Path<String>,
    State(app): State<Arc<AppState>>,
) -> Result<Response, ApiError> {
    let path = file_of(&app, &id)?;
    let bytes = tokio::fs::read(&path).await.map_err(|e| {
        ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "unreadable",
            e.to_string(),
        )
    })?;
    Ok((
        [
            ("content-type", "application/x-ndjson".to_string()),
            (
                "content-disposition",
                format!("attachment; filename=\"{id}.jsonl\""),
            ),
        ],
        bytes,
    )
        .into_response())
}

pub async fn watch(
    ws: Upgrade,
    Path(id): Path<String>,
    _: AdmittedSpectator,
    State(app): State<Arc<AppState>>,
) -> Response {
    let path = match file_of(&app, &id) {
        Ok(p) => p,
        Err(e) => return e.into_response(),
    };
    let read = tokio::task::spawn_blocking(move || replay::read(&path)).await;
    let replay = match read {
        Ok(Ok(r)) => r,
        Ok(Err(e)) => {
            // Say what is wrong without showing where the server keeps its files.
            let why = match e {
                replay::ReplayError::NotAReplay { reason, .. } => reason,
                replay::ReplayError::Io { source, .. } => source.to_string(),
            };
            let message = format!("replay \"{id}\": {why}");
            return ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, "bad_replay", message)
                .into_response();
        }
        Err(e) => {
            return ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string())
                .into_response()
        }
    };
    let config = app.config.clone();
    ws.on_upgrade(&config, move |socket| play(socket, replay, id, app))
}

/// What a replay viewer may ask.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
enum Incoming {
    Control(Control),
}

#[derive(Debug, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case", deny_unknown_fields)]
enum Control {
    Play {},
    Pause {},
    Speed { speed: f64 },
    Seek { tick: u64 },
}

/// Reads a viewer's message: only objects are messages (serde would also read one from
/// an array).
fn control(text: &str) -> Result<Incoming, String> {
    let value = crate::strict_json::parse(text.as_bytes()).map_err(|e| e.to_string())?;
    if !value.is_object() {
        return Err("a control is a JSON object".into());
    }
    serde_json::from_value(value).map_err(|e| e.to_string())
}

const MIN_SPEED: f64 = 0.25;
const MAX_SPEED: f64 = 8.0;

async fn play(socket: Socket, replay: Replay, id: String, app: Arc<AppState>) {
    let (mut sink, mut stream) = socket.split();
    let tick_hz = replay.scenario.tick_hz;
    let hello = json!({
        "type": "hello",
        "protocol": crate::protocol::PROTOCOL,
        "version": crate::protocol::VERSION,
        "role": "replay",
        "match": replay.header["match"],
        "replay": {
            "id": id,
            "frames": replay.frames.len(),
            "first_tick": replay.frames.first().map(|(t, _)| t),
            "last_tick": replay.frames.last().map(|(t, _)| t),
            "complete": replay.complete(),
        },
        "limits": {"max_message_bytes": app.config.max_message_bytes, "messages_per_second": app.config.bot_messages_per_second},
    });
    let footer = replay.footer.clone().unwrap_or(Value::Null);
    let end = encode(&End {
        kind: "end",
        match_id: replay.match_id(),
        tick: replay.frames.last().map_or(0, |(t, _)| *t),
        reason: footer["reason"].as_str().unwrap_or("incomplete"),
        result: &footer["result"],
    });
    if sink
        .send(Message::Text(hello.to_string().into()))
        .await
        .is_err()
    {
        return;
    }
    // A replay without frames has only its end to show.
    if replay.frames.is_empty() && sink.send(Message::Text(end.clone().into())).await.is_err() {
        return;
    }
    let mut stopping = app.shutdown.clone();
    let mut budget = budget(&app);
    let (mut next, mut playing, mut speed) = (0usize, true, 1.0f64);
    let mut due = Instant::now();
    loop {
        let waiting = playing && next < replay.frames.len();
        tokio::select! {
            _ = tokio::time::sleep_until(due), if waiting => {
                let (tick, line) = &replay.frames[next];
                if sink.send(Message::Text(Utf8Bytes::from(line.clone()))).await.is_err() {
                    break;
                }
                next += 1;
                match replay.frames.get(next) {
                    Some((following, _)) => {
                        let gap = following.saturating_sub(*tick) as f64 / tick_hz / speed;
                        due += Duration::from_secs_f64(gap);
                        // A viewer that fell far behind does not get a burst to catch up.
                        due = due.max(Instant::now() - Duration::from_millis(200));
                    }
                    None => {
                        playing = false;
                        if sink.send(Message::Text(end.clone().into())).await.is_err() {
                            break;
                        }
                    }
                }
            }
            _ = stopping.changed() => {
                shut(&mut sink, &mut stream, GOING_AWAY, "server shutting down").await;
                break;
            }
            incoming = stream.next() => {
                let read = classify(incoming);
                if let Some((code, reason)) = refusal(&read, &app.metrics) {
                    shut(&mut sink, &mut stream, code, reason).await;
                    break;
                }
                let text = match read {
                    Read::Text(t) => t,
                    Read::Closed => break,
                    _ => continue,
                };
                match budget.charge() {
                    Verdict::Take => {}
                    Verdict::Refuse { warn } => {
                        let error = encode(&ErrorMessage::new("rate_limited", "too many messages; slow down or be disconnected"));
                        if warn && sink.send(Message::Text(error.into())).await.is_err() {
                            break;
                        }
                        continue;
                    }
                    Verdict::Flooding => {
                        app.metrics.closed_for_rate.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        shut(&mut sink, &mut stream, POLICY, "too many messages").await;
                        break;
                    }
                }
                let reply = match control(&text) {
                    Ok(Incoming::Control(Control::Play {})) => {
                        playing = true;
                        due = Instant::now();
                        None
                    }
                    Ok(Incoming::Control(Control::Pause {})) => {
                        playing = false;
                        None
                    }
                    Ok(Incoming::Control(Control::Speed { speed: s })) if (MIN_SPEED..=MAX_SPEED).contains(&s) => {
                        speed = s;
                        None
                    }
                    Ok(Incoming::Control(Control::Speed { speed: s })) => {
                        Some(format!("speed {s} is outside {MIN_SPEED} to {MAX_SPEED}"))
                    }
                    Ok(Incoming::Control(Control::Seek { tick })) => {
                        // The first frame at or after the tick, sent at once, paused or not.
                        match replay.frames.iter().position(|(t, _)| *t >= tick) {
                            Some(k) => {
                                let line = Utf8Bytes::from(replay.frames[k].1.clone());
                                if sink.send(Message::Text(line)).await.is_err() {
                                    break;
                                }
                                next = k + 1;
                                due = Instant::now() + Duration::from_secs_f64(1.0 / tick_hz / speed);
                                None
                            }
                            None => Some(format!("tick {tick} is after the replay's last frame")),
                        }
                    }
                    Err(e) => Some(e),
                };
                if let Some(message) = reply {
                    let error = encode(&ErrorMessage::new("bad_control", &message));
                    if sink.send(Message::Text(error.into())).await.is_err() {
                        break;
                    }
                }
            }
        }
    }
}
