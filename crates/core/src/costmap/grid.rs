//! The square grid a cost map covers, centred on the agent in its own frame (the agent at
//! (0, 0) facing +x), and the obstacles that block it.
//!
//! With y up and right-handed axes, +z is on the agent's *right* when it faces +x. ("+z
//! is to its left" only holds in a mirror image, and real motion capture confirms the
//! handedness: see `motion::Clip`. A clip and its mirror image are both played, each with
//! its own handedness kept, so a left turn in the data is a left turn on the map, toward
//! −z.)

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// An n × n grid of square cells centred on the agent, in its frame: x ahead, z on its
/// right, m.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// Side of the whole grid, m: a whole number of cells.
    pub size_m: f64,
    /// Side of a cell, m.
    pub cell_m: f64,
    /// Cells along each side.
    pub n: usize,
}

impl Grid {
    /// A grid of side `size_m` (rounded up to whole cells) and cells of `cell_m`.
    pub fn new(size_m: f64, cell_m: f64) -> Grid {
        let n = (size_m / cell_m).ceil().max(1.0) as usize;
        Grid {
            size_m: n as f64 * cell_m,
            cell_m,
            n,
        }
    }

    /// Cells in the grid: n².
    pub fn cells(&self) -> usize {
        self.n * self.n
    }

    /// Corner of the grid with the smallest x and z.
    pub fn origin(&self) -> DVec2 {
        DVec2::splat(-0.5 * self.size_m)
    }

    /// Index `i * n + j` of the cell holding `p` (row i along z, column j along x).
    pub fn cell_of(&self, p: DVec2) -> Option<usize> {
        cell_index((p - self.origin()) / self.cell_m, self.n)
    }

    /// Centre of cell `index`.
    pub fn centre(&self, index: usize) -> DVec2 {
        let (i, j) = (index / self.n, index % self.n);
        self.origin()
            + DVec2::new(
                (j as f64 + 0.5) * self.cell_m,
                (i as f64 + 0.5) * self.cell_m,
            )
    }

    /// Distance from `p` to the nearest point of cell `index` (0 inside it).
    pub fn distance_to_cell(&self, p: DVec2, index: usize) -> f64 {
        let c = self.centre(index);
        let half = DVec2::splat(0.5 * self.cell_m);
        ((p - c).abs() - half).max(DVec2::ZERO).length()
    }
}

/// The index `i * n + j` of the unit cell holding `rel` (in cell units from the grid's
/// corner), or `None` outside the n × n grid. Truncation is the floor for the
/// non-negative values that can be inside, and unlike `f64::floor` it needs no call into
/// libm on baseline x86-64: this runs for every frame of every walk.
#[inline]
pub(crate) fn cell_index(rel: DVec2, n: usize) -> Option<usize> {
    let inside = rel.x >= 0.0 && rel.y >= 0.0 && rel.x < n as f64 && rel.y < n as f64;
    inside.then(|| rel.y as usize * n + rel.x as usize)
}

/// An axis-aligned rectangle on the ground that no path may enter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Obstacle {
    /// The corner with the smallest x and z, m.
    pub min: DVec2,
    /// The corner with the largest x and z, m.
    pub max: DVec2,
}

impl Obstacle {
    /// The rectangle with corners (x0, z0) and (x1, z1), in either order.
    pub fn new(a: DVec2, b: DVec2) -> Obstacle {
        Obstacle {
            min: a.min(b),
            max: a.max(b),
        }
    }

    pub(crate) fn contains(&self, p: DVec2) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

/// Whether any obstacle holds `p`.
pub(super) fn blocked(obstacles: &[Obstacle], p: DVec2) -> bool {
    obstacles.iter().any(|o| o.contains(p))
}

/// Where an agent stands in the world and which way it faces (radians from +x toward +z).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AgentPose {
    /// Where it stands on the ground, (x, z), m.
    pub position: DVec2,
    /// Which way it faces: radians from +x toward +z.
    pub heading: f64,
}

impl AgentPose {
    /// A world point in this agent's frame: the frame a cost map is built in. This is how
    /// a map embeds anywhere: without obstacles it is the same for every pose.
    pub fn to_local(&self, world: DVec2) -> DVec2 {
        (world - self.position).rotate(DVec2::from_angle(-self.heading))
    }

    /// [`AgentPose::to_local`] with the rotation worked out once, for the many look-ups
    /// of one decision.
    pub fn frame(&self) -> LocalFrame {
        LocalFrame {
            position: self.position,
            unrotate: DVec2::from_angle(-self.heading),
        }
    }
}

/// A lattice of world points in an agent's frame ([`LocalFrame::lattice`]).
#[derive(Debug, Clone, PartialEq)]
pub struct LocalLattice {
    /// Per column x: (x − x₀)·cos, (x − x₀)·sin of the frame's unrotation.
    columns: Vec<[f64; 2]>,
    /// Per row z: (z − z₀)·sin, (z − z₀)·cos.
    rows: Vec<[f64; 2]>,
}

impl LocalLattice {
    /// The point of row `i` and column `j`, in the frame.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> DVec2 {
        let (col, row) = (self.columns[j], self.rows[i]);
        // (dx, dz) rotated by (c, s): (dx·c − dz·s, dz·c + dx·s), as `DVec2::rotate`.
        DVec2::new(col[0] - row[0], row[1] + col[1])
    }
}

/// An agent's frame, ready to take many world points into it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    position: DVec2,
    unrotate: DVec2,
}

impl LocalFrame {
    #[inline]
    pub(crate) fn to_local(self, world: DVec2) -> DVec2 {
        (world - self.position).rotate(self.unrotate)
    }

    /// The points of a lattice (each x of `xs` with each z of `zs`) ready to be taken
    /// into this frame: the products of the rotation are worked out once per column and
    /// per row instead of once per point. [`LocalLattice::at`] is bit for bit what
    /// `LocalFrame::to_local` gives, since each product has the same operands and the
    /// sums the same terms.
    pub fn lattice(self, xs: &[f64], zs: &[f64]) -> LocalLattice {
        let (c, s) = (self.unrotate.x, self.unrotate.y);
        LocalLattice {
            columns: xs
                .iter()
                .map(|&x| {
                    let dx = x - self.position.x;
                    [dx * c, dx * s]
                })
                .collect(),
            rows: zs
                .iter()
                .map(|&z| {
                    let dz = z - self.position.y;
                    [dz * s, dz * c]
                })
                .collect(),
        }
    }

    /// A point of the agent's frame in the world: the inverse of [`AgentPose::to_local`],
    /// without the trigonometry.
    #[inline]
    pub fn to_world(&self, local: DVec2) -> DVec2 {
        // Rotating back by the heading is rotating by the conjugate of `unrotate`.
        self.position + local.rotate(DVec2::new(self.unrotate.x, -self.unrotate.y))
    }

    /// Where the agent stands.
    pub fn origin(&self) -> DVec2 {
        self.position
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A lattice's points are the frame's own `to_local` of them, bit for bit, for
        /// any pose and any lattice: decisions made with either are the same.
        #[test]
        fn a_lattice_is_to_local_bit_for_bit(
            x0 in -50.0f64..50.0,
            z0 in -50.0f64..50.0,
            heading in -10.0f64..10.0,
            xs in proptest::collection::vec(-100.0f64..100.0, 1..8),
            zs in proptest::collection::vec(-100.0f64..100.0, 1..8),
        ) {
            let frame = AgentPose { position: DVec2::new(x0, z0), heading }.frame();
            let lattice = frame.lattice(&xs, &zs);
            for (i, &z) in zs.iter().enumerate() {
                for (j, &x) in xs.iter().enumerate() {
                    let direct = frame.to_local(DVec2::new(x, z));
                    let at = lattice.at(i, j);
                    prop_assert_eq!(direct.x.to_bits(), at.x.to_bits());
                    prop_assert_eq!(direct.y.to_bits(), at.y.to_bits());
                }
            }
        }
    }

    #[test]
    fn cells_and_centres_agree() {
        let g = Grid::new(20.0, 0.5);
        assert_eq!(g.n, 40);
        for index in [0, 39, 40, 820, 1599] {
            assert_eq!(g.cell_of(g.centre(index)), Some(index));
        }
        assert_eq!(g.cell_of(DVec2::new(10.0, 0.0)), None);
        // The agent stands on a cell corner at the very centre.
        assert_eq!(
            g.centre(g.cell_of(DVec2::new(0.1, 0.1)).unwrap()),
            DVec2::new(0.25, 0.25)
        );
        assert_eq!(
            g.distance_to_cell(DVec2::ZERO, g.cell_of(DVec2::new(3.2, 0.1)).unwrap()),
            3.0
        );
    }

    #[test]
    fn poses_round_trip_and_face_their_heading() {
        let pose = AgentPose {
            position: DVec2::new(3.0, -2.0),
            heading: 1.0,
        };
        let w = DVec2::new(-4.0, 7.5);
        assert!((pose.frame().to_world(pose.to_local(w)) - w).length() < 1e-12);
        assert!((pose.frame().to_local(w) - pose.to_local(w)).length() < 1e-12);
        // One metre straight ahead of the agent is (1, 0) in its frame.
        let ahead = pose.position + DVec2::from_angle(1.0);
        assert!((pose.to_local(ahead) - DVec2::X).length() < 1e-12);
    }
}
