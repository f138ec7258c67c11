//! Oracles for the basketball domain: the decision rule against isotropic maps whose
//! times are known in closed form, and games that must end, repeat, and keep their
//! positions finite.

use super::*;
use crate::costmap::{AgentPose, BuildParams, CostMap, Grid, Method};
use crate::motion::fixtures;
use glam::DVec2;

/// A mover whose map is the grassfire distance at the graph's top speed: the time to a
/// point is (8-connected) distance ÷ speed, whatever the heading.
fn isotropic() -> Mover {
    let graph = fixtures::graph();
    let map = CostMap::build(
        &graph,
        &BuildParams {
            method: Method::Grassfire,
            grid: Grid::new(20.0, 0.5),
            depth: 240,
            ..BuildParams::default()
        },
        &mut |_| {},
    );
    Mover::new("run", graph, map)
}

fn pose(x: f64, z: f64, heading_deg: f64) -> AgentPose {
    AgentPose {
        position: DVec2::new(x, z),
        heading: heading_deg.to_radians(),
    }
}

fn decide(mover: &Mover, shooter: AgentPose, defender: AgentPose) -> Decision {
    let defenders = [(defender, mover)];
    Situation {
        court: &Court::default(),
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter,
        dribble: mover,
        defenders: &defenders,
    }
    .decide()
}

#[test]
fn the_chosen_square_satisfies_the_rule_and_none_better_does() {
    let mover = isotropic();
    let params = DecisionParams::default();
    for (shooter, defender) in [
        (pose(9.0, 2.0, 180.0), pose(4.0, 0.0, 0.0)),
        (pose(6.0, -4.0, 150.0), pose(3.0, 3.0, -30.0)),
        (pose(12.0, 6.0, 200.0), pose(2.0, -6.0, 20.0)),
    ] {
        let d = decide(&mover, shooter, defender);
        let chosen = d.chosen.expect("some square is safe");
        assert!(chosen.c_o > chosen.c_d + chosen.t_s + chosen.epsilon);
        for c in d.candidates.iter().filter(|c| c.qualifies(&params)) {
            assert!(c.success <= chosen.success, "{c:?} beats {chosen:?}");
        }
    }
}

/// With isotropic maps C_o and C_d are distances over the speed, so the qualifying set
/// is an Apollonius region; the rule may disagree with it only where the margin is
/// within the maps' discretisation (a cell's diagonal at each end).
#[test]
fn qualifying_squares_are_those_the_defender_reaches_late_by_the_margin() {
    let mover = isotropic();
    let params = DecisionParams::default();
    let speed = mover.map.top_speed_m_s;
    let shooter = pose(10.0, -3.0, 180.0);
    let defender = pose(5.0, 2.0, 0.0);
    let d = decide(&mover, shooter, defender);
    // Octile distance overestimates the Euclidean by up to 8 %, and each map adds up to a
    // cell's diagonal.
    let slack = 2.0 * 0.5 * std::f64::consts::SQRT_2 / speed;
    let mut checked = 0;
    for c in &d.candidates {
        let at = DVec2::from_array(c.cell);
        let margin = at.distance(defender.position) / speed
            - at.distance(shooter.position) / speed
            - params.shot_time_s
            - params.epsilon_s;
        let tolerance = slack + 0.08 * (c.c_o + c.c_d);
        if margin.abs() > tolerance {
            assert_eq!(c.qualifies(&params), margin > 0.0, "{c:?}, margin {margin}");
            checked += 1;
        }
    }
    assert!(checked > 200, "only {checked} squares were clear-cut");
}

#[test]
fn a_defender_on_the_chosen_square_moves_the_shot_elsewhere_or_away() {
    let mover = isotropic();
    let shooter = pose(8.0, 0.0, 180.0);
    let first = decide(&mover, shooter, pose(13.0, 7.0, 180.0))
        .chosen
        .expect("an undefended shooter has a shot");
    let blocker = pose(first.cell[0], first.cell[1], 0.0);
    let second = decide(&mover, shooter, blocker);
    // No safe square at all is also an answer: the plan falls back to a pass or a
    // maneuver.
    if let Some(c) = second.chosen {
        assert_ne!(c.cell, first.cell);
        // The defender now needs more than the shot and the margin to get there.
        let away = DVec2::from_array(c.cell).distance(blocker.position);
        assert!(away / mover.map.top_speed_m_s > c.t_s + c.epsilon - 0.2);
    }
}

#[test]
fn a_shooter_with_no_defender_takes_the_best_shot_it_can_reach() {
    let mover = isotropic();
    let d = Situation {
        court: &Court::default(),
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter: pose(9.0, 0.0, 180.0),
        dribble: &mover,
        defenders: &[],
    }
    .decide();
    let chosen = d.chosen.unwrap();
    assert_eq!(chosen.success, ShotModel::default().cap);
    // Of the capped squares, the closest to the shooter.
    let nearest_capped = d
        .candidates
        .iter()
        .filter(|c| c.success == chosen.success)
        .map(|c| c.c_d)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(chosen.c_d, nearest_capped);
}

fn play(params: GameParams, possessions: u64) -> (Vec<Event>, Vec<Snapshot>) {
    let mut game = Game::new(fixtures::cmu_capabilities(), params);
    let (mut events, mut snapshots) = (Vec::new(), Vec::new());
    while game.possessions() < possessions {
        game.step(&mut events);
        if game.snapshot().tick.is_multiple_of(15) {
            snapshots.push(game.snapshot());
        }
    }
    (events, snapshots)
}

#[test]
fn every_possession_ends_in_a_shot_a_turnover_or_the_shot_clock() {
    for offense in [Brain::Simple, Brain::Costmap] {
        let params = GameParams {
            offense,
            seed: 7,
            ..GameParams::default()
        };
        let (events, snapshots) = play(params, 25);
        let mut shot_pending = false;
        let mut ended = 0;
        for e in &events {
            match e {
                Event::Shot { made, blocked, .. } => {
                    assert!(!(made & blocked));
                    shot_pending = true;
                }
                Event::PossessionEnded {
                    outcome,
                    duration_s,
                    points,
                    ..
                } => {
                    ended += 1;
                    assert!(*duration_s > 0.0 && *duration_s <= params.shot_clock_s + 1e-9);
                    let by_shot =
                        matches!(outcome, Outcome::Made | Outcome::Missed | Outcome::Blocked);
                    assert_eq!(by_shot, shot_pending, "{outcome:?}");
                    assert_eq!(*points > 0, *outcome == Outcome::Made);
                    shot_pending = false;
                }
                // The chosen square satisfied the rule, so the bitmap of safe squares
                // (cut to their box) holds it.
                Event::Decision { chosen, safe, .. } => {
                    let court = &params.court;
                    match (chosen, safe) {
                        (Some(c), Some(safe)) => {
                            let square = court.square_of(DVec2::from_array(c.cell)).unwrap();
                            assert!(safe.squares(court).contains(&square), "{c:?} {safe:?}");
                        }
                        (None, None) => {}
                        other => panic!("a chosen square comes with its safe squares: {other:?}"),
                    }
                }
                _ => {}
            }
        }
        assert_eq!(ended, 25);
        for s in &snapshots {
            assert_eq!(s.agents.len(), 3, "two on offense, one defender by default");
            for a in &s.agents {
                assert!(a.position.iter().all(|v| v.is_finite()) && a.heading.is_finite());
            }
            assert!(s.ball.position.iter().all(|v| v.is_finite()));
        }
    }
}

#[test]
fn seeded_games_repeat_exactly_and_offenses_share_their_starts() {
    let params = GameParams {
        seed: 11,
        ..GameParams::default()
    };
    let (a, sa) = play(params, 6);
    let (b, sb) = play(params, 6);
    assert_eq!(a, b);
    assert_eq!(sa, sb);
    let starts = |offense| {
        let game = Game::new(
            fixtures::cmu_capabilities(),
            GameParams { offense, ..params },
        );
        game.snapshot().agents
    };
    assert_eq!(starts(Brain::Simple), starts(Brain::Costmap));
}

#[test]
fn teams_of_any_size_play() {
    let params = GameParams {
        offense_players: 3,
        defenders: 2,
        ..GameParams::default()
    };
    let (events, snapshots) = play(params, 5);
    assert!(snapshots.iter().all(|s| s.agents.len() == 5));
    assert_eq!(
        events
            .iter()
            .filter(|e| matches!(e, Event::PossessionEnded { .. }))
            .count(),
        5
    );
}

#[test]
fn moves_play_the_maps_stored_paths_at_the_data_rate() {
    let caps = fixtures::cmu_capabilities();
    let mover = &caps.run;
    let start = pose(3.0, -2.0, 90.0);
    let target = DVec2::new(3.0 + 0.0, -2.0 + 4.0); // 4 m straight ahead (heading +z)
    let cell = mover
        .reachable_cell(&start, target)
        .expect("4 m ahead is reachable");
    let strides = mover.strides_to(&start, cell);
    // One stride per frame of the stored path, and the path's end is in the cell.
    assert_eq!(strides.len() as u32, mover.map.costs[cell].unwrap() + 1);
    let end = strides.last().unwrap().at.position;
    assert_eq!(mover.map.grid.cell_of(start.to_local(end)), Some(cell));
}

#[test]
fn a_move_toward_a_goal_beyond_the_map_sets_off_and_stays_on_the_court() {
    let caps = fixtures::cmu_capabilities();
    let court = Court::default();
    for mover in [&caps.run, &caps.dribble, &caps.defense] {
        // From the middle of the court toward a goal far beyond the map: the cell it
        // stands in (no frames, the whole way at top speed) must not win.
        let at = pose(7.0, 0.0, 180.0);
        let goal = DVec2::new(-40.0, 0.0);
        let cell = mover
            .cell_toward(&at, goal, &court, 0.0)
            .expect("some move gets nearer");
        let end = mover.strides_to(&at, cell).last().unwrap().at.position;
        assert!(
            end.distance(goal) < at.position.distance(goal) - 0.25,
            "{}: ends at {end}",
            mover.behaviour
        );
        assert!(mover
            .strides_to(&at, cell)
            .iter()
            .all(|s| court.contains(s.at.position)));
    }
}

#[test]
fn a_path_is_on_the_court_exactly_when_every_frame_is() {
    // The shortcut (a start far enough inside) must agree with walking the path, from
    // poses near every line and in the middle, facing every way.
    let caps = fixtures::cmu_capabilities();
    let court = Court::default();
    let mover = &caps.run;
    let mut checked = 0;
    for (x, z) in [(0.5, 0.0), (13.5, 3.0), (7.0, 7.0), (7.0, -6.5), (7.0, 0.0)] {
        for heading in (0..360).step_by(45) {
            let at = pose(x, z, f64::from(heading));
            for cell in (0..mover.map.costs.len()).step_by(7) {
                if mover.map.costs[cell].is_none() {
                    continue;
                }
                for margin in [0.0, 1.0] {
                    let walked = mover
                        .strides_to(&at, cell)
                        .iter()
                        .all(|s| court.inside_by(s.at.position) >= -margin);
                    assert_eq!(
                        mover.path_on_court(&at.frame(), cell, &court, margin),
                        walked,
                        "cell {cell} from {at:?}, margin {margin}"
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000);
}
