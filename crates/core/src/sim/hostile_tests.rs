//! Property: whatever numbers a bot sends — NaN, infinities, the largest floats,
//! subnormals — no non-finite number ever reaches the world. Each case plays a short
//! match with every agent under a hostile bot and checks every state it shows against
//! the published frame schema, whose coordinates are plain JSON numbers: a NaN or an
//! infinity would serialise as `null` there and fail it.

use super::{Action, Scenario, Sport, World};
use crate::fixtures::cmu_capabilities;
use crate::protocol::{encode, Frame};
use proptest::prelude::*;
use serde_json::Value;

/// Any float, with the hostile ones made common rather than left to chance.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::NAN),
        Just(f64::INFINITY),
        Just(f64::NEG_INFINITY),
        Just(f64::MAX),
        Just(f64::MIN),
        Just(f64::MIN_POSITIVE / 2.0),
        -100.0..100.0,
        any::<f64>(),
    ]
}

fn action() -> impl Strategy<Value = Action> {
    let pair = || [number(), number()];
    prop_oneof![
        pair().prop_map(|accel| Action::Accelerate { accel }),
        pair().prop_map(|target| Action::RunTo { target }),
        pair().prop_map(|target| Action::MoveTo { target }),
        prop_oneof![Just("o2"), Just("o1"), Just("d1"), Just("nobody")]
            .prop_map(|to| Action::Pass { to: to.into() }),
        Just(Action::Shoot {}),
        Just(Action::Stand {}),
    ]
}

/// Commands with the ticks to run after each: (agent index, action, ticks).
fn orders() -> impl Strategy<Value = Vec<(usize, Action, u8)>> {
    prop::collection::vec((0usize..5, action(), 1u8..40), 1..25)
}

fn scenario(sport: Sport) -> Scenario {
    let value =
        serde_json::json!({"sport": sport.name(), "seed": 7, "mode": "fast", "duration_s": 60.0});
    Scenario::from_value(value).expect("a valid scenario")
}

fn frame_schema() -> jsonschema::Validator {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../proto/frame.schema.json");
    let text = std::fs::read_to_string(path).expect("the frame schema");
    jsonschema::validator_for(&serde_json::from_str(&text).unwrap()).expect("a valid schema")
}

fn play(world: &mut World, orders: &[(usize, Action, u8)], schema: &jsonschema::Validator) {
    let agents = world.agent_ids().len();
    for k in 0..agents {
        world.set_controlled(k, true);
    }
    let mut events = Vec::new();
    for (k, action, ticks) in orders {
        // Refusals are fine (and expected for most of these); what matters is the world.
        let _ = world.command(k % agents, action);
        for _ in 0..*ticks {
            events.clear();
            world.step(&mut events);
            let (ball, agents, score) = world.state();
            let frame = Frame {
                kind: crate::tags::Frame,
                match_id: "hostile",
                tick: world.tick(),
                time_s: world.time_s(),
                ball,
                agents,
                score,
                events: &events,
            };
            let frame: Value = serde_json::from_str(&encode(&frame)).unwrap();
            let errors: Vec<String> = schema
                .iter_errors(&frame)
                .map(|e| format!("{e} at {}", e.instance_path))
                .collect();
            assert!(
                errors.is_empty(),
                "after {action:?}, tick {}: {errors:?}",
                world.tick()
            );
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn hostile_fielder_commands_never_reach_the_world(orders in orders()) {
        let schema = frame_schema();
        for sport in [Sport::Baseball, Sport::Cricket] {
            let mut world = World::new(&scenario(sport), None).unwrap();
            play(&mut world, &orders, &schema);
        }
    }

    #[test]
    fn hostile_player_commands_never_reach_the_world(orders in orders()) {
        let schema = frame_schema();
        let mut world = World::new(&scenario(Sport::Basketball), Some(cmu_capabilities())).unwrap();
        play(&mut world, &orders, &schema);
    }
}
