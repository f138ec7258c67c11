//! How agents decide, a few times a second: the offense follows the paper's conditional
//! plan (its Figure 9: maneuver toward the goal, pass to the teammate when pressed,
//! shoot when the plan says so) with a `simple` or a `costmap` brain; the defender
//! "simply tries to move toward the ball".

use super::agent::{Action, Movement, Team};
use super::capability::Capabilities;
use super::capability::{Motion, Mover, Reach};
use super::decision::{Chosen, Keep, Opponent, Situation};
use super::event::{ChosenView, Decided, Event, Passed};
use super::game::{Game, Order};
use super::params::{Brain, DefenderAim, DefenderModel};
use super::safe::SafeSquares;
use crate::costmap::root_speed;
use crate::tags;
use glam::DVec2;

/// What the ball handler does next, and why (in words a spectator reads).
enum Play {
    Shoot {
        reason: String,
        chosen: Option<Chosen>,
    },
    Pass {
        to: usize,
        reason: String,
    },
    Move {
        action: Action,
        goal: DVec2,
        reason: String,
        chosen: Option<Chosen>,
    },
}

/// How far beyond the lines a player without the ball may go when no move within them
/// gets it nearer its goal, m. FIBA asks for at least 2 m of clear floor around the
/// court, and a player without the ball may use it; the ball handler never leaves the
/// court (that would be a turnover). The motion capture's turns are wide (no clip turns
/// on the spot), so a player near a line facing away from its goal needs some of it.
pub const RUN_OFF_M: f64 = 1.0;

/// How far a goal may move before an agent gives up the move it is playing for a new
/// one, m.
const RETARGET_M: f64 = 1.0;
/// How near a bot's `move_to` target an agent must get for the order to be done, m:
/// a stored path ends at its map cell's centre (cells are 0.5 m), so anywhere within the
/// cell's diagonal of the target is as near as a move can aim.
const ARRIVED_M: f64 = 0.75;
/// How far ahead the `simple` offense aims on its straight line to the goal, m.
const SIMPLE_STEP_M: f64 = 3.0;
/// Where an offensive player without the ball waits for a pass: this far from the
/// basket, at one of [`OPEN_ANGLES_DEG`] from the basket's axis.
const OPEN_DISTANCE_M: f64 = 4.5;
const OPEN_ANGLES_DEG: [f64; 5] = [-60.0, -30.0, 0.0, 30.0, 60.0];

impl Game {
    /// Every agent whose time has come decides, in a fixed order.
    pub(super) fn plan(&mut self, now: f64, events: &mut Vec<Event>) {
        for k in 0..self.agents.len() {
            if self.controlled[k] {
                // A bot's order is carried out on the next tick, whenever it comes.
                if self.agents[k].shooting_s.is_none() {
                    self.obey(k, events);
                }
                continue;
            }
            let a = &self.agents[k];
            if a.shooting_s.is_some() || now + 1e-9 < a.next_plan_s {
                continue;
            }
            self.agents[k].next_plan_s = now + self.params.replan_s;
            match (self.agents[k].team, self.holder() == Some(k)) {
                (Team::Defense, _) => self.defend(k),
                (Team::Offense, true) => {
                    let play = match self.params.offense {
                        Brain::Simple => self.simple_play(k, now),
                        Brain::Costmap => self.costmap_play(k, now),
                    };
                    self.carry_out(k, play, events);
                }
                (Team::Offense, false) => self.get_open(k),
            }
        }
    }

    /// A bot-controlled agent carries out its latest order, and keeps heading for the
    /// target of a `move_to` until it gets there or nothing gets it nearer.
    fn obey(&mut self, k: usize, events: &mut Vec<Event>) {
        let order = match self.orders[k].take() {
            Some(order) => {
                self.targets[k] = match order {
                    Order::MoveTo(goal) => Some(goal),
                    _ => None,
                };
                order
            }
            None => match self.targets[k] {
                Some(goal) if self.agents[k].movement.is_none() => {
                    if self.agents[k].pose.position.distance(goal) <= ARRIVED_M {
                        self.targets[k] = None;
                        return;
                    }
                    Order::MoveTo(goal)
                }
                _ => return,
            },
        };
        let reason = "bot order".to_string();
        let holds = self.holder() == Some(k);
        let play = match order {
            Order::Shoot if holds => Play::Shoot {
                reason,
                chosen: None,
            },
            Order::Pass { to } if holds => Play::Pass { to, reason },
            Order::MoveTo(goal) if holds => Play::Move {
                action: Action::Maneuver,
                goal,
                reason,
                chosen: None,
            },
            Order::MoveTo(goal) => {
                match self.agents[k].team {
                    Team::Defense => self.defender_head_for(k, goal),
                    Team::Offense => self.head_for(k, &[&self.caps.clone().run], goal),
                }
                self.give_up_if_stuck(k);
                return;
            }
            Order::Stand => {
                self.agents[k].stop();
                return;
            }
            // The ball moved on since the order was accepted.
            Order::Shoot | Order::Pass { .. } => return,
        };
        self.candidates.clear();
        self.carry_out(k, play, events);
        self.give_up_if_stuck(k);
    }

    /// A `move_to` that found no move (none gets the agent nearer on the court) is no
    /// longer in force: trying again every tick would find the same nothing.
    fn give_up_if_stuck(&mut self, k: usize) {
        if self.agents[k]
            .movement
            .as_ref()
            .is_none_or(|m| m.finished())
        {
            self.targets[k] = None;
        }
    }

    fn carry_out(&mut self, k: usize, play: Play, events: &mut Vec<Event>) {
        let (action, reason, chosen) = match play {
            Play::Shoot { reason, chosen } => {
                self.start_shot(k);
                (Action::Shoot, reason, chosen)
            }
            Play::Pass { to, reason } => {
                self.start_pass(k, to);
                events.push(Event::Pass(Passed {
                    from: self.agents[k].id.clone(),
                    kind: tags::Pass,
                    to: self.agents[to].id.clone(),
                }));
                (Action::Pass, reason, None)
            }
            Play::Move {
                action,
                goal,
                reason,
                chosen,
            } => {
                self.head_for(k, &[&self.caps.clone().dribble], goal);
                (action, reason, chosen)
            }
        };
        self.agents[k].action = action;
        let key = Some((action, chosen.map(|c| c.cell)));
        if self.last_decision[k] != key {
            self.last_decision[k] = key;
            events.push(Event::Decision(Decided {
                action,
                agent: self.agents[k].id.clone(),
                chosen: chosen.as_ref().map(ChosenView::from),
                kind: tags::Decision,
                reason,
                safe: chosen.and_then(|_| SafeSquares::of(&self.params.court, &self.candidates)),
            }));
        }
        if action == Action::Pass {
            self.agents[k].action = Action::ReadyForPass;
        }
    }

    /// Heads agent `k` for `goal` with the first of `movers` (behaviours in order of
    /// preference) that has a way there: plays the map's stored path to the goal's cell if
    /// the map reaches it by a path that stays on the court, else to the cell that is the
    /// cheapest way nearer it on the court. A player without the ball tries the same again
    /// with the run-off beyond the lines ([`RUN_OFF_M`]); one with the ball, or with a
    /// pass on its way to it, never leaves the court. It stands if nothing gets it nearer.
    ///
    /// Every frame of a move is checked, not only where it ends: the stored paths are
    /// human motion from the map's start pose, and the cheapest way to a square near a
    /// line often swings wide of it (a turn is a curve), which would carry a player out
    /// of bounds.
    ///
    /// A move in progress toward (nearly) the same goal with the same behaviour is kept:
    /// every stored path starts from the map's start pose, so restarting one a few times
    /// a second would replay its first steps for ever and never make a turn that takes
    /// longer than that.
    fn head_for(&mut self, k: usize, movers: &[&Mover], goal: DVec2) {
        if let Some(m) = &self.agents[k].movement {
            if movers.iter().any(|mover| mover.behaviour == m.behaviour)
                && m.goal.distance(goal) <= RETARGET_M
            {
                return;
            }
        }
        let pose = self.agents[k].pose;
        let court = &self.params.court;
        let margins: &[f64] = if self.has_or_awaits_ball(k) {
            &[0.0]
        } else {
            &[0.0, RUN_OFF_M]
        };
        let reaches: Vec<Reach> = movers
            .iter()
            .map(|mover| mover.reach(&pose, self.motion_of(k, mover)))
            .collect();
        self.agents[k].movement = margins.iter().find_map(|&margin_m| {
            movers.iter().zip(&reaches).find_map(|(mover, reach)| {
                let cell = reach
                    .cell(goal)
                    .filter(|&c| reach.on_court(c, court, margin_m))
                    .or_else(|| reach.toward(goal, court, margin_m))?;
                // A move that goes on from the node being played goes on with its blend.
                let carried = match self.motion_of(k, mover) {
                    Motion::Node(_) => self.agents[k].blend,
                    _ => None,
                };
                Some(Movement::new(
                    reach.strides(cell),
                    goal,
                    mover.behaviour,
                    &mover.graph,
                    carried,
                ))
            })
        });
    }

    /// How agent `k` is moving, as `mover` plans from: the node it plays if that is on
    /// `mover`'s graph (the move goes on from it), else the speed of the node it plays
    /// with another behaviour, else standing.
    pub(super) fn motion_of(&self, k: usize, mover: &Mover) -> Motion {
        let a = &self.agents[k];
        match (a.node, a.playing) {
            (Some(n), Some(b)) if b == mover.behaviour => Motion::Node(n),
            (Some(n), Some(b)) => self
                .caps
                .by_behaviour(b)
                .and_then(|m| m.graph.nodes.get(n as usize))
                .map_or(Motion::Still, |node| Motion::Speed(root_speed(node))),
            _ => Motion::Still,
        }
    }

    /// A defender heads for `goal` with its footwork, or runs where the footwork has no
    /// way nearer on the court: the paper's defender "can use any form of nondribbling
    /// movement", and the CMU footwork turns one way only, so near a line facing the wrong
    /// way it could otherwise only stand.
    fn defender_head_for(&mut self, k: usize, goal: DVec2) {
        let caps = self.caps.clone();
        self.head_for(
            k,
            &[caps.defender(self.params.defender.motion), &caps.run],
            goal,
        );
    }

    fn shot_clock_play(&self) -> Option<Play> {
        (self.shot_clock_s <= self.params.decision.shot_time_s + self.params.replan_s).then(|| {
            Play::Shoot {
                reason: format!(
                    "shot clock: {:.1} s left, shooting before it runs out",
                    self.shot_clock_s.max(0.0)
                ),
                chosen: None,
            }
        })
    }

    /// The teammate to pass to: the one farthest from its nearest defender.
    fn open_teammate(&self, k: usize, now: f64) -> Option<usize> {
        if now < self.agents[k].not_before_s {
            return None;
        }
        // Never to a teammate beyond the lines: it would catch the ball out of bounds.
        (0..self.agents.len())
            .filter(|&t| t != k && self.agents[t].team == Team::Offense)
            .filter(|&t| self.params.court.contains(self.agents[t].pose.position))
            .max_by(|&a, &b| self.openness(a).total_cmp(&self.openness(b)))
    }

    fn openness(&self, k: usize) -> f64 {
        let at = self.agents[k].pose.position;
        self.defenders()
            .map(|d| self.agents[d].pose.position.distance(at))
            .fold(f64::INFINITY, f64::min)
    }

    fn simple_play(&self, k: usize, now: f64) -> Play {
        if let Some(play) = self.shot_clock_play() {
            return play;
        }
        let p = &self.params;
        let at = self.agents[k].pose.position;
        let to_basket = p.court.distance_to_basket(at);
        if to_basket <= p.simple.shoot_range_m {
            return Play::Shoot {
                reason: format!(
                    "{to_basket:.1} m from the basket, within the fixed {:.1} m range",
                    p.simple.shoot_range_m
                ),
                chosen: None,
            };
        }
        let nearest = self.openness(k);
        if nearest <= p.simple.pass_radius_m {
            if let Some(to) = self.open_teammate(k, now) {
                return Play::Pass {
                    to,
                    reason: format!(
                        "defender {nearest:.1} m away, inside the fixed {:.1} m radius",
                        p.simple.pass_radius_m
                    ),
                };
            }
        }
        let goal = at + (p.court.basket - at).normalize_or_zero() * SIMPLE_STEP_M.min(to_basket);
        Play::Move {
            action: Action::Maneuver,
            goal,
            reason: "straight toward the basket".to_string(),
            chosen: None,
        }
    }

    fn costmap_play(&mut self, k: usize, now: f64) -> Play {
        if let Some(play) = self.shot_clock_play() {
            return play;
        }
        let caps = self.caps.clone();
        let shooter = caps
            .dribble
            .reach(&self.agents[k].pose, self.motion_of(k, &caps.dribble));
        let shot_model = self.params.shot_model;
        let defenders = self.opponents(&caps, shot_model);
        let mut candidates = std::mem::take(&mut self.candidates);
        let chosen = Situation {
            court: &self.params.court,
            shot: &self.params.shot,
            params: &self.params.decision,
            shooter,
            defenders: &defenders,
            shot_clock_s: self.shot_clock_s,
        }
        .decide_into(&mut candidates, Keep::Qualifying);
        self.candidates = candidates;
        let why = |c: &Chosen| {
            // A map's horizon is a bound, not a time: the defender needs longer.
            let needs = if c.beyond_horizon {
                format!("beyond {:.0} s", c.c_o)
            } else {
                format!("{:.1} s", c.c_o)
            };
            format!(
                "defender needs {needs} ({} model) > {:.1} s dribble + {:.1} s shot + {:.1} s margin",
                shot_model.name(),
                c.c_d,
                c.t_s,
                c.epsilon
            )
        };
        if let Some(c) = chosen.filter(|c| c.here) {
            return Play::Shoot {
                reason: format!(
                    "shoots from ({:.1}, {:.1}): {}",
                    c.cell[0],
                    c.cell[1],
                    why(&c)
                ),
                chosen,
            };
        }
        if let Some(pressed) = self.pressed(k, &caps) {
            if let Some(to) = self.open_teammate(k, now) {
                return Play::Pass {
                    to,
                    reason: format!("pressed: {pressed}"),
                };
            }
        }
        if let Some(c) = chosen {
            return Play::Move {
                action: Action::DribbleToShot,
                goal: DVec2::from_array(c.cell),
                reason: format!(
                    "dribbles to shoot from ({:.1}, {:.1}): {}",
                    c.cell[0],
                    c.cell[1],
                    why(&c)
                ),
                chosen,
            };
        }
        Play::Move {
            action: Action::Maneuver,
            goal: self.params.court.basket,
            reason: "no safe square: cheapest way toward the basket".to_string(),
            chosen: None,
        }
    }

    /// The defenders as `model` has the shooter believe them.
    fn opponents<'c>(&self, caps: &'c Capabilities, model: DefenderModel) -> Vec<Opponent<'c>> {
        self.defenders()
            .map(|d| {
                let pose = &self.agents[d].pose;
                let map =
                    |mover: &'c Mover| Opponent::Map(mover.reach(pose, self.motion_of(d, mover)));
                match model {
                    DefenderModel::Own => map(caps.defender(self.params.defender.motion)),
                    DefenderModel::Maps { behaviour } => map(caps.defender(behaviour)),
                    DefenderModel::Kinematic(model) => Opponent::Kinematic {
                        frame: pose.frame(),
                        velocity: self.velocity_of(d),
                        model,
                    },
                    DefenderModel::Isotropic(model) => Opponent::Isotropic {
                        at: pose.position,
                        model,
                    },
                    DefenderModel::None => Opponent::Ignored,
                }
            })
            .collect()
    }

    /// Agent `k`'s velocity in its own frame (+x ahead, +z right), m/s: how the node it
    /// plays moves (zero before it has moved).
    fn velocity_of(&self, k: usize) -> DVec2 {
        let a = &self.agents[k];
        a.node
            .zip(a.playing)
            .and_then(|(n, b)| {
                self.caps
                    .by_behaviour(b)?
                    .graph
                    .nodes
                    .get(n as usize)
                    .copied()
            })
            .map_or(DVec2::ZERO, |n| {
                DVec2::new(n.forward_speed, n.lateral_speed)
            })
    }

    /// Whether the ball handler `k` is pressed, by the pass model, and why in words: a
    /// defender the model says reaches the ball's square within `pass_pressure_s`; with
    /// no model, one inside the `simple` offense's fixed radius.
    fn pressed(&self, k: usize, caps: &Capabilities) -> Option<String> {
        let p = &self.params;
        if p.pass_model == DefenderModel::None {
            let nearest = self.openness(k);
            return (nearest <= p.simple.pass_radius_m).then(|| {
                format!(
                    "the defender is {nearest:.1} m away, inside the fixed {:.1} m radius (no model)",
                    p.simple.pass_radius_m
                )
            });
        }
        let at = self.agents[k].pose.position;
        let arrives = self
            .opponents(caps, p.pass_model)
            .iter()
            .map(|o| o.seconds(at))
            .fold(f64::INFINITY, f64::min);
        (arrives <= p.pass_pressure_s).then(|| {
            format!(
                "the defender reaches the ball in {arrives:.1} s ({} model), within {:.1} s",
                p.pass_model.name(),
                p.pass_pressure_s
            )
        })
    }

    /// Ready for a pass: toward the goal, to the spot by the basket farthest from the
    /// defenders and not crowding the ball.
    fn get_open(&mut self, k: usize) {
        let basket = self.params.court.basket;
        let ball = self.ball_position();
        let spot = OPEN_ANGLES_DEG
            .iter()
            .map(|deg| basket + DVec2::from_angle(deg.to_radians()) * OPEN_DISTANCE_M)
            .max_by(|a, b| {
                self.spot_score(*a, ball)
                    .total_cmp(&self.spot_score(*b, ball))
            })
            .expect("there are spots");
        self.head_for(k, &[&self.caps.clone().run], spot);
        self.agents[k].action = Action::ReadyForPass;
    }

    fn spot_score(&self, spot: DVec2, ball: DVec2) -> f64 {
        let defended = self
            .defenders()
            .map(|d| self.agents[d].pose.position.distance(spot))
            .fold(f64::INFINITY, f64::min)
            .min(10.0);
        defended + spot.distance(ball).min(3.0)
    }

    /// The defender: toward the ball, or where the ball handler is dribbling to.
    fn defend(&mut self, k: usize) {
        let goal = match self.params.defender.aim {
            DefenderAim::Ball => None,
            DefenderAim::Goal => self
                .holder()
                .and_then(|h| self.agents[h].movement.as_ref())
                .filter(|m| m.behaviour == "dribble")
                .map(|m| m.goal),
        };
        self.defender_head_for(k, goal.unwrap_or_else(|| self.ball_position()));
        self.agents[k].action = Action::Defend;
    }
}
