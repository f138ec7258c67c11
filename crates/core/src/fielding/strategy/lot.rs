//! Gillies & Dodgson's Linear Optical Trajectory law (their equation 4).

use super::{Situation, CLEARLY_ABOVE_EYE_TAN_PSI};
use glam::DVec2;

/// Natural frequency of the tracking loop, 1/s.
const OMEGA: f64 = 4.0;

/// Keeps the ball on a fixed line of sight.
///
/// Gillies & Dodgson build LOT so that the fielder's horizontal offset from the ball
/// shrinks in proportion to the ball's height above the eye; with the reference taken at
/// a point where the ball is clearly above the eye (offset L₀·Y₀), integrated it reads
///
/// ```text
///     b − f = L₀ · (y_b − h),   i.e. the fielder should be at f* = b − L₀·(y_b − h).
/// ```
///
/// **Sign correction.** Read as the fielder's own acceleration, the printed law adds the
/// tracking error e = f* − f with the wrong sign: ë = +k·e, so any error grows like
/// e^{√k·t} and the fielder runs away from the ball. The fielder's acceleration must
/// drive the error to zero, so we use the critically damped tracking law
///
/// ```text
///     a = ω²·e + 2ω·ė     ⇒   ë = −ω²·e − 2ω·ė + (b̈ − L₀·ÿ_b)
/// ```
///
/// where ė comes from the perceived relative velocity (which already contains the
/// fielder's own velocity). It uses the ball's position relative to the eye, which the
/// paper's animated fielders had; it needs no prediction.
///
/// **Reference point.** The paper takes its reference only once the ball is clearly above
/// the eye. Where exactly matters enormously: the fielder must then keep its offset at
/// L₀ = d₀/Y₀ metres per metre of height, so a reference taken low (say at 3° of
/// elevation, L₀ ≈ 20) sends it hundreds of metres away while the ball climbs (we
/// measured peak speeds of 400+ m/s that way). We take it at the perceived apex, the
/// first tick the ball stops rising relative to the eye: the highest, most "clearly
/// above" point, and the one that asks least of the fielder. The fielder waits until then.
#[derive(Debug, Clone, Default)]
pub struct Lot {
    /// L₀: horizontal offset from fielder to ball per metre of height above the eye.
    line: Option<DVec2>,
}

impl Lot {
    /// The acceleration wanted this tick, m/s².
    pub(crate) fn command(&mut self, s: &Situation) -> DVec2 {
        let p = s.percept;
        let (rel, rel_vel) = (p.relative_position, p.relative_velocity);
        let at_apex = rel_vel.y <= 0.0 && p.tan_psi >= CLEARLY_ABOVE_EYE_TAN_PSI;
        let line = match self.line {
            Some(line) => line,
            None if at_apex => *self.line.insert(DVec2::new(rel.x, rel.z) / rel.y),
            None => return DVec2::ZERO,
        };
        let error = DVec2::new(rel.x, rel.z) - line * rel.y;
        let error_rate = DVec2::new(rel_vel.x, rel_vel.z) - line * rel_vel.y;
        OMEGA * OMEGA * error + 2.0 * OMEGA * error_rate
    }
}
