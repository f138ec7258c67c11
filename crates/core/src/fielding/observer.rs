//! Who watches the ball: the ideal observer of the papers' simulations, or a person.
//!
//! The catching papers test their strategies with fielders who see every angle exactly
//! and at once. A strategy people could use must also work with a person's senses: late,
//! noisy, and with an arm's reach. Sweeps report both, so a reader sees what the senses
//! cost each strategy.

use super::TrialConfig;
use crate::names::{lookup, UnknownName};
use serde::Serialize;
use std::fmt;
use std::str::FromStr;

/// The senses and reach of a fielder, and how long it integrates what it sees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Observer {
    /// The preset this started from (`ideal` or `human`); any setting may have been
    /// changed since (the report shows them all).
    pub name: &'static str,
    /// Visuomotor delay, s: the strategy acts on what the eye saw this long ago.
    pub delay_s: f64,
    /// Standard deviation of the noise on each look's elevation and bearing, degrees.
    pub noise_deg: f64,
    /// How far back, s, the fielder fits the ball's path (0: its last three looks).
    pub smoothing_s: f64,
    /// Horizontal reach from the fielder's centre, m.
    pub reach_m: f64,
}

impl Observer {
    /// The papers' fielder: exact angles at once, 1 m of reach (the catch zone's
    /// default), and the shortest fit (exact for a parabola).
    pub const IDEAL: Observer = Observer {
        name: "ideal",
        delay_s: 0.0,
        noise_deg: 0.0,
        smoothing_s: 0.0,
        reach_m: 1.0,
    };

    /// A person, with each figure's source:
    ///
    /// * **Delay 0.2 s.** Interception has to bridge the delay between seeing and moving
    ///   (the theme of Zago, McIntyre, Senot & Lacquaniti's 2009 review, *Exp. Brain
    ///   Res.* 192:571); the hand's course corrections follow a target's jump after about
    ///   0.11 s (Brenner & Smeets 1997, *J. Motor Behav.* 29:297). We take 0.2 s, the slow
    ///   end of the usual 0.1–0.2 s: redirecting a running body is slower than redirecting
    ///   a hand (*assumption*).
    /// * **Noise 0.05° (3 arcmin) per look.** Normal acuity resolves 1 arcmin (the
    ///   definition of 20/20 vision); locating a small ball moving against the sky, with
    ///   the head bobbing on a run, is worse. *Assumption*, three times the acuity limit,
    ///   per 60 Hz look, independent between looks.
    /// * **Reach 0.9 m.** Half the shoulder breadth plus upper arm, forearm and half the
    ///   hand, from Winter's segment proportions of body height H, 0.129 H + 0.186 H +
    ///   0.146 H + 0.054 H = 0.515 H (*Biomechanics and Motor Control of Human Movement*,
    ///   after Drillis & Contini 1966): 0.93 m for H = 1.8 m, whose eye height 0.936 H = 1.68 m
    ///   is our 1.7 m. No lean, no dive.
    /// * **Smoothing 0.2 s.** Not a sense but the fielder's remedy for the noise: the
    ///   sweeps' best window for both optical strategies (0.15–0.2 s; see
    ///   docs/catching.md). The visual system integrates motion over about 0.1 s in early
    ///   cortex and longer for speed judgements.
    pub const HUMAN: Observer = Observer {
        name: "human",
        delay_s: 0.2,
        noise_deg: 0.05,
        smoothing_s: 0.2,
        reach_m: 0.9,
    };

    /// Gives a trial this observer's senses and reach.
    pub fn apply(&self, trial: &mut TrialConfig) {
        let perception = &mut trial.fielder.perception;
        perception.delay_s = self.delay_s;
        perception.noise_rad = self.noise_deg.to_radians();
        perception.smoothing_s = self.smoothing_s;
        trial.zone.reach_m = self.reach_m;
    }
}

impl FromStr for Observer {
    type Err = UnknownName;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        lookup(
            "observer",
            s,
            &["ideal", "human"],
            &[Self::IDEAL, Self::HUMAN],
        )
    }
}

impl fmt::Display for Observer {
    /// One line a reader can check the settings by: `human: delay 0.2 s, noise 0.05°,
    /// smoothing 0.2 s, reach 0.9 m`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: delay {} s, noise {}°, smoothing {} s, reach {} m",
            self.name, self.delay_s, self.noise_deg, self.smoothing_s, self.reach_m
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_by_name_and_their_settings_reach_the_trial() {
        assert_eq!("human".parse::<Observer>(), Ok(Observer::HUMAN));
        let err = "robot".parse::<Observer>().unwrap_err().to_string();
        assert!(err.contains("ideal, human"), "{err}");
        let mut trial = TrialConfig::default();
        Observer::HUMAN.apply(&mut trial);
        assert_eq!(trial.fielder.perception.delay_s, 0.2);
        assert!((trial.fielder.perception.noise_rad - 0.05f64.to_radians()).abs() < 1e-15);
        assert_eq!(trial.fielder.perception.smoothing_s, 0.2);
        assert_eq!(trial.zone.reach_m, 0.9);
    }

    /// The ideal observer is what a trial has by default: the papers' setting.
    #[test]
    fn the_ideal_observer_changes_nothing() {
        let mut trial = TrialConfig::default();
        Observer::IDEAL.apply(&mut trial);
        assert_eq!(
            format!("{trial:?}"),
            format!("{:?}", TrialConfig::default())
        );
    }
}
