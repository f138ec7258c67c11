//! The fly-ball sports on the wire (baseball, cricket): the field, the fielders, the
//! ball, the score, the events, and what a bot's fielder perceives.
//!
//! Objects list their keys in alphabetical order, as protocol 2 always has (see
//! [`crate::tags`]): frames are compared byte for byte when a replay is verified.

use crate::physics::Launch;
use crate::tags;
use schemars::JsonSchema;
use serde::ser::{SerializeStruct, Serializer};
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
#[derive(Debug, Clone, PartialEq, JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case")]
#[schemars(rename = "FlyEvent")]
pub enum Event {
    /// A ball is hit.
    Launch {
        /// Which ball, counted from 1.
        ball: u64,
        /// How it left the bat.
        launch: Launch,
        /// Where it will land if nobody catches it, [x, z], m.
        landing: [f64; 2],
    },
    /// A fielder caught the ball.
    Caught {
        /// The fielder.
        by: String,
        /// Which ball.
        ball: u64,
        /// Where it was caught, [x, z], m.
        at: [f64; 2],
        /// From the hit to the catch, s.
        flight_time_s: f64,
    },
    /// The ball landed uncaught.
    Landed {
        /// Which ball.
        ball: u64,
        /// Where it landed, [x, z], m.
        at: [f64; 2],
        /// The fielder nearest to it then.
        nearest: Option<String>,
        /// How far that fielder was from it, m.
        miss_m: Option<f64>,
    },
}

impl Serialize for Event {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // Keys in alphabetical order, `kind` among them (see the module doc).
        match self {
            Event::Launch {
                ball,
                launch,
                landing,
            } => {
                let mut o = s.serialize_struct("launch", 4)?;
                o.serialize_field("ball", ball)?;
                o.serialize_field("kind", "launch")?;
                o.serialize_field("landing", landing)?;
                o.serialize_field("launch", launch)?;
                o.end()
            }
            Event::Caught {
                by,
                ball,
                at,
                flight_time_s,
            } => {
                let mut o = s.serialize_struct("caught", 5)?;
                o.serialize_field("at", at)?;
                o.serialize_field("ball", ball)?;
                o.serialize_field("by", by)?;
                o.serialize_field("flight_time_s", flight_time_s)?;
                o.serialize_field("kind", "caught")?;
                o.end()
            }
            Event::Landed {
                ball,
                at,
                nearest,
                miss_m,
            } => {
                let mut o = s.serialize_struct("landed", 5)?;
                o.serialize_field("at", at)?;
                o.serialize_field("ball", ball)?;
                o.serialize_field("kind", "landed")?;
                o.serialize_field("miss_m", miss_m)?;
                o.serialize_field("nearest", nearest)?;
                o.end()
            }
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
