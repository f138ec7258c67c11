//! Arguments shared by the catching subcommands, and their parsers.

use clap::Args;
use fieldhouse::costmap::AgentPose;
use fieldhouse::fielding::{CatchZone, FielderConfig, Limits, LotReference, Observer, TrialConfig};
use fieldhouse::names::UnknownName;
use fieldhouse::perception::PerceptionConfig;
use fieldhouse::physics::{AirModel, BallSpec, NATHAN_AIR_DENSITY};
use glam::DVec2;

/// The physical and perceptual setting of a catch.
#[derive(Args, Debug, Clone)]
pub(super) struct Setting {
    /// Air model: `nathan` (drag and Magnus lift) or `vacuum` (gravity only).
    #[arg(long, default_value = "nathan", value_parser = parse_str::<AirModel>)]
    pub air: AirModel,
    /// Air density in kg/m³ (default: 70 °F at sea level, 50 % humidity).
    #[arg(long, default_value_t = NATHAN_AIR_DENSITY, value_parser = positive)]
    pub air_density: f64,
    /// Ball preset: `baseball` or `cricket`.
    #[arg(long, default_value = "baseball", value_parser = parse_str::<BallSpec>)]
    pub ball: BallSpec,
    /// Fielder limits: `human` (8.5 m/s, 4.5 m/s², 0.3 s reaction) or `none`.
    #[arg(long, default_value = "human", value_parser = parse_str::<Limits>)]
    pub limits: Limits,
    /// Simulation rate in ticks per second.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u32).range(1..=10_000))]
    pub tick_hz: u32,
    /// Height of the fielder's eye in metres.
    #[arg(long, default_value_t = 1.7, value_parser = positive)]
    pub eye_height: f64,
    /// Visuomotor delay in seconds, instead of the observer's (0 = none).
    #[arg(long, value_parser = non_negative)]
    pub delay: Option<f64>,
    /// Standard deviation of Gaussian noise on each look's optical angles, in degrees,
    /// instead of the observer's (0 = none).
    #[arg(long, value_parser = non_negative)]
    pub noise_deg: Option<f64>,
    /// Seconds of looks the fielder fits the ball's path over, instead of the observer's
    /// (0: its last three looks).
    #[arg(long, value_parser = non_negative)]
    pub smoothing: Option<f64>,
    /// Weber fraction of the image's perceived angular speed (0.1: off by 10 %, one
    /// standard deviation), instead of the observer's (0 = exact).
    #[arg(long, value_parser = non_negative)]
    pub rate_weber: Option<f64>,
    /// Standard deviation of the error in the perceived direction of the image's motion,
    /// in degrees, instead of the observer's (0 = exact).
    #[arg(long, value_parser = non_negative)]
    pub direction_deg: Option<f64>,
    /// Weber fraction of the distance cue (0.15: off by about 15 %), instead of the
    /// observer's (0 = exact).
    #[arg(long, value_parser = non_negative)]
    pub distance_weber: Option<f64>,
    /// Range of the distance cue in metres, instead of the observer's: beyond it the
    /// fielder has none (`inf`: everywhere).
    #[arg(long, value_parser = positive_or_infinite)]
    pub distance_range: Option<f64>,
    /// Horizontal catching reach in metres, instead of the observer's.
    #[arg(long, value_parser = positive)]
    pub reach: Option<f64>,
    /// Seconds before the ball comes down that the fielder finishes the catch by its
    /// judgement of where, instead of the observer's (0 = its law to the end).
    #[arg(long, value_parser = non_negative)]
    pub terminal: Option<f64>,
    /// Extra reach in metres of a fielder finishing its catch (a lunge), instead of the
    /// observer's.
    #[arg(long, value_parser = non_negative)]
    pub lunge: Option<f64>,
    /// When `lot` takes its reference line of sight: `apex` (the ball's perceived apex)
    /// or seconds after the launch (e.g. 0.5; once the ball is clearly above the eye).
    #[arg(long, default_value = "apex", value_parser = clap::value_parser!(LotReference))]
    pub lot_reference: LotReference,
}

impl Setting {
    pub(super) fn dt(&self) -> f64 {
        1.0 / f64::from(self.tick_hz)
    }

    /// `observer` with whatever the sense, reach and finishing flags changed.
    pub(super) fn observer(&self, preset: Observer) -> Observer {
        Observer {
            delay_s: self.delay.unwrap_or(preset.delay_s),
            noise_deg: self.noise_deg.unwrap_or(preset.noise_deg),
            smoothing_s: self.smoothing.unwrap_or(preset.smoothing_s),
            rate_weber: self.rate_weber.unwrap_or(preset.rate_weber),
            direction_deg: self.direction_deg.unwrap_or(preset.direction_deg),
            distance_weber: self.distance_weber.unwrap_or(preset.distance_weber),
            distance_range_m: self.distance_range.unwrap_or(preset.distance_range_m),
            reach_m: self.reach.unwrap_or(preset.reach_m),
            terminal_s: self.terminal.unwrap_or(preset.terminal_s),
            lunge_m: self.lunge.unwrap_or(preset.lunge_m),
            ..preset
        }
    }

    /// A trial's configuration before an observer is applied.
    pub(super) fn trial_config(&self, seed: u64, record_trace: bool) -> TrialConfig {
        TrialConfig {
            fielder: FielderConfig {
                limits: self.limits,
                perception: PerceptionConfig {
                    eye_height_m: self.eye_height,
                    ..PerceptionConfig::default()
                },
                noise_seed: seed,
                lot_reference: self.lot_reference,
                terminal_s: 0.0,
            },
            zone: CatchZone::default(),
            record_trace,
        }
    }
}

pub(super) fn parse_str<T: std::str::FromStr<Err = UnknownName>>(
    s: &str,
) -> Result<T, UnknownName> {
    s.parse()
}

fn finite(s: &str) -> Result<f64, String> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("\"{s}\" is not a number"))?;
    if x.is_finite() {
        Ok(x)
    } else {
        Err(format!("{s} is not a finite number"))
    }
}

pub(super) fn any_number(s: &str) -> Result<f64, String> {
    finite(s)
}

pub(super) fn positive(s: &str) -> Result<f64, String> {
    let x = finite(s)?;
    if x > 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must be greater than 0"))
    }
}

/// A positive number, or `inf` for no bound.
pub(super) fn positive_or_infinite(s: &str) -> Result<f64, String> {
    if matches!(s.trim(), "inf" | "infinity") {
        Ok(f64::INFINITY)
    } else {
        positive(s)
    }
}

pub(super) fn non_negative(s: &str) -> Result<f64, String> {
    let x = finite(s)?;
    if x >= 0.0 {
        Ok(x)
    } else {
        Err(format!("{s} must not be negative"))
    }
}

/// A probability: a number from 0 to 1.
pub(super) fn probability(s: &str) -> Result<f64, String> {
    let x = finite(s)?;
    if (0.0..=1.0).contains(&x) {
        Ok(x)
    } else {
        Err(format!("{s} is not a probability (0 to 1)"))
    }
}

/// A ground position written `X,Z` in metres; either may be negative (`-12.5,40`).
pub(super) fn ground_point(s: &str) -> Result<DVec2, String> {
    let parts: Vec<&str> = s.split(',').collect();
    match parts.as_slice() {
        [x, z] => Ok(DVec2::new(finite(x)?, finite(z)?)),
        _ => Err(format!(
            "\"{s}\" is not a position; write it as X,Z in metres, e.g. -12.5,40"
        )),
    }
}

/// A pose on the ground written `X,Z,HEADING_DEG`: metres, and degrees from +x toward +z.
pub(super) fn ground_pose(s: &str) -> Result<AgentPose, String> {
    let parts: Vec<&str> = s.split(',').collect();
    match parts.as_slice() {
        [x, z, h] => Ok(AgentPose {
            position: DVec2::new(finite(x)?, finite(z)?),
            heading: finite(h)?.to_radians(),
        }),
        _ => Err(format!(
            "\"{s}\" is not a pose; write it as X,Z,HEADING_DEG, e.g. 9,2.5,180"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_points_parse_with_signs_and_reject_junk() {
        assert_eq!(ground_point("-12.5,40"), Ok(DVec2::new(-12.5, 40.0)));
        assert_eq!(ground_point(" 3 , -4 "), Ok(DVec2::new(3.0, -4.0)));
        assert!(ground_point("3").unwrap_err().contains("X,Z"));
        assert!(ground_point("3,4,5").is_err());
        assert!(ground_point("nan,4").unwrap_err().contains("finite"));
        assert!(ground_point("a,4").unwrap_err().contains("not a number"));
    }
}
