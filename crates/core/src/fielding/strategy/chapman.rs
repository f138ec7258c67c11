//! Chapman's optical acceleration cancellation, generalised by Dienes & McLeod, with
//! Tresilian's lateral term.

use super::{quarter_turn, Situation, CLEARLY_ABOVE_EYE_TAN_PSI};
use glam::DVec2;

/// Gain of the radial law, 1/s: the optical rate returns to its reference with a time
/// constant of 1/3 s. Tuned on sweeps (seed 1, 1000 launches): 2–3 catch most, 1 lets
/// the rate drift too far, 12+ chases every wobble of the second difference.
const RATE_GAIN: f64 = 3.0;
/// Gain of the lateral law, 1/s: the fielder matches the ball's sideways drift across
/// its line of sight with a time constant of 0.2 s (tuned likewise; 2–8 all work).
const LATERAL_GAIN: f64 = 5.0;

/// Keeps the rate of rise of tan ψ constant (radial) and, unless one-dimensional, the
/// bearing α constant (lateral).
///
/// **Radial term.** Gillies & Dodgson print a1 = −d(tan ψ)/dt. Taken literally that sends
/// every fielder toward the ball whenever the ball rises, however far behind it will land.
/// Chapman's point is the *change* of that rate: if the image accelerates upward
/// (d²tan ψ/dt² > 0) the ball will carry over the fielder, who must back up; if it
/// decelerates the ball drops short. Dienes & McLeod show holding the rate at *any*
/// constant brings the fielder to the ball. We hold it at the rate seen on the first
/// step, and oppose the accumulated optical acceleration since then,
///
/// ```text
///     a1 = −K · (d / tan ψ) · (ṙ − ṙ_ref),    ṙ = d(tan ψ)/dt, positive toward the ball.
/// ```
///
/// Why d / tan ψ: with Y = y − h, tan ψ = Y/d, so a radial acceleration a1 of the fielder
/// adds (Y/d²)·a1 = (tan ψ/d)·a1 to d²(tan ψ)/dt². The factor makes the loop
/// d(ṙ)/dt = P − K·(ṙ − ṙ_ref) (P: the ball's own optical acceleration), first order and
/// stable with rate constant K whatever the distance, instead of a gain that is huge far
/// away and vanishes up close. Reading a1 from the *instantaneous* optical acceleration
/// instead would feed the fielder's own last acceleration straight back (a one-tick
/// oscillation); the accumulated form is its integral and has no such loop.
///
/// **Lateral term.** Tresilian adds a2 = (1/c)·dα/dt (c = 100 in the paper's units). The
/// ball's sideways speed relative to the fielder, across the line of sight, is d·dα/dt,
/// so we use a2 = K_lat · d · dα/dt: in our terms 1/c = K_lat·d, a velocity-matching law
/// that drives dα/dt to zero (a constant bearing, which intercepts a moving target). The
/// total acceleration points at β = atan2(a2, a1) from the ball's direction; the body
/// clips its length, never its direction.
#[derive(Debug, Clone)]
pub struct Chapman {
    lateral: bool,
    rate_ref: Option<f64>,
}

impl Chapman {
    /// With `lateral` off, only the radial law (`chapman-1d`).
    pub(crate) fn new(lateral: bool) -> Chapman {
        Chapman {
            lateral,
            rate_ref: None,
        }
    }

    /// The acceleration wanted this tick, m/s².
    pub(crate) fn command(&mut self, s: &Situation) -> DVec2 {
        let Some(p) = s.percept else {
            return DVec2::ZERO;
        };
        if p.tan_psi < CLEARLY_ABOVE_EYE_TAN_PSI {
            return DVec2::ZERO;
        }
        let rate_ref = *self.rate_ref.get_or_insert(p.tan_psi_rate);
        let d = p.distance;
        let a1 = -RATE_GAIN * (d / p.tan_psi) * (p.tan_psi_rate - rate_ref);
        let a2 = if self.lateral {
            LATERAL_GAIN * d * p.alpha_rate
        } else {
            0.0
        };
        let toward = p.toward_ball;
        a1 * toward + a2 * quarter_turn(toward)
    }
}
