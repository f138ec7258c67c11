//! The WebSocket handshake, done here rather than by the framework so that the socket
//! underneath is ours: every frame the client sends passes a [`FrameMeter`] before the
//! WebSocket library sees it. The library answers pings and joins continuation frames
//! without telling its caller, so a flood of them (an endless message made of empty
//! continuation frames, hundreds of thousands of pings a second) would cost a core and
//! never reach a rate limit that counts messages.

use super::api::ApiError;
use super::config::ServerConfig;
use axum::extract::FromRequestParts;
use axum::http::request::Parts;
use axum::http::{header, HeaderValue, Method, StatusCode};
use axum::response::{IntoResponse, Response};
use fieldhouse_core::budget::Bucket;
use hyper::upgrade::OnUpgrade;
use hyper_util::rt::TokioIo;
use std::future::Future;
use std::io;
use std::pin::Pin;
use std::task::{Context, Poll};
use std::time::Duration;
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio_tungstenite::tungstenite::handshake::derive_accept_key;
use tokio_tungstenite::tungstenite::protocol::{Role, WebSocketConfig};
use tokio_tungstenite::WebSocketStream;

/// A server-side WebSocket over a metered connection.
pub type Socket = WebSocketStream<FrameMeter<TokioIo<hyper::upgrade::Upgraded>>>;

/// A spectator's connection once upgraded, for a socket that does its own writing (see
/// [`super::fanout`]): its TCP stream, what the HTTP server had read past the request,
/// its place among the connections, and the WebSocket settings its reader uses.
pub struct RawSocket {
    /// The connection, upgraded.
    pub stream: tokio::net::TcpStream,
    /// Bytes the HTTP server had read past the request: the first of the WebSocket's.
    pub read_first: Vec<u8>,
    /// Its place among the connections, held while it is open.
    pub place: std::sync::Arc<super::listener::Conn>,
    /// The reader's WebSocket limits (message and frame sizes).
    pub settings: WebSocketConfig,
}

/// Sockets buffer little: frames are small and a slow reader should skip, not queue.
const SOCKET_BUFFER_BYTES: usize = 8 * 1024;

/// Frames a client may send a second that are not whole data messages (pings, pongs,
/// closes, fragments), and at once. Browsers and bot libraries send a ping now and
/// then and fragment nothing this small; the data messages themselves are counted by
/// each socket's message budget.
pub const CONTROL_FRAMES_PER_SECOND: f64 = 20.0;
/// How many such frames may come at once before the rate applies.
pub const CONTROL_FRAME_BURST: f64 = 100.0;

/// A request to open a WebSocket, checked: `GET`, `Upgrade: websocket`, version 13.
pub struct Upgrade {
    key: HeaderValue,
    on_upgrade: OnUpgrade,
}

impl<S: Send + Sync> FromRequestParts<S> for Upgrade {
    type Rejection = ApiError;

    async fn from_request_parts(parts: &mut Parts, _: &S) -> Result<Upgrade, ApiError> {
        let bad = |message: &str| ApiError::new(StatusCode::BAD_REQUEST, "not_websocket", message);
        let has = |name: header::HeaderName, token: &str| {
            parts.headers.get_all(name).iter().any(|v| {
                v.to_str().is_ok_and(|v| {
                    v.split(',')
                        .any(|part| part.trim().eq_ignore_ascii_case(token))
                })
            })
        };
        if parts.method != Method::GET
            || !has(header::CONNECTION, "upgrade")
            || !has(header::UPGRADE, "websocket")
        {
            return Err(bad(
                "this is a WebSocket endpoint: connect with a WebSocket client",
            ));
        }
        if parts.headers.get(header::SEC_WEBSOCKET_VERSION) != Some(&HeaderValue::from_static("13"))
        {
            return Err(bad("only WebSocket version 13 is spoken here"));
        }
        let key = parts
            .headers
            .get(header::SEC_WEBSOCKET_KEY)
            .cloned()
            .ok_or_else(|| bad("Sec-WebSocket-Key is missing"))?;
        let on_upgrade = parts.extensions.remove::<OnUpgrade>().ok_or_else(|| {
            ApiError::new(
                StatusCode::UPGRADE_REQUIRED,
                "not_websocket",
                "this connection cannot be upgraded",
            )
        })?;
        Ok(Upgrade { key, on_upgrade })
    }
}

impl Upgrade {
    /// Answers 101 and, once the client has switched protocols, runs `serve` with the
    /// socket.
    pub fn on_upgrade<F, Fut>(self, config: &ServerConfig, serve: F) -> Response
    where
        F: FnOnce(Socket) -> Fut + Send + 'static,
        Fut: Future<Output = ()> + Send + 'static,
    {
        self.switch(config, move |upgraded, settings| async move {
            let io = FrameMeter::new(TokioIo::new(upgraded));
            serve(WebSocketStream::from_raw_socket(io, Role::Server, Some(settings)).await).await;
        })
    }

    /// Answers 101 and, once the client has switched protocols, runs `serve` with the
    /// connection's TCP stream itself (a [`RawSocket`]).
    pub fn on_upgrade_raw<F, Fut>(self, config: &ServerConfig, serve: F) -> Response
    where
        F: FnOnce(RawSocket) -> Fut + Send + 'static,
        Fut: Future<Output = ()> + Send + 'static,
    {
        self.switch(config, move |upgraded, settings| async move {
            // Every connection comes through the accept loop, which serves it as this.
            let parts = match upgraded.downcast::<TokioIo<super::listener::Counted>>() {
                Ok(parts) => parts,
                Err(_) => {
                    tracing::error!("an upgraded connection is not the accept loop's; closing it");
                    return;
                }
            };
            let (stream, place) = parts.io.into_inner().into_parts();
            serve(RawSocket {
                stream,
                read_first: parts.read_buf.to_vec(),
                place,
                settings,
            })
            .await;
        })
    }

    /// Answers 101 and, once the client has switched protocols (hyper has written the
    /// answer and hands the connection over), runs `then` with it and the settings of
    /// the WebSocket to make of it.
    fn switch<F, Fut>(self, config: &ServerConfig, then: F) -> Response
    where
        F: FnOnce(hyper::upgrade::Upgraded, WebSocketConfig) -> Fut + Send + 'static,
        Fut: Future<Output = ()> + Send + 'static,
    {
        let settings = socket_settings(config);
        let accept = derive_accept_key(self.key.as_bytes());
        let on_upgrade = self.on_upgrade;
        tokio::spawn(async move {
            if let Ok(upgraded) = on_upgrade.await {
                then(upgraded, settings).await;
            }
        });
        switching(accept)
    }
}

/// The settings of every WebSocket the server holds.
fn socket_settings(config: &ServerConfig) -> WebSocketConfig {
    WebSocketConfig::default()
        .max_message_size(Some(config.max_message_bytes))
        .max_frame_size(Some(config.max_message_bytes))
        .read_buffer_size(SOCKET_BUFFER_BYTES)
        .write_buffer_size(SOCKET_BUFFER_BYTES)
}

/// The 101 answer.
fn switching(accept: String) -> Response {
    (
        StatusCode::SWITCHING_PROTOCOLS,
        [
            (header::CONNECTION, "upgrade".to_string()),
            (header::UPGRADE, "websocket".to_string()),
            (header::SEC_WEBSOCKET_ACCEPT, accept),
        ],
    )
        .into_response()
}

/// Why a metered read failed: the client sent more frames than its budget.
#[derive(Debug)]
pub struct FrameFlood;

impl std::fmt::Display for FrameFlood {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("too many control or fragment frames")
    }
}

impl std::error::Error for FrameFlood {}

/// Reads a client's WebSocket frame headers as the bytes go by (RFC 6455 §5.2) and
/// charges every frame that is not a whole data message to a budget; over budget, the
/// read fails with [`FrameFlood`], and the socket's owner closes it with 1008.
pub struct FrameMeter<S> {
    inner: S,
    parser: FrameParser,
    budget: Bucket,
    /// When the budget started: it is charged at the socket's age.
    opened: tokio::time::Instant,
}

impl<S> FrameMeter<S> {
    /// `inner`, metered from a full budget.
    pub fn new(inner: S) -> FrameMeter<S> {
        FrameMeter {
            inner,
            parser: FrameParser::default(),
            budget: Bucket::new(
                CONTROL_FRAMES_PER_SECOND,
                CONTROL_FRAME_BURST,
                Duration::ZERO,
            ),
            opened: tokio::time::Instant::now(),
        }
    }
}

impl<S: AsyncRead + Unpin> AsyncRead for FrameMeter<S> {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        let before = buf.filled().len();
        let polled = Pin::new(&mut self.inner).poll_read(cx, buf);
        if let Poll::Ready(Ok(())) = polled {
            let this = &mut *self;
            let now = this.opened.elapsed();
            let metered = this
                .parser
                .feed(&buf.filled()[before..])
                .all(|_| this.budget.take(now));
            if !metered {
                return Poll::Ready(Err(io::Error::other(FrameFlood)));
            }
        }
        polled
    }
}

impl<S: AsyncWrite + Unpin> AsyncWrite for FrameMeter<S> {
    fn poll_write(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        Pin::new(&mut self.inner).poll_write(cx, buf)
    }
    fn poll_flush(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_flush(cx)
    }
    fn poll_shutdown(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        Pin::new(&mut self.inner).poll_shutdown(cx)
    }
}

/// Where in the frame stream the bytes read so far end.
#[derive(Debug, Default)]
struct FrameParser {
    /// The header being read (at most 14 bytes: 2, an extended length of 8, a mask of 4).
    header: [u8; 14],
    have: usize,
    /// Payload bytes of the current frame still to come.
    payload_left: u64,
}

impl FrameParser {
    /// Feeds bytes read; yields once for each frame header completed in them that the
    /// meter charges (every frame but an unfragmented text or binary message).
    fn feed<'a>(&'a mut self, mut bytes: &'a [u8]) -> impl Iterator<Item = ()> + 'a {
        std::iter::from_fn(move || loop {
            if bytes.is_empty() {
                return None;
            }
            if self.payload_left > 0 {
                let skip = bytes
                    .len()
                    .min(usize::try_from(self.payload_left).unwrap_or(usize::MAX));
                bytes = &bytes[skip..];
                self.payload_left -= skip as u64;
                continue;
            }
            self.header[self.have] = bytes[0];
            self.have += 1;
            bytes = &bytes[1..];
            let Some(length) = self.header_length() else {
                continue;
            };
            if self.have < length {
                continue;
            }
            let (b0, b1) = (self.header[0], self.header[1]);
            self.payload_left = match b1 & 0x7f {
                126 => u64::from(u16::from_be_bytes([self.header[2], self.header[3]])),
                127 => u64::from_be_bytes(self.header[2..10].try_into().expect("8 bytes")),
                n => u64::from(n),
            };
            self.have = 0;
            let fin = b0 & 0x80 != 0;
            let opcode = b0 & 0x0f;
            let whole_data_message = fin && (opcode == 0x1 || opcode == 0x2);
            if !whole_data_message {
                return Some(());
            }
        })
    }

    /// The current header's full length, once its second byte says it.
    fn header_length(&self) -> Option<usize> {
        (self.have >= 2).then(|| {
            let b1 = self.header[1];
            let extended = match b1 & 0x7f {
                126 => 2,
                127 => 8,
                _ => 0,
            };
            let mask = if b1 & 0x80 != 0 { 4 } else { 0 };
            2 + extended + mask
        })
    }
}

#[cfg(test)]
mod tests {
    use super::FrameParser;
    use tokio_tungstenite::tungstenite::protocol::frame::coding::OpCode;
    use tokio_tungstenite::tungstenite::protocol::frame::FrameHeader;

    /// A masked client frame: FIN flag, opcode, payload.
    fn frame(fin: bool, opcode: u8, payload: &[u8]) -> Vec<u8> {
        let mask = [1, 2, 3, 4];
        let header = FrameHeader {
            is_final: fin,
            opcode: OpCode::from(opcode),
            mask: Some(mask),
            ..FrameHeader::default()
        };
        let mut out = Vec::new();
        header.format(payload.len() as u64, &mut out).unwrap();
        out.extend(payload.iter().enumerate().map(|(k, b)| b ^ mask[k % 4]));
        out
    }

    #[test]
    fn whole_data_messages_are_free_and_every_other_frame_is_charged() {
        let mut stream = Vec::new();
        stream.extend(frame(true, 0x1, b"{\"type\":\"command\"}"));
        stream.extend(frame(true, 0x2, &[0; 300]));
        stream.extend(frame(true, 0x1, &vec![b'x'; 70_000]));
        stream.extend(frame(true, 0x9, b"ping")); // charged
        stream.extend(frame(true, 0xa, b"")); // pong, charged
        stream.extend(frame(false, 0x1, b"part")); // a fragment, charged
        for _ in 0..5 {
            stream.extend(frame(false, 0x0, b"")); // empty continuations, charged
        }
        stream.extend(frame(true, 0x8, &[0x03, 0xe8])); // close, charged
        let whole = FrameParser::default().feed(&stream).count();
        assert_eq!(whole, 9);
        // Byte by byte, and in odd chunks, the count is the same: headers and payloads
        // split across reads are followed.
        for chunk in [1, 2, 3, 7, 13, 4096] {
            let mut parser = FrameParser::default();
            let n: usize = stream.chunks(chunk).map(|c| parser.feed(c).count()).sum();
            assert_eq!(n, 9, "chunks of {chunk}");
        }
    }
}
