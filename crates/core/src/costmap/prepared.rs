//! The motion graph as the map builders walk it: only enabled edges, each with its turn
//! precomputed as a unit complex number.

use crate::motion::{MotionGraph, RootStep};
use glam::DVec2;

pub(crate) struct PreparedEdge {
    pub id: u32,
    pub to: u32,
    pub step: RootStep,
    pub turn: DVec2,
    pub frames: u32,
}

pub(crate) struct Prepared {
    edges: Vec<PreparedEdge>,
    start: Vec<usize>,
}

impl Prepared {
    pub(super) fn new(graph: &MotionGraph, enabled: &[bool]) -> Prepared {
        let mut edges = Vec::with_capacity(graph.edges.len());
        let mut start = Vec::with_capacity(graph.node_count() + 1);
        for node in 0..graph.node_count() as u32 {
            start.push(edges.len());
            for i in graph.out_edges(node).filter(|&i| enabled[i]) {
                let e = &graph.edges[i];
                edges.push(PreparedEdge {
                    id: i as u32,
                    to: e.to,
                    step: e.step,
                    turn: DVec2::from_angle(e.step.dheading),
                    frames: e.frames,
                });
            }
        }
        start.push(edges.len());
        Prepared { edges, start }
    }

    /// The enabled edges leaving `node`.
    #[inline]
    pub(super) fn out(&self, node: u32) -> &[PreparedEdge] {
        &self.edges[self.start[node as usize]..self.start[node as usize + 1]]
    }

    /// The graph compressed to clips between branch points: from every branch node (one
    /// where a walk has a choice, and, if `at_meetings`, one where walks meet), each way
    /// out followed frame by frame to the next branch node. A walk's only decisions are
    /// at choices, so a search need only tell states apart there; a forward search that
    /// merges walks also wants the meetings, where walks from different places join.
    pub(super) fn segments(&self, nodes: usize, at_meetings: bool) -> Segments {
        let mut in_degree = vec![0u32; nodes];
        for e in &self.edges {
            in_degree[e.to as usize] += 1;
        }
        let branch: Vec<bool> = (0..nodes as u32)
            .map(|n| self.out(n).len() != 1 || (at_meetings && in_degree[n as usize] != 1))
            .collect();
        let mut start = vec![0; nodes + 1];
        let mut segments = Vec::new();
        let mut steps = Vec::new();
        for n in 0..nodes {
            start[n] = segments.len();
            if !branch[n] {
                continue;
            }
            for first in self.start[n]..self.start[n + 1] {
                let from = steps.len();
                let mut i = first;
                loop {
                    steps.push(i);
                    let to = self.edges[i].to as usize;
                    // A cycle with no branch node cannot occur in a strongly connected
                    // graph with a branch, but never loop forever on one.
                    if branch[to] || steps.len() - from > nodes {
                        segments.push((from, steps.len(), to as u32));
                        break;
                    }
                    i = self.start[to];
                }
            }
        }
        start[nodes] = segments.len();
        Segments {
            start,
            segments,
            steps,
            branch,
        }
    }

    pub(super) fn edge(&self, index: usize) -> &PreparedEdge {
        &self.edges[index]
    }

    pub(super) fn edge_count(&self) -> usize {
        self.edges.len()
    }
}

/// See [`Prepared::segments`].
pub(crate) struct Segments {
    start: Vec<usize>,
    /// (first step, end of steps, branch node reached).
    segments: Vec<(usize, usize, u32)>,
    /// Indices into the prepared edges, segment after segment.
    steps: Vec<usize>,
    pub branch: Vec<bool>,
}

impl Segments {
    /// The segments leaving branch node `node`: where their frames start in
    /// [`Segments::step`] numbering, how many there are, and the branch node reached.
    pub(super) fn out(&self, node: u32) -> impl Iterator<Item = (usize, usize, u32)> + '_ {
        self.segments[self.start[node as usize]..self.start[node as usize + 1]]
            .iter()
            .map(|&(a, b, to)| (a, b - a, to))
    }

    /// The prepared-edge index of step `i`.
    pub(super) fn step(&self, i: usize) -> usize {
        self.steps[i]
    }
}
