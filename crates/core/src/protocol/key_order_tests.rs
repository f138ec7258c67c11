//! Protocol 2's byte layout: every object inside a frame, and the hello's `field`, lists
//! its keys in alphabetical order (they were built as `serde_json::Value`s, whose maps
//! sort their keys), while the frame itself keeps the order of its declaration, `type`
//! first. Replays are verified byte for byte, so the derived serialisers must keep that
//! layout: this plays a match of each sport, with every kind of event, and reads the
//! bytes as written.
//!
//! The keys are read in the order they appear in the text, by a walk of the JSON with
//! serde's visitor: a `serde_json::Value` would sort them itself (it keeps their order
//! only with serde_json's `preserve_order` feature, which would then be on for every
//! crate of the build).

use crate::fixtures::cmu_capabilities;
use crate::session::Session;
use crate::sim::{Scenario, Sport, World};
use serde::de::{self, DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use std::collections::BTreeSet;
use std::fmt;

/// What a walk of one JSON text found.
#[derive(Default)]
struct Keys {
    /// The top-level object's keys, in order.
    top: Vec<String>,
    /// `path: keys` of every object below the top whose keys are out of order.
    unsorted: Vec<String>,
    /// Every key seen below the top level.
    seen: BTreeSet<String>,
    /// Each event's `kind`.
    kinds: BTreeSet<String>,
}

/// A JSON value at `path` (`""` for the top), walked in the order of its text.
struct Walk<'k> {
    path: String,
    keys: &'k mut Keys,
}

impl<'de> DeserializeSeed<'de> for Walk<'_> {
    type Value = Option<String>;

    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Option<String>, D::Error> {
        d.deserialize_any(self)
    }
}

/// Walks a value; yields the text of a string, for an event's `kind`.
impl<'de> Visitor<'de> for Walk<'_> {
    type Value = Option<String>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }

    fn visit_bool<E: de::Error>(self, _: bool) -> Result<Option<String>, E> {
        Ok(None)
    }

    fn visit_i64<E: de::Error>(self, _: i64) -> Result<Option<String>, E> {
        Ok(None)
    }

    fn visit_u64<E: de::Error>(self, _: u64) -> Result<Option<String>, E> {
        Ok(None)
    }

    fn visit_f64<E: de::Error>(self, _: f64) -> Result<Option<String>, E> {
        Ok(None)
    }

    fn visit_str<E: de::Error>(self, text: &str) -> Result<Option<String>, E> {
        Ok(Some(text.to_owned()))
    }

    fn visit_unit<E: de::Error>(self) -> Result<Option<String>, E> {
        Ok(None)
    }

    fn visit_seq<A: SeqAccess<'de>>(self, mut items: A) -> Result<Option<String>, A::Error> {
        let mut k = 0;
        while items
            .next_element_seed(Walk {
                path: format!("{}[{k}]", self.path),
                keys: &mut *self.keys,
            })?
            .is_some()
        {
            k += 1;
        }
        Ok(None)
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Option<String>, A::Error> {
        let mut names = Vec::new();
        while let Some(name) = map.next_key::<String>()? {
            let value = map.next_value_seed(Walk {
                path: format!("{}.{name}", self.path),
                keys: &mut *self.keys,
            })?;
            if name == "kind" && self.path.starts_with(".events[") {
                self.keys.kinds.extend(value);
            }
            names.push(name);
        }
        if self.path.is_empty() {
            self.keys.top = names;
        } else {
            if !names.is_sorted() {
                self.keys
                    .unsorted
                    .push(format!("{}: {}", self.path, names.join(", ")));
            }
            self.keys.seen.extend(names);
        }
        Ok(None)
    }
}

/// Walks `json`, adding what it finds to `keys`.
fn walk(json: &str, keys: &mut Keys) {
    let mut d = serde_json::Deserializer::from_str(json);
    Walk {
        path: String::new(),
        keys,
    }
    .deserialize(&mut d)
    .expect("valid JSON");
    d.end().expect("one JSON value");
}

/// Plays `sport` until every kind of event in `kinds` has been framed, with the first
/// agent under a bot for the last seconds (so its `controller` shows); checks the order
/// of the keys of every frame and of the hello's `field`, and returns every key seen.
fn check(sport: Sport, kinds: &[&str]) -> BTreeSet<String> {
    let scenario = Scenario::from_value(serde_json::json!({
        "sport": sport.name(), "seed": 7, "mode": "fast", "duration_s": 90.0,
    }))
    .expect("a valid scenario");
    let caps = (sport == Sport::Basketball).then(cmu_capabilities);
    let world = World::new(&scenario, caps).expect("a world");
    let mut keys = Keys::default();
    walk(&crate::protocol::encode(&world.field()), &mut keys);
    let mut session = Session::new(world, "keys".into(), scenario.tick_hz, 30.0);
    let mut controlled_for = None;
    while !session.world.finished() && controlled_for.is_none_or(|frames| frames > 0) {
        let Some(frame) = session.step() else {
            continue;
        };
        let mut frame_keys = Keys::default();
        walk(&frame, &mut frame_keys);
        assert_eq!(
            frame_keys.top,
            ["type", "match", "tick", "time_s", "ball", "agents", "score", "events"],
            "a frame's own keys, in the order of its declaration"
        );
        keys.unsorted.append(&mut frame_keys.unsorted);
        keys.seen.append(&mut frame_keys.seen);
        keys.kinds.append(&mut frame_keys.kinds);
        if let Some(frames) = &mut controlled_for {
            *frames -= 1;
        } else if kinds.iter().all(|k| keys.kinds.contains(*k)) {
            session.world.set_controlled(0, true);
            controlled_for = Some(30);
        }
    }
    assert_eq!(
        keys.kinds,
        kinds.iter().map(|k| k.to_string()).collect(),
        "{sport:?}: the events framed"
    );
    assert!(
        keys.unsorted.is_empty(),
        "{sport:?}: objects whose keys are out of alphabetical order:\n{}",
        keys.unsorted.join("\n")
    );
    keys.seen
}

#[test]
fn every_object_in_a_fly_ball_frame_has_its_keys_in_alphabetical_order() {
    for sport in [Sport::Baseball, Sport::Cricket] {
        let seen = check(sport, &["caught", "landed", "launch"]);
        for optional in ["controller", "velocity", "nearest", "miss_m"] {
            assert!(
                seen.contains(optional),
                "{sport:?}: no frame had {optional}"
            );
        }
    }
}

#[test]
fn every_object_in_a_basketball_frame_has_its_keys_in_alphabetical_order() {
    let seen = check(
        Sport::Basketball,
        &[
            "decision",
            "pass",
            "pass_caught",
            "possession_ended",
            "shot",
        ],
    );
    for optional in ["controller", "blend", "chosen", "safe", "box", "c_o"] {
        assert!(seen.contains(optional), "no frame had {optional}");
    }
}
