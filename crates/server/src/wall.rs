//! The time of day, read in one place. The simulation and the replay format take times
//! as arguments (the core has no clock); the edge reads the wall clock here, for what is
//! about the world outside the match: when a recording started, when a frame left.

use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// Time since the Unix epoch now (zero on a clock set before it).
pub fn since_epoch() -> Duration {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap_or_default()
}
