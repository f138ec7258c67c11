//! Basketball as in Sukthankar, Mandel & Sycara (2008): TEAMBOTS-like agents on a half
//! court who move with motion capture, plan with cost maps, and model their opponent.
//!
//! * [`court`]: the FIBA half court and its squares.
//! * [`shot`]: shot success against distance.
//! * [`capability`]: each behaviour's motion graph and cost map (the physical
//!   capability model, a [`Mover`]), embedded at an agent's pose (a [`Reach`]); moves
//!   play a map's stored path.
//!   [`human`]: what people do, the targets the capability model is held to.
//!   `footprint`: the ground a stored path covers, to keep moves on the court.
//! * [`decision`]: opponent modelling, `C_o > C_d + T_s + ε`; [`parametric`]: the
//!   kinematic and isotropic models of an opponent, fitted to its maps, that the human
//!   model is compared with.
//! * [`agent`], `brain`, [`game`]: the game as a deterministic state machine; the
//!   offense's `simple` and `costmap` brains; the defender.
//! * [`event`]: what a game reports; [`safe`]: a decision's safe squares as a bitmap.
//! * [`eval`]: the paper's experiment, possessions and points per possession.

pub mod agent;
mod brain;
pub mod capability;
pub mod court;
pub mod decision;
pub mod eval;
pub mod event;
mod footprint;
pub mod game;
pub mod human;
pub mod parametric;
pub mod params;
pub mod safe;
pub mod shot;

pub use agent::{Action, Team};
pub use brain::RUN_OFF_M;
pub use capability::{Capabilities, DefenderMotion, Motion, Mover, Reach, StateMap, Stride};
pub use court::Court;
pub use decision::{
    BeyondHorizon, Candidate, Chosen, Decision, DecisionParams, Keep, Opponent, Situation,
};
pub use eval::{compare, evaluate, Comparison, EvalReport};
pub use event::{
    BallState, BallView, ChosenView, Decided, Event, Outcome, PassCaught, Passed, PlayerView,
    PoseBlend, PossessionEnded, Shot,
};
pub use game::{Game, Order};
pub use params::{Brain, DefenderAim, DefenderModel, DefenderParams, GameParams, SimpleParams};
pub use shot::ShotModel;
#[cfg(test)]
mod tests;
