//! The root of a body walking the motion graph: where it is on the ground, which way it
//! faces, and how an edge's root step moves it. Cost maps and playback both walk with it.

use super::RootStep;
use glam::DVec2;

/// Root position and facing (a unit vector, so a step costs no trigonometry).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Walker {
    /// Root position on the ground, (x, z) in m.
    pub(crate) position: DVec2,
    /// Unit vector of the way it faces, (x, z).
    pub(crate) facing: DVec2,
}

impl Walker {
    /// At the origin facing +x: the agent's own frame.
    pub const START: Walker = Walker {
        position: DVec2::ZERO,
        facing: DVec2::X,
    };

    /// The walker after `step`: moved by (dx forward, dz toward its +z side) in its current frame, then
    /// turned by dheading. `turn` is (cos, sin) of the step's dheading, precomputed.
    #[inline]
    pub fn after(&self, step: &RootStep, turn: DVec2) -> Walker {
        let side = self.facing.perp();
        Walker {
            position: self.position + self.facing * step.dx + side * step.dz,
            facing: self.facing.rotate(turn).normalize(),
        }
    }

    /// The walker after `step`, computing the turn from the step's `dheading`.
    pub fn step(&self, step: &RootStep) -> Walker {
        self.after(step, DVec2::from_angle(step.dheading))
    }

    /// Heading in radians from +x toward +z.
    pub fn heading(&self) -> f64 {
        self.facing.y.atan2(self.facing.x)
    }
}
