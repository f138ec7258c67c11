//! A match is a task that owns one [`World`] (in a [`Session`]) and ticks it: on the
//! wall clock (`realtime`), as fast as possible (`fast`), or in lock-step with its bots
//! (`lockstep`). Each frame is encoded once, published for the sockets, and handed to
//! the match's replay (written on a thread of its own: see [`super::recording`]) if the
//! server keeps replays.

use super::auth::new_token;
use super::config::ServerConfig;
use super::metrics::Metrics;
use super::recording::{InDir, Limit, Recording};
use super::slot::Slot;
use super::state::{AppState, Control, MatchEntry, Published, ToBot};
use fieldhouse_core::protocol::{encode, End, ErrorMessage, MatchInfo, Perception};
use fieldhouse_core::replay;
use fieldhouse_core::session::Session;
use fieldhouse_core::sim::{Mode, Scenario, ScenarioError, World};
use futures_util::FutureExt;
use serde_json::Value;
use std::panic::AssertUnwindSafe;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::{mpsc, watch};
use tokio::time::Instant;
use tokio_tungstenite::tungstenite::Utf8Bytes;

/// A bot connected to an agent.
struct Bot {
    conn: u64,
    out: mpsc::Sender<ToBot>,
    /// The latest tick it has answered.
    answered: Option<u64>,
}

/// Builds the world a scenario describes and starts its task, which holds `slot` until
/// it ends. Returns the match and the bot tokens of its bot-controlled agents.
pub fn spawn(
    app: &Arc<AppState>,
    id: String,
    scenario: Scenario,
    slot: Slot,
) -> Result<Arc<MatchEntry>, ScenarioError> {
    let world = World::new(&scenario, Some(app.caps.clone()))?;
    let agent_ids = world.agent_ids();
    let info = MatchInfo {
        id: id.clone(),
        name: scenario.name.clone(),
        sport: scenario.sport.name(),
        mode: scenario.mode.name(),
        seed: scenario.seed,
        tick_hz: scenario.tick_hz,
        frame_hz: scenario.frame_hz,
        perception_every_ticks: world.perception_every_ticks(),
        field: world.field(),
        agents: world.agents_info(),
        motion_source: app.caps.source.to_string(),
    };
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
    // Agents play their built-in brains until a bot connects.
    let controlled = vec![false; agent_ids.len()];
    let mut session = Session::new(world, id.clone(), scenario.tick_hz, scenario.frame_hz);
    let first = Utf8Bytes::from(session.frame());
    let creation_error = Mutex::new(None);
    let started = app.replay_dir.as_deref().and_then(|dir| {
        let header = replay::header(&info, &scenario, app.caps.source.fingerprint());
        let files = InDir {
            app: app.clone(),
            dir: dir.to_path_buf(),
            stem: format!("{id}-{}", unix_seconds()),
        };
        let limit = recording_limit(&app.config, &scenario);
        let made = Recording::start(files, header, limit, app.replays.queued.clone())
            .map_err(|e| e.to_string())
            .and_then(|(r, id)| r.frame(0, first.clone()).map(|()| (r, id)));
        made.map_err(|e| {
            app.metrics.replay_errors.fetch_add(1, Relaxed);
            tracing::warn!(error = %e, "cannot record this match; it runs unrecorded");
            *creation_error.lock().expect("not poisoned") = Some(e);
        })
        .ok()
    });
    let (recorder, replay) = started.unzip();
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
        controlled: Mutex::new(controlled),
        replay,
        replay_error: creation_error,
    });
    app.metrics.matches_created.fetch_add(1, Relaxed);
    let task = Ticker {
        _slot: slot,
        session,
        recorder,
        entry: entry.clone(),
        publish,
        control: control_rx,
        metrics: app.metrics.clone(),
        shutdown: app.shutdown.clone(),
        bots: (0..agent_ids.len()).map(|_| None).collect(),
        agent_ids,
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
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

struct Ticker {
    /// The match's place among `max_matches`, given back when the task is dropped.
    _slot: Slot,
    session: Session,
    recorder: Option<Recording>,
    entry: Arc<MatchEntry>,
    publish: watch::Sender<Published>,
    control: mpsc::Receiver<Control>,
    metrics: Arc<Metrics>,
    shutdown: watch::Receiver<bool>,
    bots: Vec<Option<Bot>>,
    agent_ids: Vec<String>,
    seq: u64,
    stamp_frames: bool,
}

impl Ticker {
    /// Plays the match, then ends it. A panic while playing (a bug) ends this match
    /// with reason `error`, told to its spectators and bots and logged, instead of
    /// leaving it listed as running for ever with its place taken.
    async fn run(mut self) {
        let played = AssertUnwindSafe(self.play()).catch_unwind().await;
        let reason = played.unwrap_or_else(|panic| {
            self.metrics.match_panics.fetch_add(1, Relaxed);
            tracing::error!(
                id = %self.entry.info.id,
                tick = self.entry.tick.load(Relaxed),
                panic = panic_message(panic.as_ref()),
                "the match task panicked; ending the match"
            );
            "error"
        });
        self.end(reason).await;
    }

    /// Ticks until the match ends; returns why it ended.
    async fn play(&mut self) -> &'static str {
        let info = &self.entry.info;
        let period = self.entry.scenario.tick_period();
        let perceive_every = info.perception_every_ticks;
        let deadline = self.entry.scenario.lockstep_deadline();
        let mode = self.entry.mode;
        let mut next_tick = Instant::now() + period;
        // Lockstep: when the tick waiting for bots must go anyway.
        let mut waiting_until: Option<Instant> = None;
        loop {
            if self.session.world.finished() {
                return "finished";
            }
            if mode == Mode::Fast {
                // No timer at all (even a zero sleep costs a timer tick): take whatever
                // the sockets and the API said, then tick.
                if *self.shutdown.borrow() {
                    return "shutdown";
                }
                if let Some(reason) = self.drain_controls() {
                    return reason;
                }
                self.tick();
                if self.session.world.tick().is_multiple_of(256) {
                    tokio::task::yield_now().await;
                }
                continue;
            }
            let wake = match (mode, waiting_until) {
                (Mode::Lockstep, Some(until)) => until,
                _ => next_tick,
            };
            tokio::select! {
                biased;
                _ = self.shutdown.changed() => return "shutdown",
                message = self.control.recv() => {
                    match message {
                        None | Some(Control::Stop) => return "deleted",
                        Some(m) => self.handle(m),
                    }
                    let all_answered = waiting_until.is_some() && self.all_answered();
                    if !all_answered {
                        continue;
                    }
                }
                _ = tokio::time::sleep_until(wake) => {}
            }
            // Time for a tick.
            let now = Instant::now();
            if mode == Mode::Realtime || (mode == Mode::Lockstep && waiting_until.is_none()) {
                if now > next_tick + period {
                    self.metrics.tick_overruns.fetch_add(1, Relaxed);
                    // More than a second behind: do not try to catch up that far.
                    if now > next_tick + Duration::from_secs(1) {
                        next_tick = now;
                    }
                }
                next_tick += period;
            } else {
                next_tick = now + period;
            }
            waiting_until = None;
            self.tick();
            let tick = self.session.world.tick();
            if tick.is_multiple_of(perceive_every) && self.bots.iter().any(Option::is_some) {
                self.perceive();
                if mode == Mode::Lockstep {
                    waiting_until = Some(Instant::now() + deadline);
                }
            }
        }
    }

    /// Handles every control message waiting; the reason to stop, if one says so.
    fn drain_controls(&mut self) -> Option<&'static str> {
        loop {
            match self.control.try_recv() {
                Ok(Control::Stop) | Err(mpsc::error::TryRecvError::Disconnected) => {
                    return Some("deleted")
                }
                Ok(message) => self.handle(message),
                Err(mpsc::error::TryRecvError::Empty) => return None,
            }
        }
    }

    fn all_answered(&self) -> bool {
        let tick = self.session.world.tick();
        self.bots
            .iter()
            .flatten()
            .all(|b| b.answered.is_some_and(|t| t >= tick))
    }

    fn tick(&mut self) {
        let started = std::time::Instant::now();
        let frame = self.session.step();
        self.metrics.observe_tick(started.elapsed().as_secs_f64());
        self.entry.tick.store(self.session.world.tick(), Relaxed);
        if let Some(frame) = frame {
            self.publish_frame(frame);
        }
    }

    fn publish_frame(&mut self, frame: String) {
        let tick = self.session.world.tick();
        let bytes = if self.stamp_frames {
            let recorded = Utf8Bytes::from(frame);
            let stamped = stamped(recorded.as_str());
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

    fn perceive(&mut self) {
        let world = &self.session.world;
        let (tick, time_s) = (world.tick(), world.time_s());
        for (k, bot) in self.bots.iter().enumerate() {
            let Some(bot) = bot else { continue };
            let perception = world.perception(k);
            let message = encode(&Perception {
                kind: "perception",
                tick,
                time_s,
                agent: &self.agent_ids[k],
                perception: &perception,
            });
            // A bot that is not reading misses perceptions rather than holding a tick.
            let _ = bot.out.try_send(ToBot::perception(tick, message));
        }
    }

    fn tell(&self, agent: usize, code: &str, message: &str) {
        self.tell_with(agent, code, message, ToBot::message);
    }

    /// Sends a bot an `error`, made into what its socket is told by `to_bot`.
    fn tell_with(&self, agent: usize, code: &str, message: &str, to_bot: fn(String) -> ToBot) {
        if let Some(bot) = &self.bots[agent] {
            self.metrics.client_errors.fetch_add(1, Relaxed);
            let _ = bot
                .out
                .try_send(to_bot(encode(&ErrorMessage::new(code, message))));
        }
    }

    fn set_controlled(&mut self, agent: usize, by_bot: bool) {
        self.session.world.set_controlled(agent, by_bot);
        let tick = self.session.world.tick();
        let id = self.agent_ids[agent].clone();
        self.record(|r| r.log(replay::control_record(tick, &id, by_bot)));
        self.entry.controlled.lock().expect("not poisoned")[agent] = by_bot;
    }

    fn handle(&mut self, message: Control) {
        match message {
            Control::BotJoin { agent, conn, out } => {
                if self.bots[agent].is_some() {
                    // The old connection closes once it has passed this on.
                    let why = "another connection took over this agent";
                    self.tell_with(agent, "replaced", why, ToBot::replaced);
                }
                self.bots[agent] = Some(Bot {
                    conn,
                    out,
                    answered: None,
                });
                self.set_controlled(agent, true);
            }
            Control::BotLeave { agent, conn } => {
                if self.bots[agent].as_ref().is_some_and(|b| b.conn == conn) {
                    self.bots[agent] = None;
                    // Back to the built-in brain until a bot reconnects.
                    self.set_controlled(agent, false);
                }
            }
            Control::Command {
                agent,
                conn,
                tick,
                action,
            } => {
                if self.bots[agent].as_ref().is_none_or(|b| b.conn != conn) {
                    return; // a replaced connection
                }
                let now = self.session.world.tick();
                let every = self.entry.info.perception_every_ticks;
                if let Err((code, text)) = in_window(tick, now, every) {
                    return self.tell(agent, code, &text);
                }
                // Any command answers its tick, even one the world rejects: lockstep
                // waits for bots to speak, not to be right.
                if let Some(b) = &mut self.bots[agent] {
                    b.answered = Some(b.answered.map_or(tick, |a| a.max(tick)));
                }
                match self.session.world.command(agent, &action) {
                    Ok(()) => {
                        let id = self.agent_ids[agent].clone();
                        self.record(|r| r.log(replay::command_record(now, &id, &action)));
                    }
                    Err(reason) => self.tell(agent, "rejected", &reason),
                }
            }
            Control::Stop => unreachable!("the tick loop stops on Stop"),
            #[cfg(test)]
            Control::Panic => panic!("a test asked this match task to panic"),
        }
    }

    async fn end(mut self, reason: &str) {
        // After a panic the world may be half-stepped: reading it may panic again, so
        // the last frame and the result are read under a guard, and left out if so.
        let last = std::panic::catch_unwind(AssertUnwindSafe(|| {
            let world = &self.session.world;
            (world.tick(), world.result())
        }));
        let (tick, result) = last.unwrap_or_else(|_| (self.entry.tick.load(Relaxed), Value::Null));
        let frame = std::panic::catch_unwind(AssertUnwindSafe(|| self.session.last_frame()));
        if let Ok(Some(frame)) = frame {
            self.publish_frame(frame);
        }
        let end = Utf8Bytes::from(encode(&End {
            kind: "end",
            match_id: &self.entry.info.id,
            tick,
            reason,
            result: &result,
        }));
        // The replay is complete on disk before anyone hears the match ended. Its
        // writer thread syncs it; this task waits without holding the thread that
        // ticks the other matches.
        if let Some(r) = self.recorder.take() {
            if let Err(e) = r.finish(tick, reason, &result).await {
                self.recording_stopped(format!("cannot finish the replay: {e}"));
            }
        }
        self.entry.ended.store(true, Relaxed);
        self.entry.ended_at.get_or_init(std::time::Instant::now);
        self.publish.send_modify(|p| p.end = Some(end));
        tracing::info!(id = %self.entry.info.id, reason, tick, "match ended");
    }
}

/// Whether a command for `tick` may act at tick `now` (perceptions every `every`
/// ticks): not more than four perceptions late, nor for a tick after the next
/// perception's. The sums saturate: a tick near `u64::MAX` is in the future, never
/// wrapped round into the past.
fn in_window(tick: u64, now: u64, every: u64) -> Result<(), (&'static str, String)> {
    if tick.saturating_add(every.saturating_mul(4)) < now {
        return Err((
            "stale_tick",
            format!("command for tick {tick} arrived at tick {now}"),
        ));
    }
    if tick > now.saturating_add(every) {
        return Err((
            "future_tick",
            format!("command for tick {tick}, but the match is at tick {now}"),
        ));
    }
    Ok(())
}

/// The text a panic was raised with, if it has one.
fn panic_message(payload: &(dyn std::any::Any + Send)) -> &str {
    payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(no message)")
}

/// `frame` with `"sent_us"` (now, µs since the Unix epoch) as its second field, right
/// after `"type":"frame"`, where a load generator finds it without parsing the frame.
fn stamped(frame: &str) -> String {
    const HEAD: &str = r#"{"type":"frame","#;
    let sent_us = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_micros());
    match frame.strip_prefix(HEAD) {
        Some(rest) => format!(r#"{HEAD}"sent_us":{sent_us},{rest}"#),
        None => frame.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::{in_window, spawn, stamped};
    use crate::slot::Slot;
    use crate::state::{AppState, Control};
    use crate::ServerConfig;
    use fieldhouse_core::sim::Scenario;
    use std::sync::atomic::Ordering::Relaxed;
    use std::sync::Arc;

    #[test]
    fn ticks_near_the_end_of_u64_are_in_the_future_not_wrapped_into_the_past() {
        let every = 6;
        for tick in [u64::MAX, u64::MAX - 1, u64::MAX - 4 * every, u64::MAX / 2] {
            assert_eq!(
                in_window(tick, 100, every).unwrap_err().0,
                "future_tick",
                "{tick}"
            );
        }
        assert_eq!(in_window(0, 1_000, every).unwrap_err().0, "stale_tick");
        assert!(in_window(u64::MAX, u64::MAX, every).is_ok());
        assert!(in_window(100 - 4 * every, 100, every).is_ok());
        assert!(in_window(100 + every, 100, every).is_ok());
        assert_eq!(
            in_window(101 + every, 100, every).unwrap_err().0,
            "future_tick"
        );
        assert_eq!(
            in_window(99 - 4 * every, 100, every).unwrap_err().0,
            "stale_tick"
        );
    }

    /// A server's shared state with no sockets, whose matches tick on this test's
    /// runtime; the stop sender keeps matches from seeing a shutdown.
    fn app() -> (Arc<AppState>, tokio::sync::watch::Sender<bool>) {
        let (stop, shutdown) = tokio::sync::watch::channel(false);
        let app = AppState {
            ticking: tokio::runtime::Handle::current(),
            config: ServerConfig::default(),
            admin_token: "admin".into(),
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
        let entry = spawn(&app, "m".into(), scenario, slot).unwrap();
        assert!(
            Slot::reserve(&app.metrics, 1).is_none(),
            "the match holds the place"
        );
        let mut published = entry.published.clone();
        entry.control.send(Control::Panic).await.unwrap();
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

    #[test]
    fn a_stamp_is_the_second_field_and_keeps_the_frame_valid() {
        let frame = r#"{"type":"frame","match":"m","tick":2}"#;
        let out: serde_json::Value = serde_json::from_str(&stamped(frame)).unwrap();
        assert!(out["sent_us"].as_u64().unwrap() > 1_700_000_000_000_000);
        assert_eq!(out["tick"], 2);
        assert!(stamped(frame).starts_with(r#"{"type":"frame","sent_us":"#));
    }
}
