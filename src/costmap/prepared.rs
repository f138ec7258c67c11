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
    pub fn new(graph: &MotionGraph, enabled: &[bool]) -> Prepared {
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
    pub fn out(&self, node: u32) -> &[PreparedEdge] {
        &self.edges[self.start[node as usize]..self.start[node as usize + 1]]
    }
}
