//! What a fielder's senses report of the ball on one look, with a person's errors.
//!
//! **Angles** (elevation ψ, bearing α) are what the eye measures best; each look may
//! carry independent Gaussian noise ([`PerceptionConfig::noise_rad`]).
//!
//! **Rates** are judged, not differentiated. The image of the ball moves across the eye
//! with an angular velocity (dψ/dt, cos ψ·dα/dt); people judge its speed with a Weber
//! fraction of about 7 % at best (84 % correct, 4–64°/s; De Bruyn & Orban 1988, *Vision
//! Res.* 28:1323), reached after about 0.1 s of motion (Snowden & Braddick 1991, *Vision
//! Res.* 31:907), and worse for changes of speed, about 17 % (Werkhoven, Snippe & Toet
//! 1992) to 30 % (Snowden & Braddick); gradual acceleration is detected poorly (Calderone
//! & Kaiser 1989). Its direction they judge to about 1.8° (De Bruyn & Orban). So the
//! perceived speed is off by [`PerceptionConfig::rate_weber`] of itself and the direction
//! by [`PerceptionConfig::direction_rad`] (standard deviations). The errors are the
//! fielder's, not the look's: a fit over many looks does not average them away.
//!
//! **Distance** is a cue only up close: beyond about 30 m most absolute distance cues
//! (disparity, vergence, motion parallax, optical expansion) fall below threshold
//! (Cutting & Vishton 1995; cited so by Fink, Foo & Warren 2009, *J. Vision* 9(13):14).
//! Within [`PerceptionConfig::distance_range_m`] the cue is the true distance times
//! exp(W·x), a log-normal error of about W (the Weber fraction
//! [`PerceptionConfig::distance_weber`]); beyond it there is none. How fast the ball
//! closes along the line of sight is judged with it, from the ball's optical expansion
//! (Lee 1976's τ), as a rate: off by the rate Weber fraction. It is not the distance
//! cue differentiated, which would turn a judgement that wanders by 15 % in a tenth of a
//! second into closing speeds off by tens of metres a second.
//!
//! **How errors last** (*assumption*). A judgement integrates about a tenth of a second
//! of motion, and successive judgements share most of it, so an error is not new on
//! every 60 Hz look: each of the four errors (the image's speed and direction, distance,
//! closing speed) is an
//! Ornstein–Uhlenbeck process of unit variance with correlation time [`JUDGEMENT_S`]
//! (white noise per look would be averaged away by the strategies' own loops, which take
//! a third of a second to respond, and flatter the fielder).

use super::{PerceptionConfig, Sighting};
use glam::DVec2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// The correlation time of the senses' errors, s: how long one judgement of a rate or a
/// distance is held before the next is independent of it. *Assumption*: about the
/// 0.1 s over which speed discrimination reaches its best (Snowden & Braddick 1991).
pub const JUDGEMENT_S: f64 = 0.1;

/// One look as the fielder has it: the angles its eye reported, the distance cue if it
/// has one, and what it knows of itself at that moment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Look {
    /// When the eye looked, s since the launch.
    pub t: f64,
    /// tan ψ, ψ the elevation above the horizontal through the eye.
    pub tan_psi: f64,
    /// Bearing α from +x toward +z, rad.
    pub alpha: f64,
    /// The horizontal distance as the fielder judges it; `None` beyond the cue's range.
    pub distance_cue: Option<DistanceCue>,
    /// Where the fielder stood, (x, z) in m.
    pub fielder: DVec2,
    /// How it was moving, m/s (a runner knows, by proprioception and efference copy).
    pub fielder_velocity: DVec2,
}

/// The distance to the ball and how fast it changes, as judged up close.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistanceCue {
    /// Horizontal distance, m.
    pub distance_m: f64,
    /// Its rate of change, m/s (negative while the ball closes in).
    pub rate_m_s: f64,
}

/// A fielder's senses: its settings, its random source and the errors it is carrying.
#[derive(Debug, Clone)]
pub struct Senses {
    config: PerceptionConfig,
    rng: ChaCha8Rng,
    /// How much of an error survives one tick: exp(−dt / [`JUDGEMENT_S`]).
    persistence: f64,
    /// The standard-normal states of the errors of the image's speed and direction, the
    /// distance and the closing speed.
    errors: [f64; 4],
    /// The true distance at the last look, (t, d): the closing speed's truth is its
    /// change over one tick.
    last: Option<(f64, f64)>,
    /// Whether any error is on.
    noisy: bool,
}

impl Senses {
    /// The senses of `config`, their noise drawn from `seed`, looking every `dt` s.
    pub fn new(config: &PerceptionConfig, seed: u64, dt: f64) -> Senses {
        Senses {
            config: *config,
            rng: ChaCha8Rng::seed_from_u64(seed),
            persistence: (-dt / JUDGEMENT_S).exp(),
            errors: [0.0; 4],
            last: None,
            noisy: [
                config.rate_weber,
                config.direction_rad,
                config.distance_weber,
                config.noise_rad,
            ]
            .iter()
            .any(|&sd| sd > 0.0),
        }
    }

    /// What the senses report of `truth`, seen by a fielder at `fielder` moving at
    /// `fielder_velocity`; moves the errors on by one look.
    pub fn look(&mut self, truth: &Sighting, fielder: DVec2, fielder_velocity: DVec2) -> Look {
        let c = self.config;
        // Each error starts from its stationary distribution, then drifts: exact
        // Ornstein–Uhlenbeck steps, so the variance stays 1 whatever the tick.
        let (keep, fresh) = if self.last.is_some() {
            (self.persistence, (1.0 - self.persistence.powi(2)).sqrt())
        } else {
            (0.0, 1.0)
        };
        // Every error is drawn on every look, used or not, so that switching one sense
        // off leaves the others' errors as they were: experiments compare the same
        // fielder with and without a sense, not two fielders with different luck. An
        // exact eye (every error off) draws nothing.
        let mut blur = [0.0; 2];
        if self.noisy {
            for error in &mut self.errors {
                let draw: f64 = StandardNormal.sample(&mut self.rng);
                *error = keep * *error + fresh * draw;
            }
            blur = [
                StandardNormal.sample(&mut self.rng),
                StandardNormal.sample(&mut self.rng),
            ];
        }
        let closing = self
            .last
            .map_or(0.0, |(t, d)| (truth.distance - d) / (truth.t - t).max(1e-9));
        self.last = Some((truth.t, truth.distance));
        let tan_psi = if c.noise_rad == 0.0 {
            truth.tan_psi
        } else {
            (truth.psi() + c.noise_rad * blur[0]).tan()
        };
        let alpha = truth.alpha() + c.noise_rad * blur[1];
        let distance_cue = (truth.distance <= c.distance_range_m).then(|| DistanceCue {
            distance_m: truth.distance * (c.distance_weber * self.errors[2]).exp(),
            rate_m_s: closing * (1.0 + c.rate_weber * self.errors[3]),
        });
        Look {
            t: truth.t,
            tan_psi,
            alpha,
            distance_cue,
            fielder,
            fielder_velocity,
        }
    }

    /// The errors of the judgement of the image's motion now: (relative error of its
    /// speed, error of its direction in rad), of standard deviations `rate_weber` and
    /// `direction_rad`.
    pub fn rate_errors(&self) -> (f64, f64) {
        let c = &self.config;
        (
            c.rate_weber * self.errors[0],
            c.direction_rad * self.errors[1],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn senses(config: PerceptionConfig) -> Senses {
        Senses::new(&config, 7, 1.0 / 60.0)
    }

    fn truth(t: f64, distance: f64) -> Sighting {
        Sighting::of(t, DVec3::new(distance, 10.0, 0.0), DVec2::ZERO, 1.7)
    }

    /// The errors' statistics are what the settings say: the distance cue's log error
    /// has standard deviation W and mean 0; successive errors one correlation time
    /// apart correlate by e⁻¹; the rate errors have standard deviation `rate_weber`.
    #[test]
    fn the_errors_have_the_stated_spread_and_memory() {
        let config = PerceptionConfig {
            rate_weber: 0.1,
            distance_weber: 0.15,
            ..PerceptionConfig::default()
        };
        let mut s = senses(config);
        let lag = (JUDGEMENT_S * 60.0).round() as usize;
        let (mut logs, mut rates) = (Vec::new(), Vec::new());
        for _ in 0..200_000 {
            let look = s.look(&truth(0.0, 20.0), DVec2::ZERO, DVec2::ZERO);
            logs.push((look.distance_cue.unwrap().distance_m / 20.0).ln());
            rates.push(s.rate_errors().0);
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let sd = |v: &[f64]| {
            let m = mean(v);
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt()
        };
        assert!(mean(&logs).abs() < 0.01, "{}", mean(&logs));
        assert!((sd(&logs) - 0.15).abs() < 0.01, "{}", sd(&logs));
        assert!((sd(&rates) - 0.1).abs() < 0.007, "{}", sd(&rates));
        let m = mean(&logs);
        let lagged = logs
            .iter()
            .zip(&logs[lag..])
            .map(|(a, b)| (a - m) * (b - m));
        let correlation = lagged.sum::<f64>() / (logs.len() - lag) as f64 / sd(&logs).powi(2);
        assert!(
            (correlation - (-1.0f64).exp()).abs() < 0.05,
            "{correlation}"
        );
    }

    #[test]
    fn beyond_its_range_there_is_no_distance_cue_and_within_it_an_exact_one_by_default() {
        let mut s = senses(PerceptionConfig {
            distance_range_m: 30.0,
            ..PerceptionConfig::default()
        });
        assert_eq!(
            s.look(&truth(1.0, 30.5), DVec2::ZERO, DVec2::ZERO)
                .distance_cue,
            None
        );
        let cue = s
            .look(&truth(2.0, 29.5), DVec2::ZERO, DVec2::ZERO)
            .distance_cue
            .unwrap();
        // 1 m closer one second later.
        assert_eq!((cue.distance_m, cue.rate_m_s), (29.5, -1.0));
        assert_eq!(s.rate_errors(), (0.0, 0.0));
    }
}
