//! A match being played, whoever plays it: a [`World`] with its id and frame rate, which
//! steps tick by tick and encodes a `frame` (once) whenever one is due. The server's
//! match tasks, headless runs and replay verification all drive one, so a replay's
//! frames and a live match's are the same bytes from the same code.

use crate::protocol::{encode, Frame};
use crate::sim::World;
use serde_json::Value;

/// A match being played: its world, id and frame rate, and the events not yet framed.
pub struct Session {
    /// The match's world, for its clock, status and result.
    pub world: World,
    /// The match's id, which every frame carries.
    id: String,
    frame_every: u64,
    /// Events since the last frame.
    events: Vec<Value>,
    /// The tick of the last frame encoded.
    framed: Option<u64>,
}

impl Session {
    /// A session of `world`, framed every `tick_hz / frame_hz` ticks (at least every
    /// tick); both rates in Hz of match time.
    pub fn new(world: World, id: String, tick_hz: f64, frame_hz: f64) -> Session {
        Session {
            world,
            id,
            frame_every: ((tick_hz / frame_hz).round() as u64).max(1),
            events: Vec::new(),
            framed: None,
        }
    }

    /// The frame of the world as it is now, with the events since the last one.
    pub fn frame(&mut self) -> String {
        let (mut ball, mut agents, mut score) = self.world.state();
        quantise(&mut ball);
        agents.iter_mut().for_each(quantise);
        quantise(&mut score);
        self.events.iter_mut().for_each(quantise);
        let tick = self.world.tick();
        let line = encode(&Frame {
            kind: "frame",
            match_id: &self.id,
            tick,
            time_s: quantised(self.world.time_s()),
            ball: &ball,
            agents: &agents,
            score: &score,
            events: &self.events,
        });
        self.events.clear();
        self.framed = Some(tick);
        line
    }

    /// Steps one tick; returns the frame if one is due (every `tick_hz / frame_hz` ticks,
    /// and at the end of the match).
    pub fn step(&mut self) -> Option<String> {
        self.world.step(&mut self.events);
        let tick = self.world.tick();
        (tick.is_multiple_of(self.frame_every) || self.world.finished()).then(|| self.frame())
    }

    /// The last frame, when a match stops: only if something happened since the last one.
    pub fn last_frame(&mut self) -> Option<String> {
        (self.framed != Some(self.world.tick()) || !self.events.is_empty()).then(|| self.frame())
    }
}

/// Decimal places kept in frames: a millimetre, a milliradian (0.06°), a millisecond.
const FRAME_DECIMALS: f64 = 1000.0;

fn quantised(x: f64) -> f64 {
    (x * FRAME_DECIMALS).round() / FRAME_DECIMALS
}

/// Rounds every fractional number in a frame's value to [`FRAME_DECIMALS`]: what a viewer
/// can see. `99.67935425784906` costs 17 bytes to send and `99.679` 6, and a frame goes
/// to every spectator 30 times a second. Only frames are rounded; the world keeps full
/// precision (and bots' perceptions carry it), so the simulation is unchanged, and
/// replays, which re-simulate and round the same way, still verify bit for bit.
fn quantise(value: &mut Value) {
    match value {
        Value::Number(n) if n.is_f64() => {
            if let Some(q) = n
                .as_f64()
                .map(quantised)
                .and_then(serde_json::Number::from_f64)
            {
                *n = q;
            }
        }
        Value::Array(items) => items.iter_mut().for_each(quantise),
        Value::Object(fields) => fields.values_mut().for_each(quantise),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::quantise;
    use serde_json::json;

    #[test]
    fn frames_keep_a_millimetre_and_integers_whole() {
        let mut v = json!({"position": [99.67935425784906, -0.00049], "tick": 12, "n": [1.0005, {"h": 1.23456789}]});
        quantise(&mut v);
        assert_eq!(
            v,
            json!({"position": [99.679, -0.0], "tick": 12, "n": [1.001, {"h": 1.235}]})
        );
        assert_eq!(
            v.to_string(),
            r#"{"n":[1.001,{"h":1.235}],"position":[99.679,-0.0],"tick":12}"#
        );
    }
}
