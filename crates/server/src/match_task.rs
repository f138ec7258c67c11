//! A match is a task that owns one [`World`] (in a [`Session`]) and ticks it: on the
//! wall clock (`realtime`), as fast as possible (`fast`), or in lock-step with its bots
//! (`lockstep`). Each frame is encoded once, published for the sockets, and handed to
//! the match's replay (written on a thread of its own: see [`super::recording`]) if the
//! server keeps replays.
//!
//! The rules (pacing, lock-step waits, the command window, bot seats, the end) are the
//! [`MatchDriver`]'s, which does no I/O; this task is its shell: it wakes the driver
//! when it asks, forwards what sockets and the API say, and carries out what the
//! driver wants done: publishing and recording frames, messages to bots, metrics.

use super::auth::new_token;
use super::config::ServerConfig;
use super::fanout::Published;
use super::metrics::Metrics;
use super::recording::{self, Limit, Recording, SegmentFiles};
use super::slot::Slot;
use super::state::{AppState, MatchEntry, ToMatch};
use fieldhouse_core::driver::{
    BotEvent, BotLimits, Close, Conn, EndReason, Ending, MatchDriver, Output, Transmit, Wake,
};
use fieldhouse_core::replay;
use fieldhouse_core::session::{self, Session};
use fieldhouse_core::sim::{Mode, Scenario, ScenarioError, World};
use futures_util::FutureExt;
use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use tokio::sync::{mpsc, oneshot, watch};
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::Utf8Bytes;

/// Builds the world a scenario describes and starts its task, which holds `slot` until
/// it ends, recording it if `record` and the server records matches. Returns the match
/// and the bot tokens of its bot-controlled agents.
pub fn spawn(
    app: &Arc<AppState>,
    id: String,
    scenario: Scenario,
    slot: Slot,
    record: bool,
) -> Result<Arc<MatchEntry>, ScenarioError> {
    let world = World::new(&scenario, Some(app.caps.clone()))?;
    let agent_ids = world.agent_ids();
    let info = world.match_info(
        id.clone(),
        &scenario,
        scenario.mode,
        app.caps.source.to_string(),
    );
    let tokens = scenario
        .agents
        .iter()
        .filter(|a| a.bot)
        .map(|a| {
            let k = agent_ids
                .iter()
                .position(|x| *x == a.id)
                .expect("scenario agents are in the world");
            (k, a.id.clone(), new_token())
        })
        .collect::<Vec<_>>();
    let mut session = Session::new(world, id.clone(), scenario.tick_hz, scenario.frame_hz);
    let first = Utf8Bytes::from(session.frame());
    let limits = BotLimits {
        messages_per_second: app.config.bot_messages_per_second,
        burst: app.config.bot_burst,
    };
    let driver = MatchDriver::new(session, &scenario, limits);
    let creation_error = Mutex::new(None);
    let replay = Arc::new(Mutex::new(None));
    let started = app
        .replay_dir
        .as_deref()
        .filter(|_| record)
        .and_then(|dir| {
            let header = replay::header(
                &info,
                &scenario,
                app.caps.source.fingerprint(),
                crate::wall::since_epoch(),
            );
            let files = SegmentFiles {
                app: app.clone(),
                dir: dir.to_path_buf(),
                stem: format!("{id}-{}", unix_seconds()),
                current: replay.clone(),
            };
            let limit = recording_limit(&app.config, &scenario);
            let queued = app.replays.queued.clone();
            let made = Recording::start(files, header, limit, queued, recording::CUT_AFTER)
                .map_err(|e| e.to_string())
                .and_then(|(r, _)| r.frame(0, first.clone()).map(|()| r));
            made.map_err(|e| {
                app.metrics.replay_errors.fetch_add(1, Relaxed);
                tracing::warn!(error = %e, "cannot record this match; it runs unrecorded");
                *creation_error.lock().expect("not poisoned") = Some(e);
            })
            .ok()
        });
    let recorder = started;
    let (publish, published) = watch::channel(Published {
        seq: 0,
        frame: first,
        end: None,
    });
    let (control_tx, control_rx) = mpsc::channel(1024);
    let entry = Arc::new(MatchEntry {
        info,
        mode: scenario.mode,
        scenario,
        published,
        control: control_tx,
        tokens,
        spectators: AtomicU64::new(0),
        tick: AtomicU64::new(0),
        ended: AtomicBool::new(false),
        ended_at: std::sync::OnceLock::new(),
        replay,
        replay_error: creation_error,
        fanout: Default::default(),
    });
    app.metrics.matches_created.fetch_add(1, Relaxed);
    let task = MatchTask {
        _slot: slot,
        driver,
        recorder,
        entry: entry.clone(),
        publish,
        control: control_rx,
        metrics: app.metrics.clone(),
        shutdown: app.shutdown.clone(),
        mailboxes: HashMap::new(),
        seq: 0,
        stamp_frames: app.config.stamp_frames,
    };
    app.ticking.spawn(task.run());
    Ok(entry)
}

/// How much a match's replay may write: real-time matches without bot slots (the demos)
/// may never end, so they rotate into segments; any other match, fast ones above all,
/// stops recording at `replay_max_match_bytes`.
fn recording_limit(config: &ServerConfig, scenario: &Scenario) -> Limit {
    let unattended = scenario.mode == Mode::Realtime && !scenario.agents.iter().any(|a| a.bot);
    if unattended {
        Limit::Segments(config.replay_segment_bytes)
    } else {
        Limit::Total(config.replay_max_match_bytes)
    }
}

fn unix_seconds() -> u64 {
    crate::wall::since_epoch().as_secs()
}

/// Where to reach a bot connection: its messages' queue, and the close that ends it.
/// (Who sits at which agent is the driver's to know.)
struct Mailbox {
    out: mpsc::Sender<Utf8Bytes>,
    close: oneshot::Sender<Close>,
}

struct MatchTask {
    /// The match's place among `max_matches`, given back when the task is dropped.
    _slot: Slot,
    driver: MatchDriver,
    recorder: Option<Recording>,
    entry: Arc<MatchEntry>,
    publish: watch::Sender<Published>,
    control: mpsc::Receiver<ToMatch>,
    metrics: Arc<Metrics>,
    shutdown: watch::Receiver<bool>,
    mailboxes: HashMap<Conn, Mailbox>,
    seq: u64,
    stamp_frames: bool,
}

impl MatchTask {
    /// Plays the match, then ends it. A panic while playing (a bug) ends this match
    /// with reason `error`, told to its spectators and bots and logged, instead of
    /// leaving it listed as running for ever with its place taken.
    async fn run(mut self) {
        let played = AssertUnwindSafe(self.play()).catch_unwind().await;
        let ending = played.unwrap_or_else(|panic| {
            self.metrics.match_panics.fetch_add(1, Relaxed);
            tracing::error!(
                id = %self.entry.info.id,
                tick = self.entry.tick.load(Relaxed),
                panic = panic_message(panic.as_ref()),
                "the match task panicked; ending the match"
            );
            self.stop(EndReason::Error)
        });
        self.end(ending).await;
    }

    /// Plays the match until it ends; returns how it ended. The driver is told the
    /// time as it is since this started.
    async fn play(&mut self) -> Ending {
        let start = Instant::now();
        loop {
            let wake = match self.driver.poll_timeout() {
                Wake::Now => {
                    // Fast: no timer at all (even a zero sleep costs a timer tick):
                    // take whatever the sockets and the API said, then tick.
                    if *self.shutdown.borrow() {
                        return self.stop(EndReason::Shutdown);
                    }
                    if let Some(ending) = self.drain_controls(start) {
                        return ending;
                    }
                    let ticked = Instant::now();
                    self.driver.handle_timeout(ticked - start);
                    if let Some(ending) = self.carry_out(ticked) {
                        return ending;
                    }
                    if self.driver.tick().is_multiple_of(256) {
                        tokio::task::yield_now().await;
                    }
                    continue;
                }
                Wake::At(at) => start + at,
            };
            tokio::select! {
                biased;
                _ = self.shutdown.changed() => return self.stop(EndReason::Shutdown),
                message = self.control.recv() => {
                    if let Some(ending) = self.forward(message, start) {
                        return ending;
                    }
                }
                _ = tokio::time::sleep_until(wake) => {
                    let ticked = Instant::now();
                    self.driver.handle_timeout(ticked - start);
                    if let Some(ending) = self.carry_out(ticked) {
                        return ending;
                    }
                }
            }
        }
    }

    /// Ends the match for `reason`; how it ended.
    fn stop(&mut self, reason: EndReason) -> Ending {
        self.driver.stop(reason);
        self.carry_out(Instant::now())
            .expect("a stopped driver says how the match ended")
    }

    /// Handles every control message waiting; how the match ended, if one ended it.
    fn drain_controls(&mut self, start: Instant) -> Option<Ending> {
        loop {
            let message = match self.control.try_recv() {
                Ok(message) => Some(message),
                Err(mpsc::error::TryRecvError::Disconnected) => None,
                Err(mpsc::error::TryRecvError::Empty) => return None,
            };
            if let Some(ending) = self.forward(message, start) {
                return Some(ending);
            }
        }
    }

    /// Tells the driver what a socket or the API said (`None`: no one is left to say
    /// anything, a stop), and carries out what follows; how the match ended, if it did.
    fn forward(&mut self, message: Option<ToMatch>, start: Instant) -> Option<Ending> {
        let handled = Instant::now();
        let now = handled - start;
        match message {
            None | Some(ToMatch::Stop) => return Some(self.stop(EndReason::Deleted)),
            Some(ToMatch::Join {
                agent,
                conn,
                out,
                close,
            }) => {
                self.mailboxes.insert(conn, Mailbox { out, close });
                self.driver.handle(BotEvent::Join { agent, conn }, now);
            }
            Some(ToMatch::Driver(event)) => {
                let left = match &event {
                    BotEvent::Leave { conn, .. } => Some(*conn),
                    _ => None,
                };
                self.driver.handle(event, now);
                if let Some(conn) = left {
                    self.mailboxes.remove(&conn);
                }
            }
            #[cfg(test)]
            Some(ToMatch::Panic) => panic!("a test asked this match task to panic"),
        }
        self.carry_out(handled)
    }

    /// Does what the driver asked, in order: first what goes to bots, then what is
    /// published, recorded and counted; how the match ended, if it did. A tick's
    /// duration is reported as the time since `since`, when the driver was called.
    fn carry_out(&mut self, since: Instant) -> Option<Ending> {
        while let Some(transmit) = self.driver.poll_transmit() {
            self.transmit(transmit);
        }
        while let Some(output) = self.driver.poll_output() {
            match output {
                Output::Ticked { tick } => {
                    self.metrics.observe_tick(since.elapsed().as_secs_f64());
                    self.entry.tick.store(tick, Relaxed);
                }
                Output::Frame { tick, frame } => self.publish_frame(tick, frame),
                Output::Log(record) => self.record(|r| r.log(record)),
                Output::Overrun => {
                    self.metrics.tick_overruns.fetch_add(1, Relaxed);
                }
                Output::End(ending) => return Some(ending),
            }
        }
        None
    }

    /// Hands a message to a bot connection, if its queue has room: a bot that is not
    /// reading misses perceptions rather than holding a tick. A close always arrives.
    fn transmit(&mut self, transmit: Transmit) {
        let (conn, text) = match transmit {
            Transmit::Perception { conn, text, .. } => (conn, text),
            Transmit::Error { conn, text, .. } => {
                self.metrics.client_errors.fetch_add(1, Relaxed);
                (conn, text)
            }
            Transmit::Close { conn, why } => {
                if why == Close::Flooding {
                    self.metrics.closed_for_rate.fetch_add(1, Relaxed);
                }
                if let Some(mailbox) = self.mailboxes.remove(&conn) {
                    let _ = mailbox.close.send(why);
                }
                return;
            }
        };
        if let Some(mailbox) = self.mailboxes.get(&conn) {
            let _ = mailbox.out.try_send(Utf8Bytes::from(text));
        }
    }

    fn publish_frame(&mut self, tick: u64, frame: String) {
        let bytes = if self.stamp_frames {
            let recorded = Utf8Bytes::from(frame);
            let sent_us = crate::wall::since_epoch().as_micros() as u64;
            let stamped = session::stamped(recorded.as_str(), sent_us);
            self.record(|r| r.frame(tick, recorded));
            Utf8Bytes::from(stamped)
        } else {
            let bytes = Utf8Bytes::from(frame);
            self.record(|r| r.frame(tick, bytes.clone()));
            bytes
        };
        self.seq += 1;
        let seq = self.seq;
        self.publish.send_modify(|p| {
            p.seq = seq;
            p.frame = bytes;
        });
    }

    /// Hands a record to the replay's writer; a recording that stopped (a full or
    /// unwritable disk, one that cannot keep up, the size limit) stops here, never the
    /// match, and why is logged, counted and shown in the API.
    fn record(&mut self, write: impl FnOnce(&Recording) -> Result<(), String>) {
        let Some(r) = &self.recorder else { return };
        if let Err(e) = write(r) {
            self.recording_stopped(e);
            self.recorder = None;
        }
    }

    fn recording_stopped(&self, why: String) {
        self.metrics.replay_errors.fetch_add(1, Relaxed);
        tracing::warn!(id = %self.entry.info.id, error = %why, "replay recording stopped");
        *self.entry.replay_error.lock().expect("not poisoned") = Some(why);
    }

    /// Tells everyone the match ended: its replay is finished first, then the `end` is
    /// published (spectators and bots close after it).
    async fn end(mut self, ending: Ending) {
        let Ending {
            tick,
            reason,
            result,
            message,
        } = ending;
        // The replay is complete on disk before anyone hears the match ended. Its
        // writer thread syncs it; this task waits without holding the thread that
        // ticks the other matches.
        if let Some(r) = self.recorder.take() {
            let result = serde_json::to_value(result).expect("scores serialise");
            if let Err(e) = r.finish(tick, reason.as_str(), &result).await {
                self.recording_stopped(format!("cannot finish the replay: {e}"));
            }
        }
        self.entry.ended.store(true, Relaxed);
        self.entry.ended_at.get_or_init(Instant::now);
        let end = Utf8Bytes::from(message);
        self.publish.send_modify(|p| p.end = Some(end));
        let reason = reason.as_str();
        tracing::info!(id = %self.entry.info.id, reason, tick, "match ended");
    }
}

/// The text a panic was raised with, if it has one.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> &str {
    payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(no message)")
}

#[cfg(test)]
mod tests {
    use super::spawn;
    use crate::slot::Slot;
    use crate::state::{AppState, MatchEntry, ToMatch};
    use crate::ServerConfig;
    use fieldhouse_core::driver::{BotEvent, Close, Conn};
    use fieldhouse_core::protocol::ClientMessage;
    use fieldhouse_core::sim::{Action, Scenario};
    use serde_json::{json, Value};
    use std::sync::atomic::Ordering::Relaxed;
    use std::sync::Arc;
    use std::time::Duration;
    use tokio::sync::{mpsc, oneshot};
    use tokio::time::Instant;
    use tokio_tungstenite::tungstenite::Utf8Bytes;

    /// A server's shared state with no sockets, whose matches tick on this test's
    /// runtime; the stop sender keeps matches from seeing a shutdown.
    fn app() -> (Arc<AppState>, tokio::sync::watch::Sender<bool>) {
        let (stop, shutdown) = tokio::sync::watch::channel(false);
        let app = AppState {
            ticking: tokio::runtime::Handle::current(),
            config: ServerConfig::default(),
            admin_token: crate::auth::AdminToken::chosen("admin".into()),
            caps: fieldhouse_core::fixtures::cmu_capabilities(),
            metrics: Arc::default(),
            matches: Default::default(),
            shutdown,
            next_conn: Default::default(),
            replay_dir: None,
            replays: Default::default(),
            replay_written: tokio::sync::Notify::new(),
            connections: Arc::new(crate::listener::Connections::new(16, 64)),
        };
        (Arc::new(app), stop)
    }

    #[tokio::test]
    async fn a_panic_ends_the_match_with_error_and_gives_its_place_back() {
        let (app, _stop) = app();
        let scenario = Scenario::from_value(serde_json::json!({"sport": "baseball"})).unwrap();
        let slot = Slot::reserve(&app.metrics, 1).unwrap();
        let entry = spawn(&app, "m".into(), scenario, slot, true).unwrap();
        assert!(
            Slot::reserve(&app.metrics, 1).is_none(),
            "the match holds the place"
        );
        let mut published = entry.published.clone();
        entry.control.send(ToMatch::Panic).await.unwrap();
        let ended = tokio::time::timeout(
            std::time::Duration::from_secs(10),
            published.wait_for(|p| p.end.is_some()),
        )
        .await
        .expect("the match ends")
        .unwrap()
        .clone();
        let end: serde_json::Value = serde_json::from_str(ended.end.unwrap().as_str()).unwrap();
        assert_eq!(end["reason"], "error");
        assert_eq!(end["type"], "end");
        assert!(entry.ended.load(Relaxed));
        assert_eq!(app.metrics.match_panics.load(Relaxed), 1);
        // The task gives its place back when it is dropped, just after the end.
        let freed = async {
            while app.metrics.matches_running.load(Relaxed) != 0 {
                tokio::time::sleep(std::time::Duration::from_millis(5)).await;
            }
        };
        tokio::time::timeout(std::time::Duration::from_secs(5), freed)
            .await
            .expect("the gauge goes back to 0");
        assert!(Slot::reserve(&app.metrics, 1).is_some());
    }

    const MS: Duration = Duration::from_millis(1);

    /// A baseball match in `mode` at 100 Hz (perceptions every 10 ms tick) whose `cf`
    /// (agent 0) is a bot slot, with a 250 ms lock-step deadline, spawned on this test's
    /// runtime.
    fn baseball(app: &Arc<AppState>, mode: &str) -> Arc<MatchEntry> {
        let scenario = Scenario::from_value(json!({
            "sport": "baseball",
            "mode": mode,
            "tick_hz": 100.0,
            "frame_hz": 50.0,
            "lockstep_deadline_ms": 250,
            "agents": [
                {"id": "cf", "strategy": "chapman", "position": [60.0, 60.0], "bot": true},
                {"id": "rf", "strategy": "chapman", "position": [20.0, 80.0]}
            ],
            "options": {"pause_s": 30.0}
        }))
        .unwrap();
        let slot = Slot::reserve(&app.metrics, 4).unwrap();
        spawn(app, "m".into(), scenario, slot, false).unwrap()
    }

    /// A bot connection as the match task sees one: its queue and its close.
    struct FakeBot {
        conn: Conn,
        out: mpsc::Receiver<Utf8Bytes>,
        close: oneshot::Receiver<Close>,
    }

    impl FakeBot {
        async fn join(entry: &MatchEntry, conn: u64) -> FakeBot {
            let (out_tx, out) = mpsc::channel(16);
            let (close_tx, close) = oneshot::channel();
            let conn = Conn(conn);
            let join = ToMatch::Join {
                agent: 0,
                conn,
                out: out_tx,
                close: close_tx,
            };
            entry.control.send(join).await.unwrap();
            FakeBot { conn, out, close }
        }

        /// The next message, and the (paused) time it came at.
        async fn next(&mut self) -> (Value, Instant) {
            let text = self
                .out
                .recv()
                .await
                .expect("the match task keeps the queue");
            (serde_json::from_str(text.as_str()).unwrap(), Instant::now())
        }

        async fn next_perception(&mut self) -> (u64, Instant) {
            loop {
                let (message, at) = self.next().await;
                if message["type"] == "perception" {
                    return (message["tick"].as_u64().unwrap(), at);
                }
            }
        }

        async fn say(
            &self,
            entry: &MatchEntry,
            said: Result<ClientMessage, (&'static str, String)>,
        ) {
            let event = BotEvent::Said {
                agent: 0,
                conn: self.conn,
                said,
            };
            entry.control.send(ToMatch::Driver(event)).await.unwrap();
        }

        async fn stand(&self, entry: &MatchEntry, tick: u64) {
            let action = Action::Stand {};
            self.say(entry, Ok(ClientMessage::Command { tick, action }))
                .await;
        }
    }

    /// The `end` the match published, once it has.
    async fn end_of(entry: &MatchEntry) -> Value {
        let mut published = entry.published.clone();
        let ended = published.wait_for(|p| p.end.is_some()).await.unwrap();
        serde_json::from_str(ended.end.as_ref().unwrap().as_str()).unwrap()
    }

    #[tokio::test(start_paused = true)]
    async fn realtime_perceives_on_the_tick_cadence_of_the_match_time() {
        let (app, _stop) = app();
        let entry = baseball(&app, "realtime");
        let mut bot = FakeBot::join(&entry, 1).await;
        let (mut tick, mut at) = bot.next_perception().await;
        for _ in 0..50 {
            let (next, next_at) = bot.next_perception().await;
            assert_eq!(
                (next, next_at - at),
                (tick + 1, 10 * MS),
                "one tick a period"
            );
            (tick, at) = (next, next_at);
        }
        assert_eq!(entry.tick.load(Relaxed), tick);
    }

    #[tokio::test(start_paused = true)]
    async fn lockstep_waits_for_the_answer_or_the_deadline_and_no_longer() {
        let (app, _stop) = app();
        let entry = baseball(&app, "lockstep");
        let mut bot = FakeBot::join(&entry, 1).await;
        let (tick, at) = bot.next_perception().await;
        // Silent: the next tick comes at the deadline, to the millisecond of match time.
        let (next, next_at) = bot.next_perception().await;
        assert_eq!((next, next_at - at), (tick + 1, 250 * MS));
        // Answered: at once, however long the deadline.
        for k in 0..20 {
            bot.stand(&entry, next + k).await;
            let (answered, answered_at) = bot.next_perception().await;
            assert_eq!(
                (answered, answered_at),
                (next + k + 1, next_at),
                "no time passes"
            );
        }
    }

    #[tokio::test(start_paused = true)]
    async fn a_second_bot_replaces_the_first_and_a_flooding_bot_is_closed() {
        let (app, _stop) = app();
        let entry = baseball(&app, "realtime");
        let mut first = FakeBot::join(&entry, 1).await;
        first.next_perception().await;
        let mut second = FakeBot::join(&entry, 2).await;
        // The first hears why, then is closed; the second plays on.
        let told = loop {
            let (message, _) = first.next().await;
            if message["type"] == "error" {
                break message;
            }
        };
        assert_eq!(told["code"], "replaced");
        assert_eq!((&mut first.close).await, Ok(Close::Replaced));
        second.next_perception().await;
        // Unreadable messages pay; past the budget a burst more is a flood (the default
        // budget: 200 a second, 400 at once).
        let limits = (app.config.bot_messages_per_second, app.config.bot_burst);
        assert_eq!(limits, (200, 400));
        let mut codes = Vec::new();
        for _ in 0..1000 {
            second
                .say(&entry, Err(("bad_json", "not JSON".into())))
                .await;
            // The match task handles it; the socket would write what it says meanwhile.
            tokio::task::yield_now().await;
            while let Ok(text) = second.out.try_recv() {
                let message: Value = serde_json::from_str(text.as_str()).unwrap();
                if message["type"] == "error" {
                    codes.push(message["code"].as_str().unwrap().to_owned());
                }
            }
        }
        let rate_limited = codes.iter().filter(|c| *c == "rate_limited").count();
        assert_eq!(
            (codes.len(), rate_limited),
            (401, 1),
            "400 answered, then one warning"
        );
        assert_eq!((&mut second.close).await, Ok(Close::Flooding));
        assert_eq!(app.metrics.closed_for_rate.load(Relaxed), 1);
        // The match is unharmed.
        let before = entry.tick.load(Relaxed);
        tokio::time::sleep(105 * MS).await;
        let played = entry.tick.load(Relaxed) - before;
        assert!(
            (10..=11).contains(&played),
            "{played} ticks in 105 ms at 100 Hz"
        );
    }

    #[tokio::test(start_paused = true)]
    async fn a_delete_and_a_shutdown_end_the_match_with_their_reasons() {
        let (app, stop) = app();
        let deleted = baseball(&app, "realtime");
        // Lock-step without a bot ticks in real time, for its spectators.
        let stopped = baseball(&app, "lockstep");
        // Between the ticks of 500 and 510 ms.
        tokio::time::sleep(505 * MS).await;
        deleted.control.send(ToMatch::Stop).await.unwrap();
        let end = end_of(&deleted).await;
        assert_eq!(
            (&end["type"], &end["reason"]),
            (&json!("end"), &json!("deleted"))
        );
        assert_eq!(end["tick"], 50, "500 ms at 100 Hz");
        assert!(end["result"].is_object(), "{end}");
        // The last frame is published before the end, showing the last tick.
        let frame: Value = serde_json::from_str(deleted.published.borrow().frame.as_str()).unwrap();
        assert_eq!(frame["tick"], 50);
        stop.send(true).unwrap();
        assert_eq!(end_of(&stopped).await["reason"], "shutdown");
        assert!(deleted.ended.load(Relaxed) && stopped.ended.load(Relaxed));
    }
}
