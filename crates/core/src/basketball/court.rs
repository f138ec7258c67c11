//! The half court: FIBA dimensions, in the ground plane of the simulation (y up).
//!
//! x runs from the baseline (x = 0) to the half-court line (x = 14 m); z runs across the
//! court, from −7.5 m to 7.5 m, with the basket on z = 0. The offense attacks toward −x.

use super::shot::ShotModel;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The half court's dimensions and the squares a shooter considers. Points are (x, z)
/// on the floor, m: x from the baseline, z across, the basket on z = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Court {
    /// Baseline to half-court line, m (FIBA: 14).
    pub length_m: f64,
    /// Sideline to sideline, m (FIBA: 15).
    pub width_m: f64,
    /// The centre of the ring above the floor, projected onto it, [x, z], m.
    pub basket: DVec2,
    /// The backboard's face, m from the baseline (FIBA: 1.2, the ring's centre 0.375 m in
    /// front of it): no shot goes in from behind its plane.
    pub backboard_m: f64,
    /// Distance of the three-point line from the basket, m (FIBA: 6.75).
    pub three_point_m: f64,
    /// Side of a square the shooter considers, m.
    pub square_m: f64,
}

impl Default for Court {
    fn default() -> Self {
        Court {
            length_m: 14.0,
            width_m: 15.0,
            basket: DVec2::new(1.575, 0.0),
            backboard_m: 1.2,
            three_point_m: 6.75,
            square_m: 0.5,
        }
    }
}

impl Court {
    /// Whether `p` is on the court, lines included.
    pub fn contains(&self, p: DVec2) -> bool {
        (0.0..=self.length_m).contains(&p.x) && p.y.abs() <= 0.5 * self.width_m
    }

    /// How far `p` is inside the court from its nearest line, m (negative outside).
    pub fn inside_by(&self, p: DVec2) -> f64 {
        let half = 0.5 * self.width_m;
        p.x.min(self.length_m - p.x).min(half - p.y.abs())
    }

    /// The nearest point on the court.
    pub fn clamp(&self, p: DVec2) -> DVec2 {
        let half = 0.5 * self.width_m;
        DVec2::new(p.x.clamp(0.0, self.length_m), p.y.clamp(-half, half))
    }

    pub(crate) fn distance_to_basket(&self, p: DVec2) -> f64 {
        p.distance(self.basket)
    }

    /// The chance a shot from `p` goes in: `shot`'s, by the distance to the basket, and
    /// none from behind the backboard's plane (the board is between the ball and the
    /// ring) or off the court.
    pub fn shot_success(&self, shot: &ShotModel, p: DVec2) -> f64 {
        if !self.contains(p) || p.x < self.backboard_m {
            return 0.0;
        }
        shot.success(self.distance_to_basket(p))
    }

    /// Points a made shot from `p` scores.
    pub fn points(&self, p: DVec2) -> u32 {
        if self.distance_to_basket(p) > self.three_point_m {
            3
        } else {
            2
        }
    }

    /// Squares along x and along z.
    pub fn squares_xz(&self) -> (usize, usize) {
        (
            (self.length_m / self.square_m).floor() as usize,
            (self.width_m / self.square_m).floor() as usize,
        )
    }

    /// The centre of square `index`, counted row by row (z outer, x inner).
    pub fn square_centre(&self, index: usize) -> DVec2 {
        let (nx, nz) = self.squares_xz();
        let (i, j) = (index / nx, index % nx);
        DVec2::new(
            (j as f64 + 0.5) * self.square_m,
            (i as f64 + 0.5 - 0.5 * nz as f64) * self.square_m,
        )
    }

    /// The centres of every square of the court, in index order.
    pub fn square_centres(&self) -> Vec<DVec2> {
        let (nx, nz) = self.squares_xz();
        (0..nx * nz).map(|k| self.square_centre(k)).collect()
    }

    /// The index (into [`Court::square_centres`]) of the square holding `p`.
    pub fn square_of(&self, p: DVec2) -> Option<usize> {
        let (nx, nz) = self.squares_xz();
        let j = p.x / self.square_m;
        let i = (p.y + 0.5 * nz as f64 * self.square_m) / self.square_m;
        (j >= 0.0 && i >= 0.0 && (j as usize) < nx && (i as usize) < nz)
            .then(|| i as usize * nx + j as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squares_tile_the_court_and_find_their_centres() {
        let court = Court::default();
        let centres = court.square_centres();
        assert_eq!(centres.len(), 28 * 30);
        for (k, c) in centres.iter().enumerate() {
            assert!(court.contains(*c));
            assert_eq!(court.square_of(*c), Some(k));
        }
        assert_eq!(court.square_of(DVec2::new(-0.1, 0.0)), None);
        assert_eq!(court.square_of(DVec2::new(1.0, 7.6)), None);
    }

    /// Behind the backboard's plane a shot cannot go in, however near the ring; just in
    /// front of it, the shot model's chance; off the court, none.
    #[test]
    fn no_shot_goes_in_from_behind_the_backboard() {
        let court = Court::default();
        let shot = ShotModel::default();
        let behind = DVec2::new(court.backboard_m - 0.05, 0.8);
        assert!(court.basket.distance(behind) < 1.0);
        assert_eq!(court.shot_success(&shot, behind), 0.0);
        let front = DVec2::new(court.backboard_m + 0.05, 0.8);
        assert_eq!(court.shot_success(&shot, front), shot.cap);
        assert_eq!(court.shot_success(&shot, DVec2::new(5.0, 7.6)), 0.0);
        let far = DVec2::new(9.0, 0.0);
        assert_eq!(court.shot_success(&shot, far), shot.success(9.0 - 1.575));
    }

    #[test]
    fn three_pointers_start_at_the_arc() {
        let court = Court::default();
        assert_eq!(court.points(court.basket + DVec2::new(6.7, 0.0)), 2);
        assert_eq!(court.points(court.basket + DVec2::new(6.8, 0.0)), 3);
    }
}
