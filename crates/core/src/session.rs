//! A match being played, whoever plays it: a [`World`] with its id and frame rate, which
//! steps tick by tick and encodes a `frame` (once) whenever one is due. The server's
//! match tasks, headless runs and replay verification all drive one, so a replay's
//! frames and a live match's are the same bytes from the same code.

use crate::protocol::{write_frame, Event, Frame, FrameShape};
use crate::sim::World;
use crate::tags;

/// How every frame starts: `type` is its first key.
const FRAME_HEAD: &str = r#"{"type":"frame","#;

/// `frame` with `"sent_us": sent_us` (when it was sent, µs since the Unix epoch) as its
/// second key, right after `"type":"frame"`, where a load generator finds it without
/// parsing the frame. A frame is encoded once for every spectator and the replay (which
/// must not carry the stamp); a stamped copy is made only when the server is asked to
/// stamp frames (a load test), so the stamp goes into the encoded bytes instead of
/// encoding the frame a second time. Every frame starts with the same head (tested for
/// each sport), so there is always a place for it.
pub fn stamped(frame: &str, sent_us: u64) -> String {
    let rest = frame.strip_prefix(FRAME_HEAD);
    debug_assert!(rest.is_some(), "a frame starts with {FRAME_HEAD}: {frame}");
    match rest {
        Some(rest) => format!(r#"{FRAME_HEAD}"sent_us":{sent_us},{rest}"#),
        None => frame.to_owned(),
    }
}

/// A match being played: its world, id and frame rate, and the events not yet framed.
pub struct Session {
    /// The match's world, for its clock, status and result.
    pub world: World,
    /// The match's id, which every frame carries.
    id: String,
    frame_every: u64,
    /// Events since the last frame.
    events: Vec<Event>,
    /// The tick of the last frame encoded.
    framed: Option<u64>,
    /// The protocol version the frames are written in.
    shape: FrameShape,
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
            shape: FrameShape::CURRENT,
        }
    }

    /// The match's id, as its frames and `end` carry it.
    pub fn id(&self) -> &str {
        &self.id
    }

    /// The session writing its frames as an older protocol version did: what verifying
    /// a replay recorded in that version compares.
    pub fn in_shape(self, shape: FrameShape) -> Session {
        Session { shape, ..self }
    }

    /// The frame of the world as it is now, with the events since the last one, its
    /// numbers rounded to a millimetre ([`write_frame`]).
    pub fn frame(&mut self) -> String {
        let mut out = Vec::with_capacity(1024);
        self.frame_into(&mut out);
        String::from_utf8(out).expect("frames are UTF-8")
    }

    /// Appends the frame of the world as it is now to `out` (one line, no newline): what
    /// a headless run does, batching frames without a buffer of their own each.
    pub fn frame_into(&mut self, out: &mut Vec<u8>) {
        let (ball, mut agents, score) = self.world.state();
        self.shape.shape(&mut agents);
        let tick = self.world.tick();
        write_frame(
            out,
            &Frame {
                kind: tags::Frame,
                match_id: &self.id,
                tick,
                time_s: self.world.time_s(),
                ball,
                agents,
                score,
                events: &self.events,
            },
        );
        self.events.clear();
        self.framed = Some(tick);
    }

    /// Steps one tick; returns the frame if one is due (every `tick_hz / frame_hz` ticks,
    /// and at the end of the match).
    pub fn step(&mut self) -> Option<String> {
        self.tick_and_frame_due().then(|| self.frame())
    }

    /// Steps one tick; appends the frame to `out` if one is due, and says whether it did.
    pub fn step_into(&mut self, out: &mut Vec<u8>) -> bool {
        let due = self.tick_and_frame_due();
        if due {
            self.frame_into(out);
        }
        due
    }

    /// Steps one tick; whether a frame is due now.
    fn tick_and_frame_due(&mut self) -> bool {
        self.world.step(&mut self.events);
        self.world.tick().is_multiple_of(self.frame_every) || self.world.finished()
    }

    /// The last frame, when a match stops: only if something happened since the last one.
    pub fn last_frame(&mut self) -> Option<String> {
        self.last_frame_due().then(|| self.frame())
    }

    /// Whether the match's stop needs a last frame (see [`Session::last_frame`]).
    pub fn last_frame_due(&self) -> bool {
        self.framed != Some(self.world.tick()) || !self.events.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::{stamped, Session};
    use crate::sim::{Scenario, World};
    use serde_json::{json, Value};

    #[test]
    fn every_sport_s_frames_take_the_stamp_as_their_second_key() {
        for sport in ["baseball", "cricket", "basketball"] {
            let scenario = Scenario::from_value(json!({"sport": sport})).unwrap();
            let caps = (sport == "basketball").then(crate::fixtures::cmu_capabilities);
            let world = World::new(&scenario, caps).unwrap();
            let mut session = Session::new(world, "m".into(), scenario.tick_hz, scenario.frame_hz);
            let mut frames = vec![session.frame()];
            frames.extend((0..200).filter_map(|_| session.step()));
            for frame in frames {
                let out = stamped(&frame, 1_700_000_000_123_456);
                assert!(
                    out.starts_with(r#"{"type":"frame","sent_us":1700000000123456,"#),
                    "{out}"
                );
                let mut stamped: Value = serde_json::from_str(&out).unwrap();
                let original: Value = serde_json::from_str(&frame).unwrap();
                stamped.as_object_mut().unwrap().remove("sent_us");
                assert_eq!(stamped, original, "nothing else changes");
            }
        }
    }
}
