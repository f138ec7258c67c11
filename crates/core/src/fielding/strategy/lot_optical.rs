//! McBeath, Shaffer & Kaiser's Linear Optical Trajectory, as a law on the ball's image.

use super::{quarter_turn, Situation, CLEARLY_ABOVE_EYE_TAN_PSI};
use glam::DVec2;

/// Lateral loop: natural frequency (1/s) of the line-keeping law. Tuned on sweeps
/// (seed 1, 1000 launches): 4–8 catch about equally, 3 and below drift off the line.
const LINE_OMEGA: f64 = 6.0;
/// Depth loop: rate constant (1/s) returning the image's rise rate to its reference
/// (3–6 all work).
const RISE_GAIN: f64 = 6.0;
/// How long, s, the fielder watches the image travel before it settles the line's
/// direction. Judged from the image's first instant alone, the direction is as noisy
/// as the image's velocity; over a chord of 0.3 s the noise is a small share of the
/// travel. Sweeps with the human observer (seeds 5, 11, 12; 2000 launches): 0.1 s is
/// worse than the instant, 0.3 s catches 3–4 points more, 0.5 s no more; without
/// noise it costs about one point.
const LINE_CHORD_S: f64 = 0.3;

/// Runs so that the ball's image, projected on a vertical plane facing home plate, rises
/// along a straight line.
///
/// **The image.** Let ê_f point from the fielder to home plate and ê_l be a quarter turn
/// from it toward increasing bearing. With the ball at D along ê_f, L along ê_l and Y
/// above the eye, its image on a plane one metre in front of the eye is
/// (u, v) = (L/D, Y/D): u and v are the tangents of McBeath's lateral and vertical
/// optical angles.
///
/// **Which line.** Once the ball is clearly above the eye and the fielder starts to run,
/// it latches the image point (u₀, v₀) and the direction the image is moving in; the line
/// through that point in that direction is the one it keeps. For its first 0.3 s
/// (`LINE_CHORD_S`) it refines the direction as the chord from (u₀, v₀) to the image. A
/// straight image path means the ball's path relative to the eye stays in one plane
/// through the eye (a·L + b·Y = c·D); the latched line picks the plane the ball is
/// moving in at that moment.
///
/// We do not force the line through the image origin (home plate). That reading, which
/// makes the ratio of tangents u/v constant, moves the fielder sideways only as gravity
/// bends the ball's climb, so its lateral speed grows to twice the average it needs by
/// the catch; with human limits it caught 85–89 % of catchable balls in our sweeps, this
/// one about 94 %.
///
/// **Lateral law.** The image's perpendicular distance from the line,
/// e = (u − u₀)·cos θ − (v − v₀)·sin θ (θ: the line's angle from the vertical), turned
/// into metres: a step x along +ê_l moves u by −x/D and so e by −x·cos θ/D. With
/// E = D·e / cos θ, the critically damped loop a_l = ω²·E + 2ω·Ė holds the image on the
/// line. Only lateral running changes u/v (it is independent of D), so this is the part
/// of LOT that steers; it is what bends the fielders' paths.
///
/// **Depth law.** LOT says nothing about how fast the image moves along its line, and for
/// a ball hit straight at the fielder the line is vertical whatever the fielder does;
/// McBeath et al. note that LOT reduces to Chapman's law there. We keep the image rising
/// at a constant rate, v̇ = v̇₀ (OAC on the projected vertical angle). Backing up (along
/// −ê_f) with acceleration a_b adds −(v/D)·a_b to v̈, so a_b = K·(D/v)·(v̇ − v̇₀) gives
/// d(v̇)/dt = P − K·(v̇ − v̇₀), stable at any range, as in [`super::Chapman`].
#[derive(Debug, Clone, Default)]
pub struct LotOptical {
    reference: Option<Reference>,
}

#[derive(Debug, Clone, Copy)]
struct Reference {
    /// The image point (u₀, v₀) the line passes through.
    u: f64,
    v: f64,
    /// The line's angle θ from the image vertical.
    tilt: f64,
    rise_rate: f64,
    /// When (u₀, v₀) was latched, s since the launch.
    t: f64,
}

impl LotOptical {
    /// The acceleration wanted this tick, m/s².
    pub(crate) fn command(&mut self, s: &Situation) -> DVec2 {
        let Some(p) = s.percept else {
            return DVec2::ZERO;
        };
        let forward = (s.home - s.body.pos).normalize_or(DVec2::X);
        // β: the ball's bearing from the direction of home plate, turning toward ê_l.
        let beta = forward
            .perp_dot(p.toward_ball)
            .atan2(forward.dot(p.toward_ball));
        let (sin_beta, cos_beta) = beta.sin_cos();
        // The image plane only sees balls in front of it, clearly above the eye.
        if cos_beta <= 0.0 || p.tan_psi < CLEARLY_ABOVE_EYE_TAN_PSI {
            return DVec2::ZERO;
        }
        let side = quarter_turn(forward);
        // The image from the angles alone: u = L/D = tan β, v = Y/D = tan ψ / cos β
        // (the plane's own turn as the fielder moves is left out: home is far).
        let (u, u_rate) = (sin_beta / cos_beta, p.alpha_rate / (cos_beta * cos_beta));
        let v = p.tan_psi / cos_beta;
        let v_rate =
            p.tan_psi_rate / cos_beta + p.tan_psi * sin_beta / (cos_beta * cos_beta) * p.alpha_rate;
        // Depth D, as the fielder judges the distance: it only scales the gains.
        let depth = p.distance * cos_beta;
        let reference = self.reference.get_or_insert(Reference {
            u,
            v,
            tilt: u_rate.atan2(v_rate),
            rise_rate: v_rate,
            t: s.t,
        });
        if s.t > reference.t && s.t - reference.t <= LINE_CHORD_S {
            reference.tilt = (u - reference.u).atan2(v - reference.v);
        }
        let reference = *reference;
        let (sin, cos) = reference.tilt.sin_cos();
        let off_line = depth * ((u - reference.u) * cos - (v - reference.v) * sin) / cos;
        let off_line_rate = depth * (u_rate * cos - v_rate * sin) / cos;
        let a_lateral = LINE_OMEGA * LINE_OMEGA * off_line + 2.0 * LINE_OMEGA * off_line_rate;
        let a_back = RISE_GAIN * (depth / v) * (v_rate - reference.rise_rate);
        a_lateral * side - a_back * forward
    }
}
