//! A fielder's memory of its recent looks at the ball, and the estimate of the present
//! it makes from them: the optical angles and their rates, from the angles alone.
//!
//! **Why a fit, not differences.** Reading rates off two or three noisy looks
//! multiplies the noise by the tick rate (and the optical acceleration by its square).
//! The visual system integrates motion over time instead. So the fielder fits the
//! elevation (as tan ψ, the quantity Chapman's law is about) and the bearing α over its
//! last looks, [`PerceptionConfig::smoothing_s`] of them, each with a quadratic in time
//! by least squares, and reads the value and its rate off the fit. Nothing here places
//! the ball in space: the angles are what the eye measures, and a quadratic through
//! three looks is exact to the square of the tick (and exact for Chapman's linear tan ψ).
//! The judgement of the image's motion then carries its own error
//! ([`super::Senses::rate_errors`]).
//!
//! **Distance** is the senses' cue where there is one (with its rate, judged from the
//! ball's optical expansion), carried over the delay at that rate; beyond the
//! cue's range the fielder knows only that the ball is at least that far, and takes the
//! range itself ([`Percept::distance_seen`] says which). Strategies use it only to scale
//! their gains and, at the end, to finish the catch.
//!
//! **Why predict over the delay.** With a visuomotor delay τ the newest look is τ old.
//! A loop that acts on it fights its own last τ of running, which it cannot yet see: the
//! optical strategies' loops (time constants of 0.2–0.3 s) oscillate at τ = 0.2 s. The
//! remedy the motor-control literature proposes is a Smith predictor (Miall, Weir,
//! Wolpert & Stein 1993, *J. Motor Behav.* 25:203): carry the delayed estimate forward
//! with an internal model. Here the angles' fits are extended by τ, and what the
//! fielder's own movement since the newest look did to them is taken out of what it
//! knows of itself (its position and velocity now, without delay, against what it was
//! doing then): the ball's place and motion relative to the eye are rebuilt from the
//! angles, their rates and the distance, moved by the fielder's extra step and change of
//! velocity, and seen again. A step Δp across the line of sight turns the bearing by
//! about −(r̂ × Δp)/d: the correction needs the distance, so it is only as good as the
//! cue (and beyond the cue's range, the range stands in for it).
//! The extrapolation never reaches further than the delay: this is not trajectory
//! prediction, which would forecast the landing point seconds ahead.

use super::{Look, PerceptionConfig};
use glam::{DVec2, DVec3};
use std::collections::VecDeque;
use std::f64::consts::{PI, TAU};

/// The fewest looks a fit uses: three determine a quadratic.
const MIN_LOOKS: usize = 3;

/// The last looks, newest at the back: just the delay and one fitting window, so the
/// cost does not grow with the flight.
#[derive(Debug, Clone)]
pub struct PerceptionHistory {
    looks: VecDeque<Look>,
    delay_ticks: usize,
    window: usize,
    dt: f64,
    /// The distance taken when there is no cue: the cue's range.
    unseen_distance: f64,
}

/// What a strategy sees on one tick: its estimate of the optical angles now and their
/// rates, and the distance as it judges it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percept {
    /// When the estimate is of, s since the launch.
    pub t: f64,
    /// tan ψ, ψ the ball's elevation above the horizontal through the eye.
    pub tan_psi: f64,
    /// d(tan ψ)/dt, 1/s.
    pub tan_psi_rate: f64,
    /// Unit vector on the ground toward the ball: (cos α, sin α).
    pub toward_ball: DVec2,
    /// dα/dt, rad/s.
    pub alpha_rate: f64,
    /// The horizontal distance to the ball as judged, m.
    pub distance: f64,
    /// Its rate of change, m/s (0 without a cue).
    pub distance_rate: f64,
    /// Whether the distance comes from a cue; if not, it is the cue's range: the ball is
    /// at least that far.
    pub distance_seen: bool,
}

impl PerceptionHistory {
    /// An empty history for an eye configured by `config`, looking once every `dt` s.
    pub fn new(config: &PerceptionConfig, dt: f64) -> PerceptionHistory {
        let delay_ticks = (config.delay_s / dt).round() as usize;
        let window = MIN_LOOKS.max((config.smoothing_s / dt).round() as usize + 1);
        PerceptionHistory {
            looks: VecDeque::with_capacity(delay_ticks + window),
            delay_ticks,
            window,
            dt,
            unseen_distance: config.distance_range_m,
        }
    }

    /// Adds this tick's look, forgetting the oldest once the history is full.
    pub fn record(&mut self, look: Look) {
        if self.looks.len() == self.delay_ticks + self.window {
            self.looks.pop_front();
        }
        self.looks.push_back(look);
    }

    /// The percept of a fielder now at `fielder` moving at `fielder_velocity` ((x, z) in m
    /// and m/s), its judgement of the image's motion off by `rate_errors` (a share of its
    /// speed, an angle of its direction: [`super::Senses::rate_errors`]), or `None` until
    /// enough looks have passed the delay for a fit.
    pub fn percept(
        &self,
        fielder: DVec2,
        fielder_velocity: DVec2,
        rate_errors: (f64, f64),
    ) -> Option<Percept> {
        let usable = self.looks.len().checked_sub(self.delay_ticks)?;
        let first = usable.checked_sub(self.window)?;
        let window = self.looks.range(first..usable);
        let newest = &self.looks[usable - 1];
        let ahead = self.delay_ticks as f64 * self.dt;
        let tick = |look: &Look| (look.t - newest.t) / self.dt;
        let at = ahead / self.dt;
        let (tan_psi, tan_psi_rate) = quadratic(window.clone().map(|l| (tick(l), l.tan_psi)), at);
        let psi = tan_psi.atan();
        let mut psi_rate = tan_psi_rate / self.dt * psi.cos().powi(2);
        // Bearings unwrapped about the newest, so a fit never straddles ±π.
        let unwrap = |a: f64| newest.alpha + (a - newest.alpha + PI).rem_euclid(TAU) - PI;
        let (alpha, mut alpha_rate) =
            quadratic(window.clone().map(|l| (tick(l), unwrap(l.alpha))), at);
        alpha_rate /= self.dt;
        // The image's angular velocity, judged: its speed off by a share (Weber's law),
        // its direction by an angle.
        let across = psi.cos().max(1e-6);
        let image = DVec2::new(psi_rate, across * alpha_rate);
        let judged = DVec2::from_angle(rate_errors.1).rotate(image) * (1.0 + rate_errors.0);
        (psi_rate, alpha_rate) = (judged.x, judged.y / across);
        // The distance as judged at the newest look, carried over the delay at its
        // judged rate.
        let (distance, distance_rate, distance_seen) = match newest.distance_cue {
            Some(cue) => (cue.distance_m + cue.rate_m_s * ahead, cue.rate_m_s, true),
            None => (self.unseen_distance, 0.0, false),
        };
        let delayed = Percept {
            t: newest.t + ahead,
            tan_psi,
            tan_psi_rate: psi_rate / psi.cos().powi(2),
            toward_ball: DVec2::from_angle(alpha),
            alpha_rate,
            distance: distance.max(1e-6),
            distance_rate,
            distance_seen,
        };
        // What the fielder's own movement since the newest look did, beyond carrying on
        // as it was then moving: the ball's place and motion relative to the eye, moved
        // by it, and seen again.
        let moved = fielder - newest.fielder - newest.fielder_velocity * ahead;
        let sped = fielder_velocity - newest.fielder_velocity;
        if moved == DVec2::ZERO && sped == DVec2::ZERO {
            return Some(delayed);
        }
        Some(Percept::of(
            delayed.t,
            delayed.relative_position() - DVec3::new(moved.x, 0.0, moved.y),
            delayed.relative_velocity() - DVec3::new(sped.x, 0.0, sped.y),
            distance_seen,
        ))
    }
}

/// The least-squares quadratic through `points` (u, y), evaluated at `at`: its value
/// and slope there. u is measured in ticks (order one), which keeps the normal
/// equations well conditioned; they are solved about the points' mean u.
fn quadratic(points: impl Iterator<Item = (f64, f64)> + Clone, at: f64) -> (f64, f64) {
    let (n, u_sum) = points
        .clone()
        .fold((0.0, 0.0), |(n, s), (u, _)| (n + 1.0, s + u));
    let mean = u_sum / n;
    let (mut s2, mut s3, mut s4) = (0.0, 0.0, 0.0);
    let (mut y0, mut y1, mut y2) = (0.0, 0.0, 0.0);
    for (u, y) in points {
        let v = u - mean;
        let v2 = v * v;
        (s2, s3, s4) = (s2 + v2, s3 + v2 * v, s4 + v2 * v2);
        (y0, y1, y2) = (y0 + y, y1 + v * y, y2 + v2 * y);
    }
    // [[n, 0, s2], [0, s2, s3], [s2, s3, s4]] · (a, b, c) = (y0, y1, y2), by Cramer.
    let det = n * (s2 * s4 - s3 * s3) - s2 * s2 * s2;
    let a = (y0 * (s2 * s4 - s3 * s3) + s2 * (y1 * s3 - s2 * y2)) / det;
    let b = (n * (y1 * s4 - s3 * y2) + s2 * (s3 * y0 - s2 * y1)) / det;
    let c = (n * (s2 * y2 - s3 * y1) - s2 * s2 * y0) / det;
    let v = at - mean;
    (a + b * v + c * v * v, b + 2.0 * c * v)
}

impl Percept {
    /// The percept at time `t` of a ball at `r` relative to the eye, moving at `v`.
    ///
    /// With d = |r_h| the horizontal distance, tan ψ = r_y/d and α = atan2(r_z, r_x), so
    /// d(tan ψ)/dt = (v_y·d − r_y·ḋ)/d² with ḋ = r_h·v_h/d, and dα/dt = (r_h × v_h)/d².
    /// The inverse of [`Self::relative_position`] and [`Self::relative_velocity`].
    pub(crate) fn of(t: f64, r: DVec3, v: DVec3, distance_seen: bool) -> Percept {
        let (r_h, v_h) = (DVec2::new(r.x, r.z), DVec2::new(v.x, v.z));
        let d = r_h.length().max(1e-6);
        let distance_rate = r_h.dot(v_h) / d;
        Percept {
            t,
            tan_psi: r.y / d,
            tan_psi_rate: (v.y * d - r.y * distance_rate) / (d * d),
            toward_ball: r_h.normalize_or(DVec2::X),
            alpha_rate: r_h.perp_dot(v_h) / (d * d),
            distance: d,
            distance_rate,
            distance_seen,
        }
    }

    /// The ball relative to the eye as the fielder judges it, m: the line of sight
    /// scaled by the judged distance.
    pub fn relative_position(&self) -> DVec3 {
        let r = self.toward_ball;
        self.distance * DVec3::new(r.x, self.tan_psi, r.y)
    }

    /// The rate of change of [`Self::relative_position`], m/s: the judged distance's
    /// rate along the line of sight and the angles' rates across it.
    pub fn relative_velocity(&self) -> DVec3 {
        let (r, d) = (self.toward_ball, self.distance);
        let across = DVec2::new(-r.y, r.x) * (d * self.alpha_rate);
        let along = r * self.distance_rate;
        DVec3::new(
            along.x + across.x,
            self.distance_rate * self.tan_psi + d * self.tan_psi_rate,
            along.y + across.y,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::{DistanceCue, Sighting};

    const EYE: f64 = 1.7;
    const DT: f64 = 1.0 / 60.0;

    /// A ball whose optical variables from a fielder standing at the origin are exactly
    /// quadratic in time, tan ψ = 0.2 + 0.3t − 0.04t², α = 0.5 − 0.1t + 0.02t², at a
    /// distance that is not (d = 60 − 8t + 0.3t³): the fit must read them exactly, at
    /// any window and delay.
    fn quadratic_ball(t: f64) -> DVec3 {
        let (tan_psi, alpha, d) = (
            0.2 + 0.3 * t - 0.04 * t * t,
            0.5 - 0.1 * t + 0.02 * t * t,
            60.0 - 8.0 * t + 0.3 * t * t * t,
        );
        DVec3::new(d * alpha.cos(), EYE + d * tan_psi, d * alpha.sin())
    }

    /// A ball in vacuum.
    fn vacuum_ball(t: f64) -> DVec3 {
        let (p0, v0) = (DVec3::new(-5.0, 1.0, 3.0), DVec3::new(20.0, 18.0, -4.0));
        p0 + v0 * t + 0.5 * crate::physics::GRAVITY * t * t
    }

    /// A fielder weaving about.
    fn weaving(t: f64) -> (DVec2, DVec2) {
        let pos = DVec2::new(40.0 + 3.0 * (2.0 * t).sin(), -2.0 + t * t);
        let vel = DVec2::new(6.0 * (2.0 * t).cos(), 2.0 * t);
        (pos, vel)
    }

    /// The noise-free look at time `t` at the ball of `ball` from the fielder of
    /// `fielder`, moving at `velocity`.
    fn look(
        t: f64,
        ball: impl Fn(f64) -> DVec3,
        fielder: impl Fn(f64) -> DVec2,
        velocity: DVec2,
    ) -> Look {
        let at = |t: f64| Sighting::of(t, ball(t), fielder(t), EYE);
        let s = at(t);
        let h = 1e-6;
        Look {
            t,
            tan_psi: s.tan_psi,
            alpha: s.alpha(),
            distance_cue: Some(DistanceCue {
                distance_m: s.distance,
                rate_m_s: (at(t + h).distance - at(t - h).distance) / (2.0 * h),
            }),
            fielder: fielder(t),
            fielder_velocity: velocity,
        }
    }

    fn config(delay_s: f64, smoothing_s: f64) -> PerceptionConfig {
        PerceptionConfig {
            delay_s,
            smoothing_s,
            ..PerceptionConfig::default()
        }
    }

    /// The optical variables of `ball` seen from `fielder` at time `t`, by their
    /// definitions (tan ψ = Y/d, α = atan2(Z, X)) and central differences.
    fn truth(ball: impl Fn(f64) -> DVec3, fielder: impl Fn(f64) -> DVec2, t: f64) -> [f64; 4] {
        let at = |t: f64| Sighting::of(t, ball(t), fielder(t), EYE);
        let h = 1e-5;
        let rate = |f: &dyn Fn(&Sighting) -> f64| (f(&at(t + h)) - f(&at(t - h))) / (2.0 * h);
        [
            at(t).tan_psi,
            rate(&|s| s.tan_psi),
            at(t).alpha(),
            rate(&|s| s.alpha()),
        ]
    }

    fn read(p: &Percept) -> [f64; 4] {
        let alpha = p.toward_ball.y.atan2(p.toward_ball.x);
        [p.tan_psi, p.tan_psi_rate, alpha, p.alpha_rate]
    }

    #[test]
    fn quadratic_angles_are_read_exactly_whatever_the_window_and_the_delay() {
        for (delay_s, smoothing_s) in [(0.0, 0.0), (0.0, 0.25), (0.2, 0.1), (0.3, 0.5)] {
            let mut h = PerceptionHistory::new(&config(delay_s, smoothing_s), DT);
            for n in 0..120 {
                let t = n as f64 * DT;
                h.record(look(t, quadratic_ball, |_| DVec2::ZERO, DVec2::ZERO));
            }
            let p = h.percept(DVec2::ZERO, DVec2::ZERO, (0.0, 0.0)).unwrap();
            let t = 119.0 * DT;
            assert!((p.t - t).abs() < 1e-9);
            let exact = truth(quadratic_ball, |_| DVec2::ZERO, t);
            for (got, want) in read(&p).iter().zip(exact) {
                assert!(
                    (got - want).abs() < 1e-7,
                    "{delay_s} {smoothing_s}: {got} vs {want}"
                );
            }
        }
    }

    /// A real flight seen by a weaving fielder, no delay, three looks: the angles are not
    /// quadratic, and the fit's error is of the order of the tick squared.
    #[test]
    fn any_smooth_flight_is_read_to_the_square_of_the_tick() {
        let mut h = PerceptionHistory::new(&config(0.0, 0.0), DT);
        for n in 0..40 {
            let t = n as f64 * DT;
            h.record(look(t, vacuum_ball, |t| weaving(t).0, weaving(t).1));
        }
        let t = 39.0 * DT;
        let (f, v) = weaving(t);
        let p = h.percept(f, v, (0.0, 0.0)).unwrap();
        let exact = truth(vacuum_ball, |t| weaving(t).0, t);
        for (got, want) in read(&p).iter().zip(exact) {
            assert!(
                (got - want).abs() < 1e-3 * want.abs().max(0.1),
                "{got} vs {want}"
            );
        }
    }

    /// With a delay the newest look is old. The fits carried over it see what the
    /// fielder was doing then; what it has done since (here it braked and turned at the
    /// newest look) must be taken out. The ball is built so that from a fielder who
    /// carried on running steadily its angles are exactly quadratic: the fits carried
    /// over the delay are then exact for that fielder, and what is left is only the
    /// fielder's own turn, which the correction must take out (to second order in its
    /// displacement over the distance: here it is exact, as the distance is).
    #[test]
    fn the_fielders_own_movement_over_the_delay_is_taken_out() {
        let turn = 1.0;
        let steady = |t: f64| DVec2::new(30.0 + 5.0 * t, 10.0 - 2.0 * t);
        let ball = |t: f64| quadratic_ball(t) + DVec3::new(steady(t).x, 0.0, steady(t).y);
        // From the newest usable look on, a constant acceleration the other way.
        let fielder = |t: f64| {
            let late = (t - turn).max(0.0);
            steady(t) + DVec2::new(-2.0, 1.5) * late * late
        };
        let velocity = |t: f64| DVec2::new(5.0, -2.0) + DVec2::new(-4.0, 3.0) * (t - turn).max(0.0);
        let mut h = PerceptionHistory::new(&config(0.2, 0.1), DT);
        let last = ((turn + 0.2) / DT).round() as usize;
        for n in 0..=last {
            let t = n as f64 * DT;
            h.record(look(t, ball, fielder, velocity(t)));
        }
        let t = last as f64 * DT;
        let exact = truth(ball, fielder, t);
        let error = |p: Percept| {
            read(&p)
                .iter()
                .zip(exact)
                .map(|(g, w)| (g - w).abs())
                .fold(0.0, f64::max)
        };
        let now = h.percept(fielder(t), velocity(t), (0.0, 0.0)).unwrap();
        // Without the correction: as if it had carried on as it was moving.
        let blind = h.percept(steady(t), velocity(turn), (0.0, 0.0)).unwrap();
        assert!(error(now) < 1e-4, "{}", error(now));
        assert!(
            error(blind) > 30.0 * error(now),
            "{} vs {}",
            error(blind),
            error(now)
        );
    }

    /// The image moves at (dψ/dt, cos ψ·dα/dt). A speed judged a share e too fast and a
    /// direction turned by φ make it (1 + e)·R(φ) of that: check both rates against the
    /// closed form, and that the angles and the distance are untouched.
    #[test]
    fn the_images_motion_is_judged_off_in_speed_and_direction() {
        let mut h = PerceptionHistory::new(&config(0.0, 0.0), DT);
        for n in 0..10 {
            let t = n as f64 * DT;
            h.record(look(t, quadratic_ball, |_| DVec2::ZERO, DVec2::ZERO));
        }
        let exact = h.percept(DVec2::ZERO, DVec2::ZERO, (0.0, 0.0)).unwrap();
        let (e, phi) = (0.1, 0.05);
        let off = h.percept(DVec2::ZERO, DVec2::ZERO, (e, phi)).unwrap();
        let t = 9.0 * DT;
        let (tan_psi, tan_psi_rate) = (0.2 + 0.3 * t - 0.04 * t * t, 0.3 - 0.08 * t);
        let psi = f64::atan(tan_psi);
        let psi_rate = tan_psi_rate * psi.cos().powi(2);
        let across = psi.cos() * (-0.1 + 0.04 * t);
        let judged = (
            (1.0 + e) * (psi_rate * phi.cos() - across * phi.sin()),
            (1.0 + e) * (psi_rate * phi.sin() + across * phi.cos()),
        );
        assert!((off.tan_psi_rate - judged.0 / psi.cos().powi(2)).abs() < 1e-9);
        assert!((off.alpha_rate - judged.1 / psi.cos()).abs() < 1e-9);
        assert_eq!((off.tan_psi, off.distance), (exact.tan_psi, exact.distance));
    }

    #[test]
    fn without_a_cue_the_ball_is_taken_to_be_at_the_cues_range() {
        let cfg = PerceptionConfig {
            distance_range_m: 30.0,
            ..PerceptionConfig::default()
        };
        let mut h = PerceptionHistory::new(&cfg, DT);
        for n in 0..5 {
            let t = n as f64 * DT;
            h.record(Look {
                distance_cue: None,
                ..look(t, quadratic_ball, |_| DVec2::ZERO, DVec2::ZERO)
            });
        }
        let p = h.percept(DVec2::ZERO, DVec2::ZERO, (0.0, 0.0)).unwrap();
        assert!(!p.distance_seen && p.distance == 30.0 && p.distance_rate == 0.0);
    }

    #[test]
    fn nothing_to_perceive_until_a_window_has_passed_the_delay() {
        let cfg = config(0.1, 0.05);
        let dt = 0.01;
        let looked = |ticks: usize| {
            let mut h = PerceptionHistory::new(&cfg, dt);
            for n in 0..ticks {
                let t = n as f64 * dt;
                h.record(look(t, vacuum_ball, |_| DVec2::ZERO, DVec2::ZERO));
            }
            h.percept(DVec2::ZERO, DVec2::ZERO, (0.0, 0.0))
        };
        // 10 ticks of delay and a window of 6 looks: the 16th look is the first usable.
        assert!(looked(15).is_none());
        assert!(looked(16).is_some());
    }
}
