//! A match's replay, written on a thread of its own. The thread that ticks every match
//! only hands each record over (a channel send); compressing, writing, flushing, syncing
//! and closing happen on the recording's writer thread, so a slow or full disk, or the
//! sync of a file of gigabytes, never holds up a tick. Ending a match waits for its
//! replay's last sync without blocking a thread: the replay is complete on disk before
//! `end` is published, and meanwhile the other matches tick.
//!
//! Replays are written in format 2 (chunks of 60 lines, each compressed: see
//! [`fieldhouse_core::replay`]). A chunk is written when it is full, or when its first
//! line has waited [`CUT_AFTER`] (the core has no clock: the writer cuts it), so a live
//! viewer sees frames at most that late and a process killed loses at most that much.
//!
//! Bounds: what waits to be written is at most [`MAX_QUEUED_BYTES`] per recording and
//! [`MAX_QUEUED_ALL_BYTES`] for all (past that the disk is not keeping up and the
//! recording stops, as when the disk is full); one recording
//! writes at most `replay_max_match_bytes`, then ends its file with the footer reason
//! `size_limit`; a recording that may never end (a real-time match without bot slots,
//! like the demos) instead rotates into files of `replay_segment_bytes`, each ended with
//! the reason `rotated` and the next one's header naming its segment, first tick and
//! the file before it (see [`fieldhouse_core::replay`]). Both limits count the bytes
//! written (compressed) and the chunk being filled as it is (uncompressed, which it will
//! not exceed compressed): a file ends within them, but for its footer.

use super::replay_dir;
use super::state::AppState;
use fieldhouse_core::replay::{Durable, Encoding, Recorder};
use serde_json::Value;
use std::io;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
use std::sync::mpsc::{self, RecvTimeoutError};
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};
use tokio::sync::oneshot;
use tokio_tungstenite::tungstenite::Utf8Bytes;

/// How long a line may wait in the chunk being filled before the writer cuts the chunk
/// short and writes it (a chunk of 60 lines otherwise fills in 2 s at 30 frames a
/// second, and a match with no frames for a while would hold its last ones): what a
/// live viewer lags by at most, and what a crash loses at most.
pub const CUT_AFTER: Duration = Duration::from_secs(2);

/// The most a recording may have waiting to be written: a second of the fastest match
/// is less, so a queue this long means the disk cannot keep up.
pub const MAX_QUEUED_BYTES: u64 = 64 * 1024 * 1024;

/// The most all recordings together may have waiting: many matches on a stalled disk
/// must not each hold [`MAX_QUEUED_BYTES`].
pub const MAX_QUEUED_ALL_BYTES: u64 = 256 * 1024 * 1024;

/// Bytes handed over and not yet written: this recording's, and all recordings'.
#[derive(Clone, Default)]
struct Queued {
    mine: Arc<AtomicU64>,
    all: Arc<AtomicU64>,
}

impl Queued {
    /// Counts `bytes` in, unless that takes either count past its bound: then says why.
    fn add(&self, bytes: u64) -> Result<(), String> {
        let mine = self.mine.fetch_add(bytes, Relaxed) + bytes;
        let all = self.all.fetch_add(bytes, Relaxed) + bytes;
        if mine <= MAX_QUEUED_BYTES && all <= MAX_QUEUED_ALL_BYTES {
            return Ok(());
        }
        self.sub(bytes);
        Err(format!(
            "the disk is not keeping up: {} MiB of replay waited to be written",
            if mine > MAX_QUEUED_BYTES {
                MAX_QUEUED_BYTES >> 20
            } else {
                MAX_QUEUED_ALL_BYTES >> 20
            }
        ))
    }

    fn sub(&self, bytes: u64) {
        self.mine.fetch_sub(bytes, Relaxed);
        self.all.fetch_sub(bytes, Relaxed);
    }
}

/// How much one recording may write.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Limit {
    /// At most this many bytes, then the recording ends (`size_limit`).
    Total(u64),
    /// Files of about this many bytes, one after another, for ever (`rotated`).
    Segments(u64),
}

/// Where a recording's files come from: the replay directory, or a test's sinks.
pub trait Files: Send + 'static {
    /// A segment's file, as written.
    type Out: Durable + Send;
    /// Creates segment `n`'s file (0 is the first); returns it and its replay id.
    fn create(&mut self, segment: u32) -> io::Result<(Self::Out, String)>;
    /// Segment `n` is written no more (finished, or given up).
    fn closed(&mut self, segment: u32);
}

/// What the tick task hands the writer.
enum Record {
    Frame {
        tick: u64,
        text: Utf8Bytes,
    },
    Log(String),
    Finish {
        tick: u64,
        reason: String,
        result: Value,
        done: oneshot::Sender<Result<(), String>>,
    },
}

impl Record {
    fn bytes(&self) -> u64 {
        match self {
            Record::Frame { text, .. } => text.len() as u64 + 1,
            Record::Log(line) => line.len() as u64 + 1,
            Record::Finish { .. } => 0,
        }
    }
}

/// The tick task's end of a recording. Dropping it without [`Recording::finish`] lets
/// the writer write what it was given, flush, and stop (the file has no footer).
pub struct Recording {
    records: mpsc::Sender<Record>,
    queued: Queued,
    /// Why the writer stopped, once it has.
    stopped: Arc<OnceLock<String>>,
}

impl Recording {
    /// Creates the first file and writes `header` (here, so a directory that cannot be
    /// written is known at once), then starts the writer thread. Returns the recording
    /// and the first file's replay id. `all_queued` counts what every recording has
    /// waiting.
    pub fn start<F: Files>(
        mut files: F,
        header: Value,
        limit: Limit,
        all_queued: Arc<AtomicU64>,
        cut_after: Duration,
    ) -> io::Result<(Recording, String)> {
        let (out, id) = files.create(0)?;
        let recorder = match Recorder::new(out, &header, Encoding::Zstd) {
            Ok(r) => r,
            Err(e) => {
                files.closed(0);
                return Err(e);
            }
        };
        let (records, inbox) = mpsc::channel();
        let queued = Queued {
            mine: Arc::default(),
            all: all_queued,
        };
        let stopped = Arc::<OnceLock<String>>::default();
        let writer = Writer {
            files,
            header,
            limit,
            recorder: Some(recorder),
            segment: 0,
            segment_id: id.clone(),
            cut_after,
            last_tick: 0,
            queued: queued.clone(),
            stopped: stopped.clone(),
        };
        std::thread::Builder::new()
            .name("fieldhouse-replay".into())
            .spawn(move || writer.run(inbox))?;
        let recording = Recording {
            records,
            queued,
            stopped,
        };
        Ok((recording, id))
    }

    /// Appends a frame, the one published at `tick`. An error says why the recording
    /// has stopped; the caller drops it then.
    pub fn frame(&self, tick: u64, text: Utf8Bytes) -> Result<(), String> {
        self.hand_over(Record::Frame { tick, text })
    }

    /// Appends a bot log record.
    pub fn log(&self, record: String) -> Result<(), String> {
        self.hand_over(Record::Log(record))
    }

    fn hand_over(&self, record: Record) -> Result<(), String> {
        if let Some(why) = self.stopped.get() {
            return Err(why.clone());
        }
        let bytes = record.bytes();
        self.queued.add(bytes)?;
        self.records.send(record).map_err(|_| {
            self.queued.sub(bytes);
            self.gone()
        })
    }

    fn gone(&self) -> String {
        self.stopped
            .get()
            .cloned()
            .unwrap_or_else(|| "the replay writer has stopped".into())
    }

    /// Writes the footer, flushes and syncs, on the writer thread; resolves once the
    /// file is complete on disk. Awaiting it blocks no thread.
    pub async fn finish(self, tick: u64, reason: &str, result: &Value) -> Result<(), String> {
        let (done, answer) = oneshot::channel();
        let record = Record::Finish {
            tick,
            reason: reason.to_string(),
            result: result.clone(),
            done,
        };
        if self.records.send(record).is_err() {
            return Err(self.gone());
        }
        answer.await.unwrap_or_else(|_| Err(self.gone()))
    }
}

/// The writer thread's side.
struct Writer<F: Files> {
    files: F,
    header: Value,
    limit: Limit,
    /// None once the recording has stopped.
    recorder: Option<Recorder<F::Out>>,
    segment: u32,
    segment_id: String,
    /// How long a line may wait in a chunk being filled (see [`CUT_AFTER`]).
    cut_after: Duration,
    /// The tick of the last frame written.
    last_tick: u64,
    queued: Queued,
    stopped: Arc<OnceLock<String>>,
}

impl<F: Files> Writer<F> {
    fn run(mut self, inbox: mpsc::Receiver<Record>) {
        // When the chunk being filled is to be cut short, and which chunk it is (the
        // count of chunks written before it).
        let mut due: Option<(Instant, u64)> = None;
        loop {
            let received = match due {
                None => inbox.recv().map_err(|_| RecvTimeoutError::Disconnected),
                Some((when, _)) => {
                    inbox.recv_timeout(when.saturating_duration_since(Instant::now()))
                }
            };
            match received {
                // Everything waiting, then one flush: a frame is on disk (in the page
                // cache, for a process killed) once the writer has caught up and its
                // chunk is written.
                Ok(first) => {
                    let mut next = Some(first);
                    while let Some(record) = next {
                        self.take(record);
                        next = inbox.try_recv().ok();
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            let Some(r) = &mut self.recorder else {
                due = None;
                continue;
            };
            let now = Instant::now();
            due = match due {
                _ if r.buffered() == 0 => None,
                Some((when, chunk)) if chunk == r.chunks() && now < when => due,
                // Its first line has waited `cut_after`: out it goes, short.
                Some((_, chunk)) if chunk == r.chunks() => {
                    if let Err(e) = r.cut() {
                        self.stop(e.to_string());
                        continue;
                    }
                    None
                }
                // A chunk began filling since.
                _ => Some((now + self.cut_after, r.chunks())),
            };
            if let Err(e) = r.flush() {
                self.stop(e.to_string());
            }
        }
        // The match let go without finishing: what was recorded stays, unfinished, the
        // chunk being filled included.
        if let Some(mut r) = self.recorder.take() {
            if let Err(e) = r.cut().and_then(|()| r.flush()) {
                tracing::warn!(error = %e, "cannot write the end of an unfinished replay");
            }
            self.files.closed(self.segment);
        }
    }

    fn take(&mut self, record: Record) {
        self.queued.sub(record.bytes());
        match record {
            Record::Frame { tick, text } => self.frame(tick, &text),
            Record::Log(line) => {
                if let Some(r) = &mut self.recorder {
                    if let Err(e) = r.log(&line) {
                        self.stop(e.to_string());
                    }
                }
            }
            Record::Finish {
                tick,
                reason,
                result,
                done,
            } => {
                let finished = match self.recorder.take() {
                    Some(r) => {
                        let finished = r.finish(tick, &reason, &result);
                        self.files.closed(self.segment);
                        finished.map_err(|e| e.to_string())
                    }
                    None => Err(self.stopped.get().cloned().unwrap_or_default()),
                };
                let _ = done.send(finished);
            }
        }
    }

    fn frame(&mut self, tick: u64, text: &str) {
        let bytes = text.len() as u64 + 1;
        let Some(r) = &mut self.recorder else { return };
        match self.limit {
            Limit::Segments(most) if r.bytes() + bytes > most && r.frames() > 0 => {
                if let Err(e) = self.rotate(tick) {
                    return self.stop(format!("cannot start the next segment: {e}"));
                }
            }
            Limit::Total(most) if r.bytes() + bytes > most => {
                // Said before the footer is written: whoever sees the footer can also
                // see why the recording stopped.
                let why = format!(
                    "the replay reached replay_max_match_bytes ({most} bytes) at tick {}; \
                     recording stopped there",
                    self.last_tick
                );
                let _ = self.stopped.set(why);
                let r = self.recorder.take().expect("checked above");
                if let Err(e) = r.finish(self.last_tick, "size_limit", &Value::Null) {
                    tracing::warn!(error = %e, "cannot end a replay at its size limit");
                }
                self.files.closed(self.segment);
                return;
            }
            _ => {}
        }
        let r = self.recorder.as_mut().expect("present unless stopped");
        if let Err(e) = r.frame(text) {
            return self.stop(e.to_string());
        }
        self.last_tick = tick;
    }

    /// Ends this segment's file and starts the next, whose first frame is at `tick`.
    fn rotate(&mut self, tick: u64) -> io::Result<()> {
        let r = self
            .recorder
            .take()
            .expect("rotating a recording that runs");
        let finished = r.finish(self.last_tick, "rotated", &Value::Null);
        self.files.closed(self.segment);
        finished?;
        self.segment += 1;
        let (out, id) = self.files.create(self.segment)?;
        let mut header = self.header.clone();
        header["segment"] = self.segment.into();
        header["first_tick"] = tick.into();
        header["previous"] = std::mem::replace(&mut self.segment_id, id).into();
        match Recorder::new(out, &header, Encoding::Zstd) {
            Ok(r) => self.recorder = Some(r),
            Err(e) => {
                self.files.closed(self.segment);
                return Err(e);
            }
        }
        Ok(())
    }

    /// Stops recording: what was written stays; the tick task hears why at its next
    /// record.
    fn stop(&mut self, why: String) {
        if self.recorder.take().is_some() {
            self.files.closed(self.segment);
        }
        let _ = self.stopped.set(why);
    }
}

/// A recording's files in the server's replay directory: `STEM.jsonl.zst`, then
/// `STEM-s1.jsonl.zst`, `STEM-s2.jsonl.zst`, ... for later segments. Each is marked as being
/// written while it is, so retention leaves it alone, and retention is told when one is
/// done.
pub struct SegmentFiles {
    /// The server, told when a segment starts and is done (listing, retention).
    pub app: Arc<AppState>,
    /// The replay directory.
    pub dir: PathBuf,
    /// The first segment's file name without its extension; later ones add `-sN`.
    pub stem: String,
    /// The segment being written, named for the match's listing (`MatchEntry::replay`).
    pub current: Arc<std::sync::Mutex<Option<String>>>,
}

impl SegmentFiles {
    fn id(&self, segment: u32) -> String {
        match segment {
            0 => self.stem.clone(),
            n => format!("{}-s{n}", self.stem),
        }
    }
}

impl Files for SegmentFiles {
    type Out = io::BufWriter<std::fs::File>;

    fn create(&mut self, segment: u32) -> io::Result<(Self::Out, String)> {
        let id = self.id(segment);
        let path = replay_dir::path_of(&self.dir, &id);
        let file = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&path)
            .map_err(|e| {
                io::Error::new(e.kind(), format!("cannot create {}: {e}", path.display()))
            })?;
        self.app
            .replays
            .writing
            .lock()
            .expect("not poisoned")
            .insert(path);
        *self.current.lock().expect("not poisoned") = Some(id.clone());
        Ok((io::BufWriter::new(file), id))
    }

    fn closed(&mut self, segment: u32) {
        let path = replay_dir::path_of(&self.dir, &self.id(segment));
        self.app
            .replays
            .writing
            .lock()
            .expect("not poisoned")
            .remove(&path);
        self.app.replay_written.notify_one();
    }
}

#[cfg(test)]
mod tests {
    use super::{Files, Limit, Recording, CUT_AFTER, MAX_QUEUED_ALL_BYTES, MAX_QUEUED_BYTES};
    use fieldhouse_core::replay::{self, Durable};
    use serde_json::{json, Value};
    use std::io::{self, Write};
    use std::sync::{Arc, Mutex};
    use std::time::{Duration, Instant};
    use tokio_tungstenite::tungstenite::Utf8Bytes;

    /// A disk as slow as the test wants: every write after the header's, and the sync,
    /// take `delay` (the header is written by `start`, which the API calls, not the tick
    /// thread).
    #[derive(Clone)]
    struct Slow {
        delay: Duration,
        bytes: Arc<Mutex<Vec<u8>>>,
    }

    impl Write for Slow {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            if !self.bytes.lock().unwrap().is_empty() {
                std::thread::sleep(self.delay);
            }
            self.bytes.lock().unwrap().extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Ok(())
        }
    }

    impl Durable for Slow {
        fn sync(&mut self) -> io::Result<()> {
            std::thread::sleep(self.delay * 20);
            Ok(())
        }
    }

    /// A segment's bytes, and whether it is still being written.
    type Segment = (Arc<Mutex<Vec<u8>>>, bool);

    /// Segments in memory; remembers which are still open.
    #[derive(Clone)]
    struct Memory {
        delay: Duration,
        segments: Arc<Mutex<Vec<Segment>>>,
    }

    impl Memory {
        fn new(delay: Duration) -> Memory {
            Memory {
                delay,
                segments: Arc::default(),
            }
        }

        /// Each segment's lines, as JSON.
        fn lines(&self) -> Vec<Vec<Value>> {
            let segments = self.segments.lock().unwrap();
            segments
                .iter()
                .map(|(bytes, _)| {
                    let (text, _) = replay::decode(&bytes.lock().unwrap()).unwrap();
                    String::from_utf8(text)
                        .unwrap()
                        .lines()
                        .map(|l| serde_json::from_str(l).unwrap())
                        .collect()
                })
                .collect()
        }

        /// Each segment's size.
        fn sizes(&self) -> Vec<usize> {
            let segments = self.segments.lock().unwrap();
            segments
                .iter()
                .map(|(b, _)| b.lock().unwrap().len())
                .collect()
        }

        fn open(&self) -> usize {
            self.segments.lock().unwrap().iter().filter(|s| s.1).count()
        }
    }

    impl Files for Memory {
        type Out = Slow;
        fn create(&mut self, segment: u32) -> io::Result<(Slow, String)> {
            let bytes = Arc::<Mutex<Vec<u8>>>::default();
            self.segments.lock().unwrap().push((bytes.clone(), true));
            let out = Slow {
                delay: self.delay,
                bytes,
            };
            Ok((out, format!("m-{segment}")))
        }
        fn closed(&mut self, segment: u32) {
            self.segments.lock().unwrap()[segment as usize].1 = false;
        }
    }

    fn frame(tick: u64) -> Utf8Bytes {
        Utf8Bytes::from(json!({"type": "frame", "tick": tick, "pad": "x".repeat(80)}).to_string())
    }

    fn header() -> Value {
        json!({"record": "header", "format": 1})
    }

    #[tokio::test]
    async fn a_slow_disk_never_holds_up_the_caller_and_finishing_waits_without_blocking() {
        // 20 ms a write (of a chunk, 60 frames), 400 ms the sync: 200 frames take the
        // writer about half a second.
        let files = Memory::new(Duration::from_millis(20));
        let (recording, id) = Recording::start(
            files.clone(),
            header(),
            Limit::Total(1 << 30),
            Arc::default(),
            CUT_AFTER,
        )
        .unwrap();
        assert_eq!(id, "m-0");
        let started = Instant::now();
        for tick in 0..200 {
            recording.frame(tick, frame(tick)).unwrap();
        }
        let handing_over = started.elapsed();
        assert!(
            handing_over < Duration::from_millis(50),
            "handing 200 frames to a slow disk took {handing_over:?}"
        );
        // While the writer syncs, this thread goes on: a tick keeps its period.
        let ticker = tokio::spawn(async {
            let mut late = Duration::ZERO;
            for _ in 0..20 {
                let t = Instant::now();
                tokio::time::sleep(Duration::from_millis(5)).await;
                late = late.max(t.elapsed());
            }
            late
        });
        recording
            .finish(199, "finished", &json!({"outs": 1}))
            .await
            .unwrap();
        assert!(ticker.await.unwrap() < Duration::from_millis(50));
        let lines = &files.lines()[0];
        assert_eq!(lines.len(), 202, "header, 200 frames, footer");
        assert_eq!(lines[201]["record"], "footer");
        assert_eq!(lines[201]["frames"], 200);
        assert_eq!(files.open(), 0);
    }

    #[tokio::test]
    async fn a_never_ending_recording_rotates_into_segments_that_name_their_start() {
        let files = Memory::new(Duration::ZERO);
        let (recording, _) = Recording::start(
            files.clone(),
            header(),
            Limit::Segments(1000),
            Arc::default(),
            CUT_AFTER,
        )
        .unwrap();
        for tick in 0..40 {
            recording.frame(tick, frame(tick)).unwrap();
        }
        recording
            .finish(39, "shutdown", &Value::Null)
            .await
            .unwrap();
        let segments = files.lines();
        assert!(segments.len() >= 4, "{} segments", segments.len());
        let mut next_tick = 0;
        for (n, lines) in segments.iter().enumerate() {
            let (first, footer) = (&lines[0], lines.last().unwrap());
            assert_eq!(first["segment"].as_u64().unwrap_or(0), n as u64);
            assert_eq!(first["first_tick"].as_u64().unwrap_or(0), next_tick);
            if n > 0 {
                assert_eq!(first["previous"], format!("m-{}", n - 1));
            }
            // On disk, within the limit but for the footer's chunk and the trailer.
            let bytes = files.sizes()[n];
            assert!(bytes <= 1000 + 200, "segment {n}: {bytes} bytes");
            let last = n == segments.len() - 1;
            assert_eq!(footer["reason"], if last { "shutdown" } else { "rotated" });
            next_tick = footer["tick"].as_u64().unwrap() + 1;
        }
        assert_eq!(next_tick, 40, "every frame is in one segment");
        assert_eq!(files.open(), 0);
    }

    /// Waits (5 s at most) until the first segment reads as `lines` lines.
    fn until_lines(files: &Memory, lines: usize) {
        let started = Instant::now();
        while files.lines()[0].len() != lines {
            assert!(
                started.elapsed() < Duration::from_secs(5),
                "{} lines, not {lines}",
                files.lines()[0].len()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    #[tokio::test]
    async fn a_chunk_is_written_when_full_when_a_line_waited_long_enough_or_when_let_go() {
        // Lines wait at most 100 ms: three frames are written without 57 more.
        let files = Memory::new(Duration::ZERO);
        let short = Duration::from_millis(100);
        let (recording, _) = Recording::start(
            files.clone(),
            header(),
            Limit::Total(1 << 30),
            Arc::default(),
            short,
        )
        .unwrap();
        for tick in 0..3 {
            recording.frame(tick, frame(tick)).unwrap();
        }
        until_lines(&files, 1 + 3);
        drop(recording);
        // Lines wait an hour: a full chunk is written at once, and the rest when the
        // match lets go of its recording without finishing it.
        let files = Memory::new(Duration::ZERO);
        let (recording, _) = Recording::start(
            files.clone(),
            header(),
            Limit::Total(1 << 30),
            Arc::default(),
            Duration::from_secs(3600),
        )
        .unwrap();
        for tick in 0..70 {
            recording.frame(tick, frame(tick)).unwrap();
        }
        until_lines(&files, 1 + 60);
        drop(recording);
        until_lines(&files, 1 + 70);
        let lines = files.lines().remove(0);
        assert_eq!(lines.last().unwrap()["tick"], 69, "no footer: unfinished");
        assert_eq!(files.open(), 0);
    }

    #[tokio::test]
    async fn a_recording_stops_at_its_size_limit_with_a_footer_that_says_so() {
        let files = Memory::new(Duration::ZERO);
        let (recording, _) = Recording::start(
            files.clone(),
            header(),
            Limit::Total(1000),
            Arc::default(),
            CUT_AFTER,
        )
        .unwrap();
        let mut refused = None;
        for tick in 0..100 {
            if let Err(why) = recording.frame(tick, frame(tick)) {
                refused = Some(why);
                break;
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        let why = refused.expect("the limit stops the recording");
        assert!(why.contains("replay_max_match_bytes"), "{why}");
        let lines = &files.lines()[0];
        let footer = lines.last().unwrap();
        assert_eq!(footer["reason"], "size_limit");
        assert_eq!(footer["frames"].as_u64().unwrap() as usize, lines.len() - 2);
        assert!(recording
            .finish(99, "finished", &Value::Null)
            .await
            .is_err());
    }

    #[tokio::test]
    async fn a_disk_that_cannot_keep_up_stops_the_recording_at_the_queue_bound() {
        // A write takes a second: nothing is written while the queue fills.
        let files = Memory::new(Duration::from_secs(1));
        let all = Arc::default();
        let start = || {
            Recording::start(
                files.clone(),
                header(),
                Limit::Total(u64::MAX),
                Arc::clone(&all),
                CUT_AFTER,
            )
            .unwrap()
            .0
        };
        // One shared megabyte, handed over again and again: the queue counts bytes.
        let big = Utf8Bytes::from("x".repeat(1 << 20));
        let fill = |recording: &Recording, most: u64| {
            (0..most).find_map(|tick| recording.frame(tick, big.clone()).err())
        };
        let refused = fill(&start(), (MAX_QUEUED_BYTES >> 20) + 2).expect("bounded");
        assert!(refused.contains("not keeping up: 64 MiB"), "{refused}");
        // Recordings that each stay under their bound are bounded together too.
        let recordings: Vec<Recording> = (0..5).map(|_| start()).collect();
        let refused = recordings
            .iter()
            .find_map(|r| fill(r, (MAX_QUEUED_BYTES >> 20) - 4))
            .expect("bounded together");
        assert!(
            refused.contains(&format!("{} MiB", MAX_QUEUED_ALL_BYTES >> 20)),
            "{refused}"
        );
    }
}
