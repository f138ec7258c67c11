//! Parametric models of how soon a body reaches a point, fitted to its cost maps: the
//! baselines the human capability model has to beat.
//!
//! The paper's claim is that an agent modelling its opponent with capability maps built
//! from human motion decides better than one that does not. "Does not" must be a fair
//! rival: not a guess, but the model a game AI would use, with its parameters fitted to
//! the very maps the human model uses (never to game outcomes), so the comparison asks
//! whether the maps' detail pays, not whether a badly set constant loses.
//!
//! * [`Kinematic`]: a reaction time, a turn rate, an acceleration and a top speed
//!   forward, sideways and backward. The body turns in place until the point lies ahead,
//!   to a side or behind, then accelerates toward it from the speed it already has that
//!   way; the quickest of the four ways is the time.
//! * [`Isotropic`]: a reaction time and one speed, the same in every direction.
//!
//! Both are fitted by least squares over every cell a map reaches within
//! [`FIT_RADIUS_M`] and every start state, in seconds.

use super::capability::Mover;
use crate::costmap::CostMap;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Cells farther than this from the body do not enter a fit, m: a half court is 14 m by
/// 15 m, and a defender is rarely more than 10 m from where the ball goes.
pub const FIT_RADIUS_M: f64 = 10.0;

/// Reaction, turn, acceleration and direction-dependent top speed: what a game AI
/// would model an opponent's movement with.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kinematic {
    /// Time before the body does anything, s.
    pub reaction_s: f64,
    /// How fast it turns in place, rad/s.
    pub turn_rad_s: f64,
    /// Its acceleration (and braking), m/s².
    pub accel_m_s2: f64,
    /// Top speed running forward, m/s.
    pub forward_m_s: f64,
    /// Top speed sliding sideways (either side), m/s.
    pub sideways_m_s: f64,
    /// Top speed backing up, m/s.
    pub backward_m_s: f64,
}

/// One speed in every direction after a reaction time: a body that turns for free.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Isotropic {
    /// Time before it sets off, s.
    pub reaction_s: f64,
    /// Its speed once moving, m/s.
    pub speed_m_s: f64,
}

impl Isotropic {
    /// Seconds to reach `p` (the body's frame, or any frame: direction does not matter).
    pub fn seconds(&self, p: DVec2) -> f64 {
        self.reaction_s + p.length() / self.speed_m_s
    }
}

/// The four ways to face a point: (the bearing the point ends up at, which speed).
const WAYS: [(f64, Way); 4] = [
    (0.0, Way::Forward),
    (FRAC_PI_2, Way::Sideways),
    (-FRAC_PI_2, Way::Sideways),
    (PI, Way::Backward),
];

#[derive(Clone, Copy)]
enum Way {
    Forward,
    Sideways,
    Backward,
}

impl Kinematic {
    /// Seconds to reach `p`, in the body's frame (+x ahead, +z right), for a body moving
    /// at `velocity` (the same frame, m/s).
    pub fn seconds(&self, p: DVec2, velocity: DVec2) -> f64 {
        let d = p.length();
        if d < 1e-9 {
            return 0.0;
        }
        let bearing = p.y.atan2(p.x);
        let along = velocity.dot(p) / d;
        WAYS.iter()
            .map(|&(at, way)| {
                let turn = crate::motion::wrap_angle(bearing - at).abs();
                let top = match way {
                    Way::Forward => self.forward_m_s,
                    Way::Sideways => self.sideways_m_s,
                    Way::Backward => self.backward_m_s,
                };
                self.reaction_s + turn / self.turn_rad_s + travel_s(d, along, top, self.accel_m_s2)
            })
            .fold(f64::INFINITY, f64::min)
    }

    fn from_params(x: &[f64; 6]) -> Kinematic {
        Kinematic {
            reaction_s: x[0],
            turn_rad_s: x[1],
            accel_m_s2: x[2],
            forward_m_s: x[3],
            sideways_m_s: x[4],
            backward_m_s: x[5],
        }
    }

    /// The range each parameter is fitted in, in the order of the fields (reaction, turn,
    /// acceleration, forward, sideways, backward): wide round what bodies do (a sprinter
    /// accelerates at up to about 10 m/s² and runs 10–12 m/s) yet finite, so a map that
    /// never shows a movement (no backing up, no instant start) pins a parameter at a
    /// bound instead of sending it to 0 or infinity.
    pub const BOUNDS: [(f64, f64); 6] = [
        (0.01, 3.0),
        (0.5, 30.0),
        (0.5, 50.0),
        (0.05, 12.0),
        (0.05, 12.0),
        (0.05, 12.0),
    ];

    /// The model at `log_params` (logarithms of the parameters), each held within its
    /// [`Kinematic::BOUNDS`].
    fn from_log_params(log_params: &[f64; 6]) -> Kinematic {
        let mut x = [0.0; 6];
        for (k, (lo, hi)) in Self::BOUNDS.iter().enumerate() {
            x[k] = log_params[k].exp().clamp(*lo, *hi);
        }
        Kinematic::from_params(&x)
    }

    fn params(&self) -> [f64; 6] {
        [
            self.reaction_s,
            self.turn_rad_s,
            self.accel_m_s2,
            self.forward_m_s,
            self.sideways_m_s,
            self.backward_m_s,
        ]
    }
}

/// The least time to cover `d` metres along a line, starting at `u` m/s along it
/// (negative: moving away, which must first be braked), accelerating at `a` up to `v`.
/// It need not stop at the end: the body only has to get there.
pub fn travel_s(d: f64, u: f64, v: f64, a: f64) -> f64 {
    let (mut d, mut t, mut u) = (d, 0.0, u);
    if u < 0.0 {
        // Braking to a stop carries the body u²/2a further away.
        t += -u / a;
        d += u * u / (2.0 * a);
        u = 0.0;
    }
    let u = u.min(v);
    let to_top = (v * v - u * u) / (2.0 * a);
    if d <= to_top {
        t + ((u * u + 2.0 * a * d).sqrt() - u) / a
    } else {
        t + (v - u) / a + (d - to_top) / v
    }
}

/// One observation a model is fitted to: a point of a map, the velocity of the start
/// state the map is from, and the seconds the map gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The point, in the body's frame, m.
    pub at: DVec2,
    /// The start state's velocity, in the body's frame, m/s.
    pub velocity: DVec2,
    /// Seconds the map gives.
    pub seconds: f64,
}

/// The samples of a mover's maps: every cell within [`FIT_RADIUS_M`] each state's map
/// reaches, with that state's velocity.
pub fn samples(mover: &Mover) -> Vec<Sample> {
    mover
        .states
        .iter()
        .flat_map(|s| {
            let node = &mover.graph.nodes[s.state.node as usize];
            let velocity = DVec2::new(node.forward_speed, node.lateral_speed);
            map_samples(&s.map, velocity)
        })
        .collect()
}

fn map_samples(map: &CostMap, velocity: DVec2) -> impl Iterator<Item = Sample> + '_ {
    map.costs.iter().enumerate().filter_map(move |(cell, c)| {
        let at = map.grid.centre(cell);
        let frames = (*c)?;
        (at.length() <= FIT_RADIUS_M).then(|| Sample {
            at,
            velocity,
            seconds: f64::from(frames) / map.fps,
        })
    })
}

/// How well a model fits its samples.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitQuality {
    /// Samples fitted.
    pub samples: usize,
    /// Root-mean-square error, s.
    pub rms_s: f64,
    /// Mean error (model − map), s: positive when the model is slow on average.
    pub bias_s: f64,
    /// Share of the samples' variance the model explains.
    pub r2: f64,
}

/// How well `model` (seconds for a sample) fits `samples`.
pub fn quality(samples: &[Sample], model: impl Fn(&Sample) -> f64) -> FitQuality {
    let n = samples.len().max(1) as f64;
    let mean = samples.iter().map(|s| s.seconds).sum::<f64>() / n;
    let (mut sse, mut bias, mut sst) = (0.0, 0.0, 0.0);
    for s in samples {
        let e = model(s) - s.seconds;
        sse += e * e;
        bias += e;
        sst += (s.seconds - mean).powi(2);
    }
    FitQuality {
        samples: samples.len(),
        rms_s: (sse / n).sqrt(),
        bias_s: bias / n,
        r2: if sst > 0.0 { 1.0 - sse / sst } else { 0.0 },
    }
}

/// The isotropic model closest to `samples` by least squares (a straight line of
/// seconds against distance; closed form), with its fit. A reaction below zero or a
/// speed that is not finite and positive cannot be a body's: the fit is constrained to
/// a reaction of at least 0.
pub fn fit_isotropic(samples: &[Sample]) -> (Isotropic, FitQuality) {
    let n = samples.len().max(1) as f64;
    let (mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0);
    for s in samples {
        let (x, y) = (s.at.length(), s.seconds);
        sx += x;
        sy += y;
        sxx += x * x;
        sxy += x * y;
    }
    let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    let mut intercept = (sy - slope * sx) / n;
    let mut slope = slope;
    if intercept < 0.0 {
        // Through the origin instead.
        intercept = 0.0;
        slope = sxy / sxx;
    }
    let model = Isotropic {
        reaction_s: intercept,
        speed_m_s: 1.0 / slope.max(1e-6),
    };
    (model, quality(samples, |s| model.seconds(s.at)))
}

/// The kinematic model closest to `samples` by least squares, with its fit:
/// Levenberg–Marquardt over the logarithms of the six parameters (so every one stays
/// positive), from a few starts read off the samples (the time is a minimum over four
/// ways to move, so the error surface has kinks and more than one valley); the best fit
/// of all starts is kept. Each parameter is held within [`Kinematic::BOUNDS`]: beyond a
/// bound the error is flat, so the search stays there. Deterministic: the same samples
/// give the same model.
pub fn fit_kinematic(samples: &[Sample]) -> (Kinematic, FitQuality) {
    let (iso, _) = fit_isotropic(samples);
    let speed = iso.speed_m_s.max(0.5);
    let residuals = |x: &[f64; 6]| -> Vec<f64> {
        let k = Kinematic::from_log_params(x);
        samples
            .iter()
            .map(|s| k.seconds(s.at, s.velocity) - s.seconds)
            .collect()
    };
    let starts =
        [(1.0, 4.0, 3.0), (1.5, 2.0, 6.0), (2.0, 8.0, 2.0)].map(|(fast, turn, a)| Kinematic {
            reaction_s: iso.reaction_s.max(0.05),
            turn_rad_s: turn,
            accel_m_s2: a,
            forward_m_s: speed * fast,
            sideways_m_s: speed,
            backward_m_s: speed * 0.75,
        });
    let best = starts
        .iter()
        .map(|s| levenberg_marquardt(&residuals, s.params().map(f64::ln), 200))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("there are starts")
        .0;
    let model = Kinematic::from_log_params(&best);
    (model, quality(samples, |s| model.seconds(s.at, s.velocity)))
}

/// Minimises the sum of squares of `residuals` from `x0` by Levenberg–Marquardt
/// (forward-difference Jacobian, Marquardt's diagonal scaling, at most `iterations`
/// steps). Returns the best point and its sum of squares.
pub fn levenberg_marquardt<const N: usize>(
    residuals: &impl Fn(&[f64; N]) -> Vec<f64>,
    x0: [f64; N],
    iterations: usize,
) -> ([f64; N], f64) {
    let sum_sq = |r: &[f64]| r.iter().map(|e| e * e).sum::<f64>();
    let (mut x, mut r) = (x0, residuals(&x0));
    let mut cost = sum_sq(&r);
    let mut lambda = 1e-3;
    for _ in 0..iterations {
        // Jacobian columns by forward differences.
        let jacobian: Vec<Vec<f64>> = (0..N)
            .map(|k| {
                let h = 1e-6 * (1.0 + x[k].abs());
                let mut xh = x;
                xh[k] += h;
                residuals(&xh)
                    .iter()
                    .zip(&r)
                    .map(|(a, b)| (a - b) / h)
                    .collect()
            })
            .collect();
        let mut jtj = [[0.0; N]; N];
        let mut jtr = [0.0; N];
        for a in 0..N {
            jtr[a] = jacobian[a].iter().zip(&r).map(|(j, e)| j * e).sum();
            for b in 0..N {
                jtj[a][b] = jacobian[a]
                    .iter()
                    .zip(&jacobian[b])
                    .map(|(p, q)| p * q)
                    .sum();
            }
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut m = jtj;
            for (k, row) in m.iter_mut().enumerate() {
                row[k] += lambda * jtj[k][k].max(1e-12);
            }
            let Some(step) = solve(m, jtr.map(|v| -v)) else {
                lambda *= 10.0;
                continue;
            };
            let mut trial = x;
            for k in 0..N {
                trial[k] += step[k];
            }
            let rt = residuals(&trial);
            let ct = sum_sq(&rt);
            if ct < cost {
                improved = (cost - ct) > 1e-12 * cost;
                (x, r, cost) = (trial, rt, ct);
                lambda = (lambda / 3.0).max(1e-12);
                break;
            }
            lambda *= 3.0;
        }
        if !improved {
            break;
        }
    }
    (x, cost)
}

/// Solves `m`·x = `b` by Gaussian elimination with partial pivoting; `None` if `m` is
/// singular.
fn solve<const N: usize>(mut m: [[f64; N]; N], mut b: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[pivot][col].abs() < 1e-300 {
            return None;
        }
        m.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = m[col];
        for row in col + 1..N {
            let f = m[row][col] / pivot_row[col];
            for (x, p) in m[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let s: f64 = (row + 1..N).map(|k| m[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / m[row][row];
    }
    Some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance under constant acceleration from rest, then at top speed: the closed
    /// forms d = ½at² and d = v²/2a + v(t − v/a).
    #[test]
    fn travel_is_the_kinematics_of_a_speed_limited_start() {
        let (a, v) = (4.0, 6.0);
        // 2 m from rest: ½·4·t² = 2, t = 1 s, at 4 m/s (below the top).
        assert!((travel_s(2.0, 0.0, v, a) - 1.0).abs() < 1e-12);
        // 10 m: 4.5 m to reach 6 m/s in 1.5 s, then 5.5 m at 6 m/s.
        assert!((travel_s(10.0, 0.0, v, a) - (1.5 + 5.5 / 6.0)).abs() < 1e-12);
        // Already at top speed: d / v.
        assert!((travel_s(3.0, 6.0, v, a) - 0.5).abs() < 1e-12);
        // Moving away at 2 m/s: 0.5 s to stop, 0.5 m further, then 2.5 m from rest.
        let back = 0.5 + travel_s(2.5, 0.0, v, a);
        assert!((travel_s(2.0, -2.0, v, a) - back).abs() < 1e-12);
    }

    /// The model's ways: a point ahead is run to, one to the side slid to, one behind
    /// backed into, each at its own speed, with no turn; a point ahead-left at 45°
    /// needs a 45° turn first, and whichever way is quicker wins.
    #[test]
    fn the_quickest_way_wins() {
        let k = Kinematic {
            reaction_s: 0.2,
            turn_rad_s: PI,
            accel_m_s2: 1e6,
            forward_m_s: 6.0,
            sideways_m_s: 3.0,
            backward_m_s: 2.0,
        };
        let still = DVec2::ZERO;
        let close = |a: f64, b: f64| (a - b).abs() < 1e-4;
        assert!(close(k.seconds(DVec2::new(6.0, 0.0), still), 0.2 + 1.0));
        assert!(close(k.seconds(DVec2::new(0.0, 3.0), still), 0.2 + 1.0));
        assert!(close(k.seconds(DVec2::new(0.0, -3.0), still), 0.2 + 1.0));
        // 2 m behind: backing up takes 1 s; turning round (1 s) and running, 1.33 s.
        assert!(close(k.seconds(DVec2::new(-2.0, 0.0), still), 0.2 + 1.0));
        // 20 m behind: backing up 10 s; turning 1 s and running 3.33 s.
        assert!(close(
            k.seconds(DVec2::new(-20.0, 0.0), still),
            0.2 + 1.0 + 20.0 / 6.0
        ));
        // 45° off: turn ¼ s, then run √2·3 m; or turn ¼ s the other way and slide.
        let p = DVec2::new(3.0, 3.0);
        let d = p.length();
        assert!(close(
            k.seconds(p, still),
            0.2 + 0.25 + (d / 6.0).min(d / 3.0)
        ));
    }

    /// Samples made by a known kinematic model (a grid of points, three start
    /// velocities) are fitted back to that model: the fit's own oracle.
    #[test]
    fn a_fit_recovers_the_model_that_made_its_samples() {
        let truth = Kinematic {
            reaction_s: 0.25,
            turn_rad_s: 4.0,
            accel_m_s2: 3.5,
            forward_m_s: 4.5,
            sideways_m_s: 2.5,
            backward_m_s: 1.8,
        };
        let mut samples = Vec::new();
        for velocity in [DVec2::ZERO, DVec2::new(2.0, 0.0), DVec2::new(0.0, -1.5)] {
            for i in -12..=12 {
                for j in -12..=12 {
                    let at = DVec2::new(f64::from(i) * 0.5, f64::from(j) * 0.5);
                    samples.push(Sample {
                        at,
                        velocity,
                        seconds: truth.seconds(at, velocity),
                    });
                }
            }
        }
        let (fitted, q) = fit_kinematic(&samples);
        assert!(q.rms_s < 0.01, "{q:?} {fitted:?}");
        let (a, b) = (fitted.params(), truth.params());
        for k in 0..6 {
            assert!(
                (a[k] - b[k]).abs() < 0.05 * b[k],
                "{fitted:?} against {truth:?}"
            );
        }
    }

    /// A body that reaches top speed at once (the limit the running capture comes close
    /// to) has no finite best acceleration: the fit stops at its bound rather than
    /// running off to infinity, and still reproduces the samples.
    #[test]
    fn a_parameter_the_samples_cannot_bound_stops_at_its_bound() {
        let truth = Kinematic {
            reaction_s: 0.1,
            turn_rad_s: 3.0,
            accel_m_s2: 1e9,
            forward_m_s: 5.0,
            sideways_m_s: 2.0,
            backward_m_s: 1.0,
        };
        let samples: Vec<Sample> = (-10..=10)
            .flat_map(|i| (-10..=10).map(move |j| DVec2::new(f64::from(i), f64::from(j))))
            .map(|at| Sample {
                at,
                velocity: DVec2::ZERO,
                seconds: truth.seconds(at, DVec2::ZERO),
            })
            .collect();
        let (fitted, q) = fit_kinematic(&samples);
        for (value, (lo, hi)) in fitted.params().iter().zip(Kinematic::BOUNDS) {
            assert!((lo..=hi).contains(value), "{fitted:?}");
        }
        assert!(fitted.accel_m_s2 > 40.0, "{fitted:?}");
        assert!(q.rms_s < 0.02, "{q:?} {fitted:?}");
    }

    /// Seconds exactly linear in distance are fitted exactly; the isotropic model ignores
    /// direction.
    #[test]
    fn an_isotropic_fit_is_the_line_through_its_samples() {
        let samples: Vec<Sample> = (1..40)
            .map(|i| {
                let at = DVec2::from_angle(f64::from(i)) * (0.25 * f64::from(i));
                Sample {
                    at,
                    velocity: DVec2::ZERO,
                    seconds: 0.3 + at.length() / 4.0,
                }
            })
            .collect();
        let (model, q) = fit_isotropic(&samples);
        assert!((model.reaction_s - 0.3).abs() < 1e-9 && (model.speed_m_s - 4.0).abs() < 1e-9);
        assert!(q.rms_s < 1e-9 && (q.r2 - 1.0).abs() < 1e-9);
    }

    /// Rosenbrock's valley as residuals (1 − x, 10(y − x²)): its minimum is 0 at (1, 1).
    #[test]
    fn levenberg_marquardt_finds_the_bottom_of_a_valley() {
        let residuals = |x: &[f64; 2]| vec![1.0 - x[0], 10.0 * (x[1] - x[0] * x[0])];
        let (x, f) = levenberg_marquardt(&residuals, [-1.2, 1.0], 200);
        assert!(
            f < 1e-16 && (x[0] - 1.0).abs() < 1e-6 && (x[1] - 1.0).abs() < 1e-6,
            "{x:?}"
        );
    }
}
