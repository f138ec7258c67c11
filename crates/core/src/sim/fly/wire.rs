//! How a fly-ball world shows itself on the wire: the field a client draws, each
//! fielder's static description, the state in every frame, and what a bot's fielder
//! perceives (its own body, and the ball only as optics from its eye). It is apart from
//! the play loop because these shapes are the protocol's: they change with what clients
//! and bots read, never with how a ball is played, and the play loop must not change
//! them (replays are verified byte for byte).

use super::FlyWorld;
use crate::perception::{PerceptionConfig, Sighting};
use crate::sim::mark_bot;
use crate::sim::scenario::Sport;
use serde_json::{json, Value};

impl FlyWorld {
    /// The field as a client draws it.
    /// `eye_height_m` lets a spectator draw what a fielder sees (tan ψ, the image path)
    /// from the frames, with the eye the fielders perceive from.
    pub(crate) fn field(&self) -> Value {
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

    pub(crate) fn agents_info(&self) -> Vec<Value> {
        self.fielders
            .iter()
            .map(|f| json!({"id": f.id, "team": "fielding", "strategy": f.strategy.name(), "home": f.home.to_array()}))
            .collect()
    }

    pub(crate) fn state(&self) -> (Value, Vec<Value>, Value) {
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
    pub(crate) fn perception(&self, k: usize) -> Value {
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
}
