//! Fly balls in a live match: a batter at the origin hits ball after ball (drawn from a
//! seeded distribution), and fielders chase each one with their strategies, or as their
//! bots command. Baseball puts three outfielders in fair territory; cricket puts
//! fielders around the ring, with balls hit all round the wicket.
//!
//! This file is the world and its play loop: a ball launched, each tick the fielders
//! moved and the catch tested, the dead time between balls. Around it:
//!
//! * [`setup`]: what is checked about a fly-ball scenario, and the line-up it gives.
//! * [`wire`]: how the world shows itself: the field, frames, a fielder's perception.

mod setup;
mod wire;

use crate::fielding::{forecast, Body, CatchZone, Fielder, FielderConfig, Limits, StrategyKind};
use crate::perception::Sighting;
use crate::physics::{AirModel, BallSpec, BallState, Flight, Launch, NATHAN_AIR_DENSITY};
use crate::protocol::fly::{Caught, Event, Landed, Launched, Score};
use crate::protocol::Event as AnyEvent;
use crate::sim::scenario::{LaunchSpec, Scenario, ScenarioError, Sport};
use crate::tags;
use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use setup::Setup;

/// Longest flight simulated.
const MAX_FLIGHT_S: f64 = 20.0;
/// A bot's `run_to`: how fast a fielder closes on its target's velocity, s.
const RUN_TO_RESPONSE_S: f64 = 0.3;
/// Farthest a `run_to` target may be from the batter, m.
const MAX_TARGET_M: f64 = 250.0;

/// What a bot may tell a fielder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum FielderOrder {
    /// Accelerate along this ground vector (m/s²), clamped to the body's limits.
    Accelerate(DVec2),
    /// Run to this point as fast as the body allows, arriving at rest.
    RunTo(DVec2),
    /// Slow to a stop.
    Stand,
}

#[derive(Debug, Clone)]
struct Fielding {
    id: String,
    strategy: StrategyKind,
    config: FielderConfig,
    home: DVec2,
    fielder: Fielder,
    by_bot: bool,
    order: Option<FielderOrder>,
    /// The sighting of the previous tick, for a bot's rates.
    last_seen: Option<Sighting>,
    /// Balls it has caught in this match: its bot perceives them (a learning agent's
    /// reward needs no spectator socket).
    caught: u32,
}

#[derive(Debug, Clone)]
enum Play {
    InPlay { flight: Flight, sample: usize },
    Between { until_tick: u64 },
}

/// A baseball or cricket match: the fielders, the ball in play (or the dead time
/// before the next), the seeded draw of launches, the score.
#[derive(Debug, Clone)]
pub(crate) struct FlyWorld {
    sport: Sport,
    dt: f64,
    tick: u64,
    ball: BallSpec,
    speed: (f64, f64),
    elevation: (f64, f64),
    azimuth: (f64, f64),
    spin: (f64, f64),
    pause_ticks: u64,
    zone: CatchZone,
    /// Scripted balls, and how many have been hit.
    script: Option<Vec<LaunchSpec>>,
    scripted: usize,
    fielders: Vec<Fielding>,
    play: Play,
    rng: ChaCha8Rng,
    score: Score,
}

impl FlyWorld {
    pub(crate) fn new(s: &Scenario) -> Result<FlyWorld, ScenarioError> {
        let Setup {
            speed,
            elevation,
            azimuth,
            spin,
            pause_s,
            lineup,
            script,
        } = setup::check(s)?;
        let dt = 1.0 / s.tick_hz;
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
        rng.set_stream(3);
        let fielders = lineup
            .into_iter()
            .map(|(id, strategy, home, config)| Fielding {
                fielder: Fielder::new(
                    strategy,
                    home,
                    DVec2::ZERO,
                    &config,
                    CatchZone::default().catch_height_m(),
                    dt,
                    || crate::fielding::Forecast {
                        point: home,
                        t: 0.0,
                    },
                ),
                id,
                strategy,
                config,
                home,
                // Its built-in strategy plays until a bot connects.
                by_bot: false,
                order: None,
                last_seen: None,
                caught: 0,
            })
            .collect();
        Ok(FlyWorld {
            sport: s.sport,
            dt,
            tick: 0,
            ball: if s.sport == Sport::Cricket {
                BallSpec::CRICKET
            } else {
                BallSpec::BASEBALL
            },
            speed,
            elevation,
            azimuth,
            spin,
            pause_ticks: (pause_s / dt).round() as u64,
            zone: CatchZone::default(),
            script,
            scripted: 0,
            fielders,
            play: Play::Between { until_tick: 1 },
            rng,
            score: Score {
                balls: 0,
                caught: 0,
                dropped: 0,
            },
        })
    }

    pub(crate) fn tick(&self) -> u64 {
        self.tick
    }

    pub(crate) fn score(&self) -> Score {
        self.score
    }

    pub(crate) fn agent_ids(&self) -> impl Iterator<Item = &str> {
        self.fielders.iter().map(|f| f.id.as_str())
    }

    pub(crate) fn set_controlled(&mut self, k: usize, by_bot: bool) {
        self.fielders[k].by_bot = by_bot;
        self.fielders[k].order = None;
    }

    /// Accepts a bot's order for fielder `k`, or says why it is impossible.
    pub(crate) fn order(&mut self, k: usize, order: FielderOrder) -> Result<(), String> {
        match order {
            FielderOrder::Accelerate(a) if !a.is_finite() => {
                return Err("the acceleration is not a finite vector".into())
            }
            FielderOrder::RunTo(p) if !p.is_finite() || p.length() > MAX_TARGET_M => {
                return Err(format!(
                    "the target must be finite and within {MAX_TARGET_M} m of the batter"
                ))
            }
            _ => {}
        }
        self.fielders[k].order = Some(order);
        Ok(())
    }

    fn new_play(&mut self, events: &mut Vec<AnyEvent>) {
        let mut uniform = |(lo, hi): (f64, f64)| {
            if hi > lo {
                self.rng.gen_range(lo..hi)
            } else {
                lo
            }
        };
        let launch = match &self.script {
            Some(script) => {
                let l = script[self.scripted];
                self.scripted += 1;
                Launch {
                    speed_m_s: l.speed_m_s,
                    elevation_deg: l.elevation_deg,
                    azimuth_deg: l.azimuth_deg,
                    height_m: 1.0,
                    spin_rpm: l.spin_rpm,
                    spin_tilt_deg: 0.0,
                }
            }
            None => Launch {
                speed_m_s: uniform(self.speed),
                elevation_deg: uniform(self.elevation),
                azimuth_deg: uniform(self.azimuth),
                height_m: 1.0,
                spin_rpm: uniform(self.spin),
                spin_tilt_deg: 0.0,
            },
        };
        let air = launch.air(AirModel::Nathan, NATHAN_AIR_DENSITY, &self.ball);
        let flight = Flight::simulate(launch.initial_state(), &air, self.dt, MAX_FLIGHT_S);
        let predicted = forecast(&flight, &self.zone);
        for f in &mut self.fielders {
            f.fielder = Fielder::new(
                f.strategy,
                f.home,
                DVec2::ZERO,
                &f.config,
                self.zone.catch_height_m(),
                self.dt,
                || predicted,
            );
            // Every ball starts with the fielders at their positions, at rest, and a
            // bot's orders for the last ball forgotten.
            f.last_seen = None;
            f.order = None;
        }
        self.score.balls += 1;
        events.push(AnyEvent::Fly(Event::Launch(Launched {
            ball: self.score.balls,
            kind: tags::Launch,
            landing: [flight.landing.pos.x, flight.landing.pos.z],
            launch: (&launch).into(),
        })));
        self.play = Play::InPlay { flight, sample: 0 };
    }

    /// Advances one tick.
    pub(crate) fn step(&mut self, events: &mut Vec<AnyEvent>) {
        self.tick += 1;
        let flight_ended = match &mut self.play {
            Play::Between { until_tick } => {
                let due = match &self.script {
                    Some(script) => script.get(self.scripted).is_some_and(|l| {
                        self.tick >= *until_tick && self.tick as f64 * self.dt >= l.time_s
                    }),
                    None => self.tick >= *until_tick,
                };
                if due {
                    self.new_play(events);
                    return;
                }
                // The ball is dead: bots' fielders follow their orders, the others stop.
                for f in &mut self.fielders {
                    let order = if f.by_bot { f.order } else { None };
                    let command = bot_command(order, &f.fielder.body, &f.config.limits);
                    f.fielder.body.advance(command, &f.config.limits, self.dt);
                }
                return;
            }
            Play::InPlay { flight, sample } => {
                let (ball, next) = (flight.samples[*sample], flight.samples[*sample + 1]);
                *sample += 1;
                let last = *sample + 1 >= flight.samples.len();
                for f in &mut self.fielders {
                    let before = f.fielder.body.pos;
                    if f.by_bot {
                        f.last_seen = Some(Sighting::of(
                            ball.t,
                            ball.pos,
                            before,
                            f.config.perception.eye_height_m,
                        ));
                        let command = bot_command(f.order, &f.fielder.body, &f.config.limits);
                        f.fielder.body.advance(command, &f.config.limits, self.dt);
                    } else {
                        f.fielder.step(ball.t, ball.pos, self.dt);
                    }
                    if let Some(pass) = self.zone.pass(
                        ball.pos,
                        next.pos,
                        before,
                        f.fielder.body.pos,
                        f.fielder.finishing(),
                    ) {
                        if pass.caught_s.is_some() {
                            self.score.caught += 1;
                            f.caught += 1;
                            events.push(AnyEvent::Fly(Event::Caught(Caught {
                                at: f.fielder.body.pos.to_array(),
                                ball: self.score.balls,
                                by: f.id.clone(),
                                flight_time_s: ball.t,
                                kind: tags::Caught,
                            })));
                            self.play = Play::Between {
                                until_tick: self.tick + self.pause_ticks,
                            };
                            return;
                        }
                    }
                }
                if last {
                    let landing = flight.landing.pos;
                    let spot = DVec2::new(landing.x, landing.z);
                    let nearest = self.fielders.iter().min_by(|a, b| {
                        a.fielder
                            .body
                            .pos
                            .distance(spot)
                            .total_cmp(&b.fielder.body.pos.distance(spot))
                    });
                    Some((
                        spot,
                        nearest.map(|f| (f.id.clone(), f.fielder.body.pos.distance(spot))),
                    ))
                } else {
                    None
                }
            }
        };
        if let Some((spot, nearest)) = flight_ended {
            self.score.dropped += 1;
            let (nearest, miss_m) = nearest.unzip();
            events.push(AnyEvent::Fly(Event::Landed(Landed {
                at: spot.to_array(),
                ball: self.score.balls,
                kind: tags::Landed,
                miss_m,
                nearest,
            })));
            self.play = Play::Between {
                until_tick: self.tick + self.pause_ticks,
            };
        }
    }

    fn ball_state(&self) -> Option<BallState> {
        match &self.play {
            Play::InPlay { flight, sample } => Some(flight.samples[*sample]),
            Play::Between { .. } => None,
        }
    }

    /// A scripted session is over once its last ball is dead.
    pub(crate) fn finished(&self) -> bool {
        matches!(self.play, Play::Between { .. })
            && self
                .script
                .as_ref()
                .is_some_and(|s| self.scripted >= s.len())
    }
}

/// The acceleration a bot's order asks for now (the body clamps it to its limits).
fn bot_command(order: Option<FielderOrder>, body: &Body, limits: &Limits) -> DVec2 {
    match order {
        None | Some(FielderOrder::Stand) => -body.vel / RUN_TO_RESPONSE_S,
        Some(FielderOrder::Accelerate(a)) => a,
        Some(FielderOrder::RunTo(target)) => {
            let gap = target - body.pos;
            // The fastest speed from which the body can still stop at the target.
            let stoppable = (2.0 * limits.max_accel.min(1e6) * gap.length()).sqrt();
            let speed = stoppable.min(limits.max_speed);
            (gap.normalize_or_zero() * speed - body.vel) / RUN_TO_RESPONSE_S
        }
    }
}
