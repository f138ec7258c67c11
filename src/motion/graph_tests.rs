//! Motion-graph properties on small clips made in the test: exact alignment, strong
//! connectivity, constraints.

use super::fixtures::{clip, straight};
use super::*;
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
    super::fixtures::graph()
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
