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
/// [`LotReference::After`] takes it earlier instead, to measure what the paper warns of.
#[derive(Debug, Clone, Default)]
pub struct Lot {
    /// When the reference is taken.
    reference: LotReference,
    /// L₀: horizontal offset from fielder to ball per metre of height above the eye.
    line: Option<DVec2>,
}

/// When `lot` takes its reference line of sight (Gillies & Dodgson: "once the ball is
/// clearly above h"; taken too early, they say, the paths become very convex).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub enum LotReference {
    /// At the perceived apex: the first tick the ball stops rising relative to the eye.
    #[default]
    Apex,
    /// At the first tick this many seconds after the launch, or later, once the ball is
    /// clearly above the eye (tan ψ ≥ 0.05), whichever comes last.
    After(f64),
}

impl std::str::FromStr for LotReference {
    type Err = String;

    /// `apex`, or seconds after the launch (`0.5`).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s == "apex" {
            return Ok(LotReference::Apex);
        }
        match s.parse::<f64>() {
            Ok(t) if t.is_finite() && t >= 0.0 => Ok(LotReference::After(t)),
            _ => Err(format!(
                "\"{s}\" is not a LOT reference: write `apex` or seconds after the launch (e.g. 0.5)"
            )),
        }
    }
}

impl Lot {
    /// A `lot` fielder that takes its reference at `reference`.
    pub(crate) fn new(reference: LotReference) -> Lot {
        Lot {
            reference,
            line: None,
        }
    }

    /// The acceleration wanted this tick, m/s².
    pub(crate) fn command(&mut self, s: &Situation) -> DVec2 {
        let Some(p) = s.percept else {
            return DVec2::ZERO;
        };
        let (rel, rel_vel) = (p.relative_position(), p.relative_velocity());
        let above = p.tan_psi >= CLEARLY_ABOVE_EYE_TAN_PSI;
        let now = match self.reference {
            LotReference::Apex => above && rel_vel.y <= 0.0,
            LotReference::After(t) => above && s.t >= t,
        };
        let line = match self.line {
            Some(line) => line,
            None if now => *self.line.insert(DVec2::new(rel.x, rel.z) / rel.y),
            None => return DVec2::ZERO,
        };
        let error = DVec2::new(rel.x, rel.z) - line * rel.y;
        let error_rate = DVec2::new(rel_vel.x, rel_vel.z) - line * rel_vel.y;
        OMEGA * OMEGA * error + 2.0 * OMEGA * error_rate
    }
}
