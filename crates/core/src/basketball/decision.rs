//! Opponent modelling (Sukthankar et al. 2008): shoot from a square the defender cannot
//! reach before the shot is away.
//!
//! For every square of the court the shooter compares C_o, the defender's time to reach
//! it (the defender's non-dribbling cost map embedded at the defender's pose), with C_d,
//! its own dribbling time (its dribbling map at its pose), plus T_s, the time a shot
//! takes, and a margin ε. The squares where `C_o > C_d + T_s + ε` are safe; of those it
//! picks the one with the best shot. The maps are precomputed, so a decision is two
//! table look-ups per square: O(n) in the squares.

use super::capability::Reach;
use super::court::Court;
use super::parametric::{Isotropic, Kinematic};
use super::shot::ShotModel;
use crate::costmap::{LocalFrame, LocalLattice};
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The parameters of the rule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DecisionParams {
    /// T_s: from the decision to shoot until the ball leaves the hands, s.
    pub shot_time_s: f64,
    /// ε: the margin the defender must be late by, s.
    pub epsilon_s: f64,
    /// What a square the defender's model does not reach within its horizon counts as.
    pub beyond_horizon: BeyondHorizon,
}

impl Default for DecisionParams {
    fn default() -> Self {
        DecisionParams {
            shot_time_s: 0.4,
            epsilon_s: 0.2,
            beyond_horizon: BeyondHorizon::Horizon,
        }
    }
}

/// A square a defender's map does not reach (farther in time than its horizon, or
/// outside the map) is not proof the defender cannot get there: how the rule counts it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum BeyondHorizon {
    /// C_o is the horizon: the defender needs at least that long, which the maps do say
    /// of a square within their extent.
    Horizon,
    /// Never safe: what the maps do not show is not counted on.
    Unsafe,
}

impl BeyondHorizon {
    /// The policy's name, as users write it.
    pub fn name(self) -> &'static str {
        match self {
            BeyondHorizon::Horizon => "horizon",
            BeyondHorizon::Unsafe => "unsafe",
        }
    }
}

impl std::str::FromStr for BeyondHorizon {
    type Err = crate::names::UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        crate::names::lookup(
            "beyond-horizon policy",
            s,
            &["horizon", "unsafe"],
            &[BeyondHorizon::Horizon, BeyondHorizon::Unsafe],
        )
    }
}

/// A square the shooter considered.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Candidate {
    /// The square's centre on the court, m.
    pub cell: [f64; 2],
    /// C_o, s. Where the defender's map does not reach, its horizon (the defender needs
    /// at least that long): see `beyond_horizon`.
    pub c_o: f64,
    /// True when C_o is the horizon of a map that does not reach the square: the
    /// defender needs *at least* that long.
    pub beyond_horizon: bool,
    /// C_d, s (0 for the square the shooter stands on, and for the map's start cell
    /// beside it: the shooter need not move to shoot from either).
    pub c_d: f64,
    /// The chance a shot from the square goes in.
    pub success: f64,
}

impl Candidate {
    /// The paper's inequality: the defender arrives after the shot is away, by ε (and,
    /// with [`BeyondHorizon::Unsafe`], the maps show it).
    pub fn qualifies(&self, params: &DecisionParams) -> bool {
        !(self.beyond_horizon && params.beyond_horizon == BeyondHorizon::Unsafe)
            && self.c_o > self.c_d + params.shot_time_s + params.epsilon_s
    }
}

/// The square chosen, with everything needed to check the rule by hand.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Chosen {
    /// The square's centre on the court, (x, z), m.
    pub cell: [f64; 2],
    /// The chance a shot from the square goes in.
    pub success: f64,
    /// C_o: the defenders' soonest time to the square, s.
    pub c_o: f64,
    /// True when `c_o` is a map's horizon: the defender needs at least that long.
    pub beyond_horizon: bool,
    /// C_d: the shooter's dribbling time to the square, s.
    pub c_d: f64,
    /// T_s: from the decision to shoot until the ball leaves the hands, s.
    pub t_s: f64,
    /// ε: the margin the defender must be late by, s.
    pub epsilon: f64,
    /// True when the shooter already stands on the square: shoot now.
    pub here: bool,
}

/// A decision with its working: the square chosen and every square considered, so the
/// rule can be checked by hand (`basketball-decide`).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Decision {
    /// The safe square with the best shot (of equal shots, the one the shooter reaches
    /// sooner); `None` when no square is safe.
    pub chosen: Option<Chosen>,
    /// Every square the shooter can reach within its map's horizon.
    pub candidates: Vec<Candidate>,
}

/// The shooter's side of the rule: who it is, what it models the defenders with.
pub struct Situation<'a> {
    /// The court whose squares are considered.
    pub court: &'a Court,
    /// Shot success against distance, to rank the safe squares.
    pub shot: &'a ShotModel,
    /// T_s and ε.
    pub params: &'a DecisionParams,
    /// What the shooter reaches dribbling, from where it is and how it moves.
    pub shooter: Reach<'a>,
    /// What the shooter believes each defender needs to reach a square.
    pub defenders: &'a [Opponent<'a>],
    /// What is left of the shot clock, s: a square the shooter cannot dribble to and
    /// shoot from before it runs out is not considered.
    pub shot_clock_s: f64,
}

/// What the shooter believes a defender needs to reach a square, s: C_o.
pub enum Opponent<'a> {
    /// A cost map embedded at the defender's pose and state (its own maps, or another
    /// behaviour's); beyond the map, the map's horizon (it needs at least that).
    Map(Reach<'a>),
    /// A kinematic model from the defender's pose and velocity.
    Kinematic {
        /// The defender's frame on the court.
        frame: LocalFrame,
        /// Its velocity in its own frame (+x ahead, +z right), m/s.
        velocity: DVec2,
        /// The model.
        model: Kinematic,
    },
    /// One speed in every direction from where the defender stands.
    Isotropic {
        /// Where the defender stands on the court, (x, z), m.
        at: DVec2,
        /// The model.
        model: Isotropic,
    },
    /// No model: never in time.
    Ignored,
}

impl Opponent<'_> {
    /// C_o for the world point `world`: the seconds this model says the defender needs
    /// to get there (infinite for [`Opponent::Ignored`]); for a map that does not reach
    /// it, the map's horizon.
    #[inline]
    pub fn seconds(&self, world: DVec2) -> f64 {
        self.reaches(world).0
    }

    /// [`Opponent::seconds`], and whether that is a map's horizon (the defender needs at
    /// least that long) rather than a time the model gives.
    #[inline]
    pub fn reaches(&self, world: DVec2) -> (f64, bool) {
        self.reaches_in(world, None)
    }

    /// The lattice `xs` × `zs` in this model's frame, for a model that looks points up
    /// in one.
    fn lattice(&self, xs: &[f64], zs: &[f64]) -> Option<LocalLattice> {
        match self {
            Opponent::Map(reach) => Some(reach.frame().lattice(xs, zs)),
            Opponent::Kinematic { frame, .. } => Some(frame.lattice(xs, zs)),
            Opponent::Isotropic { .. } | Opponent::Ignored => None,
        }
    }

    /// [`Opponent::reaches`], given `local`, `world` in the model's frame if it has one
    /// (from its [`Opponent::lattice`]).
    #[inline]
    fn reaches_in(&self, world: DVec2, local: Option<DVec2>) -> (f64, bool) {
        match self {
            Opponent::Map(reach) => {
                let local = local.unwrap_or_else(|| reach.frame().to_local(world));
                match reach.seconds_local(local) {
                    Some(s) => (s, false),
                    None => (reach.horizon_s(), true),
                }
            }
            Opponent::Kinematic {
                frame,
                velocity,
                model,
            } => {
                let local = local.unwrap_or_else(|| frame.to_local(world));
                (model.seconds(local, *velocity), false)
            }
            Opponent::Isotropic { at, model } => (model.seconds(world - *at), false),
            Opponent::Ignored => (f64::INFINITY, false),
        }
    }
}

/// Which candidates a decision lists.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Keep {
    /// Every square the shooter reaches (for `basketball-decide`, to check the rule by).
    All,
    /// Only the squares that satisfy the rule (what a match reports, and cheaper).
    Qualifying,
}

impl Situation<'_> {
    /// Applies the rule to every square of the court, listing the squares `keep` says
    /// in `candidates` (reused, so a match deciding several times a second does not
    /// allocate).
    pub fn decide_into(&self, candidates: &mut Vec<Candidate>, keep: Keep) -> Option<Chosen> {
        candidates.clear();
        let court = self.court;
        let here = court.square_of(self.shooter.position());
        let (nx, nz) = court.squares_xz();
        let z0 = -0.5 * nz as f64 * court.square_m;
        let mut best: Option<(usize, bool)> = None;
        // Row by row, the centres of [`Court::square_centre`] without its per-square
        // division, each taken into the shooter's and the defenders' frames with the
        // rotation's products worked out per row and column: this loop is the decision's
        // whole cost (`cargo bench --bench basketball -- decision`: 55 µs with a
        // division per square, 29 µs without; rotating every centre, 24.2 µs for all
        // squares and 23.4 µs for the qualifying ones, against 23.2 and 21.6 µs now).
        // Bit for bit the same decisions: the same products, the same sums.
        let xs: Vec<f64> = (0..nx).map(|j| (j as f64 + 0.5) * court.square_m).collect();
        let zs: Vec<f64> = (0..nz)
            .map(|i| z0 + (i as f64 + 0.5) * court.square_m)
            .collect();
        let shooter = self.shooter.frame().lattice(&xs, &zs);
        let defenders: Vec<(&Opponent, Option<LocalLattice>)> = self
            .defenders
            .iter()
            .map(|d| (d, d.lattice(&xs, &zs)))
            .collect();
        for (i, &z) in zs.iter().enumerate() {
            for (j, &x) in xs.iter().enumerate() {
                let square = i * nx + j;
                let centre = DVec2::new(x, z);
                let c_d = if here == Some(square) {
                    0.0
                } else {
                    match self.shooter.seconds_local(shooter.at(i, j)) {
                        // No time to get there and shoot before the shot clock runs out.
                        Some(s) if s + self.params.shot_time_s <= self.shot_clock_s => s,
                        _ => continue,
                    }
                };
                // The map's own start cell costs nothing too: no need to move.
                let is_here = c_d == 0.0;
                let (c_o, beyond_horizon) = defenders
                    .iter()
                    .map(|(d, lattice)| d.reaches_in(centre, lattice.as_ref().map(|l| l.at(i, j))))
                    .fold((f64::INFINITY, false), |a, b| if b.0 < a.0 { b } else { a });
                let c = Candidate {
                    cell: centre.to_array(),
                    c_o,
                    beyond_horizon,
                    c_d,
                    success: court.shot_success(self.shot, centre),
                };
                // A square no shot goes in from (behind the backboard) is never chosen.
                let qualifies = c.qualifies(self.params) && c.success > 0.0;
                if !qualifies && keep == Keep::Qualifying {
                    continue;
                }
                if qualifies {
                    let better = best.is_none_or(|(b, _)| {
                        let b = &candidates[b];
                        c.success > b.success || (c.success == b.success && c.c_d < b.c_d)
                    });
                    if better {
                        best = Some((candidates.len(), is_here));
                    }
                }
                candidates.push(c);
            }
        }
        best.map(|(k, here)| {
            let c = candidates[k];
            Chosen {
                cell: c.cell,
                success: c.success,
                c_o: c.c_o,
                beyond_horizon: c.beyond_horizon,
                c_d: c.c_d,
                t_s: self.params.shot_time_s,
                epsilon: self.params.epsilon_s,
                here,
            }
        })
    }

    /// Applies the rule to every square and keeps them all ([`Keep::All`]), with the
    /// choice: what `basketball-decide` prints.
    pub fn decide(&self) -> Decision {
        let mut candidates = Vec::new();
        let chosen = self.decide_into(&mut candidates, Keep::All);
        Decision { chosen, candidates }
    }
}
