//! Catching strategies: how a fielder turns what it sees into an acceleration.
//!
//! Every strategy but `predictive` reads only the fielder's [`Percept`] and its own body
//! (a runner knows how it is moving). `predictive` is the "trajectory prediction" theory
//! and the baseline: it is handed the answer, and so defines which balls are catchable.

mod chapman;
mod lot;
mod lot_optical;
mod predictive;

pub use chapman::Chapman;
pub use lot::{Lot, LotReference};
pub use lot_optical::LotOptical;
pub(crate) use predictive::run_to;
pub use predictive::{Forecast, Predictive};

use super::{Body, Limits};
use crate::names::{lookup, UnknownName};
use crate::perception::Percept;
use glam::DVec2;
use serde::{Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// The ball counts as "clearly above the eye" once its elevation passes about 3°
/// (tan ψ = 0.05). Below that, optical angles are dominated by the launch height and the
/// reference values a strategy latches would be meaningless.
pub const CLEARLY_ABOVE_EYE_TAN_PSI: f64 = 0.05;

/// A strategy's name, as selected on the command line and shown in reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum StrategyKind {
    /// Chapman's optical acceleration cancellation with Tresilian's lateral term
    /// (`chapman`).
    Chapman,
    /// Chapman's law alone, radial only (`chapman-1d`).
    Chapman1d,
    /// Gillies & Dodgson's Linear Optical Trajectory law (`lot`).
    Lot,
    /// McBeath, Shaffer & Kaiser's LOT, a law on the ball's image (`lot-optical`).
    LotOptical,
    /// Trajectory prediction: told where the ball comes down (`predictive`).
    Predictive,
}

impl StrategyKind {
    /// Every strategy, in the order reports list them.
    pub const ALL: [StrategyKind; 5] = [
        StrategyKind::Chapman,
        StrategyKind::LotOptical,
        StrategyKind::Predictive,
        StrategyKind::Lot,
        StrategyKind::Chapman1d,
    ];

    /// The name as typed on the command line and shown in reports.
    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Chapman => "chapman",
            StrategyKind::Chapman1d => "chapman-1d",
            StrategyKind::Lot => "lot",
            StrategyKind::LotOptical => "lot-optical",
            StrategyKind::Predictive => "predictive",
        }
    }
}

impl fmt::Display for StrategyKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Serialize for StrategyKind {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl FromStr for StrategyKind {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        const NAMES: [&str; 5] = ["chapman", "lot-optical", "predictive", "lot", "chapman-1d"];
        lookup("strategy", s, &NAMES, &Self::ALL)
    }
}

/// What a strategy may consult on one tick.
#[derive(Debug, Clone, Copy)]
pub struct Situation<'a> {
    /// What the fielder sees this tick: `None` until its eye has looked long enough (the
    /// optical strategies then stand still; `predictive` needs no eyes).
    pub percept: Option<&'a Percept>,
    /// The fielder's own position and velocity.
    pub body: &'a Body,
    /// The fielder's limits (only `predictive` plans with them; the body applies them).
    pub limits: &'a Limits,
    /// Home plate (the launch point) on the ground: the fielder knows where the batter is.
    pub home: DVec2,
    /// Time since the launch, s.
    pub t: f64,
    /// The tick, s.
    pub dt: f64,
}

/// A fielder's running strategy with whatever it remembers between ticks.
#[derive(Debug, Clone)]
pub enum Brain {
    /// `chapman` or `chapman-1d`.
    Chapman(Chapman),
    /// `lot`.
    Lot(Lot),
    /// `lot-optical`.
    LotOptical(LotOptical),
    /// `predictive`.
    Predictive(Predictive),
}

impl Brain {
    /// A new brain of `kind`; `lot_reference` is only consulted for `lot`, `forecast` for
    /// `predictive`.
    pub fn new(
        kind: StrategyKind,
        lot_reference: LotReference,
        forecast: impl FnOnce() -> Forecast,
    ) -> Brain {
        match kind {
            StrategyKind::Chapman => Brain::Chapman(Chapman::new(true)),
            StrategyKind::Chapman1d => Brain::Chapman(Chapman::new(false)),
            StrategyKind::Lot => Brain::Lot(Lot::new(lot_reference)),
            StrategyKind::LotOptical => Brain::LotOptical(LotOptical::default()),
            StrategyKind::Predictive => Brain::Predictive(Predictive::new(forecast())),
        }
    }

    /// The acceleration the fielder wants this tick (the body clips it to its limits).
    pub fn command(&mut self, s: &Situation) -> DVec2 {
        match self {
            Brain::Chapman(b) => b.command(s),
            Brain::Lot(b) => b.command(s),
            Brain::LotOptical(b) => b.command(s),
            Brain::Predictive(b) => b.command(s),
        }
    }
}

/// The unit vector a quarter turn from `u` toward increasing bearing α (α runs from +x
/// toward +z; with y up that is a turn to the right).
pub(crate) fn quarter_turn(u: DVec2) -> DVec2 {
    DVec2::new(-u.y, u.x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_typos_list_the_choices() {
        for k in StrategyKind::ALL {
            assert_eq!(k.name().parse::<StrategyKind>(), Ok(k));
            assert_eq!(k.to_string(), k.name());
        }
        let err = "lott".parse::<StrategyKind>().unwrap_err().to_string();
        assert!(
            err.contains("\"lott\"") && err.contains("lot-optical"),
            "{err}"
        );
    }

    #[test]
    fn a_quarter_turn_goes_toward_increasing_bearing() {
        let a: f64 = 0.3;
        let u = DVec2::new(a.cos(), a.sin());
        let b = a + 1e-6;
        let ahead = DVec2::new(b.cos(), b.sin());
        assert!((ahead - u).dot(quarter_turn(u)) > 0.0);
    }
}
