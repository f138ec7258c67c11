//! Playing a walk on the motion graph as a body: the root follows the edges' steps, and a
//! transition blends the clip being left into the clip being entered over the window,
//! with an ease-in/ease-out weight, so a cut never pops.

use super::{Edge, MotionGraph, Walker};
use glam::{DVec2, DVec3};

/// One frame of playback.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaybackFrame {
    /// The graph node being played.
    pub(crate) node: u32,
    /// The root on the ground, (x, z) in m.
    pub(crate) root: DVec2,
    /// Radians from +x toward +z.
    pub heading: f64,
    /// Joint positions in world coordinates (root on the ground at `root`).
    pub joints: Vec<DVec3>,
}

/// Smoothstep: 0 at 0, 1 at 1, zero slope at both ends (ease in, ease out).
fn ease(s: f64) -> f64 {
    let s = s.clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// A cut being blended over, as a frame of playback shows it: the clip being left,
/// still playing on at node `from`, faded into the node being entered with
/// [`MotionGraph::blend_weight`]. The game keeps one per player so a spectator poses the
/// body exactly as [`MotionGraph::playback`] would.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Blend {
    /// The node the clip being left has reached.
    pub from: u32,
    /// Frames since the cut: 0 on the first frame after it.
    frames_in: usize,
}

impl MotionGraph {
    /// The edge to the node a clip plays next without a cut, if the graph kept it.
    pub(super) fn continuation_edge(&self, node: u32) -> Option<&Edge> {
        self.out_edges(node)
            .map(|i| &self.edges[i])
            .find(|e| !e.transition)
    }

    /// The node a clip plays next without a cut, if the graph kept it.
    pub(super) fn continuation(&self, node: u32) -> Option<u32> {
        self.continuation_edge(node).map(|e| e.to)
    }

    /// The blend of the frame after leaving `node` by an edge (a cut when `cut`), given
    /// the blend `shown` at `node`: a cut starts one from where the left clip was going
    /// (if the graph pruned that frame, the last one is held); otherwise a blend under way
    /// moves one frame on, and ends after the window.
    pub fn blend_on(&self, shown: Option<Blend>, node: u32, cut: bool) -> Option<Blend> {
        let on = |n: u32| self.continuation(n).unwrap_or(n);
        if cut {
            return Some(Blend {
                from: on(node),
                frames_in: 0,
            });
        }
        let b = shown?;
        (b.frames_in + 1 < self.params.window).then(|| Blend {
            from: on(b.from),
            frames_in: b.frames_in + 1,
        })
    }

    /// How much of the node being entered a frame under `blend` shows, 0 to 1 (the rest
    /// is `blend.from`'s pose): an ease-in/ease-out ramp over the window.
    pub fn blend_weight(&self, blend: &Blend) -> f64 {
        ease((blend.frames_in + 1) as f64 / (self.params.window + 1) as f64)
    }

    /// A node's pose under `blend`, in its character frame.
    fn blended_pose(&self, node: u32, blend: Option<Blend>) -> Vec<DVec3> {
        match blend {
            Some(b) => {
                let w = self.blend_weight(&b);
                self.pose(b.from)
                    .iter()
                    .zip(self.pose(node))
                    .map(|(a, b)| a.lerp(*b, w))
                    .collect()
            }
            None => self.pose(node).to_vec(),
        }
    }

    /// Plays `edges` (ids into [`MotionGraph::edges`], a walk from `start`) with the body
    /// at `root` facing `heading`. Returns one frame for the start and one per edge.
    ///
    /// # Panics
    /// If `edges` is not a walk from `start`.
    pub fn playback(
        &self,
        start: u32,
        root: DVec2,
        heading: f64,
        edges: &[u32],
    ) -> Vec<PlaybackFrame> {
        let place = |node: u32, pose: &[DVec3], at: &Walker| {
            let (cos, sin) = (at.facing.x, at.facing.y);
            PlaybackFrame {
                node,
                root: at.position,
                heading: at.heading(),
                joints: pose
                    .iter()
                    .map(|p| {
                        DVec3::new(
                            at.position.x + p.x * cos - p.z * sin,
                            p.y,
                            at.position.y + p.x * sin + p.z * cos,
                        )
                    })
                    .collect(),
            }
        };
        let mut at = Walker {
            position: root,
            facing: DVec2::from_angle(heading),
        };
        let mut frames = vec![place(start, self.pose(start), &at)];
        let mut node = start;
        let mut blend = None;
        for &id in edges {
            let e = &self.edges[id as usize];
            assert_eq!(e.from, node, "edge {id} does not leave node {node}");
            at = at.step(&e.step);
            blend = self.blend_on(blend, node, e.transition);
            node = e.to;
            frames.push(place(node, &self.blended_pose(node, blend), &at));
        }
        frames
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixtures;

    /// The largest distance any joint moves between consecutive frames.
    fn largest_jump(frames: &[PlaybackFrame]) -> f64 {
        frames
            .windows(2)
            .flat_map(|w| {
                w[0].joints
                    .iter()
                    .zip(&w[1].joints)
                    .map(|(a, b)| (*a - *b).length())
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn blending_softens_the_roughest_cut_of_every_behaviour() {
        for behaviour in ["run", "dribble", "defense"] {
            roughest_cut_is_softened(&fixtures::cmu_graph(behaviour));
        }
    }

    /// The roughest cut of `g` that a clip then plays on from for a whole blend, played
    /// with and without blending.
    fn roughest_cut_is_softened(g: &MotionGraph) {
        // The natural run of `len` edges from `node`, if its clip goes on that long.
        let run_from = |mut node: u32, len: usize| -> Option<Vec<u32>> {
            let mut edges = Vec::with_capacity(len);
            for _ in 0..len {
                let next = g.out_edges(node).find(|&i| !g.edges[i].transition)?;
                edges.push(next as u32);
                node = g.edges[next].to;
            }
            Some(edges)
        };
        let len = g.params.window + 2;
        // Of the transitions into a clip that then plays on for the whole blend, the one
        // whose target pose is furthest from where its own clip was going.
        let pop = |e: &crate::motion::Edge| {
            let next = g.continuation(e.from).unwrap_or(e.from);
            g.pose(next)
                .iter()
                .zip(g.pose(e.to))
                .map(|(p, q)| (*p - *q).length())
                .fold(0.0, f64::max)
        };
        let (id, e) = g
            .edges
            .iter()
            .enumerate()
            .filter(|(_, e)| e.transition && run_from(e.to, len).is_some())
            .max_by(|(_, a), (_, b)| pop(a).total_cmp(&pop(b)))
            .unwrap();
        let mut walk = vec![id as u32];
        walk.extend(run_from(e.to, len).unwrap());
        let blended = g.playback(e.from, DVec2::ZERO, 0.0, &walk);
        // Without blending every frame is its node's own pose: the cut pops.
        let cut: Vec<PlaybackFrame> = blended
            .iter()
            .map(|f| {
                let (sin, cos) = f.heading.sin_cos();
                let joints = g
                    .pose(f.node)
                    .iter()
                    .map(|p| {
                        DVec3::new(
                            f.root.x + p.x * cos - p.z * sin,
                            p.y,
                            f.root.y + p.x * sin + p.z * cos,
                        )
                    })
                    .collect();
                PlaybackFrame {
                    joints,
                    ..f.clone()
                }
            })
            .collect();
        // The frame across the cut: blending starts from where the old clip was going.
        let (smooth, popped) = (largest_jump(&blended[..2]), largest_jump(&cut[..2]));
        assert!(
            smooth < 0.7 * popped,
            "{}: blended {smooth} m vs cut {popped} m",
            g.behaviour
        );
        // After the window the body is wholly in the target clip.
        let last = blended.last().unwrap();
        let (sin, cos) = last.heading.sin_cos();
        for (p, q) in g.pose(last.node).iter().zip(&last.joints) {
            let expected = DVec3::new(
                last.root.x + p.x * cos - p.z * sin,
                p.y,
                last.root.y + p.x * sin + p.z * cos,
            );
            assert!((expected - *q).length() < 1e-9);
        }
    }

    #[test]
    fn the_root_follows_the_steps() {
        let g = fixtures::graph();
        let start = g.default_start();
        let mut walk = vec![];
        let mut node = start;
        for _ in 0..30 {
            let i = g.out_edges(node).start;
            walk.push(i as u32);
            node = g.edges[i].to;
        }
        let frames = g.playback(start, DVec2::new(1.0, 2.0), 0.0, &walk);
        assert_eq!(frames.len(), 31);
        // The fixture jogs straight along +x at 3.5 m/s: 30 frames is 3.5 m.
        let moved = frames[30].root - frames[0].root;
        assert!((moved - DVec2::new(3.5, 0.0)).length() < 0.05, "{moved}");
        // Joints sit around the root, the hips at about hip height.
        assert!((frames[30].joints[0].y - 0.95).abs() < 0.05);
    }
}
