//! Basketball in a live match: the core's [`Game`] with a line-up from the scenario.

use super::scenario::{Scenario, ScenarioError};
use crate::basketball::event::Snapshot;
use crate::basketball::{
    Brain, Capabilities, DefenderMotion, Event, Game, GameParams, Order, Team,
};
use crate::names::UnknownName;
use crate::protocol::{hoops, Agent, AgentInfo, Ball, Event as AnyEvent, Field, Score, Sensed};
use crate::tags;
use std::str::FromStr;
use std::sync::Arc;

/// A basketball match: the core's game, and when it ends.
pub(crate) struct HoopsWorld {
    pub(crate) game: Game,
    /// Possessions to play; none: for ever.
    pub(crate) possessions: Option<u64>,
}

/// Reads agent `i`'s strategy as its team's choice of `T`: every agent of a team that
/// names one must name the same (`clash` says what else agent j chose).
fn team_choice<T: FromStr<Err = UnknownName> + PartialEq + Copy>(
    i: usize,
    name: Option<&str>,
    chosen: &mut Option<(usize, T)>,
    clash: impl Fn(usize, T) -> String,
) -> Result<(), ScenarioError> {
    let Some(name) = name else { return Ok(()) };
    let path = format!("agents[{i}].strategy");
    let choice: T = name
        .parse()
        .map_err(|e: UnknownName| ScenarioError::at(path.clone(), e.to_string()))?;
    if let Some((j, other)) = chosen.filter(|(_, c)| *c != choice) {
        return Err(ScenarioError::at(path, clash(j, other)));
    }
    *chosen = Some((i, choice));
    Ok(())
}

impl HoopsWorld {
    pub(crate) fn new(s: &Scenario, caps: Arc<Capabilities>) -> Result<HoopsWorld, ScenarioError> {
        let mut params = GameParams {
            tick_hz: s.tick_hz,
            seed: s.seed,
            ..GameParams::default()
        };
        if let Some(clock) = s.options.shot_clock_s {
            if !(clock.is_finite() && (1.0..=600.0).contains(&clock)) {
                return Err(ScenarioError::at(
                    "options.shot_clock_s",
                    "between 1 and 600 s",
                ));
            }
            params.shot_clock_s = clock;
        }
        if s.options.possessions == Some(0) {
            return Err(ScenarioError::at("options.possessions", "at least 1"));
        }
        let (mut offense, mut defense) = (Vec::new(), Vec::new());
        let mut offense_brain: Option<(usize, Brain)> = None;
        let mut defender_motion: Option<(usize, DefenderMotion)> = None;
        if s.agents.is_empty() {
            offense = vec![("o1".to_string(), None), ("o2".to_string(), None)];
            defense = vec![("d1".to_string(), None)];
        }
        for (i, a) in s.agents.iter().enumerate() {
            if a.limits.is_some() {
                return Err(ScenarioError::at(
                    format!("agents[{i}].limits"),
                    "basketball players move with motion capture; limits are for fielders",
                ));
            }
            if let Some([x, z]) = a.position {
                let p = glam::DVec2::new(x, z);
                if !(p.is_finite() && params.court.contains(p)) {
                    return Err(ScenarioError::at(
                        format!("agents[{i}].position"),
                        "must be on the court: x 0 to 14 m, z -7.5 to 7.5 m",
                    ));
                }
            }
            let strategy = a.strategy.as_deref();
            match a.team.as_deref() {
                Some("offense") => {
                    team_choice(i, strategy, &mut offense_brain, |j, other: Brain| {
                        format!("a team has one brain; agents[{j}] uses {}", other.name())
                    })?;
                    offense.push((a.id.clone(), a.position));
                }
                Some("defense") => {
                    team_choice(i, strategy, &mut defender_motion, |j, _: DefenderMotion| {
                        format!("defenders move alike; agents[{j}] differs")
                    })?;
                    defense.push((a.id.clone(), a.position));
                }
                Some(other) => {
                    return Err(ScenarioError::at(
                        format!("agents[{i}].team"),
                        format!("unknown team \"{other}\"; expected one of offense, defense"),
                    ))
                }
                None => {
                    return Err(ScenarioError::at(
                        format!("agents[{i}].team"),
                        "a basketball agent needs a team: offense or defense",
                    ))
                }
            }
        }
        if offense.is_empty() {
            return Err(ScenarioError::at(
                "agents",
                "basketball needs at least one offensive player",
            ));
        }
        if let Some((_, brain)) = offense_brain {
            params.offense = brain;
        }
        if let Some((_, motion)) = defender_motion {
            params.defender.motion = motion;
        }
        params.offense_players = offense.len();
        params.defenders = defense.len();
        let (names, starts): (Vec<String>, Vec<Option<[f64; 2]>>) =
            offense.into_iter().chain(defense).unzip();
        // Bots' agents play their built-in brains until a bot connects.
        let game = Game::named(caps, params, names).with_starts(
            starts
                .into_iter()
                .map(|p| p.map(glam::DVec2::from_array))
                .collect(),
        );
        Ok(HoopsWorld {
            game,
            possessions: s.options.possessions,
        })
    }

    pub(crate) fn step(&mut self, events: &mut Vec<AnyEvent>) {
        let mut happened: Vec<Event> = Vec::new();
        self.game.step(&mut happened);
        events.extend(happened.into_iter().map(AnyEvent::Hoops));
    }

    pub(crate) fn finished(&self) -> bool {
        self.possessions
            .is_some_and(|n| self.game.possessions() >= n)
    }

    pub(crate) fn field(&self) -> Field {
        let p = self.game.params();
        Field::Basketball(hoops::Field {
            court: (&p.court).into(),
            decision: (&p.decision).into(),
            defender_motion: p.defender.motion.name(),
            kind: tags::Basketball,
            offense: p.offense.name(),
            shot_clock_s: p.shot_clock_s,
        })
    }

    pub(crate) fn agents_info(&self) -> Vec<AgentInfo> {
        let p = self.game.params();
        self.game
            .agents()
            .iter()
            .map(|a| {
                AgentInfo::Player(hoops::PlayerInfo {
                    id: a.id.clone(),
                    strategy: match a.team {
                        Team::Offense => p.offense.name(),
                        Team::Defense => p.defender.motion.name(),
                    },
                    team: a.team,
                })
            })
            .collect()
    }

    pub(crate) fn score(&self) -> hoops::Score {
        score_of(&self.game.snapshot())
    }

    pub(crate) fn state(&self) -> (Ball<'_>, Vec<Agent<'_>>, Score) {
        let snap = self.game.snapshot();
        let score = score_of(&snap);
        (
            Ball::Hoops(snap.ball),
            snap.agents.into_iter().map(Agent::Player).collect(),
            Score::Hoops(score),
        )
    }

    /// What agent `k` perceives: the court as a player sees it (everyone's position and
    /// heading, the ball, the clock).
    pub(crate) fn perception(&self, k: usize) -> Sensed<'_> {
        let snap = self.game.snapshot();
        let me = &snap.agents[k];
        Sensed::Player(hoops::Sensed {
            agents: snap.agents.iter().map(hoops::Seen::from).collect(),
            ball: snap.ball.clone(),
            basket: self.game.params().court.basket.to_array(),
            has_ball: self.game.holder() == Some(k),
            me: me.id,
            shot_clock_s: snap.shot_clock_s,
            team: me.team,
        })
    }

    pub(crate) fn order(&mut self, k: usize, order: Order) -> Result<(), String> {
        self.game.order(k, order)
    }
}

/// The score a snapshot shows.
fn score_of(snap: &Snapshot<'_>) -> hoops::Score {
    hoops::Score {
        points: snap.score,
        possession: snap.possession,
        shot_clock_s: snap.shot_clock_s,
    }
}
