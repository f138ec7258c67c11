//! A fielder's memory of its recent looks at the ball, and the estimate of the present
//! it makes from them.
//!
//! **Why an estimate, not differences.** Reading rates off two or three noisy looks
//! multiplies the noise by the tick rate (and the optical acceleration by its square):
//! with 0.05° of noise at 60 Hz a single difference of tan ψ is off by about 0.07/s, as
//! much as the whole rate it measures. People do not see rates that way: the visual
//! system integrates motion over time and is poor at arbitrary accelerations, but
//! judges motion under gravity well, combining a prior of gravity's effect with on-line
//! position and velocity signals (Lacquaniti et al. 2013, *Front. Integr. Neurosci.*
//! 7:101; McIntyre, Zago, Berthoz & Lacquaniti 2001, *Nat. Neurosci.* 4:693).
//!
//! So the fielder turns each look (bearing, elevation and the distance cue) into where
//! the ball was, adds back where *it* stood then (a runner knows its own movement, by
//! proprioception and efference copy), and fits the ball's recent path by least squares
//! over [`PerceptionConfig::smoothing_s`]: a straight line in the horizontal, and in the
//! vertical a line plus gravity's known ½·g·t². Removing its own movement before the
//! fit matters: the fielder's own accelerations are abrupt, the ball's path over a
//! fraction of a second is smooth, so only the ball needs a model.
//!
//! **Why predict over the delay.** With a visuomotor delay τ the newest look is τ old.
//! A loop that acts on it fights its own last τ of running, which it cannot yet see: the
//! optical strategies' loops (time constants of 0.2–0.3 s) oscillate at τ = 0.2 s. The
//! remedy the motor-control literature proposes is a Smith predictor (Miall, Weir,
//! Wolpert & Stein 1993, *J. Motor Behav.* 25:203): carry the delayed estimate forward
//! with an internal model. Here the model is the fitted path extended by τ and the
//! fielder's own position and velocity *now*, which it knows without delay. The
//! extrapolation never reaches further than the delay: this is not trajectory
//! prediction, which would forecast the landing point seconds ahead.
//!
//! With no noise and no delay the fit spans three looks and is exact for a parabola, so
//! the ideal observer sees the present as it is (to the drag's change over two ticks).

use super::{PerceptionConfig, Sighting};
use crate::physics::GRAVITY;
use glam::{DVec2, DVec3};
use std::collections::VecDeque;

/// The fewest looks a fit uses: two would give a velocity, the third keeps a single bad
/// look from steering alone.
const MIN_LOOKS: usize = 3;

/// One look at the ball, and where the fielder stood when it looked.
#[derive(Debug, Clone, Copy)]
struct Look {
    sighting: Sighting,
    fielder: DVec2,
}

/// The last looks, newest at the back: just the delay and one fitting window, so the
/// cost does not grow with the flight.
#[derive(Debug, Clone)]
pub struct PerceptionHistory {
    looks: VecDeque<Look>,
    eye_height: f64,
    delay_ticks: usize,
    window: usize,
    dt: f64,
}

/// What a strategy sees on one tick: its estimate of the ball now, relative to its eye,
/// and the optical angles and rates that estimate implies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percept {
    /// The line of sight and distance to the ball now (estimated).
    pub(crate) sighting: Sighting,
    /// That sighting's tan ψ.
    pub(crate) tan_psi: f64,
    /// d(tan ψ)/dt.
    pub tan_psi_rate: f64,
    /// dα/dt.
    pub alpha_rate: f64,
    /// The ball relative to the eye, m.
    pub relative_position: DVec3,
    /// Rate of change of `relative_position`, m/s.
    pub(crate) relative_velocity: DVec3,
}

impl PerceptionHistory {
    /// An empty history for an eye configured by `config`, looking once every `dt` s.
    pub fn new(config: &PerceptionConfig, dt: f64) -> PerceptionHistory {
        let delay_ticks = (config.delay_s / dt).round() as usize;
        let window = MIN_LOOKS.max((config.smoothing_s / dt).round() as usize + 1);
        PerceptionHistory {
            looks: VecDeque::with_capacity(delay_ticks + window),
            eye_height: config.eye_height_m,
            delay_ticks,
            window,
            dt,
        }
    }

    /// Adds this tick's look at the ball, taken with the fielder at `fielder`, forgetting
    /// the oldest once the history is full.
    pub fn record(&mut self, sighting: Sighting, fielder: DVec2) {
        if self.looks.len() == self.delay_ticks + self.window {
            self.looks.pop_front();
        }
        self.looks.push_back(Look { sighting, fielder });
    }

    /// The percept of a fielder now at `fielder` moving at `fielder_velocity` ((x, z) in m
    /// and m/s), or `None` until enough looks have passed the delay for a fit.
    pub fn percept(&self, fielder: DVec2, fielder_velocity: DVec2) -> Option<Percept> {
        let usable = self.looks.len().checked_sub(self.delay_ticks)?;
        let first = usable.checked_sub(self.window)?;
        let newest = &self.looks[usable - 1];
        let ahead = self.delay_ticks as f64 * self.dt;
        let (ball, ball_velocity) =
            self.fit(self.looks.range(first..usable), newest.sighting.t, ahead);
        let eye = DVec3::new(fielder.x, self.eye_height, fielder.y);
        Some(Percept::of(
            newest.sighting.t + ahead,
            ball - eye,
            ball_velocity - DVec3::new(fielder_velocity.x, 0.0, fielder_velocity.y),
        ))
    }

    /// The ball's position and velocity `ahead` s after `t_newest`, by least squares over
    /// `looks`: each component a + b·s (s = time since `t_newest`), after the known
    /// −½·g·s² is taken off the height.
    fn fit<'a>(
        &self,
        looks: impl ExactSizeIterator<Item = &'a Look>,
        t_newest: f64,
        ahead: f64,
    ) -> (DVec3, DVec3) {
        let n = looks.len() as f64;
        let (mut s_sum, mut ss_sum) = (0.0, 0.0);
        let (mut p_sum, mut sp_sum) = (DVec3::ZERO, DVec3::ZERO);
        for look in looks {
            let s = look.sighting.t - t_newest;
            let ground = look.fielder;
            let ball = look.sighting.relative_position()
                + DVec3::new(ground.x, self.eye_height, ground.y)
                - 0.5 * GRAVITY * s * s;
            s_sum += s;
            ss_sum += s * s;
            p_sum += ball;
            sp_sum += s * ball;
        }
        let slope = (n * sp_sum - s_sum * p_sum) / (n * ss_sum - s_sum * s_sum);
        let intercept = (p_sum - slope * s_sum) / n;
        (
            intercept + slope * ahead + 0.5 * GRAVITY * ahead * ahead,
            slope + GRAVITY * ahead,
        )
    }
}

impl Percept {
    /// The percept at time `t` of a ball at `r` relative to the eye, moving at `v`.
    ///
    /// With d = |r_h| the horizontal distance, tan ψ = r_y/d and α = atan2(r_z, r_x), so
    /// d(tan ψ)/dt = (v_y·d − r_y·ḋ)/d² with ḋ = r_h·v_h/d, and dα/dt = (r_h × v_h)/d².
    pub(crate) fn of(t: f64, r: DVec3, v: DVec3) -> Percept {
        let (r_h, v_h) = (DVec2::new(r.x, r.z), DVec2::new(v.x, v.z));
        let d = r_h.length().max(1e-9);
        let d_rate = r_h.dot(v_h) / d;
        let tan_psi = r.y / d;
        Percept {
            sighting: Sighting {
                t,
                tan_psi,
                toward_ball: r_h.normalize_or(DVec2::X),
                distance: d,
            },
            tan_psi,
            tan_psi_rate: (v.y * d - r.y * d_rate) / (d * d),
            alpha_rate: r_h.perp_dot(v_h) / (d * d),
            relative_position: r,
            relative_velocity: v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::GRAVITY;

    /// A ball in vacuum: exactly the path the fit models.
    fn vacuum_ball(t: f64) -> (DVec3, DVec3) {
        let (p0, v0) = (DVec3::new(-5.0, 1.0, 3.0), DVec3::new(20.0, 18.0, -4.0));
        (p0 + v0 * t + 0.5 * GRAVITY * t * t, v0 + GRAVITY * t)
    }

    /// A fielder weaving about: its own motion must not leak into the estimate.
    fn weaving_fielder(t: f64) -> (DVec2, DVec2) {
        let pos = DVec2::new(40.0 + 3.0 * (2.0 * t).sin(), -2.0 + t * t);
        let vel = DVec2::new(6.0 * (2.0 * t).cos(), 2.0 * t);
        (pos, vel)
    }

    fn looked_at(config: &PerceptionConfig, dt: f64, ticks: usize) -> PerceptionHistory {
        let mut h = PerceptionHistory::new(config, dt);
        for n in 0..ticks {
            let t = n as f64 * dt;
            let (ball, fielder) = (vacuum_ball(t).0, weaving_fielder(t).0);
            h.record(Sighting::of(t, ball, fielder, config.eye_height_m), fielder);
        }
        h
    }

    /// The percept's rates against the closed forms: tan ψ = Y/d, α = atan2(Z, X) of the
    /// relative position, differentiated numerically by a central difference.
    fn assert_matches_truth(p: &Percept, t: f64, eye: f64) {
        let relative = |t: f64| {
            let (f, _) = weaving_fielder(t);
            vacuum_ball(t).0 - DVec3::new(f.x, eye, f.y)
        };
        let tan_psi = |t: f64| {
            let r = relative(t);
            r.y / r.x.hypot(r.z)
        };
        let alpha = |t: f64| relative(t).z.atan2(relative(t).x);
        let h = 1e-5;
        assert!((p.sighting.t - t).abs() < 1e-9);
        assert!((p.relative_position - relative(t)).length() < 1e-6);
        assert!((p.tan_psi - tan_psi(t)).abs() < 1e-9);
        let rate = (tan_psi(t + h) - tan_psi(t - h)) / (2.0 * h);
        assert!(
            (p.tan_psi_rate - rate).abs() < 1e-6,
            "{} vs {rate}",
            p.tan_psi_rate
        );
        let alpha_rate = (alpha(t + h) - alpha(t - h)) / (2.0 * h);
        assert!((p.alpha_rate - alpha_rate).abs() < 1e-6);
    }

    #[test]
    fn a_parabola_is_seen_exactly_whatever_the_fielder_does() {
        let dt = 1.0 / 60.0;
        for smoothing_s in [0.0, 0.25] {
            let cfg = PerceptionConfig {
                smoothing_s,
                ..Default::default()
            };
            let h = looked_at(&cfg, dt, 40);
            let t = 39.0 * dt;
            let (f, v) = weaving_fielder(t);
            assert_matches_truth(&h.percept(f, v).unwrap(), t, cfg.eye_height_m);
        }
    }

    /// With a delay the newest look is old, but the estimate is of the present: the
    /// fitted path carried forward over the delay, seen from where the fielder is now.
    #[test]
    fn the_delay_is_bridged_by_the_fitted_path_and_the_fielders_own_movement() {
        let dt = 0.01;
        let cfg = PerceptionConfig {
            delay_s: 0.2,
            smoothing_s: 0.1,
            ..Default::default()
        };
        let h = looked_at(&cfg, dt, 100);
        let t = 99.0 * dt;
        let (f, v) = weaving_fielder(t);
        assert_matches_truth(&h.percept(f, v).unwrap(), t, cfg.eye_height_m);
    }

    #[test]
    fn nothing_to_perceive_until_a_window_has_passed_the_delay() {
        let cfg = PerceptionConfig {
            delay_s: 0.1,
            smoothing_s: 0.05,
            ..Default::default()
        };
        let dt = 0.01;
        // 10 ticks of delay and a window of 6 looks: the 16th look is the first usable.
        assert!(looked_at(&cfg, dt, 15)
            .percept(DVec2::ZERO, DVec2::ZERO)
            .is_none());
        assert!(looked_at(&cfg, dt, 16)
            .percept(DVec2::ZERO, DVec2::ZERO)
            .is_some());
    }

    /// Noise of sd σ on each look: a longer window must bring the rate's error down.
    /// Least squares over n looks spanning T cuts a slope's sd like 1/(√n·T): 16 looks
    /// over 0.25 s against 3 over 2 ticks is √170 ≈ 13 for the slope alone; the rate also
    /// carries the endpoint's position error, which falls only like 2/√n, so ask for 5.
    #[test]
    fn a_longer_window_averages_the_noise_away() {
        use rand::SeedableRng;
        let dt = 1.0 / 60.0;
        let rms_rate_error = |smoothing_s: f64| {
            let cfg = PerceptionConfig {
                smoothing_s,
                ..Default::default()
            };
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
            let mut h = PerceptionHistory::new(&cfg, dt);
            let (mut sum, mut count) = (0.0, 0);
            for n in 0..120 {
                let t = n as f64 * dt;
                let (ball, fielder) = (vacuum_ball(t).0, weaving_fielder(t).0);
                let seen = Sighting::of(t, ball, fielder, cfg.eye_height_m);
                h.record(seen.blurred(0.05f64.to_radians(), &mut rng), fielder);
                if n >= 60 {
                    let (f, v) = weaving_fielder(t);
                    let exact = looked_at(&PerceptionConfig::default(), dt, n + 1)
                        .percept(f, v)
                        .unwrap();
                    let p = h.percept(f, v).unwrap();
                    sum += (p.tan_psi_rate - exact.tan_psi_rate).powi(2);
                    count += 1;
                }
            }
            (sum / count as f64).sqrt()
        };
        let (three_looks, quarter_second) = (rms_rate_error(0.0), rms_rate_error(0.25));
        assert!(
            quarter_second < three_looks / 5.0,
            "{three_looks} -> {quarter_second}"
        );
    }
}
