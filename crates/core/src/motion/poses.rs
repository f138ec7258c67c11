//! A behaviour's poses as a spectator draws them: every graph node's joints in its
//! character frame, the skeleton's bones, and the running strides a fielder's figure is
//! posed from. Frames name only a node (and a blend); these are sent once.

use super::MotionGraph;
use glam::DVec3;
use serde::Serialize;

/// Shortest and longest stride cycle looked for, s: two steps of running or jogging take
/// 0.6–0.8 s; the bounds leave room either side.
const CYCLE_S: (f64, f64) = (0.55, 1.4);

/// Slowest forward speed a stride is taken from, m/s: below it the capture walks or
/// stands, which a running fielder never shows.
const STRIDE_MIN_SPEED_M_S: f64 = 1.5;

/// The most a planted foot may slide in a loop that is offered, m: a loop whose own
/// root wobbles more against an even pace than this is left out.
pub const MAX_FOOT_SLIDE_M: f64 = 0.10;

/// How far above its lowest point in a loop a foot still counts as planted, m: any
/// higher and a foot swinging in low to land counts, which no one would call sliding.
const PLANTED_M: f64 = 0.015;

/// A behaviour's poses and skeleton, as `GET /api/motion/{behaviour}` serves them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseLibrary {
    /// The behaviour, e.g. `dribble`.
    pub behaviour: String,
    /// Capture frames per second.
    pub fps: f64,
    /// Joint names, in the order of each pose's positions.
    pub joints: Vec<String>,
    /// Each joint's parent (null for the root): the bones to draw.
    pub parents: Vec<Option<usize>>,
    /// The node a body that has not moved yet shows: the slowest one.
    pub standing: u32,
    /// Per graph node, its joints in the body's own frame (root on the ground at the
    /// origin, facing +x, y up) as `[x, y, z, x, y, z, …]` in millimetres.
    pub poses_mm: Vec<Vec<i32>>,
    /// Loops of running for figures that move without a graph (fielders): a client plays
    /// one at a body's speed with its phase set by the distance run.
    pub strides: Vec<StrideCycle>,
}

/// One loop of running: consecutive frames of one clip whose last pose comes back to
/// its first, played by distance (phase = distance run / `length_m`), which keeps a
/// planted foot where it is at any speed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StrideCycle {
    /// The nodes of the loop, in order, starting as the left foot is lowest.
    pub nodes: Vec<u32>,
    /// Ground the root covers in one loop, m.
    pub length_m: f64,
    /// The capture's own speed over the loop, m/s: a client picks the loop nearest the
    /// body's speed.
    pub speed_m_s: f64,
    /// The farthest a planted foot moves while it stays planted when the loop is played
    /// by distance, m: the feet slide no more than this.
    pub foot_slide_m: f64,
}

impl PoseLibrary {
    /// The library of `graph`.
    pub fn of(graph: &MotionGraph) -> PoseLibrary {
        let nodes = graph.node_count() as u32;
        let standing = (0..nodes)
            .min_by(|&a, &b| {
                let speed = |n: u32| {
                    let n = &graph.nodes[n as usize];
                    n.forward_speed.hypot(n.lateral_speed)
                };
                speed(a).total_cmp(&speed(b))
            })
            .unwrap_or(0);
        PoseLibrary {
            behaviour: graph.behaviour.clone(),
            fps: graph.fps,
            joints: graph.joint_names.clone(),
            parents: graph.joint_parents.clone(),
            standing,
            poses_mm: (0..nodes)
                .map(|n| {
                    graph
                        .pose(n)
                        .iter()
                        .flat_map(|p| p.to_array())
                        .map(|x| (x * 1000.0).round() as i32)
                        .collect()
                })
                .collect(),
            strides: stride_cycles(graph),
        }
    }
}

/// The best stride loop of each clip that runs straight ahead, slowest first.
fn stride_cycles(graph: &MotionGraph) -> Vec<StrideCycle> {
    let (shortest, longest) = (
        (CYCLE_S.0 * graph.fps).round() as usize,
        (CYCLE_S.1 * graph.fps).round() as usize,
    );
    let feet = ["LeftFoot", "RightFoot"].map(|f| graph.joint_names.iter().position(|j| j == f));
    let [Some(left), Some(right)] = feet else {
        return Vec::new();
    };
    let straight = |n: u32| {
        let n = &graph.nodes[n as usize];
        n.forward_speed > STRIDE_MIN_SPEED_M_S
            && n.forward_speed > 3.0 * n.lateral_speed.abs()
            && n.turn_rate.abs() < 0.3
    };
    let mut best: Vec<Option<(f64, Vec<u32>)>> = vec![None; graph.clip_names.len()];
    for start in 0..graph.node_count() as u32 {
        if !straight(start) {
            continue;
        }
        let mut run = vec![start];
        while run.len() <= longest {
            match graph.continuation(run[run.len() - 1]) {
                Some(n) if straight(n) => run.push(n),
                _ => break,
            }
        }
        for period in shortest..run.len() {
            let gap = pose_distance(graph.pose(start), graph.pose(run[period]));
            let clip = graph.nodes[start as usize].clip;
            if best[clip].as_ref().is_none_or(|(g, _)| gap < *g) {
                best[clip] = Some((gap, run[..period].to_vec()));
            }
        }
    }
    let mut cycles: Vec<StrideCycle> = best
        .into_iter()
        .flatten()
        .map(|(_, mut nodes)| {
            // Start as the left foot is lowest, so phases line up between loops.
            let lowest = (0..nodes.len())
                .min_by(|&a, &b| {
                    let y = |k: usize| graph.pose(nodes[k])[left].y;
                    y(a).total_cmp(&y(b))
                })
                .unwrap_or(0);
            nodes.rotate_left(lowest);
            let length_m: f64 = nodes
                .iter()
                .map(|&n| graph.continuation_edge(n).map_or(0.0, |e| e.step.dx))
                .sum();
            let poses: Vec<&[DVec3]> = nodes.iter().map(|&n| graph.pose(n)).collect();
            StrideCycle {
                foot_slide_m: foot_slide(&poses, length_m, [left, right]),
                speed_m_s: length_m * graph.fps / nodes.len() as f64,
                length_m,
                nodes,
            }
        })
        .filter(|c| c.length_m > 0.0 && c.foot_slide_m <= MAX_FOOT_SLIDE_M)
        .collect();
    cycles.sort_by(|a, b| a.speed_m_s.total_cmp(&b.speed_m_s));
    cycles
}

/// Root-mean-square distance between two poses' joints, m.
fn pose_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    let sum: f64 = a.iter().zip(b).map(|(p, q)| p.distance_squared(*q)).sum();
    (sum / a.len().max(1) as f64).sqrt()
}

/// A loop's pose at `phase` (0 to 1), joints interpolated between its frames, as a
/// client poses it.
fn pose_at(poses: &[&[DVec3]], phase: f64) -> Vec<DVec3> {
    let x = phase.rem_euclid(1.0) * poses.len() as f64;
    let k = (x as usize).min(poses.len() - 1);
    let (a, b) = (poses[k], poses[(k + 1) % poses.len()]);
    a.iter()
        .zip(b)
        .map(|(p, q)| p.lerp(*q, x - k as f64))
        .collect()
}

/// The farthest a planted foot moves while it stays planted, when the loop is played by
/// distance along +x (phase = distance / `length_m`) over two loops, m.
fn foot_slide(poses: &[&[DVec3]], length_m: f64, feet: [usize; 2]) -> f64 {
    let samples = poses.len() * 16;
    // Each foot's lowest point in the loop: the ankle of a capture sits a few
    // centimetres apart on each side.
    let ground = feet.map(|f| poses.iter().map(|p| p[f].y).fold(f64::INFINITY, f64::min));
    let mut worst: f64 = 0.0;
    let mut planted_at: [Option<DVec3>; 2] = [None, None];
    for s in 0..=2 * samples {
        let d = length_m * s as f64 / samples as f64;
        let pose = pose_at(poses, d / length_m);
        for (k, &f) in feet.iter().enumerate() {
            let foot = pose[f] + DVec3::new(d, 0.0, 0.0);
            if foot.y > ground[k] + PLANTED_M {
                planted_at[k] = None;
                continue;
            }
            let from = *planted_at[k].get_or_insert(foot);
            worst = worst.max((foot - from).with_y(0.0).length());
        }
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;

    #[test]
    fn every_node_has_a_pose_of_every_joint_in_millimetres() {
        let g = fixtures::cmu_graph("dribble");
        let lib = PoseLibrary::of(&g);
        assert_eq!(lib.poses_mm.len(), g.node_count());
        assert_eq!(lib.parents.len(), lib.joints.len());
        let n = 7u32;
        let pose = g.pose(n);
        assert_eq!(lib.poses_mm[n as usize].len(), 3 * pose.len());
        assert_eq!(
            lib.poses_mm[n as usize][3],
            (pose[1].x * 1000.0).round() as i32
        );
        // A real skeleton: bones from parents, the hips a metre up.
        assert!(lib.parents[1..].iter().all(|p| p.is_some()));
        assert!((800..1200).contains(&lib.poses_mm[lib.standing as usize][1]));
    }

    #[test]
    fn running_strides_loop_and_keep_planted_feet_within_a_few_centimetres() {
        let lib = PoseLibrary::of(&fixtures::cmu_graph("run"));
        assert!(lib.strides.len() >= 2, "{} strides", lib.strides.len());
        for c in &lib.strides {
            assert!(
                (1.5..8.0).contains(&c.speed_m_s) && c.length_m > 0.8,
                "{c:?}"
            );
            // What the page states: feet slide no more than 10 cm while planted (the
            // capture's own root wobbles against a loop played at an even pace).
            assert!(c.foot_slide_m <= MAX_FOOT_SLIDE_M, "{} m", c.foot_slide_m);
        }
    }
}
