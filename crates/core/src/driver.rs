//! The rules of a running match, without I/O: a [`MatchDriver`] owns the match's
//! [`Session`] (and so its world) and its bot seats, and decides when to tick and what
//! to tell whom. It never reads a clock, sleeps, or touches a socket or a channel: the
//! shell (the server's match task) tells it the time, as a [`Duration`] since the match
//! task started, and the events that arrived; it asks the driver when to wake it next
//! ([`MatchDriver::poll_timeout`]), and carries out what the driver wants done
//! ([`MatchDriver::poll_output`]). This is the shape of quinn-proto's `Connection`:
//! every policy below is tested with made-up times instead of sleeps and wall-clock
//! assertions, and the driver lives in the deterministic core with the world it
//! drives, where the compiler keeps it from doing I/O. (How long a tick takes to compute is the shell's to measure, around the call
//! that ticked.)
//!
//! The policies:
//!
//! * **Pacing.** `realtime` ticks every `1/tick_hz` s on a fixed cadence: a tick that
//!   starts more than a period late counts an overrun ([`Output::Overrun`]), and the
//!   match catches up on late ticks, one after another, but never more than a second's
//!   worth: further behind, the cadence restarts from now. `fast` ticks at once, every
//!   time it is asked ([`Wake::Now`]: no timer at all; the shell takes what the sockets
//!   said between ticks). `lockstep` with a bot seated never waits for the clock: a tick
//!   on which no perception is owed plays at once, as in `fast`; after a tick that
//!   perceives for the seated bots, the next waits until every one has answered that
//!   perception (a command for its tick or a later one) and plays at once, or until the
//!   scenario's `lockstep_deadline_ms` has passed, whichever comes first. So the match
//!   goes at its bots' pace, whatever their perceptions' period (a basketball player
//!   perceives every 15th tick: the 14 between used to run in real time, which held a
//!   learner to 4 steps a second). With no bot seated, `lockstep` ticks like `realtime`
//!   (for its spectators), its cadence starting a period after the last tick.
//! * **Commands.** A command must be for a tick in the window of `in_window` (not
//!   more than four perceptions late, not after the next perception's tick): otherwise
//!   its bot gets `stale_tick` or `future_tick`, and the command neither acts nor counts
//!   as an answer. In the window, it answers its tick even if the world rejects it
//!   (lockstep waits for bots to speak, not to be right); a rejected one gets
//!   `rejected` with the world's reason, an accepted one is logged for the replay.
//! * **Seats.** An agent plays its built-in brain until a bot joins it. A second
//!   connection joining the same agent takes it over: the old one is told `replaced`,
//!   and its later commands and its leaving are ignored. A bot leaving hands its agent
//!   back to the brain. Every change of hands is logged for the replay.
//! * **The end.** A finished world ends the match with reason `finished`; a stop (the
//!   API's delete, or nobody left to send controls) with `deleted`. After the end the
//!   driver does nothing more. (A server shutdown and a panic are the shell's.)

use crate::protocol::{encode, ErrorMessage, Perception};
use crate::replay;
use crate::session::Session;
use crate::sim::{Action, Mode, Scenario};
use crate::tags;
use std::collections::VecDeque;
use std::time::Duration;

/// What the shell forwards to the driver.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A bot connection `conn` takes agent `agent`.
    BotJoin {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The shell's id of the connection.
        conn: u64,
    },
    /// Connection `conn` of agent `agent` is gone.
    BotLeave {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The shell's id of the connection.
        conn: u64,
    },
    /// A bot's command for its agent, for tick `tick`.
    Command {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The shell's id of the connection it came on.
        conn: u64,
        /// The tick of the perception it answers.
        tick: u64,
        /// What the agent is to do.
        action: Action,
    },
    /// The match is deleted.
    Stop,
}

/// When the driver next needs [`MatchDriver::handle_timeout`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// Now, with no timer (`fast`): the shell takes the events already waiting, without
    /// waiting for any, then calls `handle_timeout`.
    Now,
    /// At this time since the match task started (a time already past: at once).
    At(Duration),
    /// Never: the match has ended.
    Never,
}

/// What the driver wants done, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// A tick was played; the world is now at `tick`. (The shell shows the tick and
    /// reports the tick's duration.)
    Ticked {
        /// The tick the world is at now.
        tick: u64,
    },
    /// A frame to publish to spectators and record, encoded once.
    Frame {
        /// The tick it shows.
        tick: u64,
        /// The encoded `frame` message.
        frame: String,
    },
    /// A `perception` for the bot on connection `conn` of agent `agent`, for `tick`:
    /// it owes an answer to it.
    Perception {
        /// The agent's index.
        agent: usize,
        /// The connection to send it on.
        conn: u64,
        /// The tick perceived.
        tick: u64,
        /// The encoded `perception` message.
        text: String,
    },
    /// An `error` for the bot on connection `conn` (a client error, for the metrics);
    /// `replaced`: its agent was taken over, and this is the connection's last message.
    Error {
        /// The agent's index.
        agent: usize,
        /// The connection to send it on.
        conn: u64,
        /// The encoded `error` message.
        text: String,
        /// Whether the connection lost its agent to another and is to be closed.
        replaced: bool,
    },
    /// A record for the replay's log (a bot's `command` or `control` record).
    Log(String),
    /// Who controls `agent` now (`true`: a bot).
    Controlled {
        /// The agent's index.
        agent: usize,
        /// Whether a bot controls it (`false`: its built-in brain).
        by_bot: bool,
    },
    /// A tick started more than a tick period late.
    Overrun,
    /// The match ended, and why; nothing follows.
    End {
        /// `finished` or `deleted`.
        reason: &'static str,
    },
}

/// A bot seated at an agent.
#[derive(Debug, Clone, Copy)]
struct Seat {
    conn: u64,
    /// The latest tick it has answered.
    answered: Option<u64>,
}

/// One match's rules over its session: see the module's documentation.
pub struct MatchDriver {
    session: Session,
    mode: Mode,
    period: Duration,
    deadline: Duration,
    perceive_every: u64,
    agent_ids: Vec<String>,
    seats: Vec<Option<Seat>>,
    /// When the next tick is due on the cadence (`realtime`, and `lockstep` when no
    /// tick is waiting for bots).
    next_tick: Duration,
    /// Lockstep: a tick is waiting for the bots, until this at the latest.
    waiting_until: Option<Duration>,
    outputs: VecDeque<Output>,
    ended: bool,
}

impl MatchDriver {
    /// A driver for `session`, paced as `scenario` says, started at time zero: the first
    /// tick is due a period from now (at once in `fast`). Every agent plays its brain.
    pub fn new(session: Session, scenario: &Scenario) -> MatchDriver {
        let agents = session.world.agent_ids();
        let period = scenario.tick_period();
        MatchDriver {
            mode: scenario.mode,
            period,
            deadline: scenario.lockstep_deadline(),
            perceive_every: session.world.perception_every_ticks(),
            seats: vec![None; agents.len()],
            agent_ids: agents,
            session,
            next_tick: period,
            waiting_until: None,
            outputs: VecDeque::new(),
            ended: false,
        }
    }

    /// The session being played: its world, for the shell's status and metrics.
    pub fn session(&self) -> &Session {
        &self.session
    }

    /// The session, for the shell's last frame and result once the match has ended.
    pub fn session_mut(&mut self) -> &mut Session {
        &mut self.session
    }

    /// When to call [`MatchDriver::handle_timeout`] next.
    pub fn poll_timeout(&self) -> Wake {
        match (self.ended, self.mode, self.waiting_until) {
            (true, _, _) => Wake::Never,
            (false, Mode::Fast, _) => Wake::Now,
            (false, Mode::Lockstep, Some(until)) => Wake::At(until),
            // Seated bots are owed nothing until the next perception: no clock to wait for.
            (false, Mode::Lockstep, None) if self.seated() => Wake::Now,
            (false, _, _) => Wake::At(self.next_tick),
        }
    }

    /// The next thing to do, if any.
    pub fn poll_output(&mut self) -> Option<Output> {
        self.outputs.pop_front()
    }

    /// Time has come to `now`: ticks once if a tick is due (several late ticks take
    /// several calls, each due at once), and ends the match if its world has finished.
    pub fn handle_timeout(&mut self, now: Duration) {
        if self.ended {
            return;
        }
        if self.session.world.finished() {
            return self.end("finished");
        }
        match (self.mode, self.waiting_until) {
            (Mode::Fast, _) => {}
            (Mode::Lockstep, Some(until)) => {
                if now < until {
                    return;
                }
                // The deadline: the tick goes without the silent bots.
                self.next_tick = now + self.period;
            }
            (Mode::Lockstep, None) if self.seated() => self.next_tick = now + self.period,
            _ => {
                if now < self.next_tick {
                    return;
                }
                if now > self.next_tick + self.period {
                    self.outputs.push_back(Output::Overrun);
                    // More than a second behind: do not try to catch up that far.
                    if now > self.next_tick + Duration::from_secs(1) {
                        self.next_tick = now;
                    }
                }
                self.next_tick += self.period;
            }
        }
        self.tick(now);
    }

    /// Something the shell was told, at `now`. In lockstep, the answer (or departure)
    /// that a waiting tick lacked plays it at once.
    pub fn handle(&mut self, event: Event, now: Duration) {
        if self.ended {
            return;
        }
        match event {
            Event::Stop => return self.end("deleted"),
            Event::BotJoin { agent, conn } => {
                if let Some(old) = self.seats[agent] {
                    // The old connection closes once it has passed this on.
                    let why = "another connection took over this agent";
                    self.tell(agent, old.conn, "replaced", why, true);
                }
                self.seats[agent] = Some(Seat {
                    conn,
                    answered: None,
                });
                self.set_controlled(agent, true);
            }
            Event::BotLeave { agent, conn } => {
                if self.seats[agent].is_some_and(|s| s.conn == conn) {
                    self.seats[agent] = None;
                    // Back to the built-in brain until a bot reconnects.
                    self.set_controlled(agent, false);
                }
            }
            Event::Command {
                agent,
                conn,
                tick,
                action,
            } => self.command(agent, conn, tick, &action),
        }
        if self.waiting_until.is_some() && self.all_answered() {
            self.next_tick = now + self.period;
            self.tick(now);
        }
    }

    fn command(&mut self, agent: usize, conn: u64, tick: u64, action: &Action) {
        if self.seats[agent].is_none_or(|s| s.conn != conn) {
            return; // a replaced connection
        }
        let now = self.session.world.tick();
        if let Err((code, text)) = in_window(tick, now, self.perceive_every) {
            return self.tell(agent, conn, code, &text, false);
        }
        // Any command answers its tick, even one the world rejects: lockstep waits for
        // bots to speak, not to be right.
        if let Some(s) = &mut self.seats[agent] {
            s.answered = Some(s.answered.map_or(tick, |a| a.max(tick)));
        }
        match self.session.world.command(agent, action) {
            Ok(()) => {
                let record = replay::command_record(now, &self.agent_ids[agent], action);
                self.outputs.push_back(Output::Log(record));
            }
            Err(reason) => self.tell(agent, conn, "rejected", &reason, false),
        }
    }

    /// Whether a bot plays any agent.
    fn seated(&self) -> bool {
        self.seats.iter().any(Option::is_some)
    }

    fn all_answered(&self) -> bool {
        let tick = self.session.world.tick();
        self.seats
            .iter()
            .flatten()
            .all(|s| s.answered.is_some_and(|t| t >= tick))
    }

    /// Plays one tick at `now`: its frame if one is due, then perceptions for the bots
    /// (and, in lockstep, a wait for their answers), then the end if the world finished.
    fn tick(&mut self, now: Duration) {
        self.waiting_until = None;
        let frame = self.session.step();
        let tick = self.session.world.tick();
        self.outputs.push_back(Output::Ticked { tick });
        if let Some(frame) = frame {
            self.outputs.push_back(Output::Frame { tick, frame });
        }
        if self.mode != Mode::Fast && tick.is_multiple_of(self.perceive_every) && self.seated() {
            self.perceive();
            if self.mode == Mode::Lockstep {
                self.waiting_until = Some(now + self.deadline);
            }
        }
        if self.session.world.finished() {
            self.end("finished");
        }
    }

    fn perceive(&mut self) {
        let world = &self.session.world;
        let (tick, time_s) = (world.tick(), world.time_s());
        for (agent, seat) in self.seats.iter().enumerate() {
            let Some(seat) = seat else { continue };
            let text = encode(&Perception {
                kind: tags::Perception,
                tick,
                time_s,
                agent: &self.agent_ids[agent],
                perception: world.perception(agent),
            });
            self.outputs.push_back(Output::Perception {
                agent,
                conn: seat.conn,
                tick,
                text,
            });
        }
    }

    /// An `error` for connection `conn` of `agent`.
    fn tell(&mut self, agent: usize, conn: u64, code: &str, message: &str, replaced: bool) {
        let text = encode(&ErrorMessage::new(code, message));
        self.outputs.push_back(Output::Error {
            agent,
            conn,
            text,
            replaced,
        });
    }

    fn set_controlled(&mut self, agent: usize, by_bot: bool) {
        self.session.world.set_controlled(agent, by_bot);
        let tick = self.session.world.tick();
        let record = replay::control_record(tick, &self.agent_ids[agent], by_bot);
        self.outputs.push_back(Output::Log(record));
        self.outputs.push_back(Output::Controlled { agent, by_bot });
    }

    fn end(&mut self, reason: &'static str) {
        self.ended = true;
        self.waiting_until = None;
        self.outputs.push_back(Output::End { reason });
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

#[cfg(test)]
mod tests {
    use super::{in_window, Event, MatchDriver, Output, Wake};
    use crate::session::Session;
    use crate::sim::{Action, Scenario, World};
    use serde_json::{json, Value};
    use std::time::Duration;

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

    const MS: Duration = Duration::from_millis(1);

    /// A baseball match in `mode` at 100 Hz (a 10 ms period, perceptions every tick)
    /// with a 400 ms lockstep deadline, whose fielders `cf` (agent 0) and `lf` (agent 1)
    /// are bot slots and `rf` (agent 2) is not, plus `extra` fields.
    fn driver(mode: &str, extra: Value) -> MatchDriver {
        let mut scenario = json!({
            "sport": "baseball",
            "mode": mode,
            "tick_hz": 100.0,
            "frame_hz": 50.0,
            "lockstep_deadline_ms": 400,
            "agents": [
                {"id": "cf", "strategy": "chapman", "position": [60.0, 60.0], "bot": mode != "fast"},
                {"id": "lf", "strategy": "chapman", "position": [-60.0, 60.0], "bot": mode != "fast"},
                {"id": "rf", "strategy": "lot-optical", "position": [20.0, 80.0]}
            ],
            "options": {"pause_s": 30.0}
        });
        for (k, v) in extra.as_object().unwrap() {
            scenario[k] = v.clone();
        }
        let scenario = Scenario::from_value(scenario).unwrap();
        // Baseball needs no motion capabilities (building them takes seconds).
        let world = World::new(&scenario, None).unwrap();
        let session = Session::new(world, "m".into(), scenario.tick_hz, scenario.frame_hz);
        MatchDriver::new(session, &scenario)
    }

    fn outputs(d: &mut MatchDriver) -> Vec<Output> {
        std::iter::from_fn(|| d.poll_output()).collect()
    }

    fn tick(d: &MatchDriver) -> u64 {
        d.session().world.tick()
    }

    fn stand(agent: usize, conn: u64, tick: u64) -> Event {
        Event::Command {
            agent,
            conn,
            tick,
            action: Action::Stand {},
        }
    }

    /// The perceptions among `outputs`: (agent, conn, tick).
    fn perceptions(outputs: &[Output]) -> Vec<(usize, u64, u64)> {
        outputs
            .iter()
            .filter_map(|o| match o {
                Output::Perception {
                    agent, conn, tick, ..
                } => Some((*agent, *conn, *tick)),
                _ => None,
            })
            .collect()
    }

    /// The errors among `outputs`: (agent, conn, code, replaced).
    fn errors(outputs: &[Output]) -> Vec<(usize, u64, String, bool)> {
        outputs
            .iter()
            .filter_map(|o| match o {
                Output::Error {
                    agent,
                    conn,
                    text,
                    replaced,
                } => {
                    let v: Value = serde_json::from_str(text).unwrap();
                    assert_eq!(v["type"], "error");
                    Some((*agent, *conn, v["code"].as_str()?.to_owned(), *replaced))
                }
                _ => None,
            })
            .collect()
    }

    fn ended(outputs: &[Output]) -> Option<&'static str> {
        outputs.iter().find_map(|o| match o {
            Output::End { reason } => Some(*reason),
            _ => None,
        })
    }

    #[test]
    fn realtime_ticks_on_its_cadence() {
        let mut d = driver("realtime", json!({}));
        assert_eq!(d.poll_timeout(), Wake::At(10 * MS));
        // Woken early (or spuriously): nothing happens.
        d.handle_timeout(9 * MS);
        assert_eq!((tick(&d), outputs(&mut d)), (0, vec![]));
        for k in 1..=10u64 {
            let Wake::At(at) = d.poll_timeout() else {
                panic!()
            };
            assert_eq!(at, k as u32 * 10 * MS);
            // A little late, as timers are: still on the cadence, no overrun.
            d.handle_timeout(at + 3 * MS);
            assert_eq!(tick(&d), k);
            let out = outputs(&mut d);
            assert!(out.contains(&Output::Ticked { tick: k }));
            assert!(!out.contains(&Output::Overrun));
            // Frames every other tick (frame_hz 50); no bots, no perceptions.
            let frames = out
                .iter()
                .filter(|o| matches!(o, Output::Frame { tick, .. } if *tick == k))
                .count();
            assert_eq!(frames, usize::from(k % 2 == 0), "tick {k}");
            assert!(perceptions(&out).is_empty());
        }
        assert_eq!(d.poll_timeout(), Wake::At(110 * MS));
    }

    #[test]
    fn realtime_counts_an_overrun_catches_up_and_gives_up_beyond_a_second() {
        let mut d = driver("realtime", json!({}));
        // 25 ms late for the tick due at 10 ms: more than a period, an overrun; the
        // ticks missed are played one after another, each due at once.
        d.handle_timeout(35 * MS);
        let out = outputs(&mut d);
        assert!(out.contains(&Output::Overrun), "{out:?}");
        assert_eq!(d.poll_timeout(), Wake::At(20 * MS));
        d.handle_timeout(35 * MS);
        assert!(
            outputs(&mut d).contains(&Output::Overrun),
            "still 15 ms late"
        );
        assert_eq!(d.poll_timeout(), Wake::At(30 * MS));
        d.handle_timeout(35 * MS);
        assert!(!outputs(&mut d).contains(&Output::Overrun), "caught up");
        assert_eq!(d.poll_timeout(), Wake::At(40 * MS));
        assert_eq!(tick(&d), 3);
        // Stalled for 2 s: an overrun, and the cadence starts again from now rather
        // than playing 200 ticks in a burst.
        d.handle_timeout(2040 * MS);
        assert!(outputs(&mut d).contains(&Output::Overrun));
        assert_eq!((tick(&d), d.poll_timeout()), (4, Wake::At(2050 * MS)));
        d.handle_timeout(2050 * MS);
        assert!(!outputs(&mut d).contains(&Output::Overrun));
        assert_eq!(tick(&d), 5);
    }

    #[test]
    fn fast_ticks_whenever_asked_without_a_timer() {
        let mut d = driver("fast", json!({"duration_s": 1.0}));
        for k in 1..=50 {
            assert_eq!(d.poll_timeout(), Wake::Now);
            d.handle_timeout(Duration::ZERO);
            assert_eq!(tick(&d), k);
        }
    }

    /// A lockstep driver with bots on cf (conn 1) and lf (conn 2), at its first tick,
    /// which perceived for both: the outputs so far are drained.
    fn lockstep_with_two_bots() -> MatchDriver {
        let mut d = driver("lockstep", json!({}));
        d.handle(Event::BotJoin { agent: 0, conn: 1 }, Duration::ZERO);
        d.handle(Event::BotJoin { agent: 1, conn: 2 }, Duration::ZERO);
        // With bots seated, a tick that owes them nothing plays at once.
        assert_eq!(d.poll_timeout(), Wake::Now);
        d.handle_timeout(10 * MS);
        let out = outputs(&mut d);
        assert_eq!(perceptions(&out), vec![(0, 1, 1), (1, 2, 1)]);
        d
    }

    #[test]
    fn lockstep_waits_for_every_seated_bot_then_ticks_at_once() {
        let mut d = lockstep_with_two_bots();
        // Waiting for both until the deadline, 400 ms after the tick.
        assert_eq!(d.poll_timeout(), Wake::At(410 * MS));
        d.handle_timeout(200 * MS);
        assert_eq!(tick(&d), 1, "not before the deadline");
        d.handle(stand(0, 1, 1), 12 * MS);
        assert_eq!(tick(&d), 1, "lf has not answered");
        assert_eq!(d.poll_timeout(), Wake::At(410 * MS));
        // The last answer plays the tick at once, and the next one waits again.
        d.handle(stand(1, 2, 1), 13 * MS);
        assert_eq!(tick(&d), 2);
        let out = outputs(&mut d);
        assert!(out.contains(&Output::Ticked { tick: 2 }));
        assert_eq!(perceptions(&out), vec![(0, 1, 2), (1, 2, 2)]);
        assert_eq!(d.poll_timeout(), Wake::At(413 * MS));
        // Commands are logged for the replay at the tick they act on.
        let logs: Vec<&Output> = out.iter().filter(|o| matches!(o, Output::Log(_))).collect();
        assert_eq!(
            logs,
            vec![
                &Output::Log(crate::replay::command_record(1, "cf", &Action::Stand {})),
                &Output::Log(crate::replay::command_record(1, "lf", &Action::Stand {})),
            ]
        );
        // An answer for a later tick counts too, a rejected one as well.
        d.handle(stand(0, 1, 3), 14 * MS);
        let shoot = Event::Command {
            agent: 1,
            conn: 2,
            tick: 2,
            action: Action::Shoot {},
        };
        d.handle(shoot, 15 * MS);
        assert_eq!(tick(&d), 3);
        let out = outputs(&mut d);
        assert_eq!(errors(&out), vec![(1, 2, "rejected".into(), false)]);
    }

    #[test]
    fn lockstep_ticks_at_the_deadline_when_a_bot_is_silent() {
        let mut d = lockstep_with_two_bots();
        d.handle(stand(0, 1, 1), 20 * MS);
        d.handle_timeout(409 * MS);
        assert_eq!(tick(&d), 1);
        d.handle_timeout(410 * MS);
        assert_eq!(tick(&d), 2);
        let out = outputs(&mut d);
        assert!(!out.contains(&Output::Overrun), "a wait is not an overrun");
        assert_eq!(perceptions(&out), vec![(0, 1, 2), (1, 2, 2)]);
        // Silent again: the next deadline, counted from this tick.
        assert_eq!(d.poll_timeout(), Wake::At(810 * MS));
        d.handle_timeout(810 * MS);
        assert_eq!(tick(&d), 3);
    }

    /// A lock-step basketball match at 60 Hz whose `o1` is a bot slot: its players
    /// perceive every 15th tick.
    fn basketball_lockstep() -> MatchDriver {
        let scenario = Scenario::from_value(json!({
            "sport": "basketball",
            "mode": "lockstep",
            "tick_hz": 60.0,
            "frame_hz": 30.0,
            "lockstep_deadline_ms": 1000,
            "agents": [
                {"id": "o1", "team": "offense", "strategy": "simple", "bot": true},
                {"id": "o2", "team": "offense", "strategy": "simple"},
                {"id": "d1", "team": "defense", "strategy": "defense"}
            ]
        }))
        .unwrap();
        let world = World::new(&scenario, Some(crate::fixtures::cmu_capabilities())).unwrap();
        let session = Session::new(world, "m".into(), scenario.tick_hz, scenario.frame_hz);
        MatchDriver::new(session, &scenario)
    }

    #[test]
    fn lockstep_plays_the_ticks_between_perceptions_at_once_and_waits_only_for_its_bots() {
        let mut d = basketball_lockstep();
        assert_eq!(d.perceive_every, 15);
        // No bot yet: real time, for the spectators.
        assert_eq!(d.poll_timeout(), Wake::At(d.period));
        d.handle(Event::BotJoin { agent: 0, conn: 1 }, MS);
        // The clock stands still from here: the match goes at the bot's pace alone.
        let now = 2 * MS;
        for perception in 1..=20u64 {
            let mut played = 0;
            while d.poll_timeout() == Wake::Now {
                d.handle_timeout(now);
                played += 1;
                assert!(
                    played <= 15,
                    "ticks owed nothing are at most a perception's period"
                );
            }
            let tick = tick(&d);
            assert_eq!(tick, 15 * perception, "a tick that perceives, then a wait");
            assert_eq!(d.poll_timeout(), Wake::At(now + 1000 * MS));
            let out = outputs(&mut d);
            assert_eq!(perceptions(&out), vec![(0, 1, tick)]);
            assert!(!out.contains(&Output::Overrun));
            // The answer plays the next tick at once, whatever the clock says.
            d.handle(stand(0, 1, tick), now);
            assert_eq!(self::tick(&d), tick + 1);
        }
        // The bot gone, real time again: a period after the last tick.
        d.handle(Event::BotLeave { agent: 0, conn: 1 }, now);
        assert_eq!(d.poll_timeout(), Wake::At(now + d.period));
    }

    #[test]
    fn lockstep_without_bots_keeps_the_realtime_cadence() {
        let mut d = driver("lockstep", json!({}));
        for k in 1..=5u32 {
            assert_eq!(d.poll_timeout(), Wake::At(k * 10 * MS));
            d.handle_timeout(k * 10 * MS);
        }
        assert_eq!(tick(&d), 5);
        // A bot leaving while a tick waits for it: the tick goes at once.
        d.handle(Event::BotJoin { agent: 0, conn: 7 }, 50 * MS);
        d.handle_timeout(60 * MS);
        assert_eq!(d.poll_timeout(), Wake::At(460 * MS));
        d.handle(Event::BotLeave { agent: 0, conn: 7 }, 70 * MS);
        assert_eq!(tick(&d), 7);
        assert_eq!(d.poll_timeout(), Wake::At(80 * MS));
    }

    #[test]
    fn stale_and_future_ticks_are_refused_and_answer_nothing() {
        let mut d = lockstep_with_two_bots();
        // Perceptions every tick: at tick 1 the window is ticks 0 to 2.
        d.handle(stand(0, 1, 3), 20 * MS);
        d.handle(stand(1, 2, 2), 20 * MS);
        let out = outputs(&mut d);
        assert_eq!(errors(&out), vec![(0, 1, "future_tick".into(), false)]);
        assert_eq!(tick(&d), 1, "cf's future command answers nothing");
        // So tick 1 waits for cf until its deadline; and so on, cf silent.
        while tick(&d) < 8 {
            let Wake::At(at) = d.poll_timeout() else {
                panic!()
            };
            d.handle_timeout(at);
        }
        assert_eq!(d.poll_timeout(), Wake::At(3210 * MS));
        outputs(&mut d);
        // At tick 8 the window is ticks 4 to 9.
        d.handle(stand(0, 1, 3), 3000 * MS);
        d.handle(stand(1, 2, 8), 3000 * MS);
        assert_eq!(tick(&d), 8, "cf's stale command answers nothing");
        let out = outputs(&mut d);
        assert_eq!(errors(&out), vec![(0, 1, "stale_tick".into(), false)]);
        assert!(
            !out.iter()
                .any(|o| matches!(o, Output::Log(r) if r.contains("\"cf\""))),
            "a refused command is not logged: {out:?}"
        );
        // An old tick still in the window acts, but does not answer tick 8.
        d.handle(stand(0, 1, 4), 3000 * MS);
        assert_eq!(tick(&d), 8);
        assert!(errors(&outputs(&mut d)).is_empty());
        d.handle(stand(0, 1, 8), 3000 * MS);
        assert_eq!(tick(&d), 9);
    }

    #[test]
    fn a_second_join_replaces_the_first() {
        let mut d = lockstep_with_two_bots();
        d.handle(Event::BotJoin { agent: 0, conn: 3 }, 20 * MS);
        let out = outputs(&mut d);
        assert_eq!(errors(&out), vec![(0, 1, "replaced".into(), true)]);
        assert!(out.contains(&Output::Controlled {
            agent: 0,
            by_bot: true
        }));
        // The old connection's commands and leave are ignored: they neither act, nor
        // answer, nor free the seat.
        d.handle(stand(0, 1, 1), 21 * MS);
        d.handle(Event::BotLeave { agent: 0, conn: 1 }, 22 * MS);
        d.handle(stand(1, 2, 1), 23 * MS);
        assert_eq!(tick(&d), 1, "waits for the new connection");
        let out = outputs(&mut d);
        assert!(errors(&out).is_empty());
        assert!(!out.iter().any(|o| matches!(o, Output::Controlled { .. })));
        assert!(!out
            .iter()
            .any(|o| matches!(o, Output::Log(r) if r.contains("\"cf\""))));
        // The new one answers for the agent, and hears its perceptions.
        d.handle(stand(0, 3, 1), 24 * MS);
        assert_eq!(tick(&d), 2);
        assert_eq!(perceptions(&outputs(&mut d)), vec![(0, 3, 2), (1, 2, 2)]);
    }

    #[test]
    fn leaving_returns_the_agent_to_its_brain() {
        let mut d = driver("realtime", json!({}));
        d.handle(Event::BotJoin { agent: 0, conn: 5 }, Duration::ZERO);
        assert_eq!(
            outputs(&mut d),
            vec![
                Output::Log(crate::replay::control_record(0, "cf", true)),
                Output::Controlled {
                    agent: 0,
                    by_bot: true
                },
            ]
        );
        d.handle_timeout(10 * MS);
        assert_eq!(perceptions(&outputs(&mut d)), vec![(0, 5, 1)]);
        let frame = |d: &mut MatchDriver| {
            let f: Value = serde_json::from_str(&d.session_mut().frame()).unwrap();
            f["agents"][0].get("controller").cloned()
        };
        assert_eq!(frame(&mut d), Some(json!("bot")));
        d.handle(Event::BotLeave { agent: 0, conn: 5 }, 15 * MS);
        assert_eq!(
            outputs(&mut d),
            vec![
                Output::Log(crate::replay::control_record(1, "cf", false)),
                Output::Controlled {
                    agent: 0,
                    by_bot: false
                },
            ]
        );
        assert_eq!(frame(&mut d), None, "the built-in brain plays cf again");
        d.handle_timeout(20 * MS);
        assert!(perceptions(&outputs(&mut d)).is_empty());
        // Its commands are no one's now.
        d.handle(stand(0, 5, 2), 25 * MS);
        assert_eq!(outputs(&mut d), vec![]);
    }

    #[test]
    fn stop_ends_the_match_as_deleted() {
        let mut d = lockstep_with_two_bots();
        d.handle(Event::Stop, 20 * MS);
        assert_eq!(outputs(&mut d), vec![Output::End { reason: "deleted" }]);
        assert_eq!(d.poll_timeout(), Wake::Never);
        // Nothing happens after the end.
        d.handle(stand(0, 1, 1), 21 * MS);
        d.handle_timeout(5000 * MS);
        assert_eq!((tick(&d), outputs(&mut d)), (1, vec![]));
    }

    #[test]
    fn a_finished_world_ends_the_match_as_finished() {
        let mut d = driver("fast", json!({"duration_s": 0.5}));
        let mut last = vec![];
        while d.poll_timeout() == Wake::Now {
            d.handle_timeout(Duration::ZERO);
            last = outputs(&mut d);
        }
        assert_eq!(tick(&d), 50);
        assert_eq!(ended(&last), Some("finished"));
        // The last tick's frame is published before the end.
        assert!(matches!(
            &last[..],
            [
                Output::Ticked { tick: 50 },
                Output::Frame { tick: 50, .. },
                Output::End { .. }
            ]
        ));
        assert_eq!(d.poll_timeout(), Wake::Never);
    }
}
