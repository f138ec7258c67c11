//! One spectator: connect, then note each message's arrival while the window is open.
//! Nothing is decoded beyond what identifies a message, so the load generator's CPU
//! goes to the sockets.

use futures_util::{SinkExt, StreamExt};
use std::hash::{Hash, Hasher};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{SystemTime, UNIX_EPOCH};
use tokio_tungstenite::tungstenite::Message;

/// Where spectators connect.
#[derive(Debug, Clone)]
pub(crate) enum Target {
    /// A fieldhouse match, `ws://…/ws/matches/ID`, the `index`th of the run.
    Fieldhouse { url: String, index: u64 },
    /// A Colyseus room: seats from `POST {http}/matchmake/joinOrCreate/match`, sockets
    /// at `{ws}/{processId}/{roomId}?sessionId=…`.
    Colyseus { http: String, ws: String },
}

/// A message seen in the window.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Arrival {
    /// The same for every spectator's copy of one message: the match's index and the
    /// frame's tick (fieldhouse), a hash of the patch's bytes (Colyseus, whose patches
    /// are the same bytes for everyone and differ from tick to tick).
    pub key: u64,
    pub at_us: u64,
    /// When the server published it (fieldhouse's `sent_us`).
    pub sent_us: Option<u64>,
}

#[derive(Debug, Default)]
pub(crate) struct Log {
    pub arrivals: Vec<Arrival>,
    pub bytes: u64,
}

/// What a round's spectators share.
#[derive(Debug, Clone)]
pub(crate) struct Shared {
    /// Handshakes allowed in flight.
    pub gate: Arc<tokio::sync::Semaphore>,
    /// Spectators done connecting, whether they made it or not.
    pub settled: Arc<AtomicUsize>,
    pub measuring: Arc<AtomicBool>,
    pub stop: Arc<AtomicBool>,
}

fn now_us() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_micros() as u64)
}

/// Runs one spectator until `stop`; `None` if it never connected.
pub(crate) async fn spectate(target: Target, round: Shared) -> Option<Log> {
    let connected = {
        let _permit = round.gate.acquire().await.ok()?;
        let socket = connect(&target).await;
        round.settled.fetch_add(1, Ordering::SeqCst);
        socket
    };
    let mut socket = match connected {
        Ok(s) => s,
        Err(e) => {
            tracing::warn!(error = %e, "a spectator could not connect");
            return None;
        }
    };
    let mut log = Log::default();
    while !round.stop.load(Ordering::Relaxed) {
        let next = tokio::time::timeout(std::time::Duration::from_millis(200), socket.next()).await;
        let message = match next {
            Err(_) => continue,
            Ok(Some(Ok(m))) => m,
            Ok(_) => break,
        };
        let at_us = now_us();
        let seen = match (&target, &message) {
            (Target::Fieldhouse { index, .. }, Message::Text(text)) => {
                fieldhouse_frame(text.as_str())
                    .map(|(tick, sent)| (index << MATCH_SHIFT | tick, sent))
            }
            (Target::Colyseus { .. }, Message::Binary(bytes)) => {
                colyseus_patch(&mut socket, bytes).await
            }
            _ => None,
        };
        if let (Some((key, sent_us)), true) = (seen, round.measuring.load(Ordering::Relaxed)) {
            log.bytes += message.len() as u64;
            log.arrivals.push(Arrival {
                key,
                at_us,
                sent_us,
            });
        }
    }
    let _ = socket.close(None).await;
    Some(log)
}

pub(super) type Socket =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

async fn connect(target: &Target) -> anyhow::Result<Socket> {
    let url = match target {
        Target::Fieldhouse { url, .. } => url.clone(),
        Target::Colyseus { http, ws } => {
            let http = format!("{http}/matchmake/joinOrCreate/match");
            let seat: serde_json::Value = tokio::task::spawn_blocking(move || {
                ureq::post(&http)
                    .set("content-type", "application/json")
                    .send_string("{}")?
                    .into_json::<serde_json::Value>()
                    .map_err(anyhow::Error::from)
            })
            .await??;
            let field = |name: &str| seat[name].as_str().unwrap_or_default().to_owned();
            format!(
                "{ws}/{}/{}?sessionId={}",
                field("processId"),
                field("roomId"),
                field("sessionId")
            )
        }
    };
    let (socket, _) = tokio_tungstenite::connect_async(url).await?;
    Ok(socket)
}

/// The whole number right after the first `label` in `text` (`"tick":` → 42), read
/// without decoding the message.
pub(super) fn number_after(text: &str, label: &str) -> Option<u64> {
    let at = text.find(label)? + label.len();
    let digits = text[at..].bytes().take_while(u8::is_ascii_digit).count();
    text[at..at + digits].parse().ok()
}

/// A fieldhouse frame's tick and publish time: `{"type":"frame","sent_us":N,…"tick":T`.
fn fieldhouse_frame(text: &str) -> Option<(u64, Option<u64>)> {
    if !text.starts_with(r#"{"type":"frame""#) {
        return None;
    }
    Some((
        number_after(text, r#""tick":"#)?,
        number_after(text, r#""sent_us":"#),
    ))
}

/// A message's key is its match's index shifted this far, then the message within the
/// match (a fieldhouse frame's tick; a hash of a Colyseus patch, whose one room is 0).
pub(crate) const MATCH_SHIFT: u32 = 40;

/// Colyseus protocol codes (`@colyseus/shared-types` Protocol): the low five bits of the
/// first byte; the high bits are modifiers.
const JOIN_ROOM: u8 = 10;
const ROOM_STATE_PATCH: u8 = 15;

/// A state patch's key; a JOIN_ROOM is acknowledged (the server sends the state only
/// after the client echoes it).
async fn colyseus_patch(socket: &mut Socket, bytes: &[u8]) -> Option<(u64, Option<u64>)> {
    match bytes.first()? & 31 {
        JOIN_ROOM => {
            let _ = socket.send(Message::Binary(vec![JOIN_ROOM].into())).await;
            None
        }
        ROOM_STATE_PATCH => {
            let mut hasher = std::collections::hash_map::DefaultHasher::new();
            bytes.hash(&mut hasher);
            // The peer's one room is match 0.
            Some((hasher.finish() & ((1 << MATCH_SHIFT) - 1), None))
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::fieldhouse_frame;

    #[test]
    fn a_stamped_frame_gives_its_tick_and_send_time() {
        let frame =
            r#"{"type":"frame","sent_us":1795320000123456,"match":"m","tick":42,"time_s":0.7}"#;
        assert_eq!(
            fieldhouse_frame(frame),
            Some((42, Some(1_795_320_000_123_456)))
        );
        let plain = r#"{"type":"frame","match":"m","tick":42,"time_s":0.7}"#;
        assert_eq!(fieldhouse_frame(plain), Some((42, None)));
        assert_eq!(fieldhouse_frame(r#"{"type":"hello"}"#), None);
    }
}
