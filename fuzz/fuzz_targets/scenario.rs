//! A scenario (the body of POST /api/matches, or a file for `fieldhouse run`), any
//! bytes: refused naming a field, never a panic, whether by the document's check or by
//! the world it describes (some values, like a scripted launch's speed, are checked
//! there). A fly-ball world that builds must also play a few ticks; basketball needs
//! motion data and stops at the check.
#![no_main]

use fieldhouse_core::sim::{Scenario, Sport, World};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(scenario) = Scenario::from_json(data) else {
        return;
    };
    if scenario.sport == Sport::Basketball {
        return;
    }
    let Ok(mut world) = World::new(&scenario, None) else {
        return;
    };
    let mut events = Vec::new();
    for _ in 0..30 {
        world.step(&mut events);
    }
    let _ = world.state();
});
