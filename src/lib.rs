//! fieldhouse: a multi-agent team sports simulation core.
//!
//! # Layout
//!
//! The library is the deterministic simulation core: no I/O, no clock, no threads of its
//! own (a sweep may fan work out with rayon, but its results never depend on it). The
//! same inputs give the same bits on the same build, which keeps tests simple and
//! results reproducible. Modules, in the order data flows:
//!
//! * [`physics`]: ball flight. Gravity, Nathan's drag and Magnus lift, a fixed-step RK4
//!   integrator, bounces and rolls; baseball and cricket presets.
//! * [`perception`]: what a fielder can see from its eye: the elevation tan ψ and bearing
//!   α of the ball and their rates by differences, with optional delay and noise.
//! * [`fielding`]: fielders with human limits, the sub-tick catch test, the catching
//!   strategies (Chapman/OAC with Tresilian's lateral term, Gillies & Dodgson's LOT,
//!   McBeath's optical LOT, trajectory prediction), single trials and sweeps.
//! * [`names`]: the names users type for presets, and the error a wrong one gets.
//!
//! The `fieldhouse` binary (`src/main.rs`, `src/cli/`) is a thin shell: it parses the
//! command line, runs the core, prints text or JSON and draws SVG plots.

pub mod costmap;
pub mod fielding;
pub mod motion;
pub mod names;
pub mod perception;
pub mod physics;
