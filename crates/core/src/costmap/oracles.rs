//! Cost-map properties checked against oracles that do not come from the builders: the
//! physical speed bound, obstacles, replaying the stored paths, pose invariance.

use super::*;
use crate::fixtures;
use crate::motion::MotionGraph;

fn params(method: Method) -> BuildParams {
    BuildParams {
        method,
        grid: Grid::new(12.0, 0.5),
        iterations: 20_000,
        depth: 90,
        ..BuildParams::default()
    }
}

fn build(graph: &MotionGraph, p: &BuildParams) -> CostMap {
    CostMap::build(graph, p, &mut |_| {})
}

/// The fastest a root ever moves in one frame of the graph, m/s: nothing can beat
/// straight-line distance at this speed. (The oracle is often stated with grassfire's
/// distance; our 8-connected grassfire overestimates the straight line by up to 8 %, so
/// the bound that must hold is the straight line itself.)
fn fastest(graph: &MotionGraph) -> f64 {
    graph
        .edges
        .iter()
        .map(|e| e.step.length())
        .fold(0.0, f64::max)
        * graph.fps
}

/// Replays a stored path from the start pose: it must end in its cell after exactly the
/// cell's cost, use only enabled edges, and never enter an obstacle.
fn replay(graph: &MotionGraph, map: &CostMap, cell: usize, enabled: &[bool]) {
    let mut at = Walker::START;
    let mut node = map.start_node;
    let mut frames = 0;
    for &id in &map.paths[cell] {
        let e = &graph.edges[id as usize];
        assert_eq!(e.from, node, "the path is not a walk on the graph");
        assert!(enabled[id as usize], "the path uses a disabled edge");
        at = at.step(&e.step);
        assert!(
            !map.obstacles.iter().any(|o| o.contains(at.position)),
            "the path enters an obstacle"
        );
        frames += e.frames;
        node = e.to;
    }
    assert_eq!(map.grid.cell_of(at.position), Some(cell));
    assert_eq!(Some(frames), map.costs[cell]);
}

#[test]
fn no_map_beats_the_straight_line_at_top_speed() {
    let graph = fixtures::graph();
    let top = fastest(&graph);
    for method in [Method::Mc, Method::Search] {
        let map = build(&graph, &params(method));
        assert!(
            map.reachable_cells() > 100,
            "{method:?} reached {}",
            map.reachable_cells()
        );
        for (c, cost) in map.costs.iter().enumerate() {
            if let Some(frames) = cost {
                let bound = map.grid.distance_to_cell(DVec2::ZERO, c) / top * graph.fps;
                assert!(
                    f64::from(*frames) + 1e-9 >= bound.floor(),
                    "{method:?} cell {c}: {frames} < {bound}"
                );
            }
        }
        let enabled = vec![true; graph.edges.len()];
        for c in (0..map.costs.len()).filter(|&c| map.costs[c].is_some_and(|f| f > 0)) {
            replay(&graph, &map, c, &enabled);
        }
    }
}

/// On the CMU running data (mirrored), search finds costs as good as 50,000 Monte Carlo
/// walks, or better, in at least 95 % of the cells the walks reach, within 1 frame in at
/// least 98 %, and never worse within the horizon its exhaustive walks cover. (Against
/// 200,000 walks, every behaviour and start state: `scripts/search-vs-mc`, BENCHMARKS.md.)
#[test]
fn search_keeps_up_with_many_monte_carlo_walks_on_real_running() {
    let graph = fixtures::cmu_graph("run");
    let p = BuildParams {
        grid: Grid::new(16.0, 0.5),
        depth: 120,
        ..BuildParams::default()
    };
    let mc = build(
        &graph,
        &BuildParams {
            method: Method::Mc,
            iterations: 50_000,
            ..p.clone()
        },
    );
    let search = build(
        &graph,
        &BuildParams {
            method: Method::Search,
            ..p
        },
    );
    // Every walk this short is followed exactly, so no random walk can beat search here.
    let enabled = graph.enabled(&Constraints::default());
    let horizon = super::backward::exhaustive_horizon(
        &Prepared::new(&graph, &enabled),
        search.start_node,
        graph.node_count(),
        p.depth,
    );
    // The mirror images double the branching, so the exhaustive budget covers 7 frames
    // (28 without them); enough that the check below means something.
    assert!(horizon >= 5, "{horizon}");
    let (mut reached, mut close, mut as_good) = (0, 0, 0);
    for (m, s) in mc.costs.iter().zip(&search.costs) {
        if let Some(m) = m {
            if *m <= horizon {
                assert!(s.is_some_and(|s| s <= *m), "{s:?} > {m} within the horizon");
            }
            reached += 1;
            close += usize::from(s.is_some_and(|s| s <= m + 1));
            as_good += usize::from(s.is_some_and(|s| s <= *m));
        }
    }
    assert!(reached > 300, "{reached}");
    assert!(
        close * 100 >= 98 * reached,
        "search within 1 frame in {close} of {reached} cells"
    );
    assert!(
        as_good * 100 >= 95 * reached,
        "search as good or better in {as_good} of {reached} cells"
    );
}

/// The paper's central claim against grassfire: from a forward-running pose a real
/// runner needs far longer to reach a point 5 m behind than one 5 m ahead.
#[test]
fn real_running_is_asymmetric_unlike_grassfire() {
    let graph = fixtures::cmu_graph("run");
    let p = BuildParams {
        grid: Grid::new(14.0, 0.5),
        depth: 300,
        ..BuildParams::default()
    };
    let ahead = DVec2::new(5.2, 0.2);
    let behind = DVec2::new(-4.8, 0.2);
    let search = build(
        &graph,
        &BuildParams {
            method: Method::Search,
            ..p.clone()
        },
    );
    let (a, b) = (search.cost(ahead).unwrap(), search.cost(behind));
    // Beyond the map counts as its horizon, which must itself be more than twice ahead.
    let b_or_horizon = b.unwrap_or(search.depth);
    assert!(b_or_horizon > 2 * a, "ahead {a}, behind {b:?}");
    let grassfire = build(
        &graph,
        &BuildParams {
            method: Method::Grassfire,
            ..p
        },
    );
    // Both reached: equal because both are costs, not because neither is.
    assert!(grassfire.cost(ahead).is_some(), "ahead is within the map");
    assert_eq!(grassfire.cost(ahead), grassfire.cost(behind));
}

#[test]
fn grassfire_is_distance_at_top_speed() {
    let graph = fixtures::graph();
    let map = build(&graph, &params(Method::Grassfire));
    let speed = graph.stats.top_speed_m_s;
    // Straight ahead, 4 m from the start cell's centre: 4 m / v in frames.
    let ahead = map.grid.cell_of(DVec2::new(4.1, 0.1)).unwrap();
    assert_eq!(
        map.costs[ahead],
        Some((4.0 / speed * graph.fps).ceil() as u32)
    );
    // The grassfire map is symmetric: behind costs what ahead costs.
    let behind = map.grid.cell_of(DVec2::new(-3.9, 0.1)).unwrap();
    assert_eq!(map.costs[behind], map.costs[ahead]);
}

#[test]
fn obstacles_are_unreachable_and_never_crossed() {
    let graph = fixtures::graph();
    let wall = Obstacle::new(DVec2::new(2.0, -3.0), DVec2::new(3.0, 3.0));
    for method in [Method::Mc, Method::Search, Method::Grassfire] {
        let map = build(
            &graph,
            &BuildParams {
                obstacles: vec![wall],
                ..params(method)
            },
        );
        let inside = map.grid.cell_of(DVec2::new(2.6, 0.2)).unwrap();
        assert_eq!(map.costs[inside], None, "{method:?}");
        // Unreachable because of the wall: without it the cell is reached.
        let open = build(&graph, &params(method));
        assert!(open.costs[inside].is_some(), "{method:?}");
        let enabled = vec![true; graph.edges.len()];
        for c in (0..map.costs.len())
            .filter(|&c| map.costs[c].is_some_and(|f| f > 0) && !map.paths[c].is_empty())
        {
            replay(&graph, &map, c, &enabled);
        }
        // Straight ahead behind the wall now costs more than without it.
        let beyond = map.grid.cell_of(DVec2::new(4.2, 0.2)).unwrap();
        assert!(open.costs[beyond].is_some(), "{method:?}");
        assert!(
            map.costs[beyond].is_none_or(|c| Some(c) > open.costs[beyond]),
            "{method:?}"
        );
    }
}

#[test]
fn walks_respect_disabled_edges() {
    let graph = fixtures::graph();
    let limit = 3.8;
    let enabled = graph.enabled(&crate::motion::Constraints {
        max_speed: Some(limit),
    });
    for method in [Method::Mc, Method::Search] {
        let map = build(
            &graph,
            &BuildParams {
                max_speed: Some(limit),
                ..params(method)
            },
        );
        assert!(
            map.reachable_cells() > 20,
            "{method:?}: {}",
            map.reachable_cells()
        );
        for c in (0..map.costs.len()).filter(|&c| map.costs[c].is_some_and(|f| f > 0)) {
            replay(&graph, &map, c, &enabled);
        }
    }
}

#[test]
fn a_map_embeds_at_any_pose() {
    let graph = fixtures::graph();
    let map = build(&graph, &params(Method::Search));
    let pose = AgentPose {
        position: DVec2::new(30.0, -12.0),
        heading: 2.2,
    };
    for local in [
        DVec2::new(3.0, 0.2),
        DVec2::new(-2.0, 4.0),
        DVec2::new(0.7, -5.1),
    ] {
        assert!(map.cost(local).is_some(), "{local} is within the map");
        assert_eq!(
            map.cost_for(&pose, pose.frame().to_world(local)),
            map.cost(local)
        );
    }
}

#[test]
fn monte_carlo_records_convergence_and_only_improves() {
    let graph = fixtures::graph();
    let map = build(&graph, &params(Method::Mc));
    assert!(map.convergence.len() > 10);
    assert_eq!(map.convergence.last().unwrap().iterations, 20_000);
    for pair in map.convergence.windows(2) {
        for (a, b) in pair[0].costs.iter().zip(&pair[1].costs) {
            // A cell's cost never rises, and a reached cell stays reached.
            assert!(a.is_none() || (b.is_some() && b <= a), "{a:?} -> {b:?}");
        }
    }
}

/// A longer horizon only adds walks, so no cell may get dearer: on every CMU behaviour,
/// from standing and from the default start, over a ladder of depths. (Search once
/// coarsened its local cells with the depth, and some cells rose by a few frames.)
#[test]
fn search_never_gets_dearer_with_a_longer_horizon() {
    for behaviour in ["run", "dribble", "defense"] {
        let graph = fixtures::cmu_graph(behaviour);
        for start in [Start::Standing, Start::Default] {
            let node = start.node(&graph).unwrap();
            let mut shorter: Option<CostMap> = None;
            for depth in [30, 60, 120] {
                let map = build(
                    &graph,
                    &BuildParams {
                        depth,
                        start_node: Some(node),
                        grid: Grid::new(10.0, 0.5),
                        ..params(Method::Search)
                    },
                );
                if let Some(s) = &shorter {
                    for (c, (a, b)) in s.costs.iter().zip(&map.costs).enumerate() {
                        if let Some(a) = a {
                            assert!(
                                b.is_some_and(|b| b <= *a),
                                "{behaviour} {start:?}: cell {c} costs {a} at depth {}, {b:?} at {depth}",
                                s.depth
                            );
                        }
                    }
                }
                shorter = Some(map);
            }
        }
    }
}
