//! The `fieldhouse` binary driven as a user drives it: the command line, a real server
//! over real sockets, the page in a real browser. One test crate with a
//! module per area (each file was its own crate, and each linked the whole workspace: 16
//! links and their disk on every build); run one area with
//! `cargo nextest run --test it -E 'test(/^server::/)'`.

mod common;

mod browser;
mod cli_basketball;
mod cli_catch;
mod cli_motion;
mod connections;
mod court_bounds;
mod docs_commands;
mod independent_fielder;
mod loadgen;
mod match_safety;
mod mocap_data;
mod operations;
mod reliability;
mod replay;
mod replay_files;
mod server;
