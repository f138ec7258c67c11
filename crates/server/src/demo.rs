//! The built-in demo matches a newcomer sees at once: an outfield of three fielders with
//! different strategies, a cricket ring, and the paper's 2-v-1 basketball. They run for
//! ever, in real time.

use super::api;
use super::state::AppState;
use fieldhouse_core::sim::{Mode, Options, Scenario, Sport};
use std::sync::Arc;

/// The demo matches, each with the fixed id it is listed under.
pub fn scenarios() -> Vec<(&'static str, Scenario)> {
    let demo = |sport: Sport, name: &str| Scenario {
        name: Some(name.to_string()),
        sport,
        seed: 1,
        tick_hz: 60.0,
        frame_hz: 30.0,
        mode: Mode::Realtime,
        lockstep_deadline_ms: 1000,
        duration_s: None,
        agents: Vec::new(),
        options: Options::default(),
    };
    vec![
        (
            "demo-baseball",
            demo(
                Sport::Baseball,
                "Outfield: chapman, lot-optical and predictive",
            ),
        ),
        (
            "demo-cricket",
            demo(Sport::Cricket, "Cricket: five fielders on the ring"),
        ),
        (
            "demo-basketball",
            demo(Sport::Basketball, "Basketball 2-v-1: cost-map offense"),
        ),
    ]
}

/// Starts every demo match in `app` (a failure is logged: the server serves without it).
pub fn start_all(app: &Arc<AppState>) {
    for (id, scenario) in scenarios() {
        match api::start(app, scenario, Some(id.to_string()), true) {
            Ok(_) => tracing::info!(id, "demo match started"),
            Err(e) => tracing::warn!(id, error = ?e, "demo match could not start"),
        }
    }
}
