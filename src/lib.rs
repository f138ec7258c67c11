//! fieldhouse: a multi-agent team sports simulation server and its simulation core.
//!
//! # Layout
//!
//! The workspace's crates show the architecture; this package is the binary and puts
//! them under one name for its command line, tests and benchmarks:
//!
//! * `fieldhouse-core` (re-exported here module by module: [`physics`], [`perception`],
//!   [`fielding`], [`motion`], [`costmap`], [`basketball`], [`sim`], [`driver`], [`budget`],
//!   [`protocol`], [`session`], [`replay`], [`strict_json`], [`names`], [`words`]): the deterministic
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
//! 1. A bot's command arrives on its socket (`server::bot`, the bot socket loop), is
//!    checked for size and WebSocket framing, decoded by [`protocol::decode`] (strict
//!    JSON), and sent to its match's task as a `server::state::ToMatch::Driver`.
//! 2. The match task (`server::match_task`, `MatchTask::forward`) hands it to the match's
//!    [`driver::MatchDriver::handle`] as a [`driver::BotEvent::Said`] with `now`; the
//!    driver decides what it costs (an answer to a perception is free, anything else
//!    pays the seat's [`budget`]), checks its tick window and passes it to
//!    [`sim::World::command`].
//! 3. The task sleeps until the time [`driver::MatchDriver::poll_timeout`] names, then
//!    calls [`driver::MatchDriver::handle_timeout`], which steps the
//!    [`session::Session`]: [`sim::World::step`], and on frame ticks the frame encoded
//!    once ([`session::Session::step`]).
//! 4. The task drains [`driver::MatchDriver::poll_transmit`] (perceptions, errors and
//!    closes for bot connections, each to its connection's queue) and
//!    [`driver::MatchDriver::poll_output`] (`MatchTask::carry_out`): an
//!    [`driver::Output::Frame`] is published on the match's watch channel, whose bytes
//!    a few fan-out tasks (`server::fanout`) write unchanged to every spectator's socket,
//!    and handed to the replay's writer thread (`server::recording`). When the match
//!    ends, the driver frames what is left and encodes the `end` once
//!    ([`driver::Output::End`]); the task finishes the replay, then publishes it.

pub use fieldhouse_core::{
    basketball, budget, costmap, driver, fielding, motion, names, perception, physics, protocol,
    replay, session, sim, strict_json, words,
};
pub use fieldhouse_loadgen as loadgen;
pub use fieldhouse_server as server;
