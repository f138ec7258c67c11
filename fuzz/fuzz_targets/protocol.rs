//! A bot's message, any bytes: decoding either gives a command or a `(code, message)`
//! error, never a panic. A command that decodes is given to a world, which must accept
//! or refuse it without panicking either.
#![no_main]

use fieldhouse_core::protocol::{decode, ClientMessage};
use fieldhouse_core::sim::{Scenario, World};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(ClientMessage::Command { action, .. }) = decode(text) {
        let scenario =
            Scenario::from_json(br#"{"sport": "baseball", "mode": "fast", "duration_s": 1}"#)
                .expect("a valid scenario");
        let mut world = World::new(&scenario, None).expect("a world");
        world.set_controlled(0, true);
        let _ = world.command(0, &action);
        let mut events = Vec::new();
        world.step(&mut events);
    }
});
