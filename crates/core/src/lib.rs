//! The deterministic simulation core of fieldhouse: no clock, no sockets, no threads of
//! its own (a sweep may fan work out with rayon, but its results never depend on it).
//! The same inputs give the same bits on the same build, which keeps tests simple,
//! results reproducible and replays verifiable. This crate cannot depend on tokio, axum
//! or a network crate (`scripts/check-architecture` fails if it does), so "the core does
//! no I/O" is checked, not a convention.
//!
//! It reads no clock and no environment, and opens no file but motion capture: times
//! (when a recording started) are handed in by the edge, the server and the CLI; the
//! cost-map cache is a [`costmap::cache::Store`] the CLI implements over its directory;
//! replays are written to a writer the edge opened and read from bytes, or at positions
//! from a [`replay::Source`] (the server's open file). The one named reader is the
//! motion loader (a user's `--mocap DIR`; the CMU clips are embedded), which walks a
//! directory of BVH and ASF/AMC files; the formats' parsers take bytes, as the fuzz
//! targets do. `clippy.toml` forbids clocks, the environment and `std::fs` elsewhere in
//! the crate (tests excepted), and `scripts/check-architecture` fails if a new place
//! allows them.
//!
//! # Layout
//!
//! Modules, in the order data flows:
//!
//! * [`physics`]: ball flight. Gravity, Nathan's drag and Magnus lift, a fixed-step RK4
//!   integrator, bounces and rolls; baseball and cricket presets.
//! * [`perception`]: what a fielder can see from its eye (the elevation tan ψ and bearing
//!   α of the ball) and judge, with a person's errors (the image's speed and direction, a
//!   distance cue only up close), and its estimate of the present from its looks:
//!   least-squares fits of the angles, carried over the delay with its own movement
//!   taken out.
//! * [`fielding`]: fielders with human limits, the ideal and human observers, the
//!   sub-tick catch test, the catching strategies (Chapman/OAC with Tresilian's lateral
//!   term, Gillies & Dodgson's LOT, McBeath's optical LOT, trajectory prediction), single
//!   trials, sweeps, path shapes and the optical signatures.
//! * [`motion`]: human motion: motion capture in BVH or CMU's ASF/AMC (the CMU clips
//!   embedded in the binary, or a user's own directory) loaded into clips, each also
//!   mirrored, and the motion graph of a behaviour (Kovar et al. 2002): transitions
//!   between similar frames, as many as the capture's own smoothness allows, pruned to
//!   the largest strongly connected component; how good each cut is; how soon a body
//!   turns around.
//! * [`costmap`]: Sukthankar et al.'s physical capability model: the frames a human needs
//!   to reach each square around it from a start state (a stance and its mirror image,
//!   or a way of moving), by Monte Carlo walks, search, or grassfire.
//! * [`basketball`]: the paper's basketball domain: a half court, agents that move with
//!   motion capture along cost-map paths that go on from the node each body is playing
//!   (one continuous walk on the graph), opponent modelling (`C_o > C_d + T_s + ε`) with
//!   the defender modelled by maps or by kinematic and isotropic models fitted to them,
//!   the `simple` and `costmap` offenses, the capability targets against people, and
//!   the possession experiment.
//! * [`sim`]: a whole match of any sport as one deterministic [`sim::World`]: scenarios
//!   checked field by field, fly balls with fielders, basketball, bots' commands.
//! * [`protocol`]: the WebSocket messages (version 3) as Rust types, as the server sends
//!   and reads them; frames are written with their numbers rounded to a millimetre.
//! * [`tags`]: the constant strings on the wire (`"type": "frame"`, `"controller":
//!   "bot"`) as types, which the game's own views share with the protocol.
//! * [`schemas`]: the JSON Schemas in `proto/`, generated from the protocol's types.
//! * [`session`]: a world with its id and frame rate, stepping and encoding frames: what
//!   the server, headless runs and replay verification all drive.
//! * [`driver`]: a match as a sans-IO state machine: the realtime, fast and lock-step
//!   tick policies, lock-step deadlines, the stale/future tick windows and bot seats.
//!   It takes events and `now` and says when it next needs waking; the server's match
//!   task only forwards sockets and timers to it.
//! * [`budget`]: token buckets: what a client may send a second (a bot's, kept by the
//!   driver; a spectator's, by its socket), with the time handed in.
//! * [`replay`]: replay files (JSON lines: header, frames, bot commands, footer with a
//!   hash over the frames), written append-only, read back to a torn record, verified by
//!   re-simulation.
//! * [`strict_json`]: JSON as read from clients, refusing an object that names a key
//!   twice.
//! * [`names`]: the names users type for presets, and the error a wrong one gets.
//! * [`words`]: how counts and figures read in text for people (`1 possession`, `2.82`).

// Tests may touch files and read the environment; the crate itself may not (clippy.toml).
#![cfg_attr(test, allow(clippy::disallowed_methods))]
// Every public item of the core is documented: other crates build on it, and its
// documentation is where units, frames and the papers' conventions are stated.
#![warn(missing_docs)]

pub mod basketball;
pub mod budget;
pub mod costmap;
pub mod driver;
pub mod fielding;
/// Shared test inputs (synthetic clips and graphs; the CMU library, graphs and
/// capabilities built once per test binary): this crate's tests and, with the `fixtures`
/// feature, other crates' tests.
#[cfg(any(test, feature = "fixtures"))]
#[doc(hidden)]
pub mod fixtures;
pub mod motion;
pub mod names;
pub mod perception;
pub mod physics;
pub mod protocol;
pub mod replay;
pub mod schemas;
pub mod session;
pub mod sim;
pub mod strict_json;
pub mod tags;
pub mod words;
