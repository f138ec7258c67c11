//! What every WebSocket the server holds shares, spectator, bot and replay viewer alike:
//! the close codes, the `hello` limits and message budget a socket starts with, reading
//! (what a read gave, and when it means the client is refused: 1002 for a frame that
//! breaks RFC 6455, 1007 for text that is not UTF-8, 1009 for a message over the size
//! limit, 1008 for flooding), writing under `send_timeout_ms`, and closing so the client
//! gets the code. It lives apart from the sockets so that each of them, and
//! replays, uses one set of rules and none borrows from another socket's module.
//!
//! On shutdown every match ends: its sockets get `end` and close with 1001 (`ending`).

use super::state::AppState;
use super::upgrade::{FrameFlood, Socket};
use fieldhouse_core::budget::MessageBudget;
use fieldhouse_core::protocol::Limits;
use futures_util::stream::{SplitSink, SplitStream};
use futures_util::{SinkExt, StreamExt};
use std::sync::atomic::Ordering::Relaxed;
use std::time::Duration;
use tokio_tungstenite::tungstenite::error::ProtocolError;
use tokio_tungstenite::tungstenite::protocol::frame::coding::CloseCode;
use tokio_tungstenite::tungstenite::protocol::CloseFrame;
use tokio_tungstenite::tungstenite::{self, Message, Utf8Bytes};

/// Close codes (RFC 6455).
pub(super) const GOING_AWAY: u16 = 1001;
pub(super) const PROTOCOL_ERROR: u16 = 1002;
pub(super) const NOT_UTF8: u16 = 1007;
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

/// The message budget every spectator and replay viewer starts with, charged at the
/// socket's age (time since `budget` was called). A bot's is its seat's, in the driver.
pub(super) fn budget(app: &AppState) -> MessageBudget {
    MessageBudget::new(
        app.config.bot_messages_per_second,
        app.config.bot_burst,
        std::time::Duration::ZERO,
    )
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
    /// A frame RFC 6455 forbids: reserved bits set, an unmasked frame, a reserved
    /// opcode, a continuation with nothing to continue, a data frame inside a fragmented
    /// message, a fragmented or oversized control frame, a close with a code a client may
    /// not send or a one-byte body.
    Protocol,
    /// A text message, or a close's reason, that is not UTF-8.
    NotUtf8,
}

/// What the library made of the next frames. The library itself only answers a close
/// whose code a client may not send (under 1000, 1004–1006, 1014–2999, 5000 up): it
/// queues a 1002 close, which [`refusal`] then has sent. Every other protocol error it
/// returns, leaving the socket to its owner, who must say 1002 (RFC 6455 §7.1.7, §7.4.1)
/// rather than drop the connection without a word.
pub(super) fn classify(incoming: Option<Result<Message, tungstenite::Error>>) -> Read {
    match incoming {
        Some(Ok(Message::Close(Some(close)))) if close.code == CloseCode::Protocol => {
            Read::Protocol
        }
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
        // The client went without a close frame: nobody is left to tell.
        Some(Err(tungstenite::Error::Protocol(ProtocolError::ResetWithoutClosingHandshake))) => {
            Read::Closed
        }
        Some(Err(tungstenite::Error::Protocol(_))) => Read::Protocol,
        Some(Err(tungstenite::Error::Utf8(_))) => Read::NotUtf8,
        Some(Err(_)) => Read::Closed,
    }
}

/// How a socket closes because of what its client sent, if it does: 1002 for a
/// protocol error, 1007 for text that is not UTF-8, 1009 for a message over the size
/// limit, 1008 for flooding. Counted in the metrics.
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
        Read::Protocol => {
            metrics.closed_for_protocol.fetch_add(1, Relaxed);
            Some((PROTOCOL_ERROR, "protocol error"))
        }
        Read::NotUtf8 => {
            metrics.closed_for_protocol.fetch_add(1, Relaxed);
            Some((NOT_UTF8, "text that is not UTF-8"))
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
    let _ = tokio::time::timeout(Duration::from_secs(1), send_close(sink, code, reason)).await;
    let _ = tokio::time::timeout(Duration::from_secs(1), async {
        while let Some(Ok(message)) = stream.next().await {
            if matches!(message, Message::Close(_)) {
                break;
            }
        }
    })
    .await;
}

/// Answers a client's close, as RFC 6455 asks: the library queues the answer (the
/// client's own code) when it reads the close, and it goes out on the next flush.
/// Bounded, like every send: a client that closed may have stopped reading too.
pub(super) async fn answer_close<S>(sink: &mut S)
where
    S: futures_util::Sink<Message> + Unpin,
{
    let _ = tokio::time::timeout(Duration::from_secs(1), sink.flush()).await;
}

/// Sends a close frame with `code`. If the client's own close came first, the library
/// has its answer queued (a 1002 for a code a client may not send) and refuses a second
/// close: that answer is what goes out.
pub(super) async fn send_close<S>(sink: &mut S, code: u16, reason: &str)
where
    S: futures_util::Sink<Message> + Unpin,
{
    if sink.send(close(code, reason)).await.is_err() {
        let _ = sink.flush().await;
    }
}
