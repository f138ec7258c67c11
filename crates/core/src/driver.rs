//! The rules of a running match, without I/O: a [`MatchDriver`] owns the match's
//! [`Session`] (and so its world), its bot seats (who plays each agent, what each bot
//! owes and may still send) and its end, and decides when to tick and what to tell whom.
//! It never reads a clock, sleeps, or touches a socket or a channel: the shell (the
//! server's match task) tells it the time, as a [`Duration`] since the match task
//! started, and what arrived; it asks the driver when to wake it next
//! ([`MatchDriver::poll_timeout`]), and carries out what the driver wants done: what to
//! send to which bot connection ([`MatchDriver::poll_transmit`]) and what to publish,
//! record and count ([`MatchDriver::poll_output`]). This is the shape of quinn-proto's
//! `Connection`: every policy below is tested with made-up times instead of sleeps and
//! wall-clock assertions, and the driver lives in the deterministic core with the world
//! it drives, where the compiler keeps it from doing I/O. (How long a tick takes to
//! compute is the shell's to measure, around the call that ticked.)
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
//! * **What a bot may send.** Each seat has a message budget ([`MessageBudget`]). A
//!   command that answers a perception the bot was sent passes free, once (a lock-step
//!   bot answers every perception at once, and a match may perceive faster than any
//!   fixed rate: charging those answers disconnected bots that did exactly what the
//!   protocol asks). Everything else pays, unreadable messages too: over budget it is
//!   dropped (`rate_limited`, said once a run), and a bot that goes on sending a burst
//!   past it is flooding: its connection is closed ([`Close::Flooding`]) and its agent
//!   goes back to its brain. Only the newest [`OWED_MAX`] perceptions are remembered.
//! * **Seats.** An agent plays its built-in brain until a bot joins it. A second
//!   connection joining the same agent takes it over: the old one is told `replaced`
//!   and closed ([`Close::Replaced`]), and its later messages and its leaving are
//!   ignored. A bot leaving hands its agent back to the brain. Every change of hands is
//!   logged for the replay, and the world shows it in its frames (`controller`).
//! * **The end.** A finished world ends the match ([`EndReason::Finished`]); the shell
//!   ends it for any other reason with [`MatchDriver::stop`]. Either way the driver
//!   frames what happened since the last frame, encodes the `end` message once, and
//!   does nothing more.

use crate::budget::{MessageBudget, Verdict};
use crate::protocol::{encode, ClientMessage, End, ErrorMessage, Perception, Score};
use crate::replay;
use crate::session::Session;
use crate::sim::{Action, Mode, Scenario};
use crate::tags;
use std::collections::VecDeque;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Duration;

/// A bot connection, as the shell numbers them (unique while the server runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Conn(pub u64);

/// What a client sent that is not a message of the protocol: the `error` code and text
/// it is answered with (see [`crate::protocol::decode`]).
pub type Unreadable = (&'static str, String);

/// What the shell forwards to the driver.
#[derive(Debug, Clone, PartialEq)]
pub enum BotEvent {
    /// A bot connection `conn` takes agent `agent`.
    Join {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The connection.
        conn: Conn,
    },
    /// Connection `conn` of agent `agent` is gone.
    Leave {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The connection.
        conn: Conn,
    },
    /// Connection `conn` of agent `agent` sent a message, read as the protocol says, or
    /// something that is not one.
    Said {
        /// The agent's index, in the world's order of agents.
        agent: usize,
        /// The connection it came on.
        conn: Conn,
        /// What it said.
        said: Result<ClientMessage, Unreadable>,
    },
}

/// Why a match ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EndReason {
    /// Its world reached its end (duration, possessions or launches).
    Finished,
    /// The API deleted it, or nobody is left who could send it anything.
    Deleted,
    /// The server is stopping.
    Shutdown,
    /// The server failed while running it (a bug, logged).
    Error,
}

impl EndReason {
    /// The reason as `end` messages and replay footers write it.
    pub fn as_str(self) -> &'static str {
        match self {
            EndReason::Finished => "finished",
            EndReason::Deleted => "deleted",
            EndReason::Shutdown => "shutdown",
            EndReason::Error => "error",
        }
    }
}

/// When the driver next needs [`MatchDriver::handle_timeout`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Wake {
    /// Now, with no timer (`fast`): the shell takes the events already waiting, without
    /// waiting for any, then calls `handle_timeout`.
    Now,
    /// At this time since the match task started (a time already past: at once).
    At(Duration),
}

/// Why the driver closes a bot's connection.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Close {
    /// Another connection took over its agent.
    Replaced,
    /// It went on sending a whole burst past its budget.
    Flooding,
}

impl Close {
    /// The reason the close frame gives.
    pub fn reason(self) -> &'static str {
        match self {
            Close::Replaced => "another connection took over this agent",
            Close::Flooding => "too many messages",
        }
    }
}

/// What to send to a bot connection, in order.
#[derive(Debug, Clone, PartialEq)]
pub enum Transmit {
    /// A `perception` for `tick`, which the bot owes an answer.
    Perception {
        /// The connection to send it on.
        conn: Conn,
        /// The tick perceived.
        tick: u64,
        /// The encoded `perception` message.
        text: String,
    },
    /// An `error` (a client error, for the metrics).
    Error {
        /// The connection to send it on.
        conn: Conn,
        /// Its code, as the message carries it.
        code: &'static str,
        /// The encoded `error` message.
        text: String,
    },
    /// Close the connection, after what was sent before: nothing follows for it.
    Close {
        /// The connection to close.
        conn: Conn,
        /// Why.
        why: Close,
    },
}

/// How a match ended: what the shell tells everyone and writes in the replay's footer.
#[derive(Debug, Clone, PartialEq)]
pub struct Ending {
    /// The last tick played.
    pub tick: u64,
    /// Why it ended.
    pub reason: EndReason,
    /// The final score; `None` when the world could not be read (after a panic).
    pub result: Option<Score>,
    /// The encoded `end` message.
    pub message: String,
}

/// What to publish, record and count, in order.
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
    /// A record for the replay's log (a bot's `command` or `control` record).
    Log(String),
    /// A tick started more than a tick period late.
    Overrun,
    /// The match ended; nothing follows.
    End(Ending),
}

/// How many of a bot's unanswered perceptions are remembered: an answer to an older one
/// pays its way like any message.
pub const OWED_MAX: usize = 64;

/// A bot seated at an agent.
#[derive(Debug)]
struct Seat {
    conn: Conn,
    /// The ticks of the perceptions it was sent and has not answered, oldest first.
    owed: VecDeque<u64>,
    budget: MessageBudget,
}

impl Seat {
    fn owe(&mut self, tick: u64) {
        if self.owed.len() == OWED_MAX {
            self.owed.pop_front();
        }
        self.owed.push_back(tick);
    }

    /// Whether a command for `tick` answers a perception still owed; every owed
    /// perception up to `tick` is answered from now on.
    fn settle(&mut self, tick: u64) -> bool {
        let before = self.owed.len();
        self.owed.retain(|&t| t > tick);
        self.owed.len() < before
    }
}

/// How much a bot may send: the same for every seat of every match.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BotLimits {
    /// Messages a second, sustained.
    pub messages_per_second: u32,
    /// Messages at once.
    pub burst: u32,
}

/// One match's rules over its session: see the module's documentation.
pub struct MatchDriver {
    session: Session,
    mode: Mode,
    period: Duration,
    deadline: Duration,
    perceive_every: u64,
    limits: BotLimits,
    agent_ids: Vec<String>,
    seats: Vec<Option<Seat>>,
    /// When the next tick is due on the cadence (`realtime`, and `lockstep` when no
    /// tick is waiting for bots).
    next_tick: Duration,
    /// Lockstep: a tick is waiting for the bots, until this at the latest.
    waiting_until: Option<Duration>,
    /// The last tick played, as reported: what the end says if the world cannot be read.
    ticked: u64,
    transmits: VecDeque<Transmit>,
    outputs: VecDeque<Output>,
    ended: bool,
}

impl MatchDriver {
    /// A driver for `session`, paced as `scenario` says, started at time zero: the first
    /// tick is due a period from now (at once in `fast`). Every agent plays its brain
    /// until a bot joins it; bots may send as `limits` say.
    pub fn new(session: Session, scenario: &Scenario, limits: BotLimits) -> MatchDriver {
        let agents = session.world.agent_ids();
        let period = scenario.tick_period();
        MatchDriver {
            mode: scenario.mode,
            period,
            deadline: scenario.lockstep_deadline(),
            perceive_every: session.world.perception_every_ticks(),
            limits,
            seats: agents.iter().map(|_| None).collect(),
            agent_ids: agents,
            ticked: session.world.tick(),
            session,
            next_tick: period,
            waiting_until: None,
            transmits: VecDeque::new(),
            outputs: VecDeque::new(),
            ended: false,
        }
    }

    /// The tick the world is at.
    pub fn tick(&self) -> u64 {
        self.session.world.tick()
    }

    /// When to call [`MatchDriver::handle_timeout`] next. (After the end there is nothing
    /// to wait for: the shell stops driving the driver once it has the end.)
    pub fn poll_timeout(&self) -> Wake {
        match (self.mode, self.waiting_until) {
            _ if self.ended => Wake::Now,
            (Mode::Fast, _) => Wake::Now,
            (Mode::Lockstep, Some(until)) => Wake::At(until),
            // Seated bots are owed nothing until the next perception: no clock to wait for.
            (Mode::Lockstep, None) if self.seated() => Wake::Now,
            _ => Wake::At(self.next_tick),
        }
    }

    /// The next thing to publish, record or count, if any.
    pub fn poll_output(&mut self) -> Option<Output> {
        self.outputs.pop_front()
    }

    /// The next thing to send to a bot connection, if any.
    pub fn poll_transmit(&mut self) -> Option<Transmit> {
        self.transmits.pop_front()
    }

    /// Time has come to `now`: ticks once if a tick is due (several late ticks take
    /// several calls, each due at once), and ends the match if its world has finished.
    pub fn handle_timeout(&mut self, now: Duration) {
        if self.ended {
            return;
        }
        if self.session.world.finished() {
            return self.end(EndReason::Finished);
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
        self.tick_at(now);
    }

    /// Something a bot connection did, at `now`. In lockstep, the answer (or departure)
    /// that a waiting tick lacked plays it at once.
    pub fn handle(&mut self, event: BotEvent, now: Duration) {
        if self.ended {
            return;
        }
        match event {
            // The shell joins each connection once; a second join changes nothing.
            BotEvent::Join { agent, conn } if self.seated_at(agent, conn) => {}
            BotEvent::Join { agent, conn } => {
                if let Some(old) = self.seats[agent].take() {
                    self.tell(old.conn, "replaced", Close::Replaced.reason());
                    self.transmits.push_back(Transmit::Close {
                        conn: old.conn,
                        why: Close::Replaced,
                    });
                }
                let (rate, burst) = (self.limits.messages_per_second, self.limits.burst);
                self.seats[agent] = Some(Seat {
                    conn,
                    owed: VecDeque::new(),
                    budget: MessageBudget::new(rate, burst, now),
                });
                self.set_controlled(agent, true);
            }
            BotEvent::Leave { agent, conn } => {
                if self.seated_at(agent, conn) {
                    self.vacate(agent);
                }
            }
            BotEvent::Said { agent, conn, said } => self.said(agent, conn, said, now),
        }
        if self.waiting_until.is_some() && self.all_answered() {
            self.next_tick = now + self.period;
            self.tick_at(now);
        }
    }

    /// Ends the match now, for `reason` (the shell's: a delete, a shutdown, a failure),
    /// unless it has ended already. After a panic inside the world (`Error`) the world
    /// may be half-stepped: the last frame and the result are read under a guard, and
    /// left out if reading them panics too.
    pub fn stop(&mut self, reason: EndReason) {
        if !self.ended {
            self.end(reason);
        }
    }

    /// Whether `conn` holds the seat of `agent` (not a connection replaced or closed).
    fn seated_at(&self, agent: usize, conn: Conn) -> bool {
        self.seats[agent].as_ref().is_some_and(|s| s.conn == conn)
    }

    /// The seat of `agent` is free again: the agent plays its brain until a bot joins.
    fn vacate(&mut self, agent: usize) {
        self.seats[agent] = None;
        self.set_controlled(agent, false);
    }

    fn said(
        &mut self,
        agent: usize,
        conn: Conn,
        said: Result<ClientMessage, Unreadable>,
        now: Duration,
    ) {
        if !self.seated_at(agent, conn) {
            return; // a replaced or closed connection
        }
        // A command is read once: its tick, what it asks, and whether its tick is in
        // the window (only then may it act, or answer a perception).
        let (now_tick, every) = (self.session.world.tick(), self.perceive_every);
        let said = said.map(|ClientMessage::Command { tick, action }| {
            (tick, action, in_window(tick, now_tick, every))
        });
        let seat = self.seats[agent].as_mut().expect("seated");
        let answers = match &said {
            Ok((tick, _, Ok(()))) => seat.settle(*tick),
            _ => false,
        };
        if !answers {
            match seat.budget.charge(now) {
                Verdict::Take => {}
                Verdict::Refuse { warn } => {
                    if warn {
                        let why = "too many messages; slow down or be disconnected";
                        self.tell(conn, "rate_limited", why);
                    }
                    return;
                }
                Verdict::Flooding => {
                    let why = Close::Flooding;
                    self.transmits.push_back(Transmit::Close { conn, why });
                    return self.vacate(agent);
                }
            }
        }
        match said {
            Ok((_, action, Ok(()))) => self.command(agent, conn, &action),
            Ok((_, _, Err((code, text)))) => self.tell(conn, code, &text),
            Err((code, message)) => self.tell(conn, code, &message),
        }
    }

    /// A command whose tick is in the window, for the world.
    fn command(&mut self, agent: usize, conn: Conn, action: &Action) {
        let now = self.session.world.tick();
        // Any command in the window answers its tick, even one the world rejects:
        // lockstep waits for bots to speak, not to be right.
        match self.session.world.command(agent, action) {
            Ok(()) => {
                let record = replay::command_record(now, &self.agent_ids[agent], action);
                self.outputs.push_back(Output::Log(record));
            }
            Err(reason) => self.tell(conn, "rejected", &reason),
        }
    }

    /// Whether a bot plays any agent.
    fn seated(&self) -> bool {
        self.seats.iter().any(Option::is_some)
    }

    /// Whether no seated bot owes the perception of the tick the world is at.
    fn all_answered(&self) -> bool {
        let tick = self.session.world.tick();
        self.seats.iter().flatten().all(|s| !s.owed.contains(&tick))
    }

    /// Plays one tick at `now`: its frame if one is due, then perceptions for the bots
    /// (and, in lockstep, a wait for their answers), then the end if the world finished.
    fn tick_at(&mut self, now: Duration) {
        self.waiting_until = None;
        let frame = self.session.step();
        let tick = self.session.world.tick();
        self.ticked = tick;
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
            self.end(EndReason::Finished);
        }
    }

    fn perceive(&mut self) {
        let world = &self.session.world;
        let (tick, time_s) = (world.tick(), world.time_s());
        for (agent, seat) in self.seats.iter_mut().enumerate() {
            let Some(seat) = seat else { continue };
            let text = encode(&Perception {
                kind: tags::Perception,
                tick,
                time_s,
                agent: &self.agent_ids[agent],
                perception: world.perception(agent),
            });
            seat.owe(tick);
            let conn = seat.conn;
            self.transmits
                .push_back(Transmit::Perception { conn, tick, text });
        }
    }

    /// An `error` for connection `conn`.
    fn tell(&mut self, conn: Conn, code: &'static str, message: &str) {
        let text = encode(&ErrorMessage::new(code, message));
        self.transmits
            .push_back(Transmit::Error { conn, code, text });
    }

    fn set_controlled(&mut self, agent: usize, by_bot: bool) {
        self.session.world.set_controlled(agent, by_bot);
        let tick = self.session.world.tick();
        let record = replay::control_record(tick, &self.agent_ids[agent], by_bot);
        self.outputs.push_back(Output::Log(record));
    }

    /// The end: the last frame if anything happened since the previous one, then the
    /// `end` message, encoded once.
    fn end(&mut self, reason: EndReason) {
        self.ended = true;
        self.waiting_until = None;
        let session = &mut self.session;
        let read = catch_unwind(AssertUnwindSafe(|| {
            let frame = session.last_frame();
            (session.world.tick(), session.world.result(), frame)
        }));
        let (tick, result) = match read {
            Ok((tick, result, frame)) => {
                if let Some(frame) = frame {
                    self.outputs.push_back(Output::Frame { tick, frame });
                }
                (tick, Some(result))
            }
            Err(_) => (self.ticked, None),
        };
        let message = encode(&End {
            kind: tags::End,
            match_id: session.id(),
            tick,
            reason: reason.as_str(),
            result: result.as_ref(),
        });
        self.outputs.push_back(Output::End(Ending {
            tick,
            reason,
            result,
            message,
        }));
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
    use super::{
        in_window, BotEvent, BotLimits, Close, Conn, EndReason, MatchDriver, Output, Transmit, Wake,
    };
    use crate::protocol::ClientMessage;
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

    /// A bot may send 20 messages a second, 10 at once (answers to perceptions aside).
    const LIMITS: BotLimits = BotLimits {
        messages_per_second: 20,
        burst: 10,
    };

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
        MatchDriver::new(session, &scenario, LIMITS)
    }

    fn outputs(d: &mut MatchDriver) -> Vec<Output> {
        std::iter::from_fn(|| d.poll_output()).collect()
    }

    fn sent(d: &mut MatchDriver) -> Vec<Transmit> {
        std::iter::from_fn(|| d.poll_transmit()).collect()
    }

    fn tick(d: &MatchDriver) -> u64 {
        d.tick()
    }

    fn join(agent: usize, conn: u64) -> BotEvent {
        BotEvent::Join {
            agent,
            conn: Conn(conn),
        }
    }

    fn leave(agent: usize, conn: u64) -> BotEvent {
        BotEvent::Leave {
            agent,
            conn: Conn(conn),
        }
    }

    fn command(agent: usize, conn: u64, tick: u64, action: Action) -> BotEvent {
        BotEvent::Said {
            agent,
            conn: Conn(conn),
            said: Ok(ClientMessage::Command { tick, action }),
        }
    }

    fn stand(agent: usize, conn: u64, tick: u64) -> BotEvent {
        command(agent, conn, tick, Action::Stand {})
    }

    /// The perceptions sent: (conn, tick).
    fn perceptions(sent: &[Transmit]) -> Vec<(u64, u64)> {
        sent.iter()
            .filter_map(|t| match t {
                Transmit::Perception { conn, tick, .. } => Some((conn.0, *tick)),
                _ => None,
            })
            .collect()
    }

    /// The errors sent: (conn, code), each checked to be the `error` message it says.
    fn errors(sent: &[Transmit]) -> Vec<(u64, &'static str)> {
        sent.iter()
            .filter_map(|t| match t {
                Transmit::Error { conn, code, text } => {
                    let v: Value = serde_json::from_str(text).unwrap();
                    assert_eq!(
                        (v["type"].as_str(), v["code"].as_str()),
                        (Some("error"), Some(*code))
                    );
                    Some((conn.0, *code))
                }
                _ => None,
            })
            .collect()
    }

    fn closes(sent: &[Transmit]) -> Vec<(u64, Close)> {
        sent.iter()
            .filter_map(|t| match t {
                Transmit::Close { conn, why } => Some((conn.0, *why)),
                _ => None,
            })
            .collect()
    }

    /// The `end` among `outputs`, as its message says it.
    fn ended(outputs: &[Output]) -> Option<Value> {
        outputs.iter().find_map(|o| match o {
            Output::End(ending) => {
                let end: Value = serde_json::from_str(&ending.message).unwrap();
                assert_eq!(end["reason"], ending.reason.as_str());
                assert_eq!(end["tick"], ending.tick);
                Some(end)
            }
            _ => None,
        })
    }

    /// The controller of agent `k` in the frames among `outputs` (the last one).
    fn controller(outputs: &[Output], k: usize) -> Option<Option<Value>> {
        outputs.iter().rev().find_map(|o| match o {
            Output::Frame { frame, .. } => {
                let f: Value = serde_json::from_str(frame).unwrap();
                Some(f["agents"][k].get("controller").cloned())
            }
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
            assert!(sent(&mut d).is_empty());
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
        d.handle(join(0, 1), Duration::ZERO);
        d.handle(join(1, 2), Duration::ZERO);
        // With bots seated, a tick that owes them nothing plays at once.
        assert_eq!(d.poll_timeout(), Wake::Now);
        d.handle_timeout(10 * MS);
        outputs(&mut d);
        assert_eq!(perceptions(&sent(&mut d)), vec![(1, 1), (2, 1)]);
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
        assert_eq!(perceptions(&sent(&mut d)), vec![(1, 2), (2, 2)]);
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
        d.handle(command(1, 2, 2, Action::Shoot {}), 15 * MS);
        assert_eq!(tick(&d), 3);
        assert_eq!(errors(&sent(&mut d)), vec![(2, "rejected")]);
    }

    #[test]
    fn lockstep_ticks_at_the_deadline_when_a_bot_is_silent() {
        let mut d = lockstep_with_two_bots();
        d.handle(stand(0, 1, 1), 20 * MS);
        d.handle_timeout(409 * MS);
        assert_eq!(tick(&d), 1);
        d.handle_timeout(410 * MS);
        assert_eq!(tick(&d), 2);
        assert!(
            !outputs(&mut d).contains(&Output::Overrun),
            "a wait is not an overrun"
        );
        assert_eq!(perceptions(&sent(&mut d)), vec![(1, 2), (2, 2)]);
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
        MatchDriver::new(session, &scenario, LIMITS)
    }

    #[test]
    fn lockstep_plays_the_ticks_between_perceptions_at_once_and_waits_only_for_its_bots() {
        let mut d = basketball_lockstep();
        assert_eq!(d.perceive_every, 15);
        // No bot yet: real time, for the spectators.
        assert_eq!(d.poll_timeout(), Wake::At(d.period));
        d.handle(join(0, 1), MS);
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
            assert!(!outputs(&mut d).contains(&Output::Overrun));
            assert_eq!(perceptions(&sent(&mut d)), vec![(1, tick)]);
            // The answer plays the next tick at once, whatever the clock says.
            d.handle(stand(0, 1, tick), now);
            assert_eq!(self::tick(&d), tick + 1);
        }
        // The bot gone, real time again: a period after the last tick.
        d.handle(leave(0, 1), now);
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
        d.handle(join(0, 7), 50 * MS);
        d.handle_timeout(60 * MS);
        assert_eq!(d.poll_timeout(), Wake::At(460 * MS));
        d.handle(leave(0, 7), 70 * MS);
        assert_eq!(tick(&d), 7);
        assert_eq!(d.poll_timeout(), Wake::At(80 * MS));
    }

    #[test]
    fn stale_and_future_ticks_are_refused_and_answer_nothing() {
        let mut d = lockstep_with_two_bots();
        // Perceptions every tick: at tick 1 the window is ticks 0 to 2.
        d.handle(stand(0, 1, 3), 20 * MS);
        d.handle(stand(1, 2, 2), 20 * MS);
        assert_eq!(errors(&sent(&mut d)), vec![(1, "future_tick")]);
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
        sent(&mut d);
        // At tick 8 the window is ticks 4 to 9.
        d.handle(stand(0, 1, 3), 3000 * MS);
        d.handle(stand(1, 2, 8), 3000 * MS);
        assert_eq!(tick(&d), 8, "cf's stale command answers nothing");
        assert_eq!(errors(&sent(&mut d)), vec![(1, "stale_tick")]);
        let out = outputs(&mut d);
        assert!(
            !out.iter()
                .any(|o| matches!(o, Output::Log(r) if r.contains("\"cf\""))),
            "a refused command is not logged: {out:?}"
        );
        // An old tick still in the window acts, but does not answer tick 8.
        d.handle(stand(0, 1, 4), 3000 * MS);
        assert_eq!(tick(&d), 8);
        assert!(errors(&sent(&mut d)).is_empty());
        d.handle(stand(0, 1, 8), 3000 * MS);
        assert_eq!(tick(&d), 9);
    }

    #[test]
    fn a_second_join_replaces_the_first() {
        let mut d = lockstep_with_two_bots();
        d.handle(join(0, 3), 20 * MS);
        let out = sent(&mut d);
        assert_eq!(errors(&out), vec![(1, "replaced")]);
        assert_eq!(closes(&out), vec![(1, Close::Replaced)]);
        assert!(
            matches!(out.last(), Some(Transmit::Close { .. })),
            "the close comes last"
        );
        assert_eq!(
            outputs(&mut d),
            vec![Output::Log(crate::replay::control_record(1, "cf", true))]
        );
        // The old connection's commands and leave are ignored: they neither act, nor
        // answer, nor free the seat, nor are charged.
        for _ in 0..100 {
            d.handle(stand(0, 1, 1), 21 * MS);
        }
        d.handle(leave(0, 1), 22 * MS);
        assert_eq!((outputs(&mut d), sent(&mut d)), (vec![], vec![]));
        // The new connection was sent no perception yet, so it owes none: lf's answer
        // plays the tick, and the next perception goes to the new one.
        d.handle(stand(1, 2, 1), 23 * MS);
        assert_eq!(tick(&d), 2);
        assert_eq!(perceptions(&sent(&mut d)), vec![(3, 2), (2, 2)]);
        d.handle(stand(1, 2, 2), 24 * MS);
        assert_eq!(tick(&d), 2, "waits for the new connection");
        d.handle(stand(0, 3, 2), 24 * MS);
        assert_eq!(tick(&d), 3);
        let logs = outputs(&mut d);
        assert!(logs.contains(&Output::Log(crate::replay::command_record(
            2,
            "cf",
            &Action::Stand {}
        ))));
    }

    #[test]
    fn leaving_returns_the_agent_to_its_brain() {
        let mut d = driver("realtime", json!({}));
        d.handle(join(0, 5), Duration::ZERO);
        assert_eq!(
            outputs(&mut d),
            vec![Output::Log(crate::replay::control_record(0, "cf", true))]
        );
        d.handle_timeout(10 * MS);
        assert_eq!(perceptions(&sent(&mut d)), vec![(5, 1)]);
        d.handle_timeout(20 * MS);
        let frames = outputs(&mut d);
        assert_eq!(
            controller(&frames, 0),
            Some(Some(json!("bot"))),
            "the frame says so"
        );
        assert_eq!(perceptions(&sent(&mut d)), vec![(5, 2)]);
        d.handle(leave(0, 5), 25 * MS);
        assert_eq!(
            outputs(&mut d),
            vec![Output::Log(crate::replay::control_record(2, "cf", false))]
        );
        d.handle_timeout(30 * MS);
        d.handle_timeout(40 * MS);
        let frames = outputs(&mut d);
        assert_eq!(
            controller(&frames, 0),
            Some(None),
            "the built-in brain plays cf again"
        );
        assert!(sent(&mut d).is_empty());
        // Its commands are no one's now.
        d.handle(stand(0, 5, 4), 45 * MS);
        assert_eq!((outputs(&mut d), sent(&mut d)), (vec![], vec![]));
    }

    #[test]
    fn answers_pass_free_and_anything_else_pays_until_a_flood_closes_the_connection() {
        let mut d = lockstep_with_two_bots();
        // 300 answers in 3 s of match time, 5 times the 20 a second allowed: all free.
        for k in 1..=300u64 {
            let now = k * 10 * MS.as_millis() as u64;
            let now = Duration::from_millis(now);
            d.handle(stand(0, 1, k), now);
            d.handle(stand(1, 2, k), now);
            assert_eq!(tick(&d), k + 1);
            let out = sent(&mut d);
            assert!(errors(&out).is_empty(), "{out:?}");
        }
        outputs(&mut d);
        // What is not an answer pays: a second command for the same tick, an unreadable
        // message. The burst of 10 is taken, the 11th refused with a warning, once.
        let at = 3010 * MS;
        let garbage = || BotEvent::Said {
            agent: 0,
            conn: Conn(1),
            said: Err(("bad_json", "expected value at line 1 column 1".into())),
        };
        d.handle(garbage(), at);
        for _ in 0..9 {
            d.handle(stand(0, 1, 300), at);
        }
        let out = sent(&mut d);
        assert_eq!(
            errors(&out),
            vec![(1, "bad_json")],
            "the unreadable one is answered"
        );
        assert_eq!(outputs(&mut d).len(), 9, "the paid commands act");
        for _ in 0..5 {
            d.handle(garbage(), at);
        }
        assert_eq!(
            errors(&sent(&mut d)),
            vec![(1, "rate_limited")],
            "dropped, warned once"
        );
        // A whole burst past the budget: flooding, closed, the agent back to its brain.
        for _ in 0..6 {
            d.handle(garbage(), at);
        }
        let out = sent(&mut d);
        assert_eq!(closes(&out), vec![(1, Close::Flooding)]);
        assert_eq!(
            outputs(&mut d),
            vec![Output::Log(crate::replay::control_record(301, "cf", false))]
        );
        // Its later messages and its leaving are ignored; lf plays on.
        d.handle(garbage(), at);
        d.handle(leave(0, 1), at);
        assert_eq!((outputs(&mut d), sent(&mut d)), (vec![], vec![]));
        d.handle(stand(1, 2, 301), at);
        assert_eq!(tick(&d), 302, "only lf is waited for");
    }

    #[test]
    fn a_stop_frames_what_is_unframed_then_ends_once_and_nothing_follows() {
        let mut d = lockstep_with_two_bots();
        d.stop(EndReason::Deleted);
        let out = outputs(&mut d);
        // Tick 1 had no frame (frames every other tick): the end brings it.
        assert!(
            matches!(&out[..], [Output::Frame { tick: 1, .. }, Output::End(_)]),
            "{out:?}"
        );
        let end = ended(&out).unwrap();
        assert_eq!(
            (&end["type"], &end["match"], &end["reason"], &end["tick"]),
            (&json!("end"), &json!("m"), &json!("deleted"), &json!(1))
        );
        assert!(end["result"].is_object(), "{end}");
        // Nothing happens after the end, a second stop included.
        d.stop(EndReason::Shutdown);
        d.handle(stand(0, 1, 1), 21 * MS);
        d.handle(join(2, 9), 21 * MS);
        d.handle_timeout(5000 * MS);
        assert_eq!(
            (tick(&d), outputs(&mut d), sent(&mut d)),
            (1, vec![], vec![])
        );
    }

    #[test]
    fn a_finished_world_ends_the_match_as_finished() {
        let mut d = driver("fast", json!({"duration_s": 0.5}));
        let mut last = vec![];
        while !last.iter().any(|o| matches!(o, Output::End(_))) {
            assert_eq!(d.poll_timeout(), Wake::Now);
            d.handle_timeout(Duration::ZERO);
            last = outputs(&mut d);
        }
        assert_eq!(tick(&d), 50);
        assert_eq!(ended(&last).unwrap()["reason"], "finished");
        // The last tick's frame is published before the end, and not twice.
        assert!(matches!(
            &last[..],
            [
                Output::Ticked { tick: 50 },
                Output::Frame { tick: 50, .. },
                Output::End(_)
            ]
        ));
    }

    /// What a property test does to a driver: wait, or a bot connection does something.
    #[derive(Debug, Clone)]
    enum Step {
        Wait {
            ms: u64,
        },
        Join {
            agent: usize,
            conn: u64,
        },
        Leave {
            agent: usize,
            conn: u64,
        },
        /// A command for the world's tick plus `lag` (−2 to 1: stale-ish to future, all
        /// in the window at one perception a tick).
        Answer {
            agent: usize,
            conn: u64,
            lag: i64,
        },
        Garbage {
            agent: usize,
            conn: u64,
        },
        Stop,
    }

    fn step() -> impl proptest::strategy::Strategy<Value = Step> {
        use proptest::prelude::*;
        let who = (0..2usize, 1..4u64);
        prop_oneof![
            4 => (0..600u64).prop_map(|ms| Step::Wait { ms }),
            2 => who.clone().prop_map(|(agent, conn)| Step::Join { agent, conn }),
            1 => who.clone().prop_map(|(agent, conn)| Step::Leave { agent, conn }),
            6 => (who.clone(), -2..2i64).prop_map(|((agent, conn), lag)| Step::Answer { agent, conn, lag }),
            2 => who.prop_map(|(agent, conn)| Step::Garbage { agent, conn }),
            1 => Just(Step::Stop),
        ]
    }

    /// What the test knows of the match from outside: who sits where (by what it told
    /// the driver and what the driver closed), and the perception each seated
    /// connection was last sent and has not answered, with when.
    #[derive(Default)]
    struct Model {
        seats: [Option<u64>; 2],
        owed: std::collections::HashMap<u64, (u64, Duration)>,
        closed: std::collections::HashSet<u64>,
        ticks: u64,
        ended: bool,
    }

    impl Model {
        fn seated(&self, conn: u64) -> bool {
            self.seats.contains(&Some(conn))
        }

        /// Checks what the driver did at `now` against the invariants, and follows it.
        fn follow(
            &mut self,
            d: &mut MatchDriver,
            now: Duration,
            lockstep: bool,
            replaced: Option<u64>,
        ) {
            let (out, sent) = (outputs(d), sent(d));
            if let Some(old) = replaced.filter(|_| !self.ended) {
                let why = Close::Replaced;
                assert!(
                    sent.contains(&Transmit::Close {
                        conn: Conn(old),
                        why
                    }),
                    "{old} not closed"
                );
            }
            if self.ended {
                assert_eq!((out.len(), sent.len()), (0, 0), "nothing after the end");
                return;
            }
            // Closes first: a seat a flood vacated is waited for no more on this step.
            for t in &sent {
                let (Transmit::Perception { conn, .. }
                | Transmit::Error { conn, .. }
                | Transmit::Close { conn, .. }) = t;
                assert!(!self.closed.contains(&conn.0), "{t:?} after its close");
                assert!(
                    self.seated(conn.0) || replaced == Some(conn.0),
                    "{t:?} to no seat"
                );
                if let Transmit::Close { conn, why } = t {
                    self.closed.insert(conn.0);
                    self.owed.remove(&conn.0);
                    if *why == Close::Flooding {
                        let seat = self.seats.iter_mut().find(|s| **s == Some(conn.0));
                        *seat.expect("a flooding bot is seated") = None;
                    }
                }
            }
            for o in &out {
                match o {
                    Output::Ticked { tick } => {
                        assert_eq!(*tick, self.ticks + 1, "ticks go one by one");
                        self.ticks = *tick;
                        if lockstep {
                            // A tick after a perception waited for every seated bot's
                            // answer or for the deadline.
                            for (conn, (owed, at)) in &self.owed {
                                if *owed == tick - 1 && self.seated(*conn) {
                                    assert!(now >= *at + 400 * MS, "tick {tick} at {now:?} without {conn}'s answer to {owed} (sent {at:?})");
                                }
                            }
                        }
                    }
                    Output::End(_) => {
                        assert!(
                            matches!(out.last(), Some(Output::End(_))),
                            "the end is last"
                        );
                        self.ended = true;
                    }
                    _ => {}
                }
            }
            // Then the perceptions of the tick just played.
            for t in &sent {
                if let Transmit::Perception { conn, tick, .. } = t {
                    self.owed.insert(conn.0, (*tick, now));
                }
            }
            if lockstep && !self.ended {
                // A wait is only ever for a seated bot that owes the perception of now.
                let owes = self
                    .owed
                    .iter()
                    .any(|(c, (t, _))| *t == d.tick() && self.seated(*c));
                if let Wake::At(_) = d.poll_timeout() {
                    assert!(
                        owes || self.seats.iter().all(Option::is_none),
                        "waits for no one"
                    );
                }
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        #[test]
        fn any_sequence_keeps_ticks_seats_answers_and_the_end_in_order(
            lockstep in proptest::bool::ANY,
            steps in proptest::collection::vec(step(), 1..80),
        ) {
            let mut d = driver(if lockstep { "lockstep" } else { "realtime" }, json!({}));
            let mut model = Model::default();
            let mut now = Duration::ZERO;
            for step in steps {
                let mut replaced = None;
                match step {
                    Step::Wait { ms } => {
                        // A shell woken every 7 ms, early or late, and at once while
                        // the driver says a tick is due.
                        let until = now + Duration::from_millis(ms);
                        while now < until && !model.ended {
                            now = (now + 7 * MS).min(until);
                            d.handle_timeout(now);
                            model.follow(&mut d, now, lockstep, None);
                            let due = |d: &MatchDriver| match d.poll_timeout() {
                                Wake::Now => true,
                                Wake::At(at) => at <= now,
                            };
                            while !model.ended && due(&d) {
                                d.handle_timeout(now);
                                model.follow(&mut d, now, lockstep, None);
                            }
                        }
                    }
                    Step::Join { agent, conn } => {
                        if model.closed.contains(&conn) || model.seats.iter().enumerate().any(|(k, s)| k != agent && *s == Some(conn)) {
                            continue; // the shell numbers each connection once
                        }
                        replaced = model.seats[agent].filter(|&old| old != conn);
                        d.handle(join(agent, conn), now);
                        if !model.ended {
                            if let Some(old) = replaced {
                                model.owed.remove(&old);
                            }
                            model.seats[agent] = Some(conn);
                        }
                    }
                    Step::Leave { agent, conn } => {
                        d.handle(leave(agent, conn), now);
                        if model.seats[agent] == Some(conn) && !model.ended {
                            model.seats[agent] = None;
                            model.owed.remove(&conn);
                        }
                    }
                    Step::Answer { agent, conn, lag } => {
                        let tick = d.tick().saturating_add_signed(lag);
                        d.handle(stand(agent, conn, tick), now);
                        if model.seats[agent] == Some(conn) {
                            if let Some((owed, _)) = model.owed.get(&conn) {
                                if *owed <= tick {
                                    model.owed.remove(&conn);
                                }
                            }
                        }
                    }
                    Step::Garbage { agent, conn } => {
                        let said = Err(("bad_json", "not JSON".to_owned()));
                        d.handle(BotEvent::Said { agent, conn: Conn(conn), said }, now);
                    }
                    Step::Stop => d.stop(EndReason::Deleted),
                }
                model.follow(&mut d, now, lockstep, replaced);
            }
        }
    }
}
