//! A spectator's socket after the handshake, shared by the fan-out, its spectator task
//! and its reader, each writing whole WebSocket frames at a time so none lands inside
//! another: the fan-out offers frames without waiting, the others write through it.

use crate::listener::Conn;
use std::io;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::task::{ready, Context, Poll};
use tokio::io::{AsyncRead, AsyncWrite, ReadBuf};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::protocol::frame::coding::{Data, OpCode};
use tokio_tungstenite::tungstenite::protocol::frame::FrameHeader;

/// A spectator's connection after the handshake: written by the fan-out, its spectator
/// task and its reader, whole WebSocket frames at a time.
pub struct Wire {
    stream: TcpStream,
    /// Bytes of whole frames the socket has not taken yet; they go before anything else.
    pending: Mutex<Vec<u8>>,
    /// Set when its spectator task ends: the fan-out lets it go at the next frame. (A
    /// flag beside what the fan-out touches anyway: asking the member's channel whether
    /// its receiver is gone was a cache miss per spectator per frame, 3 % of the CPU.)
    left: AtomicBool,
    /// The connection's place among the server's connections, held while it is open.
    _place: Arc<Conn>,
}

/// What offering a frame to a socket did.
pub(super) enum Offered {
    /// Nothing: its spectator has left.
    Left,
    /// Written (perhaps partly: its tail is pending and goes first next time).
    Sent,
    /// Not written: the socket is full. `progress`: it took some pending bytes.
    Skipped { progress: bool },
}

impl Wire {
    /// A spectator's upgraded `stream`, holding its `place` among the connections.
    pub fn new(stream: TcpStream, place: Arc<Conn>) -> Wire {
        Wire {
            stream,
            pending: Mutex::new(Vec::new()),
            left: AtomicBool::new(false),
            _place: place,
        }
    }

    /// Its spectator is done with it: the fan-out writes it no more frames (set under
    /// the lock the fan-out writes under, so a close written after this is the last
    /// thing on the wire) and lets it go at the next frame.
    pub fn leave(&self) {
        let _writing = self.pending.lock().expect("not poisoned");
        self.left.store(true, Relaxed);
    }

    /// Whether its spectator has left (see [`Wire::leave`]).
    pub(super) fn has_left(&self) -> bool {
        self.left.load(Relaxed)
    }

    /// Bytes of frames the socket has not taken yet.
    #[cfg(test)]
    pub(super) fn pending_len(&self) -> usize {
        self.pending.lock().expect("not poisoned").len()
    }

    /// Writes what is pending as far as the socket takes it; whether it took any.
    fn drain(&self, pending: &mut Vec<u8>) -> io::Result<bool> {
        match self.stream.try_write(pending) {
            Ok(n) => {
                pending.drain(..n);
                Ok(n > 0)
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// Writes `bytes` (whole frames) after what is pending: what the socket does not
    /// take now is kept and goes first at the next write.
    pub fn write_whole(&self, bytes: &[u8]) -> io::Result<()> {
        let mut pending = self.pending.lock().expect("not poisoned");
        if !pending.is_empty() {
            self.drain(&mut pending)?;
        }
        if !pending.is_empty() {
            pending.extend_from_slice(bytes);
            return Ok(());
        }
        let written = match self.stream.try_write(bytes) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => 0,
            Err(e) => return Err(e),
        };
        pending.extend_from_slice(&bytes[written..]);
        Ok(())
    }

    /// A text message, framed and written as [`Wire::write_whole`] does.
    pub fn write_text(&self, text: &str) -> io::Result<()> {
        self.write_whole(&text_frame(text.as_bytes()))
    }

    /// Offers a frame: written if the socket takes what is pending and then at least
    /// part of the frame; else skipped.
    pub(super) fn offer(&self, frame: &[u8]) -> io::Result<Offered> {
        let mut pending = self.pending.lock().expect("not poisoned");
        if self.left.load(Relaxed) {
            return Ok(Offered::Left);
        }
        let mut progress = false;
        if !pending.is_empty() {
            progress = self.drain(&mut pending)?;
            if !pending.is_empty() {
                return Ok(Offered::Skipped { progress });
            }
        }
        match self.stream.try_write(frame) {
            Ok(n) => {
                pending.extend_from_slice(&frame[n..]);
                Ok(Offered::Sent)
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => Ok(Offered::Skipped { progress }),
            Err(e) => Err(e),
        }
    }
}

/// An unmasked server text frame (RFC 6455 §5.2) of `payload`: the header as the
/// WebSocket library writes it, then the payload, in one buffer.
pub fn text_frame(payload: &[u8]) -> Vec<u8> {
    let header = FrameHeader {
        opcode: OpCode::Data(Data::Text),
        ..FrameHeader::default()
    };
    let length = payload.len() as u64;
    let mut frame = Vec::with_capacity(header.len(length) + payload.len());
    header
        .format(length, &mut frame)
        .expect("writing to a Vec does not fail");
    frame.extend_from_slice(payload);
    frame
}

/// The socket as its reader sees it (under the frame meter and the WebSocket library):
/// reads come from the socket, after whatever the HTTP server had read past the
/// handshake; writes (pongs, the close handshake) go through the [`Wire`] whole, and
/// flushing waits until nothing is pending. Only the reader waits for the socket to be
/// writable; the fan-out only tries.
pub struct WireIo {
    wire: Arc<Wire>,
    read_first: Vec<u8>,
}

impl WireIo {
    /// The reader's view of `wire`, starting with `read_first` (what the HTTP server had
    /// read past the handshake).
    pub fn new(wire: Arc<Wire>, read_first: Vec<u8>) -> WireIo {
        WireIo { wire, read_first }
    }
}

impl AsyncRead for WireIo {
    fn poll_read(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
        buf: &mut ReadBuf<'_>,
    ) -> Poll<io::Result<()>> {
        if !self.read_first.is_empty() {
            let n = self.read_first.len().min(buf.remaining());
            buf.put_slice(&self.read_first[..n]);
            self.read_first.drain(..n);
            return Poll::Ready(Ok(()));
        }
        loop {
            ready!(self.wire.stream.poll_read_ready(cx))?;
            let unfilled = buf.initialize_unfilled();
            match self.wire.stream.try_read(unfilled) {
                Ok(n) => {
                    buf.advance(n);
                    return Poll::Ready(Ok(()));
                }
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => continue,
                Err(e) => return Poll::Ready(Err(e)),
            }
        }
    }
}

impl AsyncWrite for WireIo {
    fn poll_write(
        self: Pin<&mut Self>,
        _: &mut Context<'_>,
        buf: &[u8],
    ) -> Poll<io::Result<usize>> {
        // The library writes whole frames: all of them are taken, so no frame is ever
        // left half written for another writer to cut into.
        Poll::Ready(self.wire.write_whole(buf).map(|()| buf.len()))
    }

    fn poll_flush(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        loop {
            {
                let mut pending = self.wire.pending.lock().expect("not poisoned");
                if pending.is_empty() {
                    return Poll::Ready(Ok(()));
                }
                self.wire.drain(&mut pending)?;
                if pending.is_empty() {
                    return Poll::Ready(Ok(()));
                }
            }
            ready!(self.wire.stream.poll_write_ready(cx))?;
        }
    }

    fn poll_shutdown(self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<io::Result<()>> {
        self.poll_flush(cx)
    }
}

#[cfg(test)]
mod tests {
    use super::text_frame;

    #[test]
    fn text_frames_have_the_length_in_the_header_the_rfc_gives_it() {
        assert_eq!(text_frame(b"hi"), [0x81, 2, b'h', b'i']);
        let mid = text_frame(&[b'x'; 300]);
        assert_eq!(&mid[..4], &[0x81, 126, 1, 44]);
        assert_eq!(mid.len(), 304);
        let big = text_frame(&vec![b'x'; 70_000]);
        assert_eq!(&big[..2], &[0x81, 127]);
        assert_eq!(u64::from_be_bytes(big[2..10].try_into().unwrap()), 70_000);
    }
}
