//! Shapes that tell the catching theories apart: how a fielder's path bends, and how
//! straight the ball's optical trajectory stays.

use super::strategy::CLEARLY_ABOVE_EYE_TAN_PSI;
use glam::{DMat3, DVec2, DVec3};
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
pub enum PathShape {
    /// Its largest deviation is under 2 % of the chord (or 0.25 m).
    Straight,
    /// It bends toward the batter.
    BulgesTowardHome,
    /// It bends away from the batter.
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

/// What one fielder's run under one ball says about the catching theories: the path's
/// shape and bulge, and the optical signatures of OAC (`rate_drift`), LOT (`image_bend`)
/// and Chapman's lateral law (`bearing_sweep_deg`), each `None` where the run gave it
/// too little to measure (see `fieldhouse catch-sweep`'s columns and docs/catching.md).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Signatures {
    /// Straight, or which way it bulges.
    pub shape: PathShape,
    /// The largest deviation from the chord over the chord, positive toward home.
    pub bulge: Option<f64>,
    /// How much d(tan ψ)/dt changed relative to its mean: 0 under OAC.
    pub rate_drift: Option<f64>,
    /// How far the ball's image strayed from a straight line: 0 under LOT.
    pub image_bend: Option<f64>,
    /// How far the ball's bearing from the fielder turned, degrees: 0 under Chapman's
    /// lateral law.
    pub bearing_sweep_deg: Option<f64>,
}

impl Signatures {
    pub(crate) fn of(path: &[DVec2], home: DVec2, optical: &OpticalFit) -> Signatures {
        Signatures {
            shape: PathShape::of(path, home),
            bulge: bulge(path, home),
            rate_drift: optical.rate_drift(),
            image_bend: optical.image_bend(),
            bearing_sweep_deg: optical.bearing_sweep_deg(),
        }
    }
}

/// Many runs' signatures in sum, as `catch-sweep` and `fieldhouse replay paths` report
/// them: the share of each path shape, and the median of each measure over the runs
/// that have it (the upper median of an even count; `None` when no run has it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SignatureSummary {
    /// Share of runs whose path was straight.
    pub share_straight: f64,
    /// Share of runs whose path bulged toward home plate.
    pub share_bulging_toward_home: f64,
    /// Share of runs whose path bulged away from home plate.
    pub share_bulging_away_from_home: f64,
    /// Median bulge.
    pub median_bulge: Option<f64>,
    /// Median ṙ drift.
    pub median_rate_drift: Option<f64>,
    /// Median image bend.
    pub median_image_bend: Option<f64>,
    /// Median bearing sweep, degrees.
    pub median_bearing_sweep_deg: Option<f64>,
}

impl SignatureSummary {
    /// The summary of `runs`.
    pub fn of(runs: &[Signatures]) -> SignatureSummary {
        let share = |shape: PathShape| {
            runs.iter().filter(|s| s.shape == shape).count() as f64 / runs.len().max(1) as f64
        };
        let median = |f: fn(&Signatures) -> Option<f64>| {
            let mut xs: Vec<f64> = runs.iter().filter_map(f).collect();
            xs.sort_by(f64::total_cmp);
            xs.get(xs.len() / 2).copied()
        };
        SignatureSummary {
            share_straight: share(PathShape::Straight),
            share_bulging_toward_home: share(PathShape::BulgesTowardHome),
            share_bulging_away_from_home: share(PathShape::BulgesAwayFromHome),
            median_bulge: median(|s| s.bulge),
            median_rate_drift: median(|s| s.rate_drift),
            median_image_bend: median(|s| s.image_bend),
            median_bearing_sweep_deg: median(|s| s.bearing_sweep_deg),
        }
    }
}

/// One fielder's run under one ball, watched from outside a look at a time: where the
/// fielder was and where the ball was. A sweep knows its strategies' runs from the
/// inside; this measures a run whose brain the measurer cannot see (a bot's, read from a
/// match's recorded frames) with the very same signatures.
#[derive(Debug, Clone, Default)]
pub struct RunWatch {
    path: Vec<DVec2>,
    optical: OpticalFit,
}

impl RunWatch {
    /// The fielder at `fielder` on the ground sees the ball at `ball` at time `t`, its
    /// eye `eye` m up, home plate at `home`.
    pub fn look(&mut self, t: f64, ball: DVec3, fielder: DVec2, home: DVec2, eye: f64) {
        self.path.push(fielder);
        self.optical.add(t, ball, fielder, home, eye);
    }

    /// Where the fielder was as the ball's flight ended (caught or landed): the run's
    /// last point, though the ball is no longer seen there.
    pub fn arrive(&mut self, fielder: DVec2) {
        self.path.push(fielder);
    }

    /// The run's signatures so far.
    pub fn signatures(&self, home: DVec2) -> Signatures {
        Signatures::of(&self.path, home, &self.optical)
    }

    /// How far the fielder ran, m.
    pub fn path_length_m(&self) -> f64 {
        self.path.windows(2).map(|w| (w[1] - w[0]).length()).sum()
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

/// Running sums for the optical signatures of the catching theories, accumulated a
/// tick at a time so a sweep never stores a trace.
///
/// Each theory keeps one thing constant, so each measure asks how far the flight was from
/// that, relative to its own scale (an R² of a straight-line fit does not separate them:
/// the trend of a rising tan ψ dwarfs any curvature, and every strategy scores 0.98+):
///
/// * `rate_drift`: OAC (Chapman) holds d(tan ψ)/dt constant. Fit tan ψ(s) = a + b·s + c·s²
///   by least squares (s: time since the first counted look, up to S); the rate goes from
///   b to b + 2c·S while its mean is b + c·S, so the drift is |2c·S / (b + c·S)|: 0 for a
///   constant rate, 2/3 for tan ψ = 0.1 + 0.2·s + 0.05·s² over 2 s.
/// * `bearing_sweep_deg`: Chapman's lateral law (Tresilian's term) drives dα/dt to zero,
///   so the ball keeps its bearing from the fielder: the angle between the first and the
///   latest line of sight, 0 for a constant bearing. LOT lets the image slide along a
///   tilted line, which turns the bearing.
/// * `image_bend`: LOT (McBeath et al.) keeps the ball's image (u, v) on a straight line
///   (u, v: the tangents of the lateral and vertical angles on a plane facing home). With
///   λ_max ≥ λ_min the principal variances of the image points, the bend is
///   √(λ_min/λ_max): the scatter across the best line over the spread along it, 0 for a
///   straight image, 1 for points round a circle.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct OpticalFit {
    n: f64,
    /// Time of the first counted look, s.
    t0: Option<f64>,
    /// Time since `t0` of the latest, s.
    s_last: f64,
    /// Σ s^k for k = 1..4 and Σ s^k·tan ψ for k = 0..2.
    s_pow: [f64; 4],
    tan_psi_s_pow: [f64; 3],
    u: Moments,
    v: Moments,
    uv: f64,
    n_image: f64,
    /// The ball's first and latest counted bearings from the fielder (unit vectors).
    bearings: Option<(DVec2, DVec2)>,
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
        let s = t - *self.t0.get_or_insert(t);
        let bearing = r.normalize();
        self.bearings = Some(
            self.bearings
                .map_or((bearing, bearing), |(first, _)| (first, bearing)),
        );
        self.n += 1.0;
        self.s_last = s;
        let mut power = 1.0;
        for k in 0..4 {
            if k < 3 {
                self.tan_psi_s_pow[k] += power * tan_psi;
            }
            power *= s;
            self.s_pow[k] += power;
        }
        if depth > 0.0 {
            let (u, v) = (
                r.dot(DVec2::new(-forward.y, forward.x)) / depth,
                (ball.y - eye) / depth,
            );
            self.n_image += 1.0;
            self.u.add(u);
            self.v.add(v);
            self.uv += u * v;
        }
    }

    /// `None` with fewer than four looks, or looks the fit cannot tell apart.
    pub(crate) fn rate_drift(&self) -> Option<f64> {
        if self.n < 4.0 {
            return None;
        }
        let [s1, s2, s3, s4] = self.s_pow;
        let normal = DMat3::from_cols(
            DVec3::new(self.n, s1, s2),
            DVec3::new(s1, s2, s3),
            DVec3::new(s2, s3, s4),
        );
        if normal.determinant().abs() < 1e-12 {
            return None;
        }
        let [_, b, c] = (normal.inverse() * DVec3::from(self.tan_psi_s_pow)).to_array();
        let span = self.s_last;
        Some((2.0 * c * span / (b + c * span)).abs())
    }

    /// The angle between the ball's first and latest counted bearings, degrees; `None`
    /// before any look counts.
    pub(crate) fn bearing_sweep_deg(&self) -> Option<f64> {
        self.bearings.map(|(first, last)| {
            first
                .perp_dot(last)
                .atan2(first.dot(last))
                .abs()
                .to_degrees()
        })
    }

    /// `None` with fewer than three looks in front of the fielder.
    pub(crate) fn image_bend(&self) -> Option<f64> {
        if self.n_image < 3.0 {
            return None;
        }
        let n = self.n_image;
        let covariance = |a: &Moments, b: &Moments, ab: f64| ab / n - (a.sum / n) * (b.sum / n);
        let a = covariance(&self.u, &self.u, self.u.sum_sq);
        let c = covariance(&self.v, &self.v, self.v.sum_sq);
        let b = covariance(&self.u, &self.v, self.uv);
        let half_trace = 0.5 * (a + c);
        let root = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let (l_max, l_min) = (half_trace + root, (half_trace - root).max(0.0));
        Some(if l_max <= 0.0 {
            0.0
        } else {
            (l_min / l_max).sqrt()
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

    /// A fielder at the origin facing home far down −x: a ball `depth` m toward home,
    /// `u·depth` to the fielder's left and `v·depth` above the eye has image (u, v), and
    /// tan ψ = v / √(1 + u²).
    fn look(fit: &mut OpticalFit, t: f64, u: f64, v: f64) {
        let (eye, depth) = (1.7, 30.0);
        let ball = DVec3::new(-depth, eye + v * depth, -u * depth);
        fit.add(t, ball, DVec2::ZERO, DVec2::new(-1000.0, 0.0), eye);
    }

    #[test]
    fn rate_drift_is_zero_for_a_constant_rate_and_two_thirds_for_the_worked_quadratic() {
        let (mut constant, mut quadratic) = (OpticalFit::default(), OpticalFit::default());
        for k in 0..=120 {
            let s = k as f64 / 60.0;
            look(&mut constant, 1.0 + s, 0.0, 0.1 + 0.2 * s);
            look(&mut quadratic, 1.0 + s, 0.0, 0.1 + 0.2 * s + 0.05 * s * s);
        }
        assert!(constant.rate_drift().unwrap() < 1e-9);
        // 2c·S / (b + c·S) = 2·0.05·2 / (0.2 + 0.05·2).
        assert!((quadratic.rate_drift().unwrap() - 2.0 / 3.0).abs() < 1e-9);
        assert_eq!(OpticalFit::default().rate_drift(), None);
    }

    #[test]
    fn image_bend_is_zero_on_a_line_and_one_round_a_circle() {
        let (mut line, mut circle) = (OpticalFit::default(), OpticalFit::default());
        for k in 0..360 {
            let a = (k as f64).to_radians();
            look(&mut line, k as f64, 0.01 * k as f64, 0.1 + 0.02 * k as f64);
            look(&mut circle, k as f64, 0.3 * a.cos(), 0.5 + 0.3 * a.sin());
        }
        assert!(line.image_bend().unwrap() < 1e-6);
        assert!((circle.image_bend().unwrap() - 1.0).abs() < 1e-9);
    }

    /// A ball whose image slides sideways as it rises turns its bearing by atan(u) (the
    /// image plane faces along the fielder's line to home); one rising straight up the
    /// image keeps its bearing.
    #[test]
    fn bearing_sweep_is_the_turn_of_the_line_of_sight_in_degrees() {
        let (mut sliding, mut rising) = (OpticalFit::default(), OpticalFit::default());
        for k in 0..=100 {
            let s = k as f64 / 100.0;
            look(&mut sliding, s, s, 0.1 + s);
            look(&mut rising, s, 0.0, 0.1 + s);
        }
        assert!((sliding.bearing_sweep_deg().unwrap() - 45.0).abs() < 1e-9);
        assert!(rising.bearing_sweep_deg().unwrap() < 1e-9);
        assert_eq!(OpticalFit::default().bearing_sweep_deg(), None);
    }

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
