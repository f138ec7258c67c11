//! Motion-graph properties on small clips made in the test: exact alignment, strong
//! connectivity, constraints.

use super::*;
use crate::fixtures::{clip, straight};
use glam::DVec2;

#[test]
fn a_moved_copy_of_a_clip_is_at_distance_zero() {
    let a = clip("a", 3.0, straight(4.0));
    // The same motion rotated 70° and shifted: every frame aligns exactly.
    let turn = 70f64.to_radians();
    let b = clip("b", 3.0, move |t| {
        let (p, h) = straight(4.0)(t);
        (
            DVec2::new(5.0, -3.0) + p.rotate(DVec2::from_angle(turn)),
            h + turn,
        )
    });
    let found = transitions::find(&[&a, &b], 10, 1e-6);
    let across: Vec<_> = found.iter().filter(|t| t.from_clip != t.to_clip).collect();
    assert!(!across.is_empty());
    for t in across {
        assert!(t.rms_m < 1e-6, "{t:?}");
        // Zero distance means the same moment of the gait (a stride of 2.4 m at 4 m/s
        // is 18 frames): to = from + 1 + 18k.
        assert_eq!((t.to + 18 * 10 - t.from - 1) % 18, 0, "{t:?}");
    }
}

fn graph() -> MotionGraph {
    crate::fixtures::graph()
}

/// Every node reaches every other, both ways: walk forward and backward from node 0.
#[test]
fn the_pruned_graph_is_strongly_connected() {
    let g = graph();
    assert!(g.stats.transitions_after_pruning > 0);
    assert!(g.stats.largest_scc > g.stats.frames / 2, "{:?}", g.stats);
    let n = g.node_count();
    let reach = |forward: bool| {
        let mut seen = vec![false; n];
        let mut stack = vec![0u32];
        seen[0] = true;
        while let Some(v) = stack.pop() {
            for e in g
                .edges
                .iter()
                .filter(|e| if forward { e.from == v } else { e.to == v })
            {
                let w = if forward { e.to } else { e.from };
                if !std::mem::replace(&mut seen[w as usize], true) {
                    stack.push(w);
                }
            }
        }
        seen.iter().all(|s| *s)
    };
    assert!(reach(true) && reach(false));
    for node in 0..n as u32 {
        assert!(!g.out_edges(node).is_empty(), "dead end at {node}");
        for i in g.out_edges(node) {
            assert_eq!(g.edges[i].from, node);
        }
    }
}

#[test]
fn root_steps_are_in_the_characters_frame() {
    let g = graph();
    for e in g.edges.iter().filter(|e| !e.transition) {
        let r = g.nodes[e.from as usize];
        let speed = e.step.length() * FPS;
        match g.clip_names[r.clip].as_str() {
            "jog" => assert!((e.step.dx * FPS - 3.5).abs() < 0.3 && e.step.dz.abs() < 0.01),
            // Turning right (toward +z): heading grows, at v/r rad/s.
            "right" => assert!(
                (e.step.dheading * FPS - 3.5 / 6.0).abs() < 0.05,
                "{:?}",
                e.step
            ),
            "left" => assert!((e.step.dheading * FPS + 3.5 / 6.0).abs() < 0.05),
            "tight_right" => assert!((e.step.dheading * FPS - 3.5 / 2.5).abs() < 0.05),
            "tight_left" => assert!((e.step.dheading * FPS + 3.5 / 2.5).abs() < 0.05),
            _ => assert!((speed - 4.2).abs() < 0.3),
        }
    }
    assert!(
        (g.stats.top_speed_m_s - 4.2).abs() < 0.1,
        "{}",
        g.stats.top_speed_m_s
    );
}

#[test]
fn constraints_disable_fast_edges_and_keep_no_dead_ends() {
    let g = graph();
    let enabled = g.enabled(&Constraints {
        max_speed: Some(3.8),
    });
    for (e, on) in g.edges.iter().zip(&enabled) {
        if e.step.length() * FPS > 3.8 {
            assert!(!on, "a fast edge stayed enabled");
        }
    }
    assert!(enabled.iter().any(|e| !e) && enabled.iter().any(|e| *e));
    // What stays enabled is strongly connected: no walk can get stuck.
    let n = g.node_count();
    let (mut has_out, mut has_in) = (vec![false; n], vec![false; n]);
    for (e, _) in g.edges.iter().zip(&enabled).filter(|(_, on)| **on) {
        has_out[e.from as usize] = true;
        has_in[e.to as usize] = true;
    }
    assert!(has_out == has_in, "a node is entered but never left");
}

#[test]
fn the_default_start_runs_forward_at_a_moderate_speed() {
    let g = graph();
    let n = g.default_start();
    let name = &g.clip_names[g.nodes[n as usize].clip];
    // Half of the 4.2 m/s top speed is closest to the straight 3.5 m/s jog; the circles
    // turn too fast to count as running forward.
    assert_eq!(name, "jog");
    // The pose is in the character's frame: facing +x, the left hip is on −z.
    let pose = g.pose(n);
    assert!(pose[1].z < -0.05 && pose[2].z > 0.05 && pose[0].x.abs() < 1e-9);
}

/// A clip that no transition can join (a sprint whose stride differs from everything
/// else) leaves no trace in the graph: not its frames, not its speed.
#[test]
fn top_speed_comes_from_the_kept_frames() {
    let clips = [
        clip("jog", 4.0, straight(3.5)),
        clip("jog_again", 4.0, straight(3.5)),
        // Far above the joggers' height, so nothing aligns with it.
        {
            let sprint = clip("sprint", 2.0, straight(8.0));
            let lifted: Vec<glam::DVec3> = (0..sprint.frame_count())
                .flat_map(|f| sprint.frame(f).iter().map(|p| *p + glam::DVec3::Y * 3.0))
                .collect();
            Clip::new("sprint", "run", FPS, sprint.joint_names.clone(), lifted).unwrap()
        },
    ];
    let refs: Vec<&Clip> = clips.iter().collect();
    let g = MotionGraph::build("run", &refs, GraphParams::default()).unwrap();
    let sprint = &g.coverage[2];
    assert_eq!((sprint.name.as_str(), sprint.kept), ("sprint", 0));
    assert!(!sprint.joined() && g.coverage[0].joined());
    assert!((g.stats.top_speed_m_s - 3.5).abs() < 0.1, "{:?}", g.stats);
    // Its best transition is as far as the lift: about 3 m RMS.
    assert!(
        sprint.best_transition_m.is_none_or(|d| d > 2.0),
        "{sprint:?}"
    );
}

/// Every clip of the CMU capture keeps at least half its frames (the bar the automatic
/// choice sets), the behaviours' transitions are reported, and no walk on a graph is
/// faster than its top speed.
#[test]
fn every_cmu_clip_is_in_its_behaviours_graph() {
    for behaviour in ["run", "dribble", "defense"] {
        let g = crate::fixtures::cmu_graph(behaviour);
        for c in &g.coverage {
            assert!(2 * c.kept >= c.frames, "{behaviour}: {c:?}");
            assert!(c.transitions_in > 0 && c.transitions_out > 0, "{c:?}");
        }
        assert_eq!(
            g.coverage.iter().map(|c| c.kept).sum::<usize>(),
            g.node_count()
        );
        let s = &g.stats;
        assert!(s.transition_p95_m <= s.transition_worst_m);
        assert!(s.transition_worst_m < g.params.threshold_m);
        // Over any ⅓ s of a walk, clip frames or cuts, the root is no faster than the
        // top speed, give or take the sway a cut can add within one frame.
        let span = 10;
        let mut rng = 1u64;
        for _ in 0..200 {
            let mut node = (rng % g.node_count() as u64) as u32;
            let mut at = crate::motion::Walker::START;
            let mut trail = vec![at.position];
            for _ in 0..span {
                rng = rng
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let out = g.out_edges(node);
                let e = &g.edges[out.start + (rng >> 33) as usize % out.len()];
                at = at.step(&e.step);
                trail.push(at.position);
                node = e.to;
            }
            let speed = (trail[span] - trail[0]).length() * FPS / span as f64;
            assert!(
                speed <= s.top_speed_m_s * 1.1,
                "{behaviour}: {speed} > {s:?}"
            );
        }
    }
}
