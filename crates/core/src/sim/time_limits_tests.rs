//! Property: a scenario that passes validation can be run. Whatever its time-like
//! numbers (rates, deadlines, durations, pauses, clocks) — near the limits, subnormal,
//! huge — if `Scenario::from_value` accepts it, its world builds, its periods convert
//! to `Duration`s and it steps, without a panic. A panic there once killed a match task
//! and left a zombie match (`tick_hz` 1e-300, found by an outside attacker).

use super::{Scenario, World};
use crate::fixtures::cmu_capabilities;
use crate::session::Session;
use proptest::prelude::*;
use serde_json::{json, Value};

/// A time-like number: the limits and their neighbours, and hostile floats.
fn number() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(f64::MIN_POSITIVE / 2.0),
        Just(1e-300),
        Just(f64::MAX),
        Just(0.0),
        Just(-1.0),
        Just(0.1),
        Just(0.099_999),
        Just(1.0),
        Just(0.999_999),
        Just(1000.0),
        Just(1_000.000_1),
        Just(604_800.0),
        Just(604_800.1),
        Just(1e6),
        0.0..2000.0,
        any::<f64>(),
    ]
}

/// The JSON a client could send; NaN and infinities are not JSON, so they become null.
fn scenario() -> impl Strategy<Value = Value> {
    (
        prop_oneof![Just("baseball"), Just("cricket"), Just("basketball")],
        prop_oneof![Just("realtime"), Just("lockstep"), Just("fast")],
        [number(), number(), number(), number(), number()],
        prop_oneof![
            Just(0u64),
            Just(1),
            Just(60_000),
            Just(60_001),
            Just(u64::MAX)
        ],
    )
        .prop_map(
            |(sport, mode, [tick_hz, frame_hz, duration_s, pause_s, clock], deadline)| {
                let mut s = json!({
                    "sport": sport, "mode": mode, "tick_hz": tick_hz, "frame_hz": frame_hz,
                    "duration_s": duration_s, "lockstep_deadline_ms": deadline,
                });
                s["options"] = if sport == "basketball" {
                    json!({"shot_clock_s": clock, "possessions": 1})
                } else {
                    json!({"pause_s": pause_s, "launches": [{"time_s": clock, "speed_m_s": 30.0,
                    "elevation_deg": 40.0, "azimuth_deg": 45.0}]})
                };
                s
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn a_scenario_that_validates_runs(value in scenario()) {
        let Ok(s) = Scenario::from_value(value) else { return Ok(()) };
        let _ = (s.tick_period(), s.lockstep_deadline());
        let caps = (s.sport == super::Sport::Basketball).then(cmu_capabilities);
        let Ok(world) = World::new(&s, caps) else { return Ok(()) };
        prop_assert!(world.perception_every_ticks() >= 1);
        let mut session = Session::new(world, "m".into(), s.tick_hz, s.frame_hz);
        for _ in 0..3 {
            session.step();
        }
        prop_assert!(session.world.time_s().is_finite());
    }
}

#[test]
fn a_tick_rate_the_timer_cannot_sleep_is_refused_with_its_field() {
    for (field, value, shown) in [
        ("tick_hz", 1e-300, "1e-300"),
        ("tick_hz", 0.5, "0.5"),
        ("frame_hz", 0.01, "0.01"),
    ] {
        let mut s = json!({"sport": "baseball", "tick_hz": 60.0, "frame_hz": 30.0});
        s[field] = json!(value);
        if field == "tick_hz" {
            s["frame_hz"] = json!(value);
        }
        let e = Scenario::from_value(s).unwrap_err();
        assert_eq!(e.path, field);
        assert!(
            e.to_string()
                .starts_with(&format!("{field}: must be from ")),
            "{e}"
        );
        assert!(e.to_string().ends_with(&format!("not {shown}")), "{e}");
    }
    let e = Scenario::from_value(json!({"sport": "cricket", "duration_s": 1e300})).unwrap_err();
    assert_eq!(e.path, "duration_s");
}
