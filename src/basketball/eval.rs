//! The paper's experiment: many possessions of one offense against the same defender,
//! and the statistics to compare offenses by.

use super::capability::Capabilities;
use super::event::{Event, Outcome};
use super::game::Game;
use super::params::GameParams;
use serde::Serialize;
use std::sync::Arc;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalReport {
    pub offense: &'static str,
    pub possessions: u64,
    pub points: u64,
    pub points_per_possession: f64,
    /// Standard error of `points_per_possession`.
    pub standard_error: f64,
    /// Shots released or blocked.
    pub shots: u64,
    pub made: u64,
    pub blocked: u64,
    /// Turnovers to a defender: steals off the dribble plus intercepted passes.
    pub stolen: u64,
    pub intercepted: u64,
    pub shot_clock_violations: u64,
    pub passes: u64,
    pub three_pointers: u64,
    /// Mean distance to the basket of the shots taken, m.
    pub mean_shot_distance_m: f64,
    /// Mean time from a possession's start to its outcome, s.
    pub mean_possession_s: f64,
    pub ticks: u64,
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
        ticks: 0,
    };
    let mut shot_distance = 0.0;
    while game.possessions() < possessions {
        events.clear();
        game.step(&mut events);
        r.ticks += 1;
        for e in &events {
            match e {
                Event::Shot {
                    distance_m, points, ..
                } => {
                    r.shots += 1;
                    shot_distance += distance_m;
                    r.three_pointers += u64::from(*points == 3);
                }
                Event::PossessionEnded {
                    outcome,
                    points,
                    duration_s,
                    passes,
                    ..
                } => {
                    let p = f64::from(*points);
                    sum += p;
                    sum_sq += p * p;
                    time += duration_s;
                    r.points += u64::from(*points);
                    r.passes += u64::from(*passes);
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

/// Welch's test that offense `a` scores more per possession than `b`: the statistic
/// and its one-sided p-value (normal approximation, sound at thousands of possessions).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    pub difference: f64,
    pub z: f64,
    pub p_one_sided: f64,
}

pub fn compare(a: &EvalReport, b: &EvalReport) -> Comparison {
    let difference = a.points_per_possession - b.points_per_possession;
    let se = a.standard_error.hypot(b.standard_error);
    let z = if se > 0.0 { difference / se } else { 0.0 };
    Comparison {
        difference,
        z,
        p_one_sided: 0.5 * erfc(z / std::f64::consts::SQRT_2),
    }
}

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
