//! The fly-ball sports on the wire (baseball, cricket): the field, the fielders, the
//! ball, the score, the events, and what a bot's fielder perceives.
//!
//! Objects list their keys in alphabetical order, as protocol 2 always has (see
//! [`crate::tags`]): frames are compared byte for byte when a replay is verified, and a
//! test reads every object of a frame of each sport for it. The simulation's own types
//! (such as [`physics::Launch`]) declare their fields as they read best and are converted
//! to the types here.

use crate::physics;
use crate::tags;
use schemars::JsonSchema;
use serde::Serialize;

/// A baseball field, as a client draws it: home plate at the origin, fair territory
/// between the foul lines.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct BaseballField {
    /// Between bases, m.
    pub base_path_m: f64,
    /// The height of a fielder's eye, m: with it a spectator can draw what a fielder
    /// sees (tan ψ, the image path) from the frames.
    pub eye_height_m: f64,
    /// Distance from home plate to the fence, m.
    pub fence_m: f64,
    /// The foul lines' directions, degrees from +x toward +z.
    pub foul_lines_deg: [f64; 2],
    /// Home plate, [x, z], m.
    pub home: [f64; 2],
    /// Always `baseball`.
    pub kind: tags::Baseball,
}

/// A cricket field, as a client draws it: the batter at the origin, balls hit all round.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct CricketField {
    /// The batter, [x, z], m.
    pub batter: [f64; 2],
    /// Distance from the batter to the boundary, m.
    pub boundary_m: f64,
    /// The height of a fielder's eye, m (as for baseball).
    pub eye_height_m: f64,
    /// The radius of the inner ring, m.
    pub inner_ring_m: f64,
    /// Always `cricket`.
    pub kind: tags::Cricket,
    /// Wicket to wicket, m.
    pub pitch_length_m: f64,
}

/// A fielder as `hello` lists it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct FielderInfo {
    /// Where it stands when a ball is hit, [x, z], m.
    pub home: [f64; 2],
    /// Its id.
    pub id: String,
    /// Its built-in catching strategy.
    pub strategy: &'static str,
    /// Always `fielding`.
    pub team: tags::Fielding,
}

/// Whether a ball is in play.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
#[schemars(rename = "FlyBallState")]
pub enum BallState {
    /// In the air: `velocity` is given.
    Flight,
    /// No ball in play (between balls): `position` is a placeholder at the batter,
    /// [0, 1, 0].
    Dead,
}

/// The ball in a fly-ball frame.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "FlyBall")]
pub struct Ball {
    /// [x, y, z], m, y up.
    pub position: [f64; 3],
    /// `flight` or `dead`.
    pub state: BallState,
    /// [x, y, z], m/s, while in flight.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity: Option<[f64; 3]>,
}

/// A fielder in a frame.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
pub struct Fielder<'a> {
    /// Present, as `bot`, while a connected bot moves the fielder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<tags::Bot>,
    /// Radians from +x toward +z: the direction of motion, or toward the batter at rest.
    pub heading: f64,
    /// Its id.
    pub id: &'a str,
    /// [x, z], m.
    pub position: [f64; 2],
    /// m/s.
    #[schemars(range(min = 0))]
    pub speed: f64,
    /// The built-in catching strategy (used when no bot controls the fielder).
    pub strategy: &'static str,
}

/// The score of a fly-ball match, in balls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[schemars(rename = "FlyScore")]
pub struct Score {
    /// Balls hit so far (including the one in play).
    pub balls: u64,
    /// Balls caught.
    pub caught: u64,
    /// Balls that landed uncaught.
    pub dropped: u64,
}

/// Something that happened in a fly-ball match, as frames carry it (`kind` names it).
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[serde(untagged)]
#[schemars(rename = "FlyEvent", transform = tags::one_of)]
pub enum Event {
    // The variants' docs describe the events in the schema: their structs are inlined
    // there, and their own docs only point back here.
    /// A ball is hit.
    Launch(Launched),
    /// A fielder caught the ball.
    Caught(Caught),
    /// The ball landed uncaught.
    Landed(Landed),
}

/// What an [`Event::Launch`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Launched {
    /// Which ball, counted from 1.
    pub ball: u64,
    /// Always `launch`.
    pub kind: tags::Launch,
    /// Where it will land if nobody catches it, [x, z], m.
    pub landing: [f64; 2],
    /// How it left the bat.
    pub launch: Launch,
}

/// What an [`Event::Caught`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Caught {
    /// Where it was caught, [x, z], m.
    pub at: [f64; 2],
    /// Which ball.
    pub ball: u64,
    /// The fielder.
    pub by: String,
    /// From the hit to the catch, s.
    pub flight_time_s: f64,
    /// Always `caught`.
    pub kind: tags::Caught,
}

/// What an [`Event::Landed`] says.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(inline)]
pub struct Landed {
    /// Where it landed, [x, z], m.
    pub at: [f64; 2],
    /// Which ball.
    pub ball: u64,
    /// Always `landed`.
    pub kind: tags::Landed,
    /// How far that fielder was from it, m.
    pub miss_m: Option<f64>,
    /// The fielder nearest to it then.
    pub nearest: Option<String>,
}

/// How a ball left the bat, in the units people quote (degrees, rpm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Launch {
    /// Horizontal direction in degrees, measured from +x toward +z.
    pub azimuth_deg: f64,
    /// Angle above the horizontal, degrees.
    pub elevation_deg: f64,
    /// Height the ball leaves the bat at, m (it starts above the origin).
    pub height_m: f64,
    /// Speed off the bat, m/s.
    pub speed_m_s: f64,
    /// Spin rate, revolutions per minute.
    pub spin_rpm: f64,
    /// Tilt of the lift direction about the velocity: 0° is pure backspin (lift up),
    /// +90° is side spin that curves the ball toward increasing azimuth.
    pub spin_tilt_deg: f64,
}

impl From<&physics::Launch> for Launch {
    fn from(l: &physics::Launch) -> Launch {
        Launch {
            azimuth_deg: l.azimuth_deg,
            elevation_deg: l.elevation_deg,
            height_m: l.height_m,
            speed_m_s: l.speed_m_s,
            spin_rpm: l.spin_rpm,
            spin_tilt_deg: l.spin_tilt_deg,
        }
    }
}

/// What a bot's fielder perceives: its own body, and the ball only as an eye sees it.
#[derive(Debug, Clone, PartialEq, Serialize, JsonSchema)]
#[schemars(rename = "FielderPerception")]
pub struct Sensed {
    /// Whether a ball is in flight (then `optics` is given).
    pub ball_in_play: bool,
    /// Balls this fielder has caught in the match so far (a reward a learning agent can
    /// read from its own perceptions).
    pub caught: u32,
    /// What the fielder's body can do.
    pub limits: BodyLimits,
    /// The ball as the fielder's eye sees it; null between balls.
    pub optics: Option<Optics>,
    /// The fielder's own body.
    #[serde(rename = "self")]
    pub body: SelfSensed,
}

/// A fielder's body limits, as its perception reports them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct BodyLimits {
    /// m/s².
    pub max_accel_m_s2: f64,
    /// m/s.
    pub max_speed_m_s: f64,
}

/// A fielder's own body, as it perceives it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct SelfSensed {
    /// Where it stands when a ball is hit, [x, z], m.
    pub home: [f64; 2],
    /// [x, z], m.
    pub position: [f64; 2],
    /// [x, z], m/s.
    pub velocity: [f64; 2],
}

/// The ball as a fielder's eye sees it (docs/catching.md, "What a fielder sees").
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Optics {
    /// The ball's bearing on the ground, radians from +x toward +z.
    pub alpha: f64,
    /// The ground distance from the fielder to the ball, m: what the built-in
    /// strategies scale their gains by, so a bot gets it too.
    pub distance_m: f64,
    /// The optical rates since the previous tick; null on the first tick of a ball.
    pub rates: Option<Rates>,
    /// Time since the hit, s.
    pub t: f64,
    /// tan ψ: the tangent of the ball's elevation angle above the eye.
    pub tan_psi: f64,
}

/// How the optics changed since the previous tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, JsonSchema)]
pub struct Rates {
    /// dα/dt, rad/s.
    pub d_alpha_dt: f64,
    /// d(tan ψ)/dt, 1/s.
    pub d_tan_psi_dt: f64,
}
