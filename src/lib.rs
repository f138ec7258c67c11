//! fieldhouse: a multi-agent team sports simulation server and its simulation core.
//!
//! # Layout
//!
//! The workspace's crates show the architecture; this package is the binary and puts
//! them under one name for its command line, tests and benchmarks:
//!
//! * `fieldhouse-core` (re-exported here module by module: [`physics`], [`perception`],
//!   [`fielding`], [`motion`], [`costmap`], [`basketball`], [`sim`], [`protocol`],
//!   [`session`], [`replay`], [`strict_json`], [`names`], [`words`]): the deterministic
//!   simulation core. It cannot depend on tokio, axum or a network crate.
//! * [`server`] (`fieldhouse-server`): the I/O shell. Match tasks drive the core's
//!   worlds on tokio; WebSockets for spectators, bots and replay viewers; the REST API;
//!   metrics. The only crate that reads a clock or opens a listening socket.
//! * [`loadgen`] (`fieldhouse-loadgen`): the load generator and soak, clients of the
//!   protocol that measure a server from outside.
//! * The `fieldhouse` binary (`src/main.rs`, `src/cli/`): a thin shell that parses the
//!   command line, runs the core or the server, prints text or JSON and draws pictures.
//!
//! # Follow one tick
//!
//! A bot's command arrives on its socket in `server::ws` (the bot socket), is checked
//! (size, strict JSON, budget) and decoded by [`protocol::decode`], and goes to its
//! match task as a `Control::Command` over the match's channel. The task
//! (`server::match_task`) forwards it to the match's sans-IO driver, which checks its
//! tick window and hands it to [`sim::World::command`]. When the driver's timer is due
//! the task calls it again; it steps the [`session::Session`], which calls
//! [`sim::World::step`] and, on frame ticks, encodes the frame once. The task publishes
//! those bytes on a watch channel that every spectator socket reads and sends unchanged,
//! and hands the same bytes to the match's replay writer (`server::recording`).

pub use fieldhouse_core::{
    basketball, costmap, fielding, motion, names, perception, physics, protocol, replay, session,
    sim, strict_json, words,
};
pub use fieldhouse_loadgen as loadgen;
pub use fieldhouse_server as server;
