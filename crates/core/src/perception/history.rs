//! A fielder's memory of its recent sightings, and the rates read off it by differences.

use super::{PerceptionConfig, Sighting};
use std::collections::VecDeque;

/// The last few sightings, newest at the back; just long enough for a delayed second
/// difference, so its cost does not grow with the flight.
#[derive(Debug, Clone)]
pub struct PerceptionHistory {
    sightings: VecDeque<Sighting>,
    delay_ticks: usize,
    span: usize,
    dt: f64,
}

/// What a strategy sees on one tick: the (possibly delayed) sighting and its rates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Percept {
    /// The sighting the rates are read at: the newest, or the one `delay_s` old.
    pub(crate) sighting: Sighting,
    /// That sighting's tan ψ.
    pub(crate) tan_psi: f64,
    /// d(tan ψ)/dt.
    pub tan_psi_rate: f64,
    /// d²(tan ψ)/dt²: Chapman's optical acceleration.
    pub optical_acceleration: f64,
    /// dα/dt, unwrapped across ±π.
    pub alpha_rate: f64,
    /// The ball relative to the eye (from angles and distance), and its rate of change.
    pub relative_position: glam::DVec3,
    /// Rate of change of `relative_position`, by a backward difference, m/s.
    pub(crate) relative_velocity: glam::DVec3,
}

impl PerceptionHistory {
    /// An empty history for an eye configured by `config`, sighting once every `dt` s.
    pub fn new(config: &PerceptionConfig, dt: f64) -> PerceptionHistory {
        let delay_ticks = (config.delay_s / dt).round() as usize;
        let span = config.difference_span.max(1);
        PerceptionHistory {
            sightings: VecDeque::with_capacity(delay_ticks + 2 * span + 1),
            delay_ticks,
            span,
            dt,
        }
    }

    /// Adds this tick's sighting, forgetting the oldest once the history is full.
    pub fn record(&mut self, sighting: Sighting) {
        if self.sightings.len() == self.delay_ticks + 2 * self.span + 1 {
            self.sightings.pop_front();
        }
        self.sightings.push_back(sighting);
    }

    /// The percept available now, or `None` until enough sightings have passed the delay
    /// for a second difference.
    pub fn percept(&self) -> Option<Percept> {
        let n = self.sightings.len();
        let newest = n.checked_sub(1 + self.delay_ticks)?;
        let oldest = newest.checked_sub(2 * self.span)?;
        let (s0, s1, s2) = (
            &self.sightings[oldest],
            &self.sightings[oldest + self.span],
            &self.sightings[newest],
        );
        let h = self.span as f64 * self.dt;
        let (t0, t1, t2) = (s0.tan_psi, s1.tan_psi, s2.tan_psi);
        // The signed angle between the two bearings: no wrap-around at ±π to handle.
        let (b1, b2) = (s1.toward_ball, s2.toward_ball);
        let turned = b1.perp_dot(b2).atan2(b1.dot(b2));
        Some(Percept {
            sighting: *s2,
            tan_psi: t2,
            tan_psi_rate: (t2 - t1) / h,
            optical_acceleration: (t2 - 2.0 * t1 + t0) / (h * h),
            alpha_rate: turned / h,
            relative_position: s2.relative_position(),
            relative_velocity: (s2.relative_position() - s1.relative_position()) / h,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec2, DVec3};

    #[test]
    fn rates_of_a_quadratic_are_exact() {
        // tan ψ = 0.1 + 0.2 t + 0.15 t² at fixed distance 10: second differences are exact.
        let cfg = PerceptionConfig::default();
        let dt = 0.02;
        let mut h = PerceptionHistory::new(&cfg, dt);
        for n in 0..10 {
            let t = n as f64 * dt;
            let tan = 0.1 + 0.2 * t + 0.15 * t * t;
            let ball = DVec3::new(10.0, cfg.eye_height_m + 10.0 * tan, 0.0);
            h.record(Sighting::of(t, ball, DVec2::ZERO, cfg.eye_height_m));
        }
        let p = h.percept().unwrap();
        let t = 9.0 * dt;
        assert!((p.optical_acceleration - 0.3).abs() < 1e-6);
        // A backward difference is the slope at the middle of its step.
        assert!((p.tan_psi_rate - (0.2 + 0.3 * (t - dt / 2.0))).abs() < 1e-9);
    }

    #[test]
    fn delay_shows_an_older_sighting() {
        let cfg = PerceptionConfig {
            delay_s: 0.1,
            ..Default::default()
        };
        let dt = 0.01;
        let mut h = PerceptionHistory::new(&cfg, dt);
        for n in 0..30 {
            let t = n as f64 * dt;
            h.record(Sighting::of(t, DVec3::new(10.0, 5.0, t), DVec2::ZERO, 1.7));
        }
        assert!((h.percept().unwrap().sighting.t - 0.19).abs() < 1e-12);
    }

    #[test]
    fn bearing_rate_survives_the_wrap_at_pi() {
        let dt = 0.1;
        let mut h = PerceptionHistory::new(&PerceptionConfig::default(), dt);
        for n in 0..3 {
            // The ball crosses the −x axis, where atan2 jumps from +π to −π.
            let z = 0.1 - 0.1 * n as f64;
            h.record(Sighting::of(
                n as f64 * dt,
                DVec3::new(-10.0, 5.0, z),
                DVec2::ZERO,
                1.7,
            ));
        }
        let rate = h.percept().unwrap().alpha_rate;
        assert!(rate > 0.0 && rate < 0.2, "{rate}");
    }

    #[test]
    fn nothing_to_perceive_until_the_history_fills() {
        let cfg = PerceptionConfig::default();
        let mut h = PerceptionHistory::new(&cfg, 0.1);
        h.record(Sighting::of(0.0, DVec3::ONE, DVec2::ZERO, 1.7));
        h.record(Sighting::of(0.1, DVec3::ONE, DVec2::ZERO, 1.7));
        assert!(h.percept().is_none());
    }
}
