//! McBeath, Shaffer & Kaiser's Linear Optical Trajectory, as a law on the ball's image.

use super::{left_of, Situation, CLEARLY_ABOVE_EYE_TAN_PSI};
use glam::DVec2;

/// Lateral loop: natural frequency (1/s) of the line-keeping law.
const LINE_OMEGA: f64 = 3.0;
/// Depth loop: rate constant (1/s) returning the image's rise rate to its reference.
const RISE_GAIN: f64 = 6.0;

/// Runs so that the ball's image, projected on a vertical plane facing home plate, rises
/// along a straight line.
///
/// **The image.** Let ê_f point from the fielder to home plate and ê_l be a quarter turn
/// to its left. With the ball at D along ê_f, L along ê_l and Y above the eye, its image
/// on a plane one metre in front of the eye is (u, v) = (L/D, Y/D): u and v are the
/// tangents of McBeath's lateral and vertical optical angles. The ball starts at home
/// plate, the image origin, so a straight image path is a ray from the origin: the ratio
/// u/v = L/Y (the ratio of the tangents, McBeath's invariant) stays at its reference
/// k = L₀/Y₀. Note that this ratio does not depend on D at all: only *lateral* running
/// can keep it, which is why LOT is at heart a lateral law.
///
/// **Lateral law.** The image leaves its line by e = L − k·Y metres (the image's
/// perpendicular distance from the line, times D/sin φ). Running along +ê_l lowers L, so
/// a critically damped loop a_l = ω²·e + 2ω·ė holds the image on the line; as Y → 0 it
/// brings L → 0, i.e. the fielder under the ball.
///
/// **Depth law.** LOT says nothing about how fast the image moves along its line, and a
/// ball hit straight at the fielder gives a line that is vertical whatever the fielder
/// does; McBeath et al. note that LOT reduces to Chapman's law there. We keep the image
/// rising at a constant rate, v̇ = v̇_ref (OAC on the projected vertical angle). Backing
/// up (along −ê_f) with acceleration a_b adds −(v/D)·a_b to v̈, so
/// a_b = K·(D/v)·(v̇ − v̇_ref) gives d(v̇)/dt = P − K·(v̇ − v̇_ref), stable at any range.
/// The two laws touch different axes of the image, so they do not fight.
#[derive(Debug, Clone, Default)]
pub struct LotOptical {
    reference: Option<Reference>,
}

#[derive(Debug, Clone, Copy)]
struct Reference {
    /// k = L₀ / Y₀.
    tangent_ratio: f64,
    rise_rate: f64,
}

impl LotOptical {
    pub fn command(&mut self, s: &Situation) -> DVec2 {
        let p = s.percept;
        let forward = (s.home - s.body.pos).normalize_or(DVec2::X);
        let left = left_of(forward);
        let (rel, rel_vel) = (p.relative_position, p.relative_velocity);
        let (r, r_vel) = (DVec2::new(rel.x, rel.z), DVec2::new(rel_vel.x, rel_vel.z));
        let (depth, lateral, height) = (r.dot(forward), r.dot(left), rel.y);
        let (depth_rate, lateral_rate, height_rate) = (r_vel.dot(forward), r_vel.dot(left), rel_vel.y);
        // The image plane only sees balls in front of it, clearly above the eye.
        if depth <= 0.0 || p.tan_psi < CLEARLY_ABOVE_EYE_TAN_PSI {
            return DVec2::ZERO;
        }
        let v = height / depth;
        let v_rate = (height_rate * depth - height * depth_rate) / (depth * depth);
        let reference = *self.reference.get_or_insert(Reference {
            tangent_ratio: lateral / height,
            rise_rate: v_rate,
        });
        let off_line = lateral - reference.tangent_ratio * height;
        let off_line_rate = lateral_rate - reference.tangent_ratio * height_rate;
        let a_lateral = LINE_OMEGA * LINE_OMEGA * off_line + 2.0 * LINE_OMEGA * off_line_rate;
        let a_back = RISE_GAIN * (depth / v) * (v_rate - reference.rise_rate);
        a_lateral * left - a_back * forward
    }
}
