//! What every WebSocket the server holds shares, spectator, bot and replay viewer alike:
//! the close codes, the `hello` limits and message budget a socket starts with, reading
//! (what a read gave, and when it means the client is refused: 1009 for a message over
//! the size limit, 1008 for flooding), writing under `send_timeout_ms`, and closing so
//! the client gets the code. It lives apart from the sockets so that each of them, and
//! replays, uses one set of rules and none borrows from another socket's module.
//!
//! On shutdown every match ends: its sockets get `end` and close with 1001 (`ending`).

use super::budget::MessageBudget;
use super::state::AppState;
use super::upgrade::{FrameFlood, Socket};
use fieldhouse_core::protocol::Limits;
use futures_util::stream::{SplitSink, SplitStream};
use futures_util::{SinkExt, StreamExt};
use std::sync::atomic::Ordering::Relaxed;
use std::time::Duration;
use tokio_tungstenite::tungstenite::protocol::CloseFrame;
use tokio_tungstenite::tungstenite::{self, Message, Utf8Bytes};

/// Close codes (RFC 6455).
pub(super) const GOING_AWAY: u16 = 1001;
pub(super) const POLICY: u16 = 1008;
pub(super) const TOO_BIG: u16 = 1009;
pub(super) const NORMAL: u16 = 1000;

/// The limits a socket's `hello` tells its client.
pub(super) fn limits(app: &AppState) -> Limits {
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
pub(super) fn ending(shutdown: &tokio::sync::watch::Receiver<bool>) -> (u16, &'static str) {
    if *shutdown.borrow() {
        (GOING_AWAY, "server shutting down")
    } else {
        (NORMAL, "match ended")
    }
}

/// A close frame with `code` and `reason`.
pub(super) fn close(code: u16, reason: &str) -> Message {
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
