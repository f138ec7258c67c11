//! Oracles for the basketball domain: the decision rule against isotropic maps whose
//! times are known in closed form, and games that must end, repeat, and keep their
//! positions finite.

use super::event::Snapshot;
use super::parametric::Isotropic;
use super::*;
use crate::costmap::{AgentPose, BuildParams, CostMap, Grid, Method};
use crate::fixtures;
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
    let state = crate::costmap::StartState {
        name: "standing".into(),
        node: map.start_node,
    };
    Mover::new("run", graph, vec![(state, map)])
}

fn pose(x: f64, z: f64, heading_deg: f64) -> AgentPose {
    AgentPose {
        position: DVec2::new(x, z),
        heading: heading_deg.to_radians(),
    }
}

fn decide(mover: &Mover, shooter: AgentPose, defender: AgentPose) -> Decision {
    let defenders = [Opponent::Map(mover.reach(&defender, Motion::Still))];
    Situation {
        court: &Court::default(),
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter: mover.reach(&shooter, Motion::Still),
        defenders: &defenders,
        shot_clock_s: 24.0,
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
    let speed = mover.top_speed_m_s();
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
        assert!(away / mover.top_speed_m_s() > c.t_s + c.epsilon - 0.2);
    }
}

#[test]
fn a_shooter_with_no_defender_takes_the_best_shot_it_can_reach() {
    let mover = isotropic();
    let d = Situation {
        court: &Court::default(),
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter: mover.reach(&pose(9.0, 0.0, 180.0), Motion::Still),
        defenders: &[],
        shot_clock_s: 24.0,
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

#[test]
fn an_isotropic_model_gives_every_square_the_formulas_time_and_no_model_the_best_shot() {
    let mover = isotropic();
    let court = Court::default();
    let shooter = mover.reach(&pose(9.0, 0.0, 180.0), Motion::Still);
    let at = DVec2::new(4.0, 1.0);
    let (reaction_s, speed_m_s) = (0.3, 7.0);
    let defenders = [Opponent::Isotropic {
        at,
        model: Isotropic {
            reaction_s,
            speed_m_s,
        },
    }];
    let modelled = Situation {
        court: &court,
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter: mover.reach(&pose(9.0, 0.0, 180.0), Motion::Still),
        defenders: &defenders,
        shot_clock_s: 24.0,
    }
    .decide();
    for c in &modelled.candidates {
        let formula = reaction_s + DVec2::from_array(c.cell).distance(at) / speed_m_s;
        assert!((c.c_o - formula).abs() < 1e-9, "{c:?}");
    }
    // No model: every square the shooter reaches is safe, and the chosen one has the best
    // shot of them all.
    let unmodelled = Situation {
        court: &court,
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter,
        defenders: &[Opponent::Ignored],
        shot_clock_s: 24.0,
    }
    .decide();
    let best = unmodelled
        .candidates
        .iter()
        .map(|c| c.success)
        .fold(0.0, f64::max);
    assert_eq!(unmodelled.chosen.unwrap().success, best);
    assert!(unmodelled
        .candidates
        .iter()
        .all(|c| c.qualifies(&DecisionParams::default())));
}

/// What a test keeps of a snapshot (which borrows its game): every agent's pose, node
/// and action, and where the ball is.
#[derive(Debug, Clone, PartialEq)]
struct Seen {
    agents: Vec<([f64; 2], f64, Option<u32>, Action)>,
    ball: [f64; 3],
}

impl Seen {
    fn of(snapshot: &Snapshot<'_>) -> Seen {
        Seen {
            agents: snapshot
                .agents
                .iter()
                .map(|a| (a.position, a.heading, a.node, a.action))
                .collect(),
            ball: snapshot.ball.position,
        }
    }
}

fn play(params: GameParams, possessions: u64) -> (Vec<Event>, Vec<Seen>) {
    let mut game = Game::new(fixtures::cmu_capabilities(), params);
    let (mut events, mut snapshots) = (Vec::new(), Vec::new());
    while game.possessions() < possessions {
        game.step(&mut events);
        let snapshot = game.snapshot();
        if snapshot.tick.is_multiple_of(15) {
            snapshots.push(Seen::of(&snapshot));
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
                Event::Shot(Shot { made, blocked, .. }) => {
                    assert!(!(made & blocked));
                    shot_pending = true;
                }
                Event::PossessionEnded(PossessionEnded {
                    outcome,
                    duration_s,
                    points,
                    ..
                }) => {
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
                Event::Decision(Decided { chosen, safe, .. }) => {
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
            for (position, heading, ..) in &s.agents {
                assert!(position.iter().all(|v| v.is_finite()) && heading.is_finite());
            }
            assert!(s.ball.iter().all(|v| v.is_finite()));
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
        Seen::of(&game.snapshot()).agents
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
            .filter(|e| matches!(e, Event::PossessionEnded(_)))
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
    let reach = mover.reach(&start, Motion::Still);
    let cell = reach.cell(target).expect("4 m ahead is reachable");
    let strides = reach.strides(cell);
    // A standing agent sets off in the stance or its mirror image, whichever is quicker.
    let stances: Vec<&CostMap> = mover
        .states
        .iter()
        .filter(|s| s.state.name == "standing" || s.state.name == crate::costmap::STANDING_MIRRORED)
        .map(|s| &s.map)
        .collect();
    assert_eq!(stances.len(), 2, "a mirrored capture has both stances");
    let (frames, map) = stances
        .iter()
        .filter_map(|m| m.costs[cell].map(|f| (f, *m)))
        .min_by_key(|(f, _)| *f)
        .unwrap();
    // One stride per frame of the stored path, from the stance it starts from, and the
    // path's end is in the cell.
    assert_eq!(strides.len() as u32, frames + 1);
    assert_eq!(strides[0].node, map.start_node);
    let end = strides.last().unwrap().at.position;
    assert_eq!(map.grid.cell_of(start.to_local(end)), Some(cell));
    assert!((reach.seconds(target).unwrap() - f64::from(frames) / map.fps).abs() < 1e-12);
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
        let reach = mover.reach(&at, Motion::Still);
        let cell = reach
            .toward(goal, &court, 0.0)
            .expect("some move gets nearer");
        let end = reach.strides(cell).last().unwrap().at.position;
        assert!(
            end.distance(goal) < at.position.distance(goal) - 0.25,
            "{}: ends at {end}",
            mover.behaviour
        );
        assert!(reach
            .strides(cell)
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
            // From a node mid-clip, so the move has a lead before its stored path.
            let node = (x * 37.0 + f64::from(heading)) as u32 % mover.graph.node_count() as u32;
            let reach = mover.reach(&at, Motion::Node(node));
            let costs = &mover
                .states
                .iter()
                .find(|s| s.state.name == reach.state())
                .unwrap()
                .map
                .costs;
            for cell in (0..costs.len()).step_by(7) {
                if costs[cell].is_none() {
                    continue;
                }
                for margin in [0.0, 1.0] {
                    let walked = reach
                        .strides(cell)
                        .iter()
                        .all(|s| court.inside_by(s.at.position) >= -margin);
                    assert_eq!(
                        reach.on_court(cell, &court, margin),
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

/// Over a long game every agent's body plays one continuous walk on its graph: between
/// two ticks its node either stays, or moves along edges of the graph (never jumps to
/// an unconnected frame, so no joint jumps more than across the roughest kept cut), and
/// its root never moves faster than the graph's largest frame step allows. A change of
/// behaviour (a catch, a pass) changes graph, and is exempt.
#[test]
fn moves_play_one_continuous_walk_on_the_graph() {
    let caps = fixtures::cmu_capabilities();
    let params = GameParams {
        seed: 3,
        ..GameParams::default()
    };
    let mut game = Game::new(caps.clone(), params);
    let mut events = Vec::new();
    let fps = caps.run.map().fps;
    let mut last: Vec<(Option<u32>, Option<&'static str>, DVec2)> = game
        .agents()
        .iter()
        .map(|a| (a.node, a.playing, a.pose.position))
        .collect();
    let mut checked = 0;
    for _ in 0..60 * 120 {
        game.step(&mut events);
        let data_frames = fps / game.params().tick_hz;
        for (k, a) in game.agents().iter().enumerate() {
            let (node, playing, position) = last[k];
            last[k] = (a.node, a.playing, a.pose.position);
            let (Some(from), Some(to), Some(b)) = (node, a.node, a.playing) else {
                continue;
            };
            if playing != Some(b) || from == to {
                continue;
            }
            let mover = caps.by_behaviour(b).unwrap();
            let g = &mover.graph;
            let largest_step = g.edges.iter().map(|e| e.step.length()).fold(0.0, f64::max);
            // A tick plays at most a couple of data frames; allow edges chained that far.
            let hops = data_frames.ceil() as usize + 1;
            let mut frontier = vec![from];
            let mut reached = false;
            for _ in 0..hops {
                frontier = frontier
                    .iter()
                    .flat_map(|&n| g.out_edges(n).map(|i| g.edges[i].to))
                    .collect();
                if frontier.contains(&to) {
                    reached = true;
                    break;
                }
            }
            assert!(reached, "{} jumped from node {from} to {to} of {b}", a.id);
            let moved = a.pose.position.distance(position);
            assert!(
                moved <= largest_step * data_frames.ceil() * 1.5 + 1e-9,
                "{} moved {moved} m in a tick (largest frame step {largest_step} m)",
                a.id
            );
            checked += 1;
        }
    }
    assert!(checked > 1000, "only {checked} steps checked");
}

/// Standing still, a body gets to a point directly behind it no later than it can
/// while already moving forward: a moving body must first undo its momentum. The CMU
/// dribbling shows it (it has backward dribbling and turns from standing). Running and
/// footwork do not, and this test does not pretend they do: no running clip starts from
/// standing (the only standing frames end 16_57's sudden stop, and leaving them takes a
/// cut back into a run), and the slowest footwork frame still moves at 0.8 m/s; see the
/// capability table in docs/motion.md.
#[test]
fn standing_is_never_worse_than_moving_for_a_cell_behind_when_dribbling() {
    let caps = fixtures::cmu_capabilities();
    let mover = &caps.dribble;
    let standing = &mover.states[0];
    assert_eq!(standing.state.name, "standing");
    for moving in &mover.states[1..] {
        if !moving.state.name.contains("forward") {
            continue;
        }
        for d in [3.0, 5.0] {
            let behind = DVec2::new(-d - 0.01, 0.01);
            let (s, m) = (standing.map.cost(behind), moving.map.cost(behind));
            assert!(
                s.is_some() && m.is_none_or(|m| s.unwrap() <= m),
                "{d} m behind: standing {s:?}, {} {m:?}",
                moving.state.name
            );
        }
    }
}

/// A 2-on-1 game with its players at `starts` (offense first), after a first tick of
/// their own play, handed to bots and told to stand: whatever comes next is the test's
/// order.
fn standing_still(
    caps: &std::sync::Arc<Capabilities>,
    params: GameParams,
    starts: [(f64, f64); 3],
) -> (Game, Vec<Event>) {
    let mut game = Game::new(caps.clone(), params).with_starts(
        starts
            .iter()
            .map(|&(x, z)| Some(DVec2::new(x, z)))
            .collect(),
    );
    let mut events = Vec::new();
    // Bots take every agent before the first decision: a brain might shoot at once.
    for k in 0..starts.len() {
        game.set_controlled(k, true);
        game.order(k, Order::Stand).unwrap();
    }
    game.step(&mut events);
    game.step(&mut events);
    (game, events)
}

/// A defender ordered to a point 3 m behind itself gets there within the time its own
/// map gives for that point (from the node it is playing), plus a tick: the game plays
/// the map's stored path, so the map's time is the game's. This is the time the shooter's
/// `own` model of the defender counts on.
#[test]
fn a_defender_reaches_a_point_behind_it_within_the_time_its_own_map_says() {
    let caps = fixtures::cmu_capabilities();
    for motion in [DefenderMotion::Defense, DefenderMotion::Run] {
        let mut params = GameParams {
            seed: 5,
            ..GameParams::default()
        };
        params.defender.motion = motion;
        // The defender mid-court, facing the offense far from it: its first steps
        // forward and the turn stay on the court.
        let (mut game, mut events) =
            standing_still(&caps, params, [(12.0, 4.0), (12.0, -4.0), (6.0, 0.0)]);
        let start = game.agents()[2].pose;
        let goal = start.position - 3.0 * DVec2::from_angle(start.heading);
        let mover = caps.defender(motion);
        let reach = mover.reach(&start, game.motion_of(2, mover));
        let promised = reach.seconds(goal).expect("3 m behind is within the map");
        let cell = reach.cell(goal).expect("3 m behind is within the map");
        assert!(
            reach.on_court(cell, &params.court, 0.0),
            "{motion:?}: the way there stays on the court"
        );
        game.order(2, Order::MoveTo(goal)).unwrap();
        let t0 = game.time_s();
        let tick = 1.0 / params.tick_hz;
        // Within half a cell's diagonal of the goal's cell centre: where the map aims.
        let centre = mover.map().grid.cell_m * std::f64::consts::FRAC_1_SQRT_2;
        while game.agents()[2].pose.position.distance(goal) > 2.0 * centre {
            game.step(&mut events);
            assert!(
                game.time_s() - t0 <= promised + 2.0 * tick + 1e-9,
                "{motion:?}: {:.2} m short {:.2} s after the order; the map says {promised:.2} s",
                game.agents()[2].pose.position.distance(goal),
                game.time_s() - t0
            );
        }
    }
}

/// A bot's `move_to` stays in force until the agent gets there: when the map's way to
/// the target leaves the court (a defender near the half-court line facing it must
/// turn), the agent takes the best way nearer, then heads on from where it got to.
#[test]
fn a_move_to_keeps_going_until_the_agent_gets_there() {
    let caps = fixtures::cmu_capabilities();
    let params = GameParams {
        seed: 5,
        ..GameParams::default()
    };
    // A defender facing the half-court line, the target 3 m behind it: the first place,
    // nearing the line, where the map's way straight there leaves the court (that
    // depends on the capture, so the test looks for it rather than assume it).
    let (mut game, mut events, goal) = [12.0, 13.0, 13.3, 13.6, 13.8]
        .into_iter()
        .find_map(|x| {
            let (game, events) =
                standing_still(&caps, params, [(13.9, 0.95), (2.0, -7.0), (x, 0.0)]);
            let start = game.agents()[2].pose;
            let goal = start.position - 3.0 * DVec2::from_angle(start.heading);
            let mover = caps.defender(params.defender.motion);
            let reach = mover.reach(&start, game.motion_of(2, mover));
            let cell = reach.cell(goal).expect("3 m behind is within the map");
            (params.court.contains(goal) && !reach.on_court(cell, &params.court, 0.0))
                .then_some((game, events, goal))
        })
        .expect("some defender's way straight to a point behind it leaves the court");
    game.order(2, Order::MoveTo(goal)).unwrap();
    let t0 = game.time_s();
    while game.agents()[2].pose.position.distance(goal) > 0.75 {
        game.step(&mut events);
        assert!(
            game.time_s() - t0 < 10.0,
            "still {:.2} m from the target after 10 s",
            game.agents()[2].pose.position.distance(goal)
        );
    }
}

/// Behind the backboard's plane no shot goes in: the rule never chooses a square there,
/// however near the ring and however safe, and over a long game no shot is taken from
/// there (nor from off the court).
#[test]
fn no_square_behind_the_backboard_is_chosen_and_no_shot_is_taken_from_there() {
    let mover = isotropic();
    let court = Court::default();
    // A shooter near the baseline beside the basket, nobody defending: the squares
    // behind the board are the nearest to the ring it can reach.
    let d = Situation {
        court: &court,
        shot: &ShotModel::default(),
        params: &DecisionParams::default(),
        shooter: mover.reach(&pose(0.75, 1.25, 90.0), Motion::Still),
        defenders: &[],
        shot_clock_s: 24.0,
    }
    .decide();
    let behind: Vec<_> = d
        .candidates
        .iter()
        .filter(|c| c.cell[0] < court.backboard_m)
        .collect();
    assert!(!behind.is_empty() && behind.iter().all(|c| c.success == 0.0));
    assert!(d.chosen.unwrap().cell[0] > court.backboard_m);

    let caps = fixtures::cmu_capabilities();
    for shot_model in [DefenderModel::Own, DefenderModel::None] {
        let params = GameParams {
            shot_model,
            seed: 3,
            ..GameParams::default()
        };
        let mut game = Game::new(caps.clone(), params);
        let mut events = Vec::new();
        let mut shots = 0;
        while game.possessions() < 150 {
            events.clear();
            game.step(&mut events);
            for e in &events {
                if let Event::Shot(Shot { from, success, .. }) = e {
                    shots += 1;
                    let at = DVec2::from_array(*from);
                    assert!(court.contains(at), "a shot from off the court: {at}");
                    assert!(
                        at.x >= court.backboard_m || *success == 0.0,
                        "a shot from behind the backboard at {at} had {success}"
                    );
                }
                if let Event::Decision(Decided {
                    chosen: Some(c), ..
                }) = e
                {
                    assert!(c.cell[0] > court.backboard_m, "{c:?}");
                }
            }
        }
        assert!(shots > 100);
    }
}

/// A square the shooter can reach but not shoot from before the shot clock runs out is
/// not considered: with 2 s left, no candidate needs more than 2 s − T_s to reach.
#[test]
fn no_square_takes_longer_than_the_shot_clock_allows() {
    let mover = isotropic();
    let params = DecisionParams::default();
    for clock in [24.0, 2.0, 1.0] {
        let d = Situation {
            court: &Court::default(),
            shot: &ShotModel::default(),
            params: &params,
            shooter: mover.reach(&pose(9.0, 0.0, 180.0), Motion::Still),
            defenders: &[],
            shot_clock_s: clock,
        }
        .decide();
        assert!(!d.candidates.is_empty());
        for c in &d.candidates {
            assert!(c.c_d + params.shot_time_s <= clock, "{clock} s: {c:?}");
        }
        let farthest = d.candidates.iter().map(|c| c.c_d).fold(0.0, f64::max);
        if clock == 24.0 {
            assert!(farthest > 2.0, "the test needs far squares: {farthest}");
        }
    }
}

/// Where the defender's map does not reach a square, C_o is its horizon and the square
/// says so: counted as the horizon it may be safe; counted unsafe, it never is.
#[test]
fn a_square_beyond_the_defenders_horizon_is_marked_and_follows_the_policy() {
    let mover = isotropic();
    let horizon = mover.horizon_s();
    // The defender 9 m from the half-court corner: squares more than 10 m from it are
    // outside its map.
    let defenders = [Opponent::Map(
        mover.reach(&pose(3.0, -6.0, 0.0), Motion::Still),
    )];
    let decide = |policy| {
        Situation {
            court: &Court::default(),
            shot: &ShotModel::default(),
            params: &DecisionParams {
                beyond_horizon: policy,
                ..DecisionParams::default()
            },
            shooter: mover.reach(&pose(13.0, 6.5, 180.0), Motion::Still),
            defenders: &defenders,
            shot_clock_s: 24.0,
        }
        .decide()
    };
    let counted = decide(BeyondHorizon::Horizon);
    let beyond: Vec<_> = counted
        .candidates
        .iter()
        .filter(|c| c.beyond_horizon)
        .collect();
    assert!(!beyond.is_empty());
    for c in &beyond {
        assert_eq!(c.c_o, horizon);
        let reached = defenders[0].seconds(DVec2::from_array(c.cell));
        assert_eq!(reached, horizon);
    }
    assert!(beyond
        .iter()
        .any(|c| c.qualifies(&DecisionParams::default())));
    let strict = decide(BeyondHorizon::Unsafe);
    let params = DecisionParams {
        beyond_horizon: BeyondHorizon::Unsafe,
        ..DecisionParams::default()
    };
    assert!(strict
        .candidates
        .iter()
        .filter(|c| c.beyond_horizon)
        .all(|c| !c.qualifies(&params)));
    if let Some(c) = strict.chosen {
        assert!(!c.beyond_horizon);
    }
}

/// With the capture mirrored, a stance reaches left and right alike: 1 m and 3 m to
/// either side within two frames of each other, for every behaviour.
#[test]
fn left_and_right_from_a_stance_agree_for_every_behaviour() {
    let caps = fixtures::cmu_capabilities();
    let stances: Vec<human::Stance> = [&caps.dribble, &caps.run, &caps.defense]
        .into_iter()
        .map(human::Stance::of)
        .collect();
    let figures = human::symmetry(&stances);
    assert_eq!(figures.len(), 6);
    for (behaviour, d, left, right) in figures {
        let (left, right) = (left.unwrap(), right.unwrap());
        assert!(
            left.abs_diff(right) <= human::SYMMETRY_FRAMES,
            "{behaviour} {d} m: left {left}, right {right}"
        );
    }
}

/// A defender that reads the play heads where the ball handler is dribbling to; one that
/// chases the ball heads for the ball handler itself. Counted on the ticks where the two
/// differ by 3 m or more.
#[test]
fn a_defender_reading_the_play_heads_where_the_ball_handler_dribbles_to() {
    let caps = fixtures::cmu_capabilities();
    for aim in [DefenderAim::Ball, DefenderAim::Goal] {
        let mut params = GameParams {
            seed: 11,
            ..GameParams::default()
        };
        params.defender.aim = aim;
        params.shot_model = DefenderModel::None;
        let mut game = Game::new(caps.clone(), params);
        let mut events = Vec::new();
        let (mut to_goal, mut to_holder) = (0, 0);
        for _ in 0..6000 {
            events.clear();
            game.step(&mut events);
            let Some(holder) = game.holder() else {
                continue;
            };
            let agents = game.agents();
            let (Some(dribble), Some(defense)) = (
                agents[holder].movement.as_ref(),
                agents[2].movement.as_ref(),
            ) else {
                continue;
            };
            let at = agents[holder].pose.position;
            if dribble.behaviour != "dribble" || dribble.goal.distance(at) < 3.0 {
                continue;
            }
            // A move in progress is kept while its goal stays within 1 m of the new one,
            // and the ball handler moves up to about 0.6 m between decisions.
            to_goal += usize::from(defense.goal.distance(dribble.goal) <= 1.0 + 1e-9);
            to_holder += usize::from(defense.goal.distance(at) <= 2.0);
        }
        match aim {
            DefenderAim::Goal => assert!(
                to_goal > 200 && to_holder < to_goal / 10,
                "{to_goal} {to_holder}"
            ),
            DefenderAim::Ball => assert!(
                to_holder > 200 && to_goal < to_holder / 10,
                "{to_goal} {to_holder}"
            ),
        }
    }
}
