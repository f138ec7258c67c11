//! Shapes that tell the catching theories apart: how a fielder's path bends, and how
//! straight the ball's optical trajectory stays.

use super::strategy::CLEARLY_ABOVE_EYE_TAN_PSI;
use glam::{DVec2, DVec3};
use serde::Serialize;

/// A run's bend relative to the straight line (chord) from where the fielder started to
/// where it ended.
///
/// The signed deviation of each point is its distance from the chord, positive on the
/// side of home plate. A path that *bulges toward home* bends toward the batter (mean
/// deviation > 0), one that *bulges away from home* bends away (< 0); a path whose
/// largest deviation is under 2 % of the chord (or 0.25 m) counts as straight. The
/// shapes are named by their geometry: "concave" and "convex" are used both ways round
/// in the literature (Gillies & Dodgson call LOT's paths, which bulge away from home,
/// convex), so they name nothing here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub(crate) enum PathShape {
    Straight,
    BulgesTowardHome,
    BulgesAwayFromHome,
}

impl PathShape {
    /// The shape of `path` (the fielder's positions on the ground) with home plate at
    /// `home`.
    pub(crate) fn of(path: &[DVec2], home: DVec2) -> PathShape {
        let Some(d) = Deviation::of(path, home) else {
            return PathShape::Straight;
        };
        if d.max_abs < (0.02 * d.chord).max(0.25) {
            PathShape::Straight
        } else if d.sum > 0.0 {
            PathShape::BulgesTowardHome
        } else {
            PathShape::BulgesAwayFromHome
        }
    }
}

/// How far a path strays from its chord, as a share of the chord's length: the largest
/// deviation, signed by the side the path bulges to on the whole (positive toward home).
/// 0.5 is a half circle; Gillies & Dodgson's "very convex" paths are the large ones.
pub(crate) fn bulge(path: &[DVec2], home: DVec2) -> Option<f64> {
    let d = Deviation::of(path, home)?;
    Some(d.max_abs / d.chord * d.sum.signum())
}

/// A path's deviations from its chord (positive on home plate's side): the largest in
/// size and their sum; `None` for a path that goes nowhere.
struct Deviation {
    chord: f64,
    max_abs: f64,
    sum: f64,
}

impl Deviation {
    fn of(path: &[DVec2], home: DVec2) -> Option<Deviation> {
        let (&start, &end) = (path.first()?, path.last()?);
        let chord = end - start;
        let length = chord.length();
        if length < 1e-9 {
            return None;
        }
        let normal = DVec2::new(-chord.y, chord.x) / length;
        // Orient the normal toward home so a positive deviation means "toward the batter".
        let toward_home = if (home - start).dot(normal) >= 0.0 {
            1.0
        } else {
            -1.0
        };
        let (mut max_abs, mut sum) = (0.0f64, 0.0);
        for p in path {
            let dev = (*p - start).dot(normal) * toward_home;
            max_abs = max_abs.max(dev.abs());
            sum += dev;
        }
        Some(Deviation {
            chord: length,
            max_abs,
            sum,
        })
    }
}

/// Running sums for two straightness measures of what the fielder saw, accumulated a
/// tick at a time so a sweep never stores a trace.
///
/// * `tan_psi_r2`: R² of a straight-line fit of tan ψ against time. Chapman's law holds
///   it at 1.
/// * `image_r2`: how much of the scatter of the image points (u, v) — the ball projected
///   on a plane facing home plate — lies along their principal axis, λ_max/(λ_max+λ_min).
///   An image that rises along a straight line (LOT) gives 1.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct OpticalFit {
    n: f64,
    t: Moments,
    tan_psi: Moments,
    u: Moments,
    v: Moments,
    t_tan_psi: f64,
    uv: f64,
}

#[derive(Debug, Clone, Copy, Default)]
struct Moments {
    sum: f64,
    sum_sq: f64,
}

impl Moments {
    fn add(&mut self, x: f64) {
        self.sum += x;
        self.sum_sq += x * x;
    }
}

impl OpticalFit {
    /// Adds the sighting at time `t` of the ball at `ball` from a fielder at `fielder`
    /// with its eye `eye` m up, facing home plate at `home`; a sighting the measures
    /// should not count (see `counts_optically`) is skipped.
    pub(crate) fn add(&mut self, t: f64, ball: DVec3, fielder: DVec2, home: DVec2, eye: f64) {
        if !counts_optically(ball, fielder, eye) {
            return;
        }
        let r = DVec2::new(ball.x, ball.z) - fielder;
        let forward = (home - fielder).normalize_or(DVec2::X);
        let depth = r.dot(forward);
        let tan_psi = (ball.y - eye) / r.length();
        self.n += 1.0;
        self.t.add(t);
        self.tan_psi.add(tan_psi);
        self.t_tan_psi += t * tan_psi;
        if depth > 0.0 {
            let (u, v) = (
                r.dot(DVec2::new(-forward.y, forward.x)) / depth,
                (ball.y - eye) / depth,
            );
            self.u.add(u);
            self.v.add(v);
            self.uv += u * v;
        }
    }

    fn covariance(&self, a: &Moments, b: &Moments, ab: f64) -> f64 {
        ab / self.n - (a.sum / self.n) * (b.sum / self.n)
    }

    /// `None` with fewer than three samples.
    pub(crate) fn tan_psi_r2(&self) -> Option<f64> {
        if self.n < 3.0 {
            return None;
        }
        let var_t = self.covariance(&self.t, &self.t, self.t.sum_sq);
        let var_p = self.covariance(&self.tan_psi, &self.tan_psi, self.tan_psi.sum_sq);
        let cov = self.covariance(&self.t, &self.tan_psi, self.t_tan_psi);
        Some(if var_p <= 0.0 {
            1.0
        } else {
            (cov * cov / (var_t * var_p)).min(1.0)
        })
    }

    /// `None` with fewer than three samples.
    pub(crate) fn image_r2(&self) -> Option<f64> {
        if self.n < 3.0 {
            return None;
        }
        let a = self.covariance(&self.u, &self.u, self.u.sum_sq);
        let c = self.covariance(&self.v, &self.v, self.v.sum_sq);
        let b = self.covariance(&self.u, &self.v, self.uv);
        let half_trace = 0.5 * (a + c);
        let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let (l_max, l_min) = (half_trace + root, (half_trace - root).max(0.0));
        Some(if l_max <= 0.0 {
            1.0
        } else {
            l_max / (l_max + l_min)
        })
    }
}

/// Whether a sighting is one the optical measures should count: ball clearly above the
/// eye and not yet nearly overhead (where tan ψ runs off to infinity for every strategy
/// that is about to miss, and says nothing about the image path before it).
fn counts_optically(ball: DVec3, fielder: DVec2, eye: f64) -> bool {
    let d = (DVec2::new(ball.x, ball.z) - fielder).length();
    d > 2.0 && (ball.y - eye) / d > CLEARLY_ABOVE_EYE_TAN_PSI
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_are_classified_by_their_bulge_relative_to_home() {
        let home = DVec2::ZERO;
        // A run from (50, −10) to (50, 10): the chord is parallel to z at x = 50.
        let arc = |bulge: f64| -> Vec<DVec2> {
            (0..=20)
                .map(|i| {
                    let s = i as f64 / 20.0;
                    DVec2::new(50.0 + bulge * 4.0 * s * (1.0 - s), -10.0 + 20.0 * s)
                })
                .collect()
        };
        assert_eq!(PathShape::of(&arc(-3.0), home), PathShape::BulgesTowardHome);
        assert_eq!(
            PathShape::of(&arc(3.0), home),
            PathShape::BulgesAwayFromHome
        );
        assert_eq!(PathShape::of(&arc(0.1), home), PathShape::Straight);
    }

    #[test]
    fn a_bulge_is_the_largest_deviation_over_the_chord_signed_toward_home() {
        let home = DVec2::ZERO;
        // A half circle of radius 5 away from home over a chord of 10: 5 / 10.
        let half_circle: Vec<DVec2> = (0..=180)
            .map(|k| {
                let a = (k as f64).to_radians();
                DVec2::new(50.0 + 5.0 * a.sin(), -5.0 * a.cos())
            })
            .collect();
        assert!((bulge(&half_circle, home).unwrap() + 0.5).abs() < 1e-9);
        // Mirrored toward home: +0.5; a straight run: 0; a run that goes nowhere: none.
        let mirrored: Vec<DVec2> = half_circle
            .iter()
            .map(|p| DVec2::new(100.0 - p.x, p.y))
            .collect();
        assert!((bulge(&mirrored, home).unwrap() - 0.5).abs() < 1e-9);
        let line = [DVec2::new(50.0, -5.0), DVec2::new(50.0, 5.0)];
        assert_eq!(bulge(&line, home), Some(0.0));
        assert_eq!(bulge(&[DVec2::ONE, DVec2::ONE], home), None);
    }
}
