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

/// The senses and reach of a fielder, how long it integrates what it sees, and how it
/// finishes a catch.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Observer {
    /// The preset this started from (`ideal` or `human`); any setting may have been
    /// changed since (the report shows them all).
    pub name: &'static str,
    /// Visuomotor delay, s: the strategy acts on what the eye saw this long ago.
    pub delay_s: f64,
    /// Standard deviation of the noise on each look's elevation and bearing, degrees.
    pub noise_deg: f64,
    /// How far back, s, the fielder fits the angles (0: its last three looks).
    pub smoothing_s: f64,
    /// Weber fraction of the image's perceived angular speed (0: exact).
    pub rate_weber: f64,
    /// Error of the perceived direction of the image's motion, degrees (0: exact).
    pub direction_deg: f64,
    /// Weber fraction of the distance cue (0: exact).
    pub distance_weber: f64,
    /// Range of the distance cue, m: beyond it the fielder has none.
    pub distance_range_m: f64,
    /// Horizontal reach from the fielder's centre, m.
    pub reach_m: f64,
    /// How long before the ball comes down the fielder finishes the catch by its
    /// judgement of where, s (0: it steers by its law to the end, as in the papers).
    pub terminal_s: f64,
    /// How much further it reaches when finishing: a lunge, m.
    pub lunge_m: f64,
}

impl Observer {
    /// The papers' fielder: exact angles, rates and distance at once, 1 m of reach (the
    /// catch zone's default), the shortest fit, and its law to the end.
    pub const IDEAL: Observer = Observer {
        name: "ideal",
        delay_s: 0.0,
        noise_deg: 0.0,
        smoothing_s: 0.0,
        rate_weber: 0.0,
        direction_deg: 0.0,
        distance_weber: 0.0,
        distance_range_m: f64::INFINITY,
        reach_m: 1.0,
        terminal_s: 0.0,
        lunge_m: 0.0,
    };

    /// A person, with each figure's source (docs/catching.md has the table):
    ///
    /// * **Delay 0.2 s.** Interception has to bridge the delay between seeing and moving
    ///   (the theme of Zago, McIntyre, Senot & Lacquaniti's 2009 review, *Exp. Brain
    ///   Res.* 192:571); the hand's course corrections follow a target's jump after about
    ///   0.11 s (Brenner & Smeets 1997, *J. Motor Behav.* 29:297). We take 0.2 s, the slow
    ///   end of the usual 0.1–0.2 s: redirecting a running body is slower than redirecting
    ///   a hand (*assumption*).
    /// * **The image's speed: Weber fraction 10 %; its direction: 2°.** Speed
    ///   discrimination reaches a Weber fraction of about 7 % (De Bruyn & Orban 1988,
    ///   *Vision Res.* 28:1323; 6 % after 0.1 s, Snowden & Braddick 1991, *Vision Res.*
    ///   31:907) and is worse for modulations of speed, about 17 % (Werkhoven, Snippe &
    ///   Toet 1992); gradual acceleration is detected poorly (Calderone & Kaiser 1989,
    ///   *Percept. Psychophys.* 45:391). 10 % is between the best and the modulations.
    ///   Direction is discriminated to 1.8° (De Bruyn & Orban); we take 2°.
    /// * **Distance: Weber fraction 15 % within 30 m, none beyond.** Beyond about 30 m most
    ///   absolute distance cues are below threshold (Cutting & Vishton 1995, as Fink, Foo
    ///   & Warren 2009, *J. Vision* 9(13):14, cite it for OAC). 15 % within it is an
    ///   *assumption*: distance judgements of a moving object at tens of metres are coarser
    ///   than speed judgements.
    /// * **No noise on single looks' angles.** The rate errors are measured on what people
    ///   judge, which already includes where the eye placed the ball; adding positional
    ///   noise as well would count it twice (`--noise-deg` adds it for experiments).
    /// * **Smoothing 0.1 s**: the judgements' integration time ([`crate::perception`]'s
    ///   `JUDGEMENT_S`, an *assumption*).
    /// * **Reach 0.9 m.** Half the shoulder breadth plus upper arm, forearm and half the
    ///   hand, from Winter's segment proportions of body height H, 0.129 H + 0.186 H +
    ///   0.146 H + 0.054 H = 0.515 H (*Biomechanics and Motor Control of Human Movement*,
    ///   after Drillis & Contini 1966): 0.93 m for H = 1.8 m, whose eye height 0.936 H = 1.68 m
    ///   is our 1.7 m.
    /// * **Finishing: the last 0.5 s, a 0.6 m lunge.** People step, reach and lunge at
    ///   the end of a run to a ball (*assumption*: half a second is the last two or three
    ///   strides; a lunging step adds about half a stride to the reach). No dive.
    pub const HUMAN: Observer = Observer {
        name: "human",
        delay_s: 0.2,
        noise_deg: 0.0,
        smoothing_s: 0.1,
        rate_weber: 0.1,
        direction_deg: 2.0,
        distance_weber: 0.15,
        distance_range_m: 30.0,
        reach_m: 0.9,
        terminal_s: 0.5,
        lunge_m: 0.6,
    };

    /// Gives a trial this observer's senses, reach and finish.
    pub fn apply(&self, trial: &mut TrialConfig) {
        let perception = &mut trial.fielder.perception;
        perception.delay_s = self.delay_s;
        perception.noise_rad = self.noise_deg.to_radians();
        perception.smoothing_s = self.smoothing_s;
        perception.rate_weber = self.rate_weber;
        perception.direction_rad = self.direction_deg.to_radians();
        perception.distance_weber = self.distance_weber;
        perception.distance_range_m = self.distance_range_m;
        trial.fielder.terminal_s = self.terminal_s;
        trial.zone.reach_m = self.reach_m;
        trial.zone.lunge_m = self.lunge_m;
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
    /// One line a reader can check the settings by: `human: delay 0.2 s, image speed
    /// ±10 % and direction ±2°, distance ±15 % within 30 m, angles ±0°, smoothing 0.1 s,
    /// reach 0.9 m, finishing 0.5 s with a 0.6 m lunge`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let range = if self.distance_range_m.is_finite() {
            format!("within {} m", self.distance_range_m)
        } else {
            "at any range".to_string()
        };
        write!(
            f,
            "{}: delay {} s, image speed ±{} % and direction ±{}°, distance ±{} % {range}, angles ±{}°, smoothing {} s, reach {} m, ",
            self.name,
            self.delay_s,
            100.0 * self.rate_weber,
            self.direction_deg,
            100.0 * self.distance_weber,
            self.noise_deg,
            self.smoothing_s,
            self.reach_m
        )?;
        if self.terminal_s > 0.0 {
            write!(
                f,
                "finishing {} s with a {} m lunge",
                self.terminal_s, self.lunge_m
            )
        } else {
            f.write_str("no finishing phase")
        }
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
        let p = trial.fielder.perception;
        assert_eq!((p.delay_s, p.noise_rad, p.smoothing_s), (0.2, 0.0, 0.1));
        assert_eq!(
            (p.rate_weber, p.distance_weber, p.distance_range_m),
            (0.1, 0.15, 30.0)
        );
        assert_eq!(trial.fielder.terminal_s, 0.5);
        assert_eq!((trial.zone.reach_m, trial.zone.lunge_m), (0.9, 0.6));
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
