//! `fieldhouse run`'s replay, written on a thread of its own: the run simulates and
//! encodes frames on its thread and hands them over in batches; hashing, compressing
//! and writing them happen on the writer's, at the same time.
//!
//! Why a thread: compressing is a fifth of a headless run's work. Measured with `perf`
//! on `fieldhouse run` of 6,000 simulated s of baseball (180,001 frames, 88 MB of JSON
//! lines) writing in line, zstd took 20 % of the CPU time at level 3 (and SHA-256 4 %);
//! level 1 compresses these small chunks faster still and a little better (`zstd -b1
//! -B48K` on the same replay: 8.9× at 460 MB/s, against 8.5× at 310–380 MB/s for level
//! 3), so [`fieldhouse::replay::chunks::LEVEL`] is 1, and it would still cost over 10 %
//! of the run in line. On its own thread it costs the run next to nothing on two cores
//! (BENCHMARKS.md, "Headless runs and replay sizes"). zstd's own worker threads would
//! not help: they split one large frame, and chunks are small frames of their own.

use fieldhouse::replay::{Durable, Recorder};
use std::io;
use std::sync::mpsc::{sync_channel, SyncSender};
use std::thread::JoinHandle;

/// Bytes of frames handed over at once (several hundred frames). A batch is one buffer
/// of lines, so a frame costs no allocation of its own, and the writer is woken once
/// per batch: with batches of 64 frames, waking it was 3–4 % of a basketball run.
const BATCH_BYTES: usize = 256 * 1024;

/// Batches that may wait for the writer (about 2 MB of frames): past that, the run
/// waits for the disk rather than holding the whole replay.
const WAITING: usize = 8;

/// A recorder on a thread of its own.
pub(super) struct Background<W: Durable + Send + 'static> {
    /// Frames not yet handed over, each a line ended by `\n`.
    batch: Vec<u8>,
    batches: Option<SyncSender<Vec<u8>>>,
    /// None once joined.
    writer: Option<JoinHandle<io::Result<Recorder<W>>>>,
}

impl<W: Durable + Send + 'static> Background<W> {
    /// Starts the writer thread, which owns `recorder` until [`Background::finish`].
    pub(super) fn start(mut recorder: Recorder<W>) -> io::Result<Background<W>> {
        let (batches, inbox) = sync_channel::<Vec<u8>>(WAITING);
        let writer = std::thread::Builder::new()
            .name("fieldhouse-replay".into())
            .spawn(move || {
                for batch in inbox {
                    for line in batch.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
                        let frame = std::str::from_utf8(line).map_err(io::Error::other)?;
                        recorder.frame(frame)?;
                    }
                }
                Ok(recorder)
            })?;
        Ok(Background {
            batch: Vec::with_capacity(BATCH_BYTES + 64 * 1024),
            batches: Some(batches),
            writer: Some(writer),
        })
    }

    /// Appends the frame `write` appends to its buffer (one line of JSON, which never
    /// holds a raw newline), if it writes one; says whether it did. An error is the
    /// writer's (it stopped at a write that failed).
    pub(super) fn frame(&mut self, write: impl FnOnce(&mut Vec<u8>) -> bool) -> io::Result<bool> {
        if !write(&mut self.batch) {
            return Ok(false);
        }
        self.batch.push(b'\n');
        if self.batch.len() < BATCH_BYTES {
            return Ok(true);
        }
        let capacity = self.batch.capacity();
        let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(capacity));
        let sent = self.batches.as_ref().map(|b| b.send(batch));
        match sent {
            Some(Ok(())) => Ok(true),
            // The writer stopped: its error says why.
            _ => Err(self.stopped()),
        }
    }

    /// Waits for the writer to be done; returns its recorder, or why it stopped.
    fn join(&mut self) -> io::Result<Recorder<W>> {
        self.batches = None;
        match self.writer.take().map(JoinHandle::join) {
            Some(Ok(done)) => done,
            Some(Err(_)) => Err(io::Error::other("the replay's writer panicked")),
            None => Err(io::Error::other("the replay's writer stopped")),
        }
    }

    /// Why the writer stopped (it did: it took no more).
    fn stopped(&mut self) -> io::Error {
        match self.join() {
            Err(e) => e,
            Ok(_) => io::Error::other("the replay's writer stopped"),
        }
    }

    /// Hands over the last frames and waits for the writer to have written them; gives
    /// back the recorder, for its footer ([`Recorder::finish`]).
    pub(super) fn done(mut self) -> io::Result<Recorder<W>> {
        let rest = std::mem::take(&mut self.batch);
        if let Some(batches) = &self.batches {
            // A writer that stopped has its error to give below.
            let _ = batches.send(rest);
        }
        self.join()
    }
}
