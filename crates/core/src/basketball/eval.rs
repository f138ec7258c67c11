//! The paper's experiment: many possessions of one offense against the same defender,
//! and the statistics to compare offenses by.

use super::capability::Capabilities;
use super::event::{Decided, Event, Outcome, PossessionEnded, Shot};
use super::game::Game;
use super::params::GameParams;
use serde::Serialize;
use std::sync::Arc;

/// What [`evaluate`] measured of one offense: totals over its possessions and the
/// statistics offenses are compared by.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    /// The offense's name (`simple` or `costmap`).
    pub offense: &'static str,
    /// Possessions played.
    pub possessions: u64,
    pub(crate) points: u64,
    /// Mean points scored per possession: the paper's measure.
    pub points_per_possession: f64,
    /// Standard error of `points_per_possession`.
    pub standard_error: f64,
    /// Shots released or blocked.
    pub shots: u64,
    /// Shots that went in.
    pub made: u64,
    /// Shots a defender blocked.
    pub blocked: u64,
    /// Turnovers to a defender: steals off the dribble plus intercepted passes.
    pub stolen: u64,
    pub(crate) intercepted: u64,
    /// Possessions that ran out the shot clock.
    pub shot_clock_violations: u64,
    /// Passes thrown (caught or intercepted).
    pub passes: u64,
    pub(crate) three_pointers: u64,
    /// Mean distance to the basket of the shots taken, m.
    pub mean_shot_distance_m: f64,
    /// Mean time from a possession's start to its outcome, s.
    pub mean_possession_s: f64,
    /// Decisions of the cost-map offense that chose a square to shoot from.
    pub chosen_squares: u64,
    /// Of those, the squares whose C_o was a map's horizon: the defender's model did
    /// not reach them, and the rule counted on "at least the horizon".
    pub chosen_beyond_horizon: u64,
    pub(crate) ticks: u64,
    /// Every possession's outcome, in order: possession k of two reports began from the
    /// same positions with the same random draws, so they pair.
    pub(crate) by_possession: Vec<Possession>,
}

/// How one possession ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Possession {
    pub(crate) points: u32,
    pub(crate) outcome: Outcome,
    /// Distance to the basket of its shot, m, if it ended in one.
    pub(crate) shot_m: Option<f64>,
}

/// Plays `possessions` possessions with `params` (possession k starts from the same
/// positions whatever the offense, so offenses compare on equal starts).
pub fn evaluate(caps: Arc<Capabilities>, params: GameParams, possessions: u64) -> EvalReport {
    let mut game = Game::new(caps, params);
    let mut events = Vec::new();
    let (mut sum, mut sum_sq, mut time) = (0.0, 0.0, 0.0);
    let mut r = EvalReport {
        offense: params.offense.name(),
        possessions,
        points: 0,
        points_per_possession: 0.0,
        standard_error: 0.0,
        shots: 0,
        made: 0,
        blocked: 0,
        stolen: 0,
        intercepted: 0,
        shot_clock_violations: 0,
        passes: 0,
        three_pointers: 0,
        mean_shot_distance_m: 0.0,
        mean_possession_s: 0.0,
        chosen_squares: 0,
        chosen_beyond_horizon: 0,
        ticks: 0,
        by_possession: Vec::with_capacity(usize::try_from(possessions).unwrap_or(0)),
    };
    let mut shot_distance = 0.0;
    let mut last_shot_m = None;
    while game.possessions() < possessions {
        events.clear();
        game.step(&mut events);
        r.ticks += 1;
        for e in &events {
            match e {
                Event::Decision(Decided {
                    chosen: Some(c), ..
                }) => {
                    r.chosen_squares += 1;
                    r.chosen_beyond_horizon += u64::from(c.beyond_horizon);
                }
                Event::Shot(Shot {
                    distance_m, points, ..
                }) => {
                    r.shots += 1;
                    shot_distance += distance_m;
                    last_shot_m = Some(*distance_m);
                    r.three_pointers += u64::from(*points == 3);
                }
                Event::PossessionEnded(PossessionEnded {
                    outcome,
                    points,
                    duration_s,
                    passes,
                    ..
                }) => {
                    let p = f64::from(*points);
                    sum += p;
                    sum_sq += p * p;
                    time += duration_s;
                    r.points += u64::from(*points);
                    r.passes += u64::from(*passes);
                    r.by_possession.push(Possession {
                        points: *points,
                        outcome: *outcome,
                        shot_m: last_shot_m.take(),
                    });
                    match outcome {
                        Outcome::Made => r.made += 1,
                        Outcome::Blocked => r.blocked += 1,
                        Outcome::Stolen => r.stolen += 1,
                        Outcome::Intercepted => {
                            r.stolen += 1;
                            r.intercepted += 1;
                        }
                        Outcome::ShotClock => r.shot_clock_violations += 1,
                        Outcome::Missed => {}
                    }
                }
                _ => {}
            }
        }
    }
    let n = possessions.max(1) as f64;
    r.points_per_possession = sum / n;
    let variance = if possessions > 1 {
        (sum_sq - sum * sum / n) / (n - 1.0)
    } else {
        0.0
    };
    r.standard_error = (variance / n).sqrt();
    r.mean_shot_distance_m = if r.shots > 0 {
        shot_distance / r.shots as f64
    } else {
        0.0
    };
    r.mean_possession_s = time / n;
    r
}

/// Offense `a` against offense `b` on the same possessions: the paired difference in
/// points per possession (possession k of each began from the same positions with the
/// same random draws), its standard error, a 95 % confidence interval and the paired
/// z test (normal approximation, sound at thousands of possessions).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// Mean of `a`'s points minus `b`'s, per possession.
    pub difference: f64,
    /// Standard error of `difference`.
    pub standard_error: f64,
    /// The 95 % confidence interval of `difference`, low then high.
    pub ci95: [f64; 2],
    /// `difference` over its standard error (0 when that is 0).
    pub z: f64,
    /// Two-sided p-value of `z`.
    pub p_two_sided: f64,
    /// Possessions paired.
    pub possessions: usize,
}

/// Pairs `a`'s and `b`'s possessions in order (as many as both have).
pub fn compare(a: &EvalReport, b: &EvalReport) -> Comparison {
    let differences: Vec<f64> = a
        .by_possession
        .iter()
        .zip(&b.by_possession)
        .map(|(x, y)| f64::from(x.points) - f64::from(y.points))
        .collect();
    let n = differences.len() as f64;
    let difference = differences.iter().sum::<f64>() / n.max(1.0);
    let variance = if n > 1.0 {
        differences
            .iter()
            .map(|d| (d - difference).powi(2))
            .sum::<f64>()
            / (n - 1.0)
    } else {
        0.0
    };
    let standard_error = (variance / n.max(1.0)).sqrt();
    let z = if standard_error > 0.0 {
        difference / standard_error
    } else {
        0.0
    };
    Comparison {
        difference,
        standard_error,
        ci95: [
            difference - Z_95 * standard_error,
            difference + Z_95 * standard_error,
        ],
        z,
        p_two_sided: erfc(z.abs() / std::f64::consts::SQRT_2),
        possessions: differences.len(),
    }
}

/// The two-sided 95 % point of the standard normal.
const Z_95: f64 = 1.959_963_985;

/// The complementary error function (Numerical Recipes' Chebyshev fit, relative error
/// below 1.2e-7 everywhere).
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -z * z - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * poly.exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erfc_matches_known_values() {
        // Values from Abramowitz & Stegun, table 7.1.
        for (x, want) in [
            (0.0, 1.0),
            (0.5, 0.479_500_122),
            (1.0, 0.157_299_207),
            (2.0, 0.004_677_735),
            (-1.0, 1.842_700_793),
        ] {
            assert!((erfc(x) - want).abs() < 2e-7, "erfc({x})");
        }
    }
}
