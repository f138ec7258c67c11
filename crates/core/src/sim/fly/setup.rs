//! What is checked about a fly-ball scenario before a world is built from it: the launch
//! ranges, the pause between balls, each fielder's strategy, position and limits, and
//! the scripted launches, each refused with the path of the field at fault. It is apart
//! from the play loop because it runs once, before any tick, and is all about what a
//! user may write; the loop only ever sees a [`Setup`] that passed.

use super::MAX_TARGET_M;
use crate::fielding::{FielderConfig, Limits, StrategyKind};
use crate::sim::scenario::{range, LaunchSpec, Scenario, ScenarioError, Sport};
use glam::DVec2;

/// A fly-ball scenario's options, checked, with its line-up.
pub(super) struct Setup {
    /// Ranges the launches are drawn from: speed (m/s), elevation, azimuth (degrees),
    /// spin (rpm).
    pub(super) speed: (f64, f64),
    pub(super) elevation: (f64, f64),
    pub(super) azimuth: (f64, f64),
    pub(super) spin: (f64, f64),
    /// Dead time after each ball, s.
    pub(super) pause_s: f64,
    /// Each fielder: id, strategy, home position (m, ground plane), body and eye.
    pub(super) lineup: Vec<(String, StrategyKind, DVec2, FielderConfig)>,
    /// Scripted balls, which replace the drawn ones.
    pub(super) script: Option<Vec<LaunchSpec>>,
}

/// Checks a baseball or cricket scenario's options and agents, in the order a user
/// reads them, and says which field is wrong.
pub(super) fn check(s: &Scenario) -> Result<Setup, ScenarioError> {
    let cricket = s.sport == Sport::Cricket;
    let o = &s.options;
    let speed = range(
        "options.launch_speed_m_s",
        o.launch_speed_m_s,
        if cricket { (20.0, 35.0) } else { (25.0, 45.0) },
        (1.0, 70.0),
    )?;
    let elevation = range(
        "options.launch_elevation_deg",
        o.launch_elevation_deg,
        if cricket { (25.0, 60.0) } else { (25.0, 65.0) },
        (1.0, 89.0),
    )?;
    let azimuth = range(
        "options.launch_azimuth_deg",
        o.launch_azimuth_deg,
        if cricket { (0.0, 360.0) } else { (0.0, 90.0) },
        (-360.0, 360.0),
    )?;
    let spin = range(
        "options.spin_rpm",
        o.spin_rpm,
        (1000.0, 3000.0),
        (0.0, 6000.0),
    )?;
    let pause_s = o.pause_s.unwrap_or(2.0);
    if !(pause_s.is_finite() && (0.0..=60.0).contains(&pause_s)) {
        return Err(ScenarioError::at("options.pause_s", "between 0 and 60 s"));
    }
    let human = FielderConfig::default();
    let lineup: Vec<(String, StrategyKind, DVec2, FielderConfig)> = if s.agents.is_empty() {
        default_lineup(s.sport)
            .into_iter()
            .map(|(id, strategy, at)| (id, strategy, at, human))
            .collect()
    } else {
        let defaults = default_lineup(s.sport);
        s.agents
            .iter()
            .enumerate()
            .map(|(i, a)| {
                if a.team.is_some() {
                    return Err(ScenarioError::at(
                        format!("agents[{i}].team"),
                        "fielders have no team",
                    ));
                }
                let strategy = match &a.strategy {
                    Some(name) => name.parse::<StrategyKind>().map_err(|e| {
                        ScenarioError::at(format!("agents[{i}].strategy"), e.to_string())
                    })?,
                    None => StrategyKind::Chapman,
                };
                let at = match a.position {
                    Some([x, z])
                        if x.is_finite() && z.is_finite() && x.hypot(z) <= MAX_TARGET_M =>
                    {
                        DVec2::new(x, z)
                    }
                    Some(_) => {
                        return Err(ScenarioError::at(
                            format!("agents[{i}].position"),
                            format!("must be finite and within {MAX_TARGET_M} m of the batter"),
                        ))
                    }
                    None => defaults[i % defaults.len()].2,
                };
                let mut config = human;
                if let Some(l) = a.limits {
                    let reaction = l.reaction_s.unwrap_or(human.limits.reaction_s);
                    let ok = |x: f64, hi: f64| x.is_finite() && x > 0.0 && x <= hi;
                    if !(ok(l.max_speed_m_s, 50.0) && ok(l.max_accel_m_s2, 100.0) && reaction.is_finite() && (0.0..=5.0).contains(&reaction)) {
                        return Err(ScenarioError::at(format!("agents[{i}].limits"), "max_speed_m_s in (0, 50], max_accel_m_s2 in (0, 100], reaction_s in [0, 5]"));
                    }
                    config.limits = Limits { max_speed: l.max_speed_m_s, max_accel: l.max_accel_m_s2, reaction_s: reaction };
                }
                Ok((a.id.clone(), strategy, at, config))
            })
            .collect::<Result<_, _>>()?
    };
    let script = match &o.launches {
        Some(list) => Some(check_script(list)?),
        None => None,
    };
    Ok(Setup {
        speed,
        elevation,
        azimuth,
        spin,
        pause_s,
        lineup,
        script,
    })
}

/// The default line-up: baseball's three outfielders (left, centre, right) with three
/// strategies; cricket's five fielders on a 55 m ring.
fn default_lineup(sport: Sport) -> Vec<(String, StrategyKind, DVec2)> {
    let at = |distance: f64, deg: f64| distance * DVec2::from_angle(f64::to_radians(deg));
    match sport {
        Sport::Cricket => [
            ("long-off", StrategyKind::Chapman, 20.0),
            ("long-on", StrategyKind::LotOptical, 92.0),
            ("deep-midwicket", StrategyKind::Predictive, 164.0),
            ("deep-square", StrategyKind::Chapman, 236.0),
            ("third-man", StrategyKind::LotOptical, 308.0),
        ]
        .into_iter()
        .map(|(id, s, deg)| (id.to_string(), s, at(55.0, deg)))
        .collect(),
        _ => [
            ("lf", StrategyKind::Chapman, 20.0),
            ("cf", StrategyKind::LotOptical, 45.0),
            ("rf", StrategyKind::Predictive, 70.0),
        ]
        .into_iter()
        .map(|(id, s, deg)| (id.to_string(), s, at(80.0, deg)))
        .collect(),
    }
}

/// Checks scripted launches field by field.
fn check_script(list: &[LaunchSpec]) -> Result<Vec<LaunchSpec>, ScenarioError> {
    if list.is_empty() {
        return Err(ScenarioError::at("options.launches", "at least one launch"));
    }
    for (i, l) in list.iter().enumerate() {
        let checks = [
            ("time_s", l.time_s, 0.0, 1e6),
            ("speed_m_s", l.speed_m_s, 1.0, 70.0),
            ("elevation_deg", l.elevation_deg, 1.0, 89.0),
            ("azimuth_deg", l.azimuth_deg, -360.0, 360.0),
            ("spin_rpm", l.spin_rpm, 0.0, 6000.0),
        ];
        for (field, x, lo, hi) in checks {
            if !(x.is_finite() && (lo..=hi).contains(&x)) {
                return Err(ScenarioError::at(
                    format!("options.launches[{i}].{field}"),
                    format!("{x} is outside [{lo}, {hi}]"),
                ));
            }
        }
    }
    Ok(list.to_vec())
}
