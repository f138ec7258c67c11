//! The ground a stored move covers, worked out once per map cell so that checking a move
//! against the court costs a handful of points instead of a walk of every frame.
//!
//! A move is a polyline of root positions (one per data frame) in the agent's own frame.
//! The court, even with a margin around it, is convex, and a polyline lies in a convex
//! region exactly when the convex hull of its points does, which holds exactly when
//! every vertex of the hull does. A hull of a 100-frame path has a dozen vertices or so.

use super::court::Court;
use crate::costmap::LocalFrame;
use glam::DVec2;

#[derive(Debug, Clone, PartialEq)]
pub(super) struct Footprint {
    /// The farthest the move strays from where it starts, m: a start at least this far
    /// inside the court keeps the whole move on it, with no vertex to check.
    reach_m: f64,
    /// The convex hull of the move's points in the agent's frame, counter-clockwise.
    hull: Vec<DVec2>,
}

impl Footprint {
    /// The footprint of the move through `points` (in the agent's frame, starting at
    /// the origin).
    pub(super) fn of(points: impl IntoIterator<Item = DVec2>) -> Footprint {
        let mut points: Vec<DVec2> = points.into_iter().collect();
        let reach_m = points.iter().map(|p| p.length()).fold(0.0, f64::max);
        Footprint {
            reach_m,
            hull: convex_hull(&mut points),
        }
    }

    /// Whether the move, played from the agent whose frame is `frame`, stays on `court`
    /// or at most `margin_m` beyond its lines at every frame.
    pub(super) fn within(&self, frame: &LocalFrame, court: &Court, margin_m: f64) -> bool {
        court.inside_by(frame.origin()) + margin_m >= self.reach_m
            || self
                .hull
                .iter()
                .all(|&p| court.inside_by(frame.to_world(p)) >= -margin_m)
    }
}

/// The convex hull of `points`, counter-clockwise (x toward z), without collinear
/// points: Andrew's monotone chain. Sorts `points` in place.
fn convex_hull(points: &mut [DVec2]) -> Vec<DVec2> {
    points.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    if points.len() < 3 {
        let mut few = points.to_vec();
        few.dedup();
        return few;
    }
    let mut lower = half_hull(points.iter());
    let mut upper = half_hull(points.iter().rev());
    // Each chain ends where the other starts.
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// One chain of the hull over points sorted along it: a point that does not turn left
/// from the last two is not on the hull.
fn half_hull<'a>(points: impl Iterator<Item = &'a DVec2>) -> Vec<DVec2> {
    let mut chain: Vec<DVec2> = Vec::new();
    for &p in points {
        while let [.., o, a] = chain[..] {
            if (a - o).perp_dot(p - o) > 0.0 {
                break;
            }
            chain.pop();
        }
        chain.push(p);
    }
    chain
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn the_hull_of_a_square_with_points_inside_is_its_corners() {
        let mut points = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(1.0, 0.0), // on an edge: not a vertex
            DVec2::new(0.0, 2.0),
            DVec2::new(0.5, 1.5),
        ];
        let hull = convex_hull(&mut points);
        assert_eq!(
            hull,
            [
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(0.0, 2.0)
            ]
        );
    }

    #[test]
    fn every_point_lies_inside_its_hull_and_every_vertex_is_a_point() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for n in [1, 2, 3, 10, 200] {
            let points: Vec<DVec2> = (0..n)
                .map(|_| DVec2::new(rng.gen_range(-5.0..5.0), rng.gen_range(-5.0..5.0)))
                .collect();
            let hull = convex_hull(&mut points.clone());
            assert!(hull.iter().all(|v| points.contains(v)));
            if hull.len() < 3 {
                continue;
            }
            for &p in &points {
                for (k, &a) in hull.iter().enumerate() {
                    let b = hull[(k + 1) % hull.len()];
                    // Counter-clockwise: every point is on the left of every edge (or on it).
                    assert!((b - a).perp_dot(p - a) >= -1e-12, "{p} outside {a}–{b}");
                }
            }
        }
    }
}
