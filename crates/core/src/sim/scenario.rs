//! A match, completely described: the JSON body of `POST /api/matches` (and the TOML of
//! a scenario file). Parsing checks every field and names the one that is wrong
//! (`agents[2].strategy: unknown strategy "lott"; expected one of ...`), before anything
//! runs.

use crate::strict_json::{self, Refused};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The game a match plays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Sport {
    /// Fly balls to outfielders in fair territory (azimuth 0 to 90°).
    Baseball,
    /// Fly balls to fielders around the ring, hit all round the wicket.
    Cricket,
    /// Half-court possessions with motion-captured players.
    Basketball,
}

impl Sport {
    /// Its name in scenarios and on the wire (`baseball`).
    pub fn name(self) -> &'static str {
        match self {
            Sport::Baseball => "baseball",
            Sport::Cricket => "cricket",
            Sport::Basketball => "basketball",
        }
    }
}

/// How a match's ticks are paced.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// One tick per 1/tick_hz of wall-clock time.
    #[default]
    Realtime,
    /// As fast as the machine goes; no bots.
    Fast,
    /// Each tick waits until every connected bot has sent its command for it, or the
    /// deadline passes (RoboCup's synchronous mode).
    Lockstep,
}

impl Mode {
    /// Its name in scenarios and on the wire (`realtime`).
    pub fn name(self) -> &'static str {
        match self {
            Mode::Realtime => "realtime",
            Mode::Fast => "fast",
            Mode::Lockstep => "lockstep",
        }
    }
}

/// One agent of a scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct AgentSpec {
    /// Unique in the match: letters, digits, `-` and `_`, at most 32.
    #[schemars(regex(pattern = "^[A-Za-z0-9_-]{1,32}$"))]
    pub id: String,
    /// Fielders: a catching strategy (`chapman`, `lot-optical`, `predictive`, `lot`,
    /// `chapman-1d`). Basketball offense: its brain (`simple`, `costmap`; one per team);
    /// defense: how it moves (`defense` footwork or `run`).
    #[serde(default)]
    pub strategy: Option<String>,
    /// Fielders: where it stands when the ball is hit; basketball: where it starts every
    /// possession (default: drawn at random each possession). Metres `[x, z]`.
    #[serde(default)]
    pub position: Option<[f64; 2]>,
    /// Basketball: `offense` or `defense`.
    #[serde(default)]
    pub team: Option<String>,
    /// Whether a bot controls it (it gets a bot token when the match is created).
    #[serde(default)]
    pub bot: bool,
    /// Fielders: the body's limits (default: a human's, 8.5 m/s, 4.5 m/s², 0.3 s).
    #[serde(default)]
    pub limits: Option<LimitsSpec>,
}

/// A fielder's physical limits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LimitsSpec {
    /// Top running speed, m/s, in (0, 50].
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = 50))]
    pub max_speed_m_s: f64,
    /// Largest acceleration on the ground plane, m/s², in (0, 100].
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = 100))]
    pub max_accel_m_s2: f64,
    /// Time from the hit to the first step, s, in [0, 5] (default: a human's 0.3 s).
    #[serde(default)]
    #[schemars(range(min = 0, max = 5))]
    pub reaction_s: Option<f64>,
}

/// One scripted ball.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LaunchSpec {
    /// Match time to hit it, s (or `pause_s` after the previous ball is dead, if later).
    #[schemars(range(min = 0, max = 1_000_000))]
    pub time_s: f64,
    /// Launch speed off the bat, m/s, 1 to 70.
    #[schemars(range(min = 1, max = 70))]
    pub speed_m_s: f64,
    /// Launch angle above the horizontal, degrees, 1 to 89.
    #[schemars(range(min = 1, max = 89))]
    pub elevation_deg: f64,
    /// Direction from +x toward +z, degrees, -360 to 360.
    #[schemars(range(min = -360, max = 360))]
    pub azimuth_deg: f64,
    /// Backspin, rpm, 0 to 6000 (default 0).
    #[serde(default)]
    #[schemars(range(min = 0, max = 6000))]
    pub spin_rpm: f64,
}

/// Sport options; each applies to the sports it names.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Options {
    /// Baseball, cricket: launch speed range, m/s.
    #[serde(default)]
    pub launch_speed_m_s: Option<[f64; 2]>,
    /// Baseball, cricket: elevation range above the horizontal, degrees.
    #[serde(default)]
    pub launch_elevation_deg: Option<[f64; 2]>,
    /// Baseball, cricket: azimuth range from +x toward +z, degrees.
    #[serde(default)]
    pub launch_azimuth_deg: Option<[f64; 2]>,
    /// Baseball, cricket: backspin range, rpm.
    #[serde(default)]
    pub spin_rpm: Option<[f64; 2]>,
    /// Baseball, cricket: seconds between one ball's end and the next launch.
    #[serde(default)]
    #[schemars(range(min = 0, max = 60))]
    pub pause_s: Option<f64>,
    /// Baseball, cricket: the balls to hit, in order, instead of drawing them from the
    /// ranges above; the match ends once the last one is dead.
    #[serde(default)]
    pub launches: Option<Vec<LaunchSpec>>,
    /// Basketball: possessions to play (the match ends after them).
    #[serde(default)]
    #[schemars(range(min = 1))]
    pub possessions: Option<u64>,
    /// Basketball: the shot clock, s.
    #[serde(default)]
    #[schemars(range(min = 1, max = 600))]
    pub shot_clock_s: Option<f64>,
}

fn default_seed() -> u64 {
    1
}
fn default_tick_hz() -> f64 {
    60.0
}
fn default_frame_hz() -> f64 {
    30.0
}
fn default_deadline_ms() -> u64 {
    1000
}

/// A match, completely described: the JSON body of `POST /api/matches` (Authorization:
/// Bearer `<admin token>`), and a scenario file's structure (scenarios/*.toml, in TOML).
/// Every field but `sport` has a default. Unknown fields are refused, and so is `null`
/// for a field that is not nullable; the server answers 422 with code `bad_scenario` and
/// the path of the field at fault. A few checks cannot be written in JSON Schema and are
/// only described: frame_hz ≤ tick_hz; agent ids unique; each range's low ≤ high; a
/// fielder's position within 250 m of the batter; a basketball position on the court;
/// one offense brain per basketball team and one footwork for all defenders.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "scenario")]
pub struct Scenario {
    /// A name for people, shown with the match.
    #[serde(default)]
    pub name: Option<String>,
    /// The game played.
    pub sport: Sport,
    /// Seeds every random draw: the same scenario and seed play the same match.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// Simulation ticks per second of match time, Hz, 1 to 1000 (default 60).
    #[serde(default = "default_tick_hz")]
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = 1000))]
    pub tick_hz: f64,
    /// Frames sent to spectators per second (a divisor of the tick rate is exact).
    #[serde(default = "default_frame_hz")]
    #[schemars(extend("exclusiveMinimum" = 0, "maximum" = 1000))]
    pub frame_hz: f64,
    /// How ticks are paced (default `realtime`).
    #[serde(default)]
    pub mode: Mode,
    /// Lockstep: how long a tick waits for bots, ms.
    #[serde(default = "default_deadline_ms")]
    #[schemars(range(min = 1, max = 60_000))]
    pub lockstep_deadline_ms: u64,
    /// Match length in simulated seconds; none: until deleted (or, in basketball, until
    /// `options.possessions` are played).
    #[serde(default)]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub duration_s: Option<f64>,
    /// The agents; none: the sport's default line-up.
    #[serde(default)]
    #[schemars(length(max = 32))]
    pub agents: Vec<AgentSpec>,
    /// The sport's options.
    #[serde(default)]
    pub options: Options,
}

/// What is wrong with a scenario, and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScenarioError {
    /// The field, as a path (`agents[2].strategy`); empty for the document as a whole.
    pub(crate) path: String,
    /// What is wrong with it.
    pub(crate) message: String,
}

impl fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.path.is_empty() {
            f.write_str(&self.message)
        } else {
            write!(f, "{}: {}", self.path, self.message)
        }
    }
}

impl std::error::Error for ScenarioError {}

impl ScenarioError {
    /// The error of the field at `path`.
    pub(crate) fn at(path: impl Into<String>, message: impl Into<String>) -> ScenarioError {
        ScenarioError {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Most agents a match may have.
pub const MAX_AGENTS: usize = 32;

/// Ticks a second: at least one (a match that never ticks is no match), at most 1000
/// (a millisecond timer).
pub const TICK_HZ: (f64, f64) = (1.0, 1000.0);
/// Fewest frames a second: a spectator hears from a match at least every ten seconds.
pub const MIN_FRAME_HZ: f64 = 0.1;
/// How long a lockstep tick may wait for its bots, ms.
pub const DEADLINE_MS: (u64, u64) = (1, 60_000);
/// Longest match, simulated seconds: a week.
pub const MAX_DURATION_S: f64 = 7.0 * 24.0 * 3600.0;

/// `x` is finite and in `[lo, hi]`; the error names the field, the range and the value.
fn within(path: &str, x: f64, lo: f64, hi: f64) -> Result<(), ScenarioError> {
    if x.is_finite() && (lo..=hi).contains(&x) {
        Ok(())
    } else {
        Err(ScenarioError::at(
            path,
            format!("must be from {lo} to {hi}, not {}", readable(x)),
        ))
    }
}

/// A number as people write it: `1e-300` rather than 300 zeros.
fn readable(x: f64) -> String {
    if x != 0.0 && !(1e-4..1e16).contains(&x.abs()) {
        format!("{x:e}")
    } else {
        x.to_string()
    }
}

impl Scenario {
    /// Parses a JSON scenario, naming the field at fault. A key given twice is refused:
    /// which of its values counts would otherwise depend on the reader.
    pub fn from_json(bytes: &[u8]) -> Result<Scenario, ScenarioError> {
        let value = strict_json::parse(bytes).map_err(|e| match e {
            Refused::Malformed(m) => ScenarioError::at("", format!("not JSON: {m}")),
            Refused::DuplicateKey { path, message } => ScenarioError::at(path, message),
        })?;
        Scenario::from_value(value)
    }

    /// Reads a scenario from JSON already parsed (or TOML converted to JSON). Only an
    /// object is a scenario: serde would otherwise also read one from an array.
    pub fn from_value(value: serde_json::Value) -> Result<Scenario, ScenarioError> {
        if !value.is_object() {
            return Err(ScenarioError::at("", "a scenario is a JSON object"));
        }
        let scenario: Scenario = serde_path_to_error::deserialize(value).map_err(|e| {
            let path = e.path().to_string();
            ScenarioError::at(
                if path == "." { String::new() } else { path },
                e.into_inner().to_string(),
            )
        })?;
        scenario.check()?;
        Ok(scenario)
    }

    /// The wall-clock time between ticks of a realtime match. Never panics for a
    /// scenario that passed [`Scenario::check`] (tick_hz is at least 1).
    pub fn tick_period(&self) -> std::time::Duration {
        std::time::Duration::from_secs_f64(1.0 / self.tick_hz)
    }

    /// How long a lockstep tick waits for its bots.
    pub fn lockstep_deadline(&self) -> std::time::Duration {
        std::time::Duration::from_millis(self.lockstep_deadline_ms)
    }

    /// Checks what types alone cannot: ranges, names, and agreement between fields.
    pub fn check(&self) -> Result<(), ScenarioError> {
        // Time-like numbers are held to what a product needs and the code represents:
        // a tick period the timer can sleep (1/tick_hz s), a frame at least every ten
        // seconds, tick counts (duration × rate) far inside a u64.
        within("tick_hz", self.tick_hz, TICK_HZ.0, TICK_HZ.1)?;
        within("frame_hz", self.frame_hz, MIN_FRAME_HZ, self.tick_hz)?;
        within(
            "lockstep_deadline_ms",
            self.lockstep_deadline_ms as f64,
            DEADLINE_MS.0 as f64,
            DEADLINE_MS.1 as f64,
        )?;
        if let Some(d) = self.duration_s {
            if !(d.is_finite() && d > 0.0 && d <= MAX_DURATION_S) {
                return Err(ScenarioError::at(
                    "duration_s",
                    format!(
                        "must be more than 0 and at most {MAX_DURATION_S} (7 days), not {}",
                        readable(d)
                    ),
                ));
            }
        }
        let o = &self.options;
        if self.mode == Mode::Fast
            && self.duration_s.is_none()
            && o.possessions.is_none()
            && o.launches.is_none()
        {
            return Err(ScenarioError::at(
                "mode",
                "a fast match needs an end: duration_s, options.possessions (basketball) or options.launches (fly balls)",
            ));
        }
        if self.agents.len() > MAX_AGENTS {
            return Err(ScenarioError::at(
                "agents",
                format!("at most {MAX_AGENTS} agents"),
            ));
        }
        for (i, a) in self.agents.iter().enumerate() {
            let valid = !a.id.is_empty()
                && a.id.len() <= 32
                && a.id
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !valid {
                return Err(ScenarioError::at(
                    format!("agents[{i}].id"),
                    format!("\"{}\" is not an id: 1–32 letters, digits, - or _", a.id),
                ));
            }
            if self.agents[..i].iter().any(|b| b.id == a.id) {
                return Err(ScenarioError::at(
                    format!("agents[{i}].id"),
                    format!("\"{}\" is used twice", a.id),
                ));
            }
            if a.bot && self.mode == Mode::Fast {
                return Err(ScenarioError::at(
                    format!("agents[{i}].bot"),
                    "a fast match has no bots (use realtime or lockstep)",
                ));
            }
        }
        let fly_only = [
            ("options.launch_speed_m_s", o.launch_speed_m_s.is_some()),
            (
                "options.launch_elevation_deg",
                o.launch_elevation_deg.is_some(),
            ),
            ("options.launch_azimuth_deg", o.launch_azimuth_deg.is_some()),
            ("options.spin_rpm", o.spin_rpm.is_some()),
            ("options.pause_s", o.pause_s.is_some()),
            ("options.launches", o.launches.is_some()),
        ];
        let hoops_only = [
            ("options.possessions", o.possessions.is_some()),
            ("options.shot_clock_s", o.shot_clock_s.is_some()),
        ];
        let foreign = match self.sport {
            Sport::Basketball => &fly_only[..],
            _ => &hoops_only[..],
        };
        if let Some((path, _)) = foreign.iter().find(|(_, given)| *given) {
            return Err(ScenarioError::at(
                *path,
                format!("does not apply to {}", self.sport.name()),
            ));
        }
        Ok(())
    }
}

/// Checks a `[lo, hi]` range option: finite, ordered, within `bounds`.
pub(crate) fn range(
    path: &str,
    given: Option<[f64; 2]>,
    default: (f64, f64),
    bounds: (f64, f64),
) -> Result<(f64, f64), ScenarioError> {
    let Some([lo, hi]) = given else {
        return Ok(default);
    };
    if !(lo.is_finite() && hi.is_finite() && lo <= hi && lo >= bounds.0 && hi <= bounds.1) {
        return Err(ScenarioError::at(
            path,
            format!(
                "[{lo}, {hi}] must be a range [low, high] within [{}, {}]",
                bounds.0, bounds.1
            ),
        ));
    }
    Ok((lo, hi))
}
