//! The REST API under `/api/`: list, show, create and delete matches. Errors are JSON,
//! `{"error": {"code": .., "message": ..}}`, with the status that fits.

use super::auth;
pub use super::error::ApiError;
use super::match_task;
use super::slot::Slot;
use super::state::{AppState, MatchEntry, ToMatch};
use super::sweep;
use axum::body::Bytes;
use axum::extract::{FromRequestParts, Path, Query, State};
use axum::http::request::Parts;
use axum::http::{HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;
use fieldhouse_core::sim::Scenario;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::Arc;

/// Checks the admin bearer token: missing is 401, wrong is 403.
/// Proof that a request carries the admin token, read from its headers alone. As an
/// extractor it runs before the body is read, so a request without the token is refused
/// at once and an anonymous slow body never holds one of the API's request slots.
pub struct Admin;

impl FromRequestParts<Arc<AppState>> for Admin {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, app: &Arc<AppState>) -> Result<Self, ApiError> {
        admin(app, &parts.headers).map(|()| Admin)
    }
}

fn admin(app: &AppState, headers: &HeaderMap) -> Result<(), ApiError> {
    let given = headers
        .get("authorization")
        .and_then(|v| v.to_str().ok())
        .and_then(auth::bearer)
        .ok_or_else(|| ApiError::unauthorized("this needs Authorization: Bearer <admin token>"))?;
    if app.admin_token.is(given) {
        Ok(())
    } else {
        Err(ApiError::forbidden(app.admin_token.refusal()))
    }
}

/// A match as the API lists it.
pub fn summary(entry: &MatchEntry) -> Value {
    // The lobby shows the score and who plays each agent; both are in the newest frame
    // (the world's own view: `controller` is there while a bot plays an agent), which is
    // parsed here rather than kept apart on the tick path, where it would cost every
    // match a copy per frame for a page that asks every few seconds.
    let mut frame = serde_json::from_str::<Value>(entry.published.borrow().frame.as_str())
        .unwrap_or(Value::Null);
    let by_bot = |id: &Value| {
        frame["agents"]
            .as_array()
            .into_iter()
            .flatten()
            .any(|a| &a["id"] == id && a["controller"] == "bot")
    };
    let agents: Vec<Value> = entry
        .info
        .agents
        .iter()
        .map(|a| {
            let a = serde_json::to_value(a).expect("agents serialise");
            json!({
                "id": a["id"],
                "team": a["team"],
                "strategy": a["strategy"],
                "controller": if by_bot(&a["id"]) { "bot" } else { "builtin" },
                "bot_slot": entry.tokens.iter().any(|(_, id, _)| Some(id.as_str()) == a["id"].as_str()),
            })
        })
        .collect();
    let score = frame["score"].take();
    json!({
        "id": entry.info.id,
        "name": entry.info.name,
        "sport": entry.info.sport,
        "mode": entry.info.mode,
        "status": if entry.ended.load(Relaxed) { "ended" } else { "running" },
        "tick": entry.tick.load(Relaxed),
        "tick_hz": entry.info.tick_hz,
        "score": score,
        "agents": agents,
        "spectators": entry.spectators.load(Relaxed),
        "motion_source": entry.info.motion_source,
        "replay": *entry.replay.lock().expect("not poisoned"),
        "replay_error": *entry.replay_error.lock().expect("not poisoned"),
    })
}

/// `GET /api/matches`: every match in the table, summarised.
pub async fn list(State(app): State<Arc<AppState>>) -> Json<Value> {
    let matches = app.matches.read().expect("not poisoned");
    Json(json!({"matches": matches.values().map(|m| summary(m)).collect::<Vec<_>>()}))
}

/// `GET /api/matches/{id}`: one match's summary with its match info and scenario.
pub async fn show(
    Path(id): Path<String>,
    State(app): State<Arc<AppState>>,
) -> Result<Json<Value>, ApiError> {
    let entry = app.get(&id).ok_or_else(|| ApiError::not_found(&id))?;
    let mut doc = summary(&entry);
    doc["match"] = serde_json::to_value(&entry.info).expect("match info serialises");
    doc["scenario"] = serde_json::to_value(&entry.scenario).expect("scenarios serialise");
    Ok(Json(doc))
}

/// `POST /api/matches`: starts a match from a scenario body (admin token required).
pub async fn create(
    State(app): State<Arc<AppState>>,
    _: Admin,
    Query(query): Query<HashMap<String, String>>,
    body: Bytes,
) -> Result<Response, ApiError> {
    let record = recorded(&query)?;
    let scenario = Scenario::from_json(&body).map_err(|e| {
        ApiError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "bad_scenario",
            e.to_string(),
        )
    })?;
    let (id, entry) = start(&app, scenario, None, record)?;
    let tokens: serde_json::Map<String, Value> = entry
        .tokens
        .iter()
        .map(|(_, agent, token)| (agent.clone(), json!(token)))
        .collect();
    tracing::info!(%id, sport = entry.info.sport, bots = tokens.len(), "match created");
    Ok((
        StatusCode::CREATED,
        Json(json!({"id": id, "bot_tokens": tokens})),
    )
        .into_response())
}

/// Whether a new match is recorded, as its query says: `record=false` leaves it out of
/// the replay directory (a learner's thousands of episodes need no replays), `true`
/// (the default) records it if the server records at all. Anything else is refused.
fn recorded(query: &HashMap<String, String>) -> Result<bool, ApiError> {
    let bad = ApiError::bad_query;
    if let Some(other) = query.keys().find(|k| *k != "record") {
        return Err(bad(format!(
            "unknown query parameter \"{other}\": a match takes only record=true or record=false"
        )));
    }
    match query.get("record").map(String::as_str) {
        None | Some("true") => Ok(true),
        Some("false") => Ok(false),
        Some(other) => Err(bad(format!("record \"{other}\" is neither true nor false"))),
    }
}

/// Starts a match; `id` picks its id (the demos), else a random one; `record`: whether
/// it is recorded (if the server records matches).
pub fn start(
    app: &Arc<AppState>,
    scenario: Scenario,
    id: Option<String>,
    record: bool,
) -> Result<(String, Arc<MatchEntry>), ApiError> {
    let slot = Slot::reserve(&app.metrics, app.config.max_matches).ok_or_else(|| {
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "too_many_matches",
            format!("the server runs at most {} matches", app.config.max_matches),
        )
    })?;
    let id = id.unwrap_or_else(|| auth::new_token()[..12].to_string());
    let entry = match_task::spawn(app, id.clone(), scenario, slot, record).map_err(|e| {
        ApiError::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "bad_scenario",
            e.to_string(),
        )
    })?;
    app.matches
        .write()
        .expect("not poisoned")
        .insert(id.clone(), entry.clone());
    // Matches that end fast could otherwise pile up between sweeps.
    sweep::sweep(app, tokio::time::Instant::now());
    Ok((id, entry))
}

/// `DELETE /api/matches/{id}`: ends a match (admin token required).
pub async fn delete(
    Path(id): Path<String>,
    State(app): State<Arc<AppState>>,
    _: Admin,
) -> Result<Json<Value>, ApiError> {
    let entry = app
        .matches
        .write()
        .expect("not poisoned")
        .remove(&id)
        .ok_or_else(|| ApiError::not_found(&id))?;
    let _ = entry.control.send(ToMatch::Stop).await;
    tracing::info!(%id, "match deleted");
    Ok(Json(json!({"id": id, "status": "deleted"})))
}

/// A behaviour's cost map in the agent's own frame (the agent at the origin facing +x),
/// with the seconds to reach each cell. Because a map without obstacles is the same at
/// every pose, one download per behaviour lets a client draw any agent's map at any tick,
/// live or in a replay, by placing it at the agent's pose in the frame it shows.
pub async fn behaviour_costmap(
    Path(behaviour): Path<String>,
    State(app): State<Arc<AppState>>,
) -> Result<Json<Value>, ApiError> {
    Ok(Json(map_json(&app, &behaviour)?))
}

/// A basketball agent's cost map as it moves now (the map of its current behaviour,
/// placed at its pose in the newest frame), for drawing on the court: costs in seconds
/// in the agent's own frame, with the pose that maps them onto the court.
pub async fn costmap(
    Path((id, agent)): Path<(String, String)>,
    State(app): State<Arc<AppState>>,
) -> Result<Json<Value>, ApiError> {
    let entry = app.get(&id).ok_or_else(|| ApiError::not_found(&id))?;
    if entry.info.sport != "basketball" {
        return Err(ApiError::new(
            StatusCode::NOT_FOUND,
            "no_costmap",
            format!(
                "match \"{id}\" is {}; cost maps belong to basketball agents",
                entry.info.sport
            ),
        ));
    }
    let frame: Value = serde_json::from_str(entry.published.borrow().frame.as_str())
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?;
    let view = frame["agents"]
        .as_array()
        .and_then(|agents| agents.iter().find(|a| a["id"] == agent.as_str()))
        .ok_or_else(|| {
            ApiError::new(
                StatusCode::NOT_FOUND,
                "not_found",
                format!("no agent \"{agent}\" in match \"{id}\""),
            )
        })?;
    let mut doc = map_json(&app, view["behaviour"].as_str().unwrap_or("run"))?;
    doc["match"] = json!(id);
    doc["agent"] = json!(agent);
    doc["tick"] = frame["tick"].clone();
    doc["pose"] = json!({"position": view["position"], "heading": view["heading"]});
    Ok(Json(doc))
}

/// The JSON both cost-map endpoints share: the map of `behaviour` in seconds.
fn map_json(app: &AppState, behaviour: &str) -> Result<Value, ApiError> {
    let mover = app.caps.by_behaviour(behaviour).ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            "no_costmap",
            format!(
                "no cost map for behaviour \"{behaviour}\" (there are dribble, run and defense)"
            ),
        )
    })?;
    let map = mover.map();
    let seconds: Vec<Vec<Option<f64>>> = map
        .rows()
        .iter()
        .map(|row| {
            row.iter()
                .map(|c| c.map(|f| f64::from(f) / map.fps))
                .collect()
        })
        .collect();
    Ok(json!({
        "behaviour": behaviour,
        "cell_m": map.grid.cell_m,
        "size_m": map.grid.size_m,
        "origin": map.grid.origin().to_array(),
        "horizon_s": mover.horizon_s(),
        "costs_s": seconds,
        "motion_source": app.caps.source.to_string(),
    }))
}

/// `GET /healthz`: the process answers (liveness).
pub async fn healthz() -> &'static str {
    "ok"
}

/// `GET /readyz`: ready to serve, with the matches running and the motion source.
pub async fn readyz(State(app): State<Arc<AppState>>) -> Json<Value> {
    let matches = app.matches.read().expect("not poisoned").len();
    Json(json!({"ready": true, "matches": matches, "motion_source": app.caps.source.to_string()}))
}

/// `GET /metrics`: the counters in Prometheus' text format.
pub async fn metrics(State(app): State<Arc<AppState>>) -> impl IntoResponse {
    (
        [("content-type", "text/plain; version=0.0.4")],
        app.metrics.render(),
    )
}

/// Makes every error response JSON, including those the framework writes itself (a body
/// over the limit, a wrong method, a WebSocket route without an upgrade).
pub async fn json_errors(response: Response) -> Response {
    let status = response.status();
    let is_json = response
        .headers()
        .get("content-type")
        .is_some_and(|v| v.as_bytes().starts_with(b"application/json"));
    if !(status.is_client_error() || status.is_server_error()) || is_json {
        return response;
    }
    let body = axum::body::to_bytes(response.into_body(), 64 * 1024)
        .await
        .unwrap_or_default();
    let text = String::from_utf8_lossy(&body).trim().to_string();
    let code = match status {
        StatusCode::PAYLOAD_TOO_LARGE => "too_large",
        StatusCode::METHOD_NOT_ALLOWED => "method_not_allowed",
        StatusCode::REQUEST_TIMEOUT => "timeout",
        _ if status.is_server_error() => "internal",
        _ => "bad_request",
    };
    let message = if text.is_empty() {
        status.canonical_reason().unwrap_or("error").to_string()
    } else {
        text
    };
    ApiError::new(status, code, message).into_response()
}

/// Any other path: a JSON 404, as every endpoint answers errors.
pub async fn fallback() -> ApiError {
    ApiError::new(
        StatusCode::NOT_FOUND,
        "not_found",
        "no such route; see /api/matches",
    )
}
