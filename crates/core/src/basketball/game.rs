//! The game as a deterministic state machine: [`Game::step`] advances one tick and
//! reports what happened. No clock and no I/O; all chance comes from one seeded RNG, so
//! the same parameters give the same game, bit for bit.
//!
//! A possession starts from random positions (seeded per possession, so two offenses
//! can be compared on the same starts):
//! * the ball handler at x ∈ [8, 12] m, z ∈ [−5, 5] m, facing the basket;
//! * each other offensive player at x ∈ [5, 10] m, 2–6.5 m to the other side of the
//!   basket's axis, facing the basket;
//! * each defender 3 m from the offensive player it starts on (the k-th defender on the
//!   k-th player), toward the basket, facing that player.
//!
//! It ends with a shot (made, missed or blocked), a steal, an intercepted pass, or the
//! shot clock. There are no rebounds: a missed shot ends the possession.

use super::agent::{Agent, Team};
use super::capability::Capabilities;
use super::decision::Candidate;
use super::event::{
    BallState, BallView, Event, Outcome, PassCaught, PlayerView, PoseBlend, PossessionEnded, Shot,
    Snapshot,
};
use super::params::GameParams;
use crate::tags;
use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;

/// How far a defender starts from the player it marks, toward the basket, m: outside
/// the `simple` offense's passing radius, so the defender has to come and press.
const DEFENDER_START_M: f64 = 3.0;
/// The first random stream of possessions' play; streams below it are the starts'
/// (`2 + possession`), so the two never share one.
const OUTCOME_STREAMS: u64 = 1 << 48;
/// The random draws of possession `possession`'s play (shots, steals, blocks).
fn play_draws(seed: u64, possession: u64) -> ChaCha8Rng {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(OUTCOME_STREAMS + possession);
    rng
}

/// Height of the ring above the floor, m.
const RING_HEIGHT_M: f64 = 3.05;

#[derive(Debug, Clone, Copy)]
pub(super) enum Ball {
    Held {
        by: usize,
    },
    Pass {
        from: usize,
        to: usize,
        at: DVec2,
        /// Defenders (bit k for agent k) that have already tried to intercept it.
        tried: u64,
    },
    /// Away: the outcome is settled; the ball flies to the ring for the spectators.
    Shot {
        from: DVec2,
        released_s: f64,
        flight_s: f64,
        outcome: Outcome,
        points: u32,
    },
}

/// A game in progress: the court, the agents, the ball, the score and the random draws;
/// [`Game::step`] plays it one tick on.
pub struct Game {
    pub(super) caps: Arc<Capabilities>,
    pub(super) params: GameParams,
    pub(super) agents: Vec<Agent>,
    pub(super) ball: Ball,
    tick: u64,
    possession: u64,
    possession_start_s: f64,
    pub(super) shot_clock_s: f64,
    score: u32,
    passes: u32,
    /// Defenders that have tried to block the shot being taken.
    blocks_tried: u64,
    rng: ChaCha8Rng,
    /// Reused by every decision, so deciding does not allocate.
    pub(super) candidates: Vec<Candidate>,
    /// Each agent's last decision (action, square), to report only changes.
    pub(super) last_decision: Vec<Option<(super::agent::Action, Option<[f64; 2]>)>>,
    /// Agent names: offense first, then defense.
    names: Vec<String>,
    /// Agents a bot controls: they follow `orders` instead of a brain.
    pub(super) controlled: Vec<bool>,
    pub(super) orders: Vec<Option<Order>>,
    /// The target of each bot-controlled agent's `move_to` while it is in force: a move
    /// can end short of it (the map's way there left the court, or the target lay beyond
    /// the map), and the agent heads on from where it got to.
    pub(super) targets: Vec<Option<DVec2>>,
    /// Fixed starting positions, where a scenario gives them (else drawn each possession).
    starts: Vec<Option<DVec2>>,
}

/// What a bot may tell its agent to do; carried out on the next tick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Order {
    /// Move (dribbling with the ball, running without) toward a point on the court.
    MoveTo(DVec2),
    /// Pass to the teammate with this agent index.
    Pass {
        /// The teammate's agent index (offense first, then defense).
        to: usize,
    },
    /// Shoot from where the agent stands; it must have the ball.
    Shoot,
    /// Stop the current move and stand.
    Stand,
}

impl Game {
    /// A game whose agents are called o1, o2, ... and d1, d2, ...
    pub fn new(caps: Arc<Capabilities>, params: GameParams) -> Game {
        let names = (0..params.offense_players)
            .map(|k| format!("o{}", k + 1))
            .chain((0..params.defenders).map(|k| format!("d{}", k + 1)))
            .collect();
        Game::named(caps, params, names)
    }

    /// A game whose agents have the given names, offense first.
    ///
    /// # Panics
    /// If there is not one name per agent.
    pub fn named(caps: Arc<Capabilities>, params: GameParams, names: Vec<String>) -> Game {
        let agents = params.offense_players + params.defenders;
        assert_eq!(names.len(), agents, "one name per agent");
        let mut game = Game {
            caps,
            params,
            agents: Vec::new(),
            ball: Ball::Held { by: 0 },
            tick: 0,
            possession: 0,
            possession_start_s: 0.0,
            shot_clock_s: params.shot_clock_s,
            score: 0,
            passes: 0,
            blocks_tried: 0,
            // Replaced at every possession's start (see `start_possession`).
            rng: play_draws(params.seed, 0),
            candidates: Vec::new(),
            last_decision: Vec::new(),
            names,
            controlled: vec![false; agents],
            orders: vec![None; agents],
            targets: vec![None; agents],
            starts: vec![None; agents],
        };
        game.start_possession();
        game
    }

    pub(crate) fn params(&self) -> &GameParams {
        &self.params
    }

    pub(crate) fn agents(&self) -> &[Agent] {
        &self.agents
    }

    pub(crate) fn tick(&self) -> u64 {
        self.tick
    }

    pub(crate) fn time_s(&self) -> f64 {
        self.tick as f64 / self.params.tick_hz
    }

    /// Possessions finished so far.
    pub fn possessions(&self) -> u64 {
        self.possession
    }

    /// Points the offense has scored so far.
    pub fn score(&self) -> u32 {
        self.score
    }

    /// Starts every possession with these agents (index, offense first) at these points
    /// instead of random ones; the game restarts its first possession.
    pub fn with_starts(mut self, starts: Vec<Option<DVec2>>) -> Game {
        assert_eq!(starts.len(), self.starts.len(), "one start per agent");
        self.starts = starts;
        self.start_possession();
        self
    }

    /// Hands agent `k` to a bot (`true`) or back to its brain.
    pub fn set_controlled(&mut self, k: usize, by_bot: bool) {
        self.controlled[k] = by_bot;
        self.orders[k] = None;
        self.targets[k] = None;
    }

    pub(crate) fn is_controlled(&self, k: usize) -> bool {
        self.controlled[k]
    }

    /// Accepts a bot's order for agent `k`, or says why it is impossible now. The order
    /// is carried out on the next tick.
    pub fn order(&mut self, k: usize, order: Order) -> Result<(), String> {
        let agent = &self.agents[k];
        let holds = self.holder() == Some(k);
        match order {
            Order::MoveTo(p) => {
                if !p.is_finite() {
                    return Err("the target is not a finite point".into());
                }
                let court = self.params.court;
                // A metre's grace beyond the lines: a body near one may aim past it.
                if court.clamp(p).distance(p) > 1.0 {
                    return Err(format!(
                        "the target ({:.1}, {:.1}) is off the court (x 0 to {} m, z ±{} m)",
                        p.x,
                        p.y,
                        court.length_m,
                        court.width_m / 2.0
                    ));
                }
            }
            Order::Pass { to } => {
                if !holds {
                    return Err(format!("{} does not have the ball", agent.id));
                }
                if to == k || self.agents.get(to).is_none_or(|a| a.team != Team::Offense) {
                    return Err("a pass goes to a teammate".into());
                }
            }
            Order::Shoot if !holds => {
                return Err(format!("{} does not have the ball", agent.id));
            }
            Order::Shoot | Order::Stand => {}
        }
        if agent.shooting_s.is_some() {
            return Err(format!("{} is taking a shot", agent.id));
        }
        self.orders[k] = Some(order);
        Ok(())
    }

    /// The behaviour an agent moves with now: the ball handler dribbles, other
    /// offensive players run, defenders use their footwork.
    pub fn behaviour_of(&self, agent: usize) -> &'static str {
        match self.agents[agent].team {
            Team::Defense => self.params.defender.motion.name(),
            Team::Offense if self.holder() == Some(agent) => "dribble",
            Team::Offense => "run",
        }
    }

    /// The agent index of the one holding the ball, if any.
    pub fn holder(&self) -> Option<usize> {
        match self.ball {
            Ball::Held { by } => Some(by),
            _ => None,
        }
    }

    pub(super) fn ball_position(&self) -> DVec2 {
        match self.ball {
            Ball::Held { by } => self.agents[by].pose.position,
            Ball::Pass { at, .. } => at,
            Ball::Shot { .. } => self.params.court.basket,
        }
    }

    /// Whether agent `k` has the ball or a pass on its way to it: it must not leave the
    /// court.
    pub(super) fn has_or_awaits_ball(&self, k: usize) -> bool {
        self.holder() == Some(k) || matches!(self.ball, Ball::Pass { to, .. } if to == k)
    }

    /// Defenders' agent indices: agents are offense first, then defense.
    pub(super) fn defenders(&self) -> std::ops::Range<usize> {
        self.params.offense_players..self.agents.len()
    }

    /// Advances one tick, appending what happened to `events`.
    pub fn step(&mut self, events: &mut Vec<Event>) {
        let dt = 1.0 / self.params.tick_hz;
        self.tick += 1;
        let now = self.time_s();
        let data_frames = dt * self.caps.run.map().fps;
        if let Ball::Shot {
            released_s,
            flight_s,
            outcome,
            points,
            ..
        } = self.ball
        {
            for a in &mut self.agents {
                a.advance(data_frames);
            }
            if now >= released_s + flight_s {
                let duration = released_s - self.possession_start_s;
                self.end_possession(outcome, points, duration, events);
            }
            return;
        }
        self.shot_clock_s -= dt;
        self.plan(now, events);
        for a in &mut self.agents {
            a.advance(data_frames);
        }
        if self.take_shot(dt, now, events) || self.move_ball(dt, now, events) {
            return;
        }
        if self.try_steals(now, events) {
            return;
        }
        if self.shot_clock_s <= 0.0 {
            let duration = now - self.possession_start_s;
            self.end_possession(Outcome::ShotClock, 0, duration, events);
        }
    }

    /// A shot being taken: the defender's block attempts, then the release. True if the
    /// possession's outcome is now settled.
    fn take_shot(&mut self, dt: f64, now: f64, events: &mut Vec<Event>) -> bool {
        let Some(shooter) = self.holder() else {
            return false;
        };
        let Some(left) = self.agents[shooter].shooting_s else {
            return false;
        };
        let at = self.agents[shooter].pose.position;
        let court = self.params.court;
        let distance_m = court.distance_to_basket(at);
        let success = court.shot_success(&self.params.shot, at);
        let shot_event = |made: bool, blocked: bool, points: u32, id: &str| {
            Event::Shot(Shot {
                blocked,
                by: id.to_string(),
                distance_m,
                from: at.to_array(),
                kind: tags::Shot,
                made,
                points,
                success,
            })
        };
        for d in self.defenders() {
            let bit = 1u64 << d.min(63);
            if self.blocks_tried & bit == 0
                && self.agents[d].pose.position.distance(at) <= self.params.defender.reach_m
            {
                self.blocks_tried |= bit;
                if self.rng.gen_bool(self.params.defender.block_success) {
                    events.push(shot_event(false, true, 0, &self.agents[shooter].id));
                    let duration = now - self.possession_start_s;
                    self.end_possession(Outcome::Blocked, 0, duration, events);
                    return true;
                }
            }
        }
        let left = left - dt;
        if left > 0.0 {
            self.agents[shooter].shooting_s = Some(left);
            return false;
        }
        let made = self.rng.gen_bool(success);
        let points = if made { court.points(at) } else { 0 };
        events.push(shot_event(made, false, points, &self.agents[shooter].id));
        self.agents[shooter].shooting_s = None;
        self.ball = Ball::Shot {
            from: at,
            released_s: now,
            flight_s: distance_m / self.params.shot_speed_m_s,
            outcome: if made { Outcome::Made } else { Outcome::Missed },
            points,
        };
        true
    }

    /// A pass in flight: toward the receiver's current position, past the defenders'
    /// hands. True if it was intercepted (the possession is over).
    fn move_ball(&mut self, dt: f64, now: f64, events: &mut Vec<Event>) -> bool {
        let Ball::Pass {
            from,
            to,
            at,
            mut tried,
        } = self.ball
        else {
            return false;
        };
        let target = self.agents[to].pose.position;
        let travel = self.params.pass_speed_m_s * dt;
        let gap = target - at;
        if gap.length() <= travel.max(0.3) {
            self.ball = Ball::Held { by: to };
            let receiver = &mut self.agents[to];
            receiver.not_before_s = now + 1.0;
            receiver.next_plan_s = now;
            events.push(Event::PassCaught(PassCaught {
                by: receiver.id.clone(),
                kind: tags::PassCaught,
            }));
            return false;
        }
        let at = at + gap / gap.length() * travel;
        for d in self.defenders() {
            let bit = 1u64 << d.min(63);
            if tried & bit == 0
                && self.agents[d].pose.position.distance(at) <= self.params.defender.reach_m
            {
                tried |= bit;
                if self.rng.gen_bool(self.params.defender.steal_success) {
                    let duration = now - self.possession_start_s;
                    self.end_possession(Outcome::Intercepted, 0, duration, events);
                    return true;
                }
            }
        }
        self.ball = Ball::Pass {
            from,
            to,
            at,
            tried,
        };
        false
    }

    /// Defenders within reach of the dribbler try to steal, each at most once per
    /// `attempt_every_s`. True if one did.
    fn try_steals(&mut self, now: f64, events: &mut Vec<Event>) -> bool {
        let Some(holder) = self.holder() else {
            return false;
        };
        if self.agents[holder].shooting_s.is_some() {
            return false; // a shot being taken can be blocked, not stolen
        }
        let at = self.agents[holder].pose.position;
        for d in self.defenders() {
            let defender = &mut self.agents[d];
            if now >= defender.not_before_s
                && defender.pose.position.distance(at) <= self.params.defender.reach_m
            {
                defender.not_before_s = now + self.params.defender.attempt_every_s;
                if self.rng.gen_bool(self.params.defender.steal_success) {
                    let duration = now - self.possession_start_s;
                    self.end_possession(Outcome::Stolen, 0, duration, events);
                    return true;
                }
            }
        }
        false
    }

    pub(super) fn start_shot(&mut self, shooter: usize) {
        self.agents[shooter].stop();
        self.agents[shooter].shooting_s = Some(self.params.decision.shot_time_s);
        self.blocks_tried = 0;
    }

    pub(super) fn start_pass(&mut self, from: usize, to: usize) {
        // The receiver re-plans at once, as one about to have the ball: its move may not
        // take it beyond the lines (a catch out of bounds would put the ball handler
        // off the court). The new move goes on from where its body is.
        let receiver = &mut self.agents[to];
        receiver.stop();
        receiver.next_plan_s = 0.0;
        self.ball = Ball::Pass {
            from,
            to,
            at: self.agents[from].pose.position,
            tried: 0,
        };
        self.passes += 1;
    }

    fn end_possession(
        &mut self,
        outcome: Outcome,
        points: u32,
        duration_s: f64,
        events: &mut Vec<Event>,
    ) {
        self.score += points;
        events.push(Event::PossessionEnded(PossessionEnded {
            duration_s,
            kind: tags::PossessionEnded,
            outcome,
            passes: self.passes,
            points,
            possession: self.possession,
        }));
        self.possession += 1;
        self.start_possession();
    }

    fn start_possession(&mut self) {
        let p = &self.params;
        let mut rng = ChaCha8Rng::seed_from_u64(p.seed);
        // Starts depend only on the seed and the possession's number.
        rng.set_stream(2 + self.possession);
        // So do the draws the possession's play makes (shots, steals, blocks): two
        // offenses compared on the same possessions face the same luck, draw for draw,
        // as far as they make the same draws (common random numbers).
        self.rng = play_draws(p.seed, self.possession);
        let now = self.time_s();
        let basket = p.court.basket;
        let facing = |from: DVec2, to: DVec2| (to - from).y.atan2((to - from).x);
        let mut agents = Vec::with_capacity(p.offense_players + p.defenders);
        // A fixed start replaces the drawn one (drawn all the same, so the draws of the
        // others do not change), and everything placed relative to a player uses where
        // it really stands.
        let starts = &self.starts;
        let place = |k: usize, drawn: DVec2| starts[k].unwrap_or(drawn);
        let handler = place(
            0,
            DVec2::new(rng.gen_range(8.0..12.0), rng.gen_range(-5.0..5.0)),
        );
        agents.push(Agent::new(
            self.names[0].clone(),
            Team::Offense,
            handler,
            facing(handler, basket),
        ));
        let other_side = if handler.y >= 0.0 { -1.0 } else { 1.0 };
        for k in 1..p.offense_players {
            let side = if k % 2 == 1 { other_side } else { -other_side };
            let drawn = DVec2::new(rng.gen_range(5.0..10.0), side * rng.gen_range(2.0..6.5));
            let at = place(k, drawn);
            agents.push(Agent::new(
                self.names[k].clone(),
                Team::Offense,
                at,
                facing(at, basket),
            ));
        }
        for k in 0..p.defenders {
            let mark = agents[k % p.offense_players].pose.position;
            let drawn = mark + (basket - mark).normalize_or_zero() * DEFENDER_START_M;
            let at = place(p.offense_players + k, drawn);
            agents.push(Agent::new(
                self.names[p.offense_players + k].clone(),
                Team::Defense,
                at,
                facing(at, mark),
            ));
        }
        for a in &mut agents {
            a.next_plan_s = now;
        }
        self.last_decision = vec![None; agents.len()];
        self.orders = vec![None; agents.len()];
        self.targets = vec![None; agents.len()];
        self.agents = agents;
        self.ball = Ball::Held { by: 0 };
        self.possession_start_s = now;
        self.shot_clock_s = p.shot_clock_s;
        self.passes = 0;
        self.blocks_tried = 0;
    }

    /// The whole court now, as a client draws it.
    pub(crate) fn snapshot(&self) -> Snapshot<'_> {
        let now = self.time_s();
        let ball = match self.ball {
            Ball::Held { by } => {
                let p = self.agents[by].pose.position;
                // A dribble bounces about twice a second between hand and floor.
                let height = 0.55 + 0.45 * (now * std::f64::consts::TAU * 2.0).cos().abs();
                BallView {
                    state: BallState::Held,
                    position: [p.x, height, p.y],
                    holder: Some(&self.agents[by].id),
                }
            }
            Ball::Pass { at, .. } => BallView {
                state: BallState::Pass,
                position: [at.x, 1.3, at.y],
                holder: None,
            },
            Ball::Shot {
                from,
                released_s,
                flight_s,
                ..
            } => {
                let s = ((now - released_s) / flight_s.max(1e-6)).clamp(0.0, 1.0);
                let p = from.lerp(self.params.court.basket, s);
                let height = 2.0 + (RING_HEIGHT_M - 2.0) * s + 6.0 * s * (1.0 - s);
                BallView {
                    state: BallState::Shot,
                    position: [p.x, height, p.y],
                    holder: None,
                }
            }
        };
        Snapshot {
            tick: self.tick,
            possession: self.possession,
            shot_clock_s: self.shot_clock_s.max(0.0),
            score: self.score,
            ball,
            agents: self
                .agents
                .iter()
                .enumerate()
                .map(|(k, a)| {
                    let behaviour = a
                        .movement
                        .as_ref()
                        .map_or_else(|| self.behaviour_of(k), |m| m.behaviour);
                    let graph = a.playing.filter(|&p| p != behaviour);
                    let blend = a.blend.and_then(|b| {
                        let mover = self.caps.by_behaviour(a.playing?)?;
                        Some(PoseBlend(b.from, mover.graph.blend_weight(&b)))
                    });
                    PlayerView {
                        id: &a.id,
                        team: a.team,
                        controller: crate::tags::controller(self.is_controlled(k)),
                        behaviour,
                        blend,
                        graph,
                        position: a.pose.position.to_array(),
                        heading: a.pose.heading,
                        node: a.node,
                        action: a.action,
                    }
                })
                .collect(),
        }
    }
}
