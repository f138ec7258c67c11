//! How a fly-ball world shows itself on the wire ([`crate::protocol::fly`]): the field a
//! client draws, each fielder's static description, the state in every frame, and what
//! a bot's fielder perceives (its own body, and the ball only as optics from its eye).
//! It is apart from the play loop because these are the protocol's shapes: they change
//! with what clients and bots read, never with how a ball is played.

use super::FlyWorld;
use crate::perception::{PerceptionConfig, Sighting};
use crate::protocol::fly::{
    BallState, BaseballField, BodyLimits, CricketField, Fielder, FielderInfo, Optics, Rates,
    SelfSensed, Sensed,
};
use crate::protocol::{fly, Agent, AgentInfo, Ball, Field, Score};
use crate::sim::scenario::Sport;
use crate::tags;

impl FlyWorld {
    /// The field as a client draws it, with the eye the fielders perceive from.
    pub(crate) fn field(&self) -> Field {
        let eye_height_m = self
            .fielders
            .first()
            .map_or(PerceptionConfig::default().eye_height_m, |f| {
                f.config.perception.eye_height_m
            });
        match self.sport {
            Sport::Cricket => Field::Cricket(CricketField {
                batter: [0.0, 0.0],
                boundary_m: 65.0,
                eye_height_m,
                inner_ring_m: 27.4,
                kind: tags::Cricket,
                pitch_length_m: 20.12,
            }),
            _ => Field::Baseball(BaseballField {
                base_path_m: 27.43,
                eye_height_m,
                fence_m: 110.0,
                foul_lines_deg: [0.0, 90.0],
                home: [0.0, 0.0],
                kind: tags::Baseball,
            }),
        }
    }

    pub(crate) fn agents_info(&self) -> Vec<AgentInfo> {
        self.fielders
            .iter()
            .map(|f| {
                AgentInfo::Fielder(FielderInfo {
                    home: f.home.to_array(),
                    id: f.id.clone(),
                    strategy: f.strategy.name(),
                    team: tags::Fielding,
                })
            })
            .collect()
    }

    pub(crate) fn state(&self) -> (Ball<'_>, Vec<Agent<'_>>, Score) {
        let ball = match self.ball_state() {
            Some(b) => fly::Ball {
                position: b.pos.to_array(),
                state: BallState::Flight,
                velocity: Some(b.vel.to_array()),
            },
            None => fly::Ball {
                position: [0.0, 1.0, 0.0],
                state: BallState::Dead,
                velocity: None,
            },
        };
        let agents = self
            .fielders
            .iter()
            .map(|f| {
                let b = &f.fielder.body;
                Agent::Fielder(Fielder {
                    controller: tags::controller(f.by_bot),
                    heading: if b.vel.length() > 1e-6 {
                        b.vel.y.atan2(b.vel.x)
                    } else {
                        (-f.home).y.atan2(-f.home.x)
                    },
                    id: &f.id,
                    position: b.pos.to_array(),
                    speed: b.vel.length(),
                    strategy: f.strategy.name(),
                })
            })
            .collect();
        (Ball::Fly(ball), agents, Score::Fly(self.score))
    }

    /// What fielder `k` can perceive: its own body, and the ball only as an eye sees it.
    pub(crate) fn perception(&self, k: usize) -> Sensed {
        let f = &self.fielders[k];
        let b = &f.fielder.body;
        let eye = f.config.perception.eye_height_m;
        let optics = self.ball_state().map(|ball| {
            let now = Sighting::of(ball.t, ball.pos, b.pos, eye);
            let rates = f.last_seen.map(|prev| {
                let dt = (now.t - prev.t).max(self.dt);
                let d_alpha = crate::motion::wrap_angle(now.alpha() - prev.alpha());
                Rates {
                    d_alpha_dt: d_alpha / dt,
                    d_tan_psi_dt: (now.tan_psi - prev.tan_psi) / dt,
                }
            });
            Optics {
                alpha: now.alpha(),
                distance_m: now.distance,
                rates,
                t: ball.t,
                tan_psi: now.tan_psi,
            }
        });
        let limits = &f.config.limits;
        Sensed {
            ball_in_play: optics.is_some(),
            caught: f.caught,
            limits: BodyLimits {
                max_accel_m_s2: limits.max_accel,
                max_speed_m_s: limits.max_speed,
            },
            optics,
            body: SelfSensed {
                home: f.home.to_array(),
                position: b.pos.to_array(),
                velocity: b.vel.to_array(),
            },
        }
    }
}
