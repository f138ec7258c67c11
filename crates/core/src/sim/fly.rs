//! Fly balls in a live match: a batter at the origin hits ball after ball (drawn from a
//! seeded distribution), and fielders chase each one with their strategies, or as their
//! bots command. Baseball puts three outfielders in fair territory; cricket puts
//! fielders around the ring, with balls hit all round the wicket.

use super::mark_bot;
use super::scenario::{range, LaunchSpec, Scenario, ScenarioError, Sport};
use crate::fielding::{forecast, Body, CatchZone, Fielder, FielderConfig, Limits, StrategyKind};
use crate::perception::{PerceptionConfig, Sighting};
use crate::physics::{AirModel, BallSpec, BallState, Flight, Launch, NATHAN_AIR_DENSITY};
use glam::DVec2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use serde_json::{json, Value};

/// Longest flight simulated.
const MAX_FLIGHT_S: f64 = 20.0;
/// A bot's `run_to`: how fast a fielder closes on its target's velocity, s.
const RUN_TO_RESPONSE_S: f64 = 0.3;
/// Farthest a `run_to` target may be from the batter, m.
const MAX_TARGET_M: f64 = 250.0;

/// What a bot may tell a fielder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FielderOrder {
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
}

#[derive(Debug, Clone)]
enum Play {
    InPlay { flight: Flight, sample: usize },
    Between { until_tick: u64 },
}

#[derive(Debug, Clone, Serialize)]
pub struct Score {
    pub balls: u64,
    pub caught: u64,
    pub dropped: u64,
}

#[derive(Debug, Clone)]
pub struct FlyWorld {
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

/// The default line-up: baseball's three outfielders (left, centre, right) with three
/// strategies; cricket's five fielders on a 55 m ring.
fn default_lineup(sport: Sport) -> Vec<(String, StrategyKind, DVec2)> {
    let at = |distance: f64, deg: f64| distance * DVec2::from_angle(f64::to_radians(deg));
    match sport {
        Sport::Cricket => [
            ("long-off", StrategyKind::Chapman, 20.0),
            ("long-on", StrategyKind::LotOptical, 92.0),
            ("deep-midwicket", StrategyKind::Predictive, 164.0),
            ("deep-square", StrategyKind::Chapman, 236.0),
            ("third-man", StrategyKind::LotOptical, 308.0),
        ]
        .into_iter()
        .map(|(id, s, deg)| (id.to_string(), s, at(55.0, deg)))
        .collect(),
        _ => [
            ("lf", StrategyKind::Chapman, 20.0),
            ("cf", StrategyKind::LotOptical, 45.0),
            ("rf", StrategyKind::Predictive, 70.0),
        ]
        .into_iter()
        .map(|(id, s, deg)| (id.to_string(), s, at(80.0, deg)))
        .collect(),
    }
}

impl FlyWorld {
    pub fn new(s: &Scenario) -> Result<FlyWorld, ScenarioError> {
        let cricket = s.sport == Sport::Cricket;
        let o = &s.options;
        let speed = range(
            "options.launch_speed_m_s",
            o.launch_speed_m_s,
            if cricket { (20.0, 35.0) } else { (25.0, 45.0) },
            (1.0, 70.0),
        )?;
        let elevation = range(
            "options.launch_elevation_deg",
            o.launch_elevation_deg,
            if cricket { (25.0, 60.0) } else { (25.0, 65.0) },
            (1.0, 89.0),
        )?;
        let azimuth = range(
            "options.launch_azimuth_deg",
            o.launch_azimuth_deg,
            if cricket { (0.0, 360.0) } else { (0.0, 90.0) },
            (-360.0, 360.0),
        )?;
        let spin = range(
            "options.spin_rpm",
            o.spin_rpm,
            (1000.0, 3000.0),
            (0.0, 6000.0),
        )?;
        let pause_s = o.pause_s.unwrap_or(2.0);
        if !(pause_s.is_finite() && (0.0..=60.0).contains(&pause_s)) {
            return Err(ScenarioError::at("options.pause_s", "between 0 and 60 s"));
        }
        let human = FielderConfig::default();
        let lineup: Vec<(String, StrategyKind, DVec2, FielderConfig)> = if s.agents.is_empty() {
            default_lineup(s.sport)
                .into_iter()
                .map(|(id, strategy, at)| (id, strategy, at, human))
                .collect()
        } else {
            let defaults = default_lineup(s.sport);
            s.agents
                .iter()
                .enumerate()
                .map(|(i, a)| {
                    if a.team.is_some() {
                        return Err(ScenarioError::at(
                            format!("agents[{i}].team"),
                            "fielders have no team",
                        ));
                    }
                    let strategy = match &a.strategy {
                        Some(name) => name.parse::<StrategyKind>().map_err(|e| {
                            ScenarioError::at(format!("agents[{i}].strategy"), e.to_string())
                        })?,
                        None => StrategyKind::Chapman,
                    };
                    let at = match a.position {
                        Some([x, z])
                            if x.is_finite() && z.is_finite() && x.hypot(z) <= MAX_TARGET_M =>
                        {
                            DVec2::new(x, z)
                        }
                        Some(_) => {
                            return Err(ScenarioError::at(
                                format!("agents[{i}].position"),
                                format!("must be finite and within {MAX_TARGET_M} m of the batter"),
                            ))
                        }
                        None => defaults[i % defaults.len()].2,
                    };
                    let mut config = human;
                    if let Some(l) = a.limits {
                        let reaction = l.reaction_s.unwrap_or(human.limits.reaction_s);
                        let ok = |x: f64, hi: f64| x.is_finite() && x > 0.0 && x <= hi;
                        if !(ok(l.max_speed_m_s, 50.0) && ok(l.max_accel_m_s2, 100.0) && reaction.is_finite() && (0.0..=5.0).contains(&reaction)) {
                            return Err(ScenarioError::at(format!("agents[{i}].limits"), "max_speed_m_s in (0, 50], max_accel_m_s2 in (0, 100], reaction_s in [0, 5]"));
                        }
                        config.limits = Limits { max_speed: l.max_speed_m_s, max_accel: l.max_accel_m_s2, reaction_s: reaction };
                    }
                    Ok((a.id.clone(), strategy, at, config))
                })
                .collect::<Result<_, _>>()?
        };
        let dt = 1.0 / s.tick_hz;
        let script = match &o.launches {
            Some(list) => Some(check_script(list)?),
            None => None,
        };
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed);
        rng.set_stream(3);
        let fielders = lineup
            .into_iter()
            .map(|(id, strategy, home, config)| Fielding {
                fielder: Fielder::new(strategy, home, DVec2::ZERO, &config, dt, || {
                    crate::fielding::Forecast {
                        point: home,
                        t: 0.0,
                    }
                }),
                id,
                strategy,
                config,
                home,
                // Its built-in strategy plays until a bot connects.
                by_bot: false,
                order: None,
                last_seen: None,
            })
            .collect();
        Ok(FlyWorld {
            sport: s.sport,
            dt,
            tick: 0,
            ball: if cricket {
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

    pub fn tick(&self) -> u64 {
        self.tick
    }

    pub fn agent_ids(&self) -> impl Iterator<Item = &str> {
        self.fielders.iter().map(|f| f.id.as_str())
    }

    pub fn set_controlled(&mut self, k: usize, by_bot: bool) {
        self.fielders[k].by_bot = by_bot;
        self.fielders[k].order = None;
    }

    /// Accepts a bot's order for fielder `k`, or says why it is impossible.
    pub fn order(&mut self, k: usize, order: FielderOrder) -> Result<(), String> {
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

    fn new_play(&mut self, events: &mut Vec<Value>) {
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
            f.fielder = Fielder::new(f.strategy, f.home, DVec2::ZERO, &f.config, self.dt, || {
                predicted
            });
            // Every ball starts with the fielders at their positions, at rest, and a
            // bot's orders for the last ball forgotten.
            f.last_seen = None;
            f.order = None;
        }
        self.score.balls += 1;
        events.push(json!({
            "kind": "launch",
            "ball": self.score.balls,
            "launch": launch,
            "landing": [flight.landing.pos.x, flight.landing.pos.z],
        }));
        self.play = Play::InPlay { flight, sample: 0 };
    }

    /// Advances one tick.
    pub fn step(&mut self, events: &mut Vec<Value>) {
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
                    if let Some(pass) =
                        self.zone
                            .pass(ball.pos, next.pos, before, f.fielder.body.pos)
                    {
                        if pass.caught_s.is_some() {
                            self.score.caught += 1;
                            events.push(json!({
                                "kind": "caught",
                                "by": f.id,
                                "ball": self.score.balls,
                                "at": f.fielder.body.pos.to_array(),
                                "flight_time_s": ball.t,
                            }));
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
            events.push(json!({
                "kind": "landed",
                "ball": self.score.balls,
                "at": spot.to_array(),
                "nearest": nearest.as_ref().map(|(id, _)| id),
                "miss_m": nearest.map(|(_, d)| d),
            }));
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

    /// The field as a client draws it.
    /// `eye_height_m` lets a spectator draw what a fielder sees (tan ψ, the image path)
    /// from the frames, with the eye the fielders perceive from.
    pub fn field(&self) -> Value {
        let eye = self
            .fielders
            .first()
            .map_or(PerceptionConfig::default().eye_height_m, |f| {
                f.config.perception.eye_height_m
            });
        match self.sport {
            Sport::Cricket => {
                json!({"kind": "cricket", "batter": [0.0, 0.0], "boundary_m": 65.0, "inner_ring_m": 27.4, "pitch_length_m": 20.12, "eye_height_m": eye})
            }
            _ => {
                json!({"kind": "baseball", "home": [0.0, 0.0], "base_path_m": 27.43, "fence_m": 110.0, "foul_lines_deg": [0.0, 90.0], "eye_height_m": eye})
            }
        }
    }

    pub fn agents_info(&self) -> Vec<Value> {
        self.fielders
            .iter()
            .map(|f| json!({"id": f.id, "team": "fielding", "strategy": f.strategy.name(), "home": f.home.to_array()}))
            .collect()
    }

    pub fn state(&self) -> (Value, Vec<Value>, Value) {
        let ball = match self.ball_state() {
            Some(b) => {
                json!({"state": "flight", "position": b.pos.to_array(), "velocity": b.vel.to_array()})
            }
            None => json!({"state": "dead", "position": [0.0, 1.0, 0.0]}),
        };
        let agents = self
            .fielders
            .iter()
            .map(|f| {
                let b = &f.fielder.body;
                let mut v = json!({
                    "id": f.id,
                    "position": b.pos.to_array(),
                    "heading": if b.vel.length() > 1e-6 { b.vel.y.atan2(b.vel.x) } else { (-f.home).y.atan2(-f.home.x) },
                    "speed": b.vel.length(),
                    "strategy": f.strategy.name(),
                });
                mark_bot(&mut v, f.by_bot);
                v
            })
            .collect();
        (
            ball,
            agents,
            serde_json::to_value(&self.score).expect("scores serialise"),
        )
    }

    /// What fielder `k` can perceive: its own body, and the ball only as an eye sees it.
    pub fn perception(&self, k: usize) -> Value {
        let f = &self.fielders[k];
        let b = &f.fielder.body;
        let eye = f.config.perception.eye_height_m;
        let optics = self.ball_state().map(|ball| {
            let now = Sighting::of(ball.t, ball.pos, b.pos, eye);
            let rates = f.last_seen.map(|prev| {
                let dt = (now.t - prev.t).max(self.dt);
                let d_alpha = crate::motion::wrap_angle(now.alpha() - prev.alpha());
                json!({"d_tan_psi_dt": (now.tan_psi - prev.tan_psi) / dt, "d_alpha_dt": d_alpha / dt})
            });
            // The ground distance is what the built-in strategies scale their gains by, so
            // a bot gets it too.
            json!({"tan_psi": now.tan_psi, "alpha": now.alpha(), "distance_m": now.distance, "rates": rates, "t": ball.t})
        });
        let limits = &f.config.limits;
        json!({
            "self": {"position": b.pos.to_array(), "velocity": b.vel.to_array(), "home": f.home.to_array()},
            "ball_in_play": optics.is_some(),
            "optics": optics,
            "limits": {"max_speed_m_s": limits.max_speed, "max_accel_m_s2": limits.max_accel},
        })
    }

    /// A scripted session is over once its last ball is dead.
    pub fn finished(&self) -> bool {
        matches!(self.play, Play::Between { .. })
            && self
                .script
                .as_ref()
                .is_some_and(|s| self.scripted >= s.len())
    }
}

/// Checks scripted launches field by field.
fn check_script(list: &[LaunchSpec]) -> Result<Vec<LaunchSpec>, ScenarioError> {
    if list.is_empty() {
        return Err(ScenarioError::at("options.launches", "at least one launch"));
    }
    for (i, l) in list.iter().enumerate() {
        let checks = [
            ("time_s", l.time_s, 0.0, 1e6),
            ("speed_m_s", l.speed_m_s, 1.0, 70.0),
            ("elevation_deg", l.elevation_deg, 1.0, 89.0),
            ("azimuth_deg", l.azimuth_deg, -360.0, 360.0),
            ("spin_rpm", l.spin_rpm, 0.0, 6000.0),
        ];
        for (field, x, lo, hi) in checks {
            if !(x.is_finite() && (lo..=hi).contains(&x)) {
                return Err(ScenarioError::at(
                    format!("options.launches[{i}].{field}"),
                    format!("{x} is outside [{lo}, {hi}]"),
                ));
            }
        }
    }
    Ok(list.to_vec())
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
