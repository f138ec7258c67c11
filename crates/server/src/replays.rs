//! Replays the server recorded: listed and downloaded over REST, and played over a
//! WebSocket with the live protocol (`hello`, `frame`s, `end`) plus the client's
//! `control` messages: play, pause, speed (0.25× to 8×), seek to a tick.
//!
//! No request costs a file's size in memory: a download is streamed from the opened
//! file with a small buffer; the viewers of a file share one [`Index`] (an entry per
//! block of the file, never per frame) and each reads frames from the file a block at a
//! time; a seek is a binary search over the blocks. Every send to a viewer is bounded
//! by `send_timeout_ms`, like a spectator's.

use super::admission::AdmittedSpectator;
use super::error::ApiError;
use super::range::{self, Wanted};
use super::replay_dir::{self, OnDisk};
use super::socket::{
    answer_close, budget, classify, limits, refusal, shut, Read, Sender, Sent, GOING_AWAY, POLICY,
};
use super::state::AppState;
use super::upgrade::{Socket, Upgrade};
use axum::body::Body;
use axum::extract::{Path, Query, State};
use axum::http::header::{
    ACCEPT_RANGES, CONTENT_DISPOSITION, CONTENT_LENGTH, CONTENT_RANGE, CONTENT_TYPE, RANGE,
};
use axum::http::{HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;
use fieldhouse_core::budget::{Bucket, Verdict};
use fieldhouse_core::protocol::{
    decode_control, encode, Control, End, ErrorMessage, Hello, ReplayInfo, Role, ViewerMessage,
    MAX_LEAD_IN_S,
};
use fieldhouse_core::replay::{self, At, BlockCache, Frame, Index};
use fieldhouse_core::tags;
use futures_util::stream::SplitStream;
use futures_util::StreamExt;
use serde_json::{json, Value};
use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::sync::atomic::Ordering::Relaxed;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncSeekExt};
use tokio::time::Instant;
use tokio_util::io::ReaderStream;

/// The replay directory, or why there is none.
fn dir_of(app: &AppState) -> Result<&std::path::Path, ApiError> {
    app.replay_dir.as_deref().ok_or_else(|| {
        ApiError::new(
            StatusCode::NOT_FOUND,
            "no_replays",
            "this server does not record replays (serve --replay-dir DIR)",
        )
    })
}

/// Opens replay `id` as [`replay_dir::open`] does: a link, a device, a FIFO or a
/// missing file is the same 404, and no answer shows where the server keeps its files.
async fn open(app: &AppState, id: &str) -> Result<replay_dir::Found, ApiError> {
    let dir = dir_of(app)?.to_path_buf();
    if !replay_dir::valid_id(id) {
        return Err(ApiError::new(
            StatusCode::BAD_REQUEST,
            "bad_id",
            format!("\"{id}\" is not a replay id"),
        ));
    }
    let owned = id.to_string();
    let opened = tokio::task::spawn_blocking(move || replay_dir::open(&dir, &owned)).await;
    match opened {
        Ok(Ok(found)) => Ok(found),
        Ok(Err(e)) if e.kind() == std::io::ErrorKind::NotFound => Err(ApiError::new(
            StatusCode::NOT_FOUND,
            "not_found",
            format!("no replay \"{id}\""),
        )),
        Ok(Err(e)) => Err(ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "unreadable",
            format!("replay \"{id}\" cannot be read: {}", e.kind()),
        )),
        Err(e) => Err(ApiError::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            e.to_string(),
        )),
    }
}

/// Replays a listing page holds unless `limit` says otherwise, and the most it may ask.
pub const PAGE: usize = 100;
/// The largest `limit` a listing page may ask for.
pub const MAX_PAGE: usize = 1000;

/// `GET /api/replays?limit=N&after=CURSOR`: a page of the replay directory, newest
/// first (by the time each file was last written; ties by id), with the cursor of the
/// next page in `next` if more remain, and how many replays there are in `total`. The
/// directory is walked without opening its files; the page's files are opened one at a
/// time, and only those the listing has not described as they are now.
pub async fn list(
    Query(query): Query<HashMap<String, String>>,
    State(app): State<Arc<AppState>>,
) -> Result<Json<Value>, ApiError> {
    let page = Page::asked(&query)?;
    let Some(dir) = app.replay_dir.clone() else {
        return Ok(Json(json!({"replays": [], "next": null, "total": 0})));
    };
    let turn = app.replays.listing_turn().await;
    let listed = tokio::task::spawn_blocking(move || {
        let _turn = turn;
        list_page(&app, &dir, &page)
    })
    .await
    .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))?;
    listed.map(Json)
}

/// The page a listing asks for.
#[derive(Debug)]
struct Page {
    limit: usize,
    after: Option<Cursor>,
}

impl Page {
    fn asked(query: &HashMap<String, String>) -> Result<Page, ApiError> {
        let bad = ApiError::bad_query;
        let limit = match query.get("limit") {
            None => PAGE,
            Some(n) => n
                .parse()
                .ok()
                .filter(|n| (1..=MAX_PAGE).contains(n))
                .ok_or_else(|| {
                    bad(format!(
                        "limit \"{n}\" is not a number from 1 to {MAX_PAGE}"
                    ))
                })?,
        };
        let after = match query.get("after") {
            None => None,
            Some(c) => Some(Cursor::parse(c).ok_or_else(|| {
                bad(format!(
                    "after \"{c}\" is not a cursor: pass a listing's `next` as it is"
                ))
            })?),
        };
        Ok(Page { limit, after })
    }
}

/// Where a page ends: the last replay listed, by the listing's order. Written
/// `MODIFIED_NS.ID`: digits (a sign, for a file written before 1970), then an id.
#[derive(Debug)]
struct Cursor {
    modified_ns: i128,
    id: String,
}

impl Cursor {
    fn at(entry: &replay_dir::Entry) -> Cursor {
        Cursor {
            modified_ns: entry.modified_ns(),
            id: entry.id.clone(),
        }
    }

    fn parse(text: &str) -> Option<Cursor> {
        let (modified_ns, id) = text.split_once('.')?;
        Some(Cursor {
            modified_ns: modified_ns.parse().ok()?,
            id: replay_dir::valid_id(id).then(|| id.to_string())?,
        })
    }

    /// Whether `entry` comes after this cursor in the listing's order.
    fn precedes(&self, entry: &replay_dir::Entry) -> bool {
        newest_first(entry.modified_ns(), &entry.id, self.modified_ns, &self.id).is_gt()
    }
}

impl std::fmt::Display for Cursor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.modified_ns, self.id)
    }
}

/// The listing's order: the newest first, by the time a file was last written (a
/// recording being written comes first), and by id among files of the same time.
fn newest_first(a_ns: i128, a_id: &str, b_ns: i128, b_id: &str) -> std::cmp::Ordering {
    b_ns.cmp(&a_ns).then_with(|| a_id.cmp(b_id))
}

/// One page of the listing of `dir`. Blocking.
fn list_page(app: &AppState, dir: &std::path::Path, page: &Page) -> Result<Value, ApiError> {
    // The directory unreadable (out of descriptors, say) is said, not listed as empty.
    let mut entries = replay_dir::scan(dir).map_err(|e| {
        ApiError::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "replays_unavailable",
            format!("the replay directory cannot be read now ({e}); try again"),
        )
    })?;
    app.replays
        .forget_all_but(&entries.iter().map(|e| e.id.as_str()).collect());
    entries.sort_by(|a, b| newest_first(a.modified_ns(), &a.id, b.modified_ns(), &b.id));
    let start = match &page.after {
        Some(cursor) => entries.partition_point(|e| !cursor.precedes(e)),
        None => 0,
    };
    let end = entries.len().min(start + page.limit);
    let mut replays = Vec::with_capacity(end - start);
    for entry in &entries[start..end] {
        let Some(mut listed) = listed(&app.replays, entry) else {
            continue;
        };
        // Whether it is being written changes without the file changing.
        listed["recording"] = app.replays.is_writing(&entry.path).into();
        replays.push(listed);
    }
    let next = (end < entries.len()).then(|| Cursor::at(&entries[end - 1]).to_string());
    Ok(json!({"replays": replays, "next": next, "total": entries.len()}))
}

/// A replay's entry in a page of the listing: remembered, or described from the file
/// (see [`describe`]); if the file cannot be opened now (the process out of
/// descriptors, say), listed all the same from what its directory entry says, with the
/// error, and tried again by the next listing. None: gone since the walk, or no replay
/// now (a link, say).
fn listed(replays: &replay_dir::Replays, entry: &replay_dir::Entry) -> Option<Value> {
    match replays.listing(entry, describe) {
        Ok(listed) => Some(listed),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => None,
        Err(e) => Some(json!({
            "id": entry.id,
            "bytes": entry.meta.len(),
            "error": format!("cannot be opened now: {e}"),
        })),
    }
}

/// A replay's entry in the listing, from its header and footer (read with bounds).
fn describe(found: &replay_dir::Found) -> Value {
    let (id, bytes) = (&found.id, found.meta.len());
    match replay::peek(&OnDisk(&found.file)) {
        Ok((header, footer)) => json!({
            "id": id,
            "bytes": bytes,
            // What a download is named: what the file holds, format 2 or 1.
            "file": format!("{id}.{}", found.encoding().extension()),
            "match": header["match"]["id"],
            "name": header["match"]["name"],
            "sport": header["match"]["sport"],
            "started_unix_ms": header["started_unix_ms"],
            "segment": header["segment"].as_u64().unwrap_or(0),
            "first_tick": replay::first_tick(&header),
            "complete": footer.is_some(),
            "reason": footer.as_ref().map(|f| f["reason"].clone()),
            "result": footer.as_ref().map(|f| f["result"].clone()),
        }),
        Err(e) => json!({"id": id, "bytes": bytes, "error": e}),
    }
}

/// Streams replay `id` from the handle opened, a buffer at a time, so a download costs
/// the same small memory whatever the file's size; `Range: bytes=…` serves one part.
pub async fn download(
    Path(id): Path<String>,
    headers: HeaderMap,
    State(app): State<Arc<AppState>>,
) -> Result<Response, ApiError> {
    let found = open(&app, &id).await?;
    // Served as stored, named and typed for what it holds (format 2 or 1).
    let encoding = found.encoding();
    let (file, len) = (found.file, found.meta.len());
    let asked = headers.get(RANGE).and_then(|v| v.to_str().ok());
    let (status, start, end) = match range::wanted(asked, len) {
        Wanted::Whole => (StatusCode::OK, 0, len),
        Wanted::Part { start, end } => (StatusCode::PARTIAL_CONTENT, start, end + 1),
        Wanted::Unsatisfiable => {
            let mut refused = ApiError::new(
                StatusCode::RANGE_NOT_SATISFIABLE,
                "bad_range",
                format!("replay \"{id}\" has {len} bytes"),
            )
            .into_response();
            let whole = HeaderValue::from_str(&format!("bytes */{len}")).expect("ASCII");
            refused.headers_mut().insert(CONTENT_RANGE, whole);
            return Ok(refused);
        }
    };
    let mut file = tokio::fs::File::from_std(file);
    file.seek(std::io::SeekFrom::Start(start))
        .await
        .map_err(|e| {
            ApiError::new(
                StatusCode::INTERNAL_SERVER_ERROR,
                "unreadable",
                e.to_string(),
            )
        })?;
    let body = Body::from_stream(ReaderStream::with_capacity(
        file.take(end - start),
        DOWNLOAD_BUFFER_BYTES,
    ));
    let mut response = Response::builder()
        .status(status)
        .header(CONTENT_TYPE, encoding.media_type())
        .header(
            CONTENT_DISPOSITION,
            format!("attachment; filename=\"{id}.{}\"", encoding.extension()),
        )
        .header(ACCEPT_RANGES, "bytes")
        .header(CONTENT_LENGTH, end - start);
    if status == StatusCode::PARTIAL_CONTENT {
        let part = format!("bytes {start}-{}/{len}", end - 1);
        response = response.header(CONTENT_RANGE, part);
    }
    response
        .body(body)
        .map_err(|e| ApiError::new(StatusCode::INTERNAL_SERVER_ERROR, "internal", e.to_string()))
}

/// What one download reads from the file at a time.
const DOWNLOAD_BUFFER_BYTES: usize = 64 * 1024;

/// `GET /ws/replays/{id}`: a replay played to a viewer at the recorded pace, with
/// playback controls (pause, speed, seek).
pub async fn watch(
    ws: Upgrade,
    Path(id): Path<String>,
    _: AdmittedSpectator,
    State(app): State<Arc<AppState>>,
) -> Response {
    let (file, meta) = match open(&app, &id).await {
        Ok(found) => (found.file, found.meta),
        Err(e) => return e.into_response(),
    };
    let index = match app.replays.index(&file, &meta).await {
        Ok(index) => index,
        Err(why) => return unreadable(&id, &why),
    };
    let viewed = Viewed {
        index,
        file: Arc::new(file),
        cache: Arc::default(),
    };
    // The first and last ticks, for the hello: a block or two read from each end.
    let ends = viewed
        .blocking(|index, file, cache| index.ends(&OnDisk(file), cache))
        .await;
    let ends = match ends {
        Ok(ends) => ends,
        Err(why) => return unreadable(&id, &why),
    };
    let config = app.config.clone();
    ws.on_upgrade(&config, move |socket| play(socket, viewed, ends, id, app))
}

/// The refusal of a replay that does not read, saying what is wrong without showing
/// where the server keeps its files.
fn unreadable(id: &str, why: &str) -> Response {
    let message = format!("replay \"{id}\": {why}");
    ApiError::new(StatusCode::UNPROCESSABLE_ENTITY, "bad_replay", message).into_response()
}

/// A viewer's replay: the shared index, the viewer's own handle on the file, and the
/// block it decoded last, for the frames after it.
struct Viewed {
    index: Arc<Index>,
    file: Arc<File>,
    cache: Arc<Mutex<BlockCache>>,
}

/// Frames a viewer reads from the file at once, at most (and 64 KiB at most).
const BATCH_FRAMES: usize = 64;
const BATCH_BYTES: usize = 64 * 1024;

impl Viewed {
    /// Runs `read` on the index, the file and the viewer's cache on a blocking thread.
    async fn blocking<T: Send + 'static>(
        &self,
        read: impl FnOnce(&Index, &File, &mut BlockCache) -> std::io::Result<T> + Send + 'static,
    ) -> Result<T, String> {
        let (index, file, cache) = (self.index.clone(), self.file.clone(), self.cache.clone());
        let done = tokio::task::spawn_blocking(move || {
            // One read at a time per viewer: never waited on.
            let mut cache = cache.lock().expect("not poisoned");
            read(&index, &file, &mut cache)
        });
        match done.await {
            Ok(Ok(value)) => Ok(value),
            Ok(Err(e)) => Err(e.to_string()),
            Err(e) => Err(e.to_string()),
        }
    }

    /// If `ahead` is empty, frames from `next` on, a batch of them, into it; `next`
    /// moves past them. Still empty after: the replay's end.
    async fn top_up(&self, next: &mut At, ahead: &mut VecDeque<Frame>) -> Result<(), String> {
        if !ahead.is_empty() {
            return Ok(());
        }
        let from = *next;
        let (frames, after) = self
            .blocking(move |index, file, cache| {
                index.read(&OnDisk(file), cache, from, BATCH_FRAMES, BATCH_BYTES)
            })
            .await?;
        ahead.extend(frames);
        *next = after;
        Ok(())
    }
}

const MIN_SPEED: f64 = 0.25;
const MAX_SPEED: f64 = 8.0;

async fn play(socket: Socket, viewed: Viewed, ends: Ends, id: String, app: Arc<AppState>) {
    let (mut sink, mut stream) = socket.split();
    let mut send = Sender {
        sink: &mut sink,
        timeout: Duration::from_millis(app.config.send_timeout_ms),
        metrics: &app.metrics,
    };
    if let Err(Sent::TimedOut) = view(&mut send, &mut stream, &viewed, ends, &id, &app).await {
        tracing::info!(%id, "dropping a replay viewer that stopped reading");
    }
}

/// The ticks of a replay's first and last frames (None without frames).
type Ends = (Option<u64>, Option<u64>);

/// Plays a replay to one viewer until it leaves, the server stops, or its socket stops
/// taking messages.
async fn view(
    send: &mut Sender<'_>,
    stream: &mut SplitStream<Socket>,
    viewed: &Viewed,
    (first_tick, last_tick): Ends,
    id: &str,
    app: &AppState,
) -> Result<(), Sent> {
    let index = &viewed.index;
    let tick_hz = index.scenario.tick_hz;
    // The match as the file recorded it: a file from an older release may hold
    // shapes this one would not write, so it goes on as it was read.
    let hello = encode(&Hello {
        replay: Some(ReplayInfo {
            complete: index.complete(),
            first_tick,
            frames: index.frames(),
            id,
            last_tick,
            protocol: fieldhouse_core::replay::protocol(&index.header),
        }),
        ..Hello::new(Role::Replay, &index.header["match"], limits(app))
    });
    let footer = index.footer.clone().unwrap_or(Value::Null);
    let end = encode(&End {
        kind: tags::End,
        match_id: index.header["match"]["id"].as_str().unwrap_or_default(),
        tick: last_tick.unwrap_or(0),
        reason: footer["reason"].as_str().unwrap_or("incomplete"),
        result: Some(&footer["result"]),
    });
    send.deliver(hello).await?;
    // A replay without frames has only its end to show.
    let mut ended = first_tick.is_none();
    if ended {
        send.deliver(end.clone()).await?;
    }
    let mut stopping = app.shutdown.clone();
    let mut inbound = budget(app);
    // The budgets' time: this socket's age.
    let opened = Instant::now();
    let mut lead_ins = Bucket::new(LEAD_IN_FRAMES_PER_S, LEAD_IN_FRAMES_BURST, Duration::ZERO);
    let (mut playing, mut speed) = (true, 1.0f64);
    // Frames from `next` on are read ahead into `ahead`: a batch at a time, never the
    // whole file.
    let mut next = At::START;
    let mut ahead: VecDeque<Frame> = VecDeque::new();
    let mut due = Instant::now();
    loop {
        tokio::select! {
            _ = tokio::time::sleep_until(due), if playing && !ended => {
                if let Err(why) = viewed.top_up(&mut next, &mut ahead).await {
                    ended = cannot_read_on(send, id, &why, &end).await?;
                    continue;
                }
                let Some(frame) = ahead.pop_front() else {
                    ended = true;
                    send.deliver(end.clone()).await?;
                    continue;
                };
                send.deliver(frame.text).await?;
                if let Err(why) = viewed.top_up(&mut next, &mut ahead).await {
                    ended = cannot_read_on(send, id, &why, &end).await?;
                    continue;
                }
                match ahead.front() {
                    Some(following) => {
                        due += frame_gap(following.tick.saturating_sub(frame.tick), tick_hz, speed);
                        // A viewer that fell far behind does not get a burst to catch up.
                        due = due.max(Instant::now() - Duration::from_millis(200));
                    }
                    None => {
                        ended = true;
                        send.deliver(end.clone()).await?;
                    }
                }
            }
            _ = stopping.changed() => {
                shut(send.sink, stream, GOING_AWAY, "server shutting down").await;
                return Ok(());
            }
            incoming = stream.next() => {
                let read = classify(incoming);
                if let Some((code, reason)) = refusal(&read, &app.metrics) {
                    shut(send.sink, stream, code, reason).await;
                    return Ok(());
                }
                let text = match read {
                    Read::Text(t) => t,
                    Read::Closed => {
                        answer_close(send.sink).await;
                        return Ok(());
                    }
                    _ => continue,
                };
                match inbound.charge(opened.elapsed()) {
                    Verdict::Take => {}
                    Verdict::Refuse { warn } => {
                        if warn {
                            let error = ErrorMessage::new("rate_limited", "too many messages; slow down or be disconnected");
                            send.deliver(encode(&error)).await?;
                        }
                        continue;
                    }
                    Verdict::Flooding => {
                        app.metrics.closed_for_rate.fetch_add(1, Relaxed);
                        shut(send.sink, stream, POLICY, "too many messages").await;
                        return Ok(());
                    }
                }
                let reply = match decode_control(&text) {
                    Ok(ViewerMessage::Control(Control::Play {})) => {
                        playing = true;
                        due = Instant::now();
                        None
                    }
                    Ok(ViewerMessage::Control(Control::Pause {})) => {
                        playing = false;
                        None
                    }
                    Ok(ViewerMessage::Control(Control::Speed { speed: s })) if (MIN_SPEED..=MAX_SPEED).contains(&s) => {
                        speed = s;
                        None
                    }
                    Ok(ViewerMessage::Control(Control::Speed { speed: s })) => {
                        Some(format!("speed {s} is outside {MIN_SPEED} to {MAX_SPEED}"))
                    }
                    Ok(ViewerMessage::Control(Control::Seek { lead_in_s: Some(s), .. })) if !(0.0..=MAX_LEAD_IN_S).contains(&s) => {
                        Some(format!("lead_in_s {s} is outside 0 to {MAX_LEAD_IN_S}"))
                    }
                    Ok(ViewerMessage::Control(Control::Seek { tick, lead_in_s })) => {
                        // The first frame at or after the tick, sent at once, paused or
                        // not, after the lead-in's: found by binary searches over the
                        // index's blocks, then read a batch at a time. The lead-in is cut
                        // to what the viewer's lead-in budget has: a seek is one
                        // message, its lead-in many frames.
                        let lead_in = (lead_in_s.unwrap_or(0.0) * tick_hz) as u64;
                        let most = lead_ins.available(opened.elapsed());
                        let found = viewed.blocking(move |index, file, cache| {
                            let Some(at) = index.seek(&OnDisk(file), cache, tick)? else {
                                return Ok(None);
                            };
                            let floor = index.seek(&OnDisk(file), cache, tick.saturating_sub(lead_in))?;
                            let floor = floor.unwrap_or(at).min(at);
                            index.back(&OnDisk(file), cache, at, floor, most).map(Some)
                        }).await;
                        match found {
                            Ok(Some((first, lead))) => {
                                lead_ins.take_up_to(lead, opened.elapsed());
                                (next, ended) = (first, false);
                                ahead.clear();
                                for _ in 0..=lead {
                                    viewed.top_up(&mut next, &mut ahead).await.map_err(|_| Sent::Failed)?;
                                    let Some(frame) = ahead.pop_front() else { break };
                                    send.deliver(frame.text).await?;
                                }
                                due = Instant::now() + frame_gap(1, tick_hz, speed);
                                None
                            }
                            Ok(None) => Some(format!("tick {tick} is after the replay's last frame")),
                            Err(why) => Some(format!("the replay cannot be read there: {why}")),
                        }
                    }
                    Err(e) => Some(e),
                };
                if let Some(message) = reply {
                    send.deliver(encode(&ErrorMessage::new("bad_control", &message))).await?;
                }
            }
        }
    }
}

/// Tells a viewer that its replay cannot be read on from here (a damaged block: the
/// file's readable part ends there), then shows the end. The socket stays open, for
/// seeks back. Returns that the replay has ended.
async fn cannot_read_on(
    send: &mut Sender<'_>,
    id: &str,
    why: &str,
    end: &str,
) -> Result<bool, Sent> {
    tracing::warn!(%id, error = %why, "a replay stopped reading back");
    let message = format!("replay \"{id}\" cannot be read on from here: {why}");
    send.deliver(encode(&ErrorMessage::new("bad_replay", &message)))
        .await?;
    send.deliver(end.to_string()).await?;
    Ok(true)
}

/// Lead-in frames a viewer gets a second, sustained, and at once: seeks are cheap
/// messages, and without a bound of its own 400 seeks with 15 s of lead-in each made
/// 1.3 GB out of 30 kB in. A burst covers a whole lead-in of a 60 Hz replay (15 s is 900
/// frames); past it a seek's lead-in is cut short, the seek itself still done.
const LEAD_IN_FRAMES_PER_S: f64 = 100.0;
const LEAD_IN_FRAMES_BURST: f64 = 1000.0;

/// The longest a viewer waits between two frames, whatever the file says.
const MAX_FRAME_GAP: Duration = Duration::from_secs(10);

/// The shortest: a viewer gets at most 1,000 frames a second (a recording has at most a
/// frame a tick; at 60 Hz and 8× that is 480 a second), however many frames a file puts
/// at one tick.
const MIN_FRAME_GAP: Duration = Duration::from_millis(1);

/// How long `ticks` ticks take at `tick_hz` and `speed`, within [`MIN_FRAME_GAP`] and
/// [`MAX_FRAME_GAP`]: a crafted file (frames at tick 0 and u64::MAX, or a rate of
/// almost nothing) asks for a wait no clock can hold, which panicked the viewer's task,
/// and one with millions of frames at a tick asked for them all at once.
fn frame_gap(ticks: u64, tick_hz: f64, speed: f64) -> Duration {
    Duration::try_from_secs_f64(ticks as f64 / tick_hz / speed)
        .map_or(MAX_FRAME_GAP, |gap| gap.clamp(MIN_FRAME_GAP, MAX_FRAME_GAP))
}

#[cfg(test)]
mod tests {
    use super::{listed, newest_first, Cursor, Page, MAX_PAGE, PAGE};
    use crate::replay_dir::{self, Replays};
    use std::collections::HashMap;

    fn page(query: &[(&str, &str)]) -> Result<Page, String> {
        let query: HashMap<String, String> = query
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        Page::asked(&query).map_err(|e| format!("{e:?}"))
    }

    #[test]
    fn a_page_is_asked_for_with_a_limit_and_a_cursor_and_bad_ones_are_refused() {
        assert_eq!(page(&[]).unwrap().limit, PAGE);
        assert_eq!(page(&[("limit", "1")]).unwrap().limit, 1);
        assert_eq!(page(&[("limit", "1000")]).unwrap().limit, MAX_PAGE);
        for limit in ["0", "1001", "-1", "ten", ""] {
            let refused = page(&[("limit", limit)]).unwrap_err();
            assert!(refused.contains("bad_query"), "{limit}: {refused}");
        }
        let after = page(&[("after", "-5.old-one")]).unwrap().after.unwrap();
        assert_eq!((after.modified_ns, after.id.as_str()), (-5, "old-one"));
        for cursor in ["", "5", "x.id", "5.", "5.a/b", "5.a.b", ".id"] {
            let refused = page(&[("after", cursor)]).unwrap_err();
            assert!(refused.contains("bad_query"), "{cursor}: {refused}");
        }
        let cursor = Cursor {
            modified_ns: 1_795_318_528_487_000_123,
            id: "demo-cricket-1795318471-s2".into(),
        };
        let again = Cursor::parse(&cursor.to_string()).unwrap();
        assert_eq!(
            (again.modified_ns, again.id),
            (cursor.modified_ns, cursor.id)
        );
    }

    #[test]
    fn the_newest_come_first_and_ids_break_ties() {
        let mut files = [(1, "b"), (3, "a"), (2, "c"), (3, "b"), (1, "a")];
        files.sort_by(|a, b| newest_first(a.0, a.1, b.0, b.1));
        assert_eq!(files, [(3, "a"), (3, "b"), (2, "c"), (1, "a"), (1, "b")]);
    }

    /// A file that cannot be opened when the listing comes to it (here a socket put in
    /// its place after the walk: opening a socket fails, as opening anything does out of
    /// descriptors) is listed from its directory entry with the error, not left out.
    #[test]
    fn a_replay_that_cannot_be_opened_now_is_listed_with_an_error_not_left_out() {
        let scratch = tempfile::tempdir().unwrap();
        let dir = scratch.path().to_path_buf();
        std::fs::write(dir.join("busy.jsonl"), "not read\n").unwrap();
        std::fs::write(dir.join("gone.jsonl"), "not read\n").unwrap();
        let entries = replay_dir::scan(&dir).unwrap();
        std::fs::remove_file(dir.join("busy.jsonl")).unwrap();
        let _socket = std::os::unix::net::UnixListener::bind(dir.join("busy.jsonl")).unwrap();
        std::fs::remove_file(dir.join("gone.jsonl")).unwrap();
        let replays = Replays::default();
        let busy = listed(&replays, &entries[0]).expect("listed");
        assert_eq!(busy["id"], "busy");
        assert_eq!(busy["bytes"], 9);
        let error = busy["error"].as_str().unwrap();
        assert!(error.starts_with("cannot be opened now: "), "{error}");
        assert!(!error.contains(dir.to_str().unwrap()), "{error}");
        assert_eq!(entries[1].id, "gone");
        assert!(listed(&replays, &entries[1]).is_none());
    }
}
