//! The ground alignment of two weighted point clouds (Kovar, Gleicher & Pighin 2002): how
//! far apart they are after the rotation about the vertical axis and the translation on
//! the ground that best map one onto the other, in closed form. Finding transitions needs
//! only that distance; judging a cut (`cuts`) needs the transform itself, and the tests
//! check the two agree.

use glam::{DVec2, DVec3};

/// Weighted sums over pairs of points (p, p′) that the closed form needs. The same sums
/// give the aligned distance without a second pass over the points.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Moments {
    w: f64,
    x: f64,
    z: f64,
    x2: f64,
    z2: f64,
    /// Σw(x·x′ + z·z′) and Σw(x·z′ − x′·z).
    dot: f64,
    cross: f64,
    /// Σw·|p|² and Σw·|p′|² (all three axes), Σw·y·y′.
    norm: f64,
    norm2: f64,
    yy: f64,
}

impl Moments {
    /// Moments from sums computed elsewhere (unit weights, `w` points): Σx, Σz, Σ|p|² of
    /// each cloud and the cross sums Σ(x x′ + z z′), Σ(x z′ − x′ z), Σ y y′. Lets a caller
    /// that compares many windows reuse per-frame sums instead of revisiting points.
    pub(crate) fn from_sums(w: f64, p: [f64; 3], q: [f64; 3], cross: [f64; 3]) -> Moments {
        Moments {
            w,
            x: p[0],
            z: p[1],
            norm: p[2],
            x2: q[0],
            z2: q[1],
            norm2: q[2],
            dot: cross[0],
            cross: cross[1],
            yy: cross[2],
        }
    }

    /// Σw·|p − T(p′)|² for the best alignment T, from the sums alone, without finding T.
    ///
    /// With both clouds centred on the ground (the best offset brings their weighted
    /// centres together), what is left is Σw|p̄|² + Σw|p̄′|² − 2·Σw p̄·Rp̄′, and
    /// Σw p̄·Rp̄′ = cos θ·a + sin θ·b + Σw y y′ with a, b the centred cross sums below:
    /// at its best θ that is √(a² + b²) + Σw y y′. No angle is needed, which matters when
    /// every pair of windows of a behaviour is compared.
    pub(crate) fn aligned_distance(&self) -> f64 {
        let w = self.w;
        let a = self.dot - (self.x * self.x2 + self.z * self.z2) / w;
        let b = self.cross - (self.x * self.z2 - self.x2 * self.z) / w;
        let centred = self.norm - (self.x * self.x + self.z * self.z) / w + self.norm2
            - (self.x2 * self.x2 + self.z2 * self.z2) / w;
        (centred - 2.0 * ((a * a + b * b).sqrt() + self.yy)).max(0.0)
    }
}

/// A rigid motion of the ground: rotate by `theta` about +y, then translate by `offset`
/// (x, z). It maps (x, z) to (x·cos θ + z·sin θ + x₀, −x·sin θ + z·cos θ + z₀): the
/// rotation is by θ about +y in a right-handed, y-up frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct GroundTransform {
    /// The rotation about +y, rad.
    pub(crate) theta: f64,
    /// The translation on the ground, (x, z) in m.
    pub(crate) offset: DVec2,
}

impl GroundTransform {
    /// The point moved.
    pub(crate) fn apply(&self, p: DVec3) -> DVec3 {
        let (sin, cos) = self.theta.sin_cos();
        DVec3::new(
            p.x * cos + p.z * sin + self.offset.x,
            p.y,
            -p.x * sin + p.z * cos + self.offset.y,
        )
    }

    /// A ground vector (x, z) turned, not moved.
    pub(crate) fn rotate(&self, v: DVec2) -> DVec2 {
        let (sin, cos) = self.theta.sin_cos();
        DVec2::new(v.x * cos + v.y * sin, -v.x * sin + v.y * cos)
    }
}

impl Moments {
    /// Adds the pair (p, p′) with weight w; p′ is the cloud to be moved onto p.
    pub(crate) fn add(&mut self, w: f64, p: DVec3, q: DVec3) {
        self.w += w;
        self.x += w * p.x;
        self.z += w * p.z;
        self.x2 += w * q.x;
        self.z2 += w * q.z;
        self.dot += w * (p.x * q.x + p.z * q.z);
        self.cross += w * (p.x * q.z - q.x * p.z);
        self.norm += w * p.length_squared();
        self.norm2 += w * q.length_squared();
        self.yy += w * p.y * q.y;
    }

    /// The transform that best maps the p′ cloud onto the p cloud (least weighted
    /// squares).
    pub(crate) fn alignment(&self) -> GroundTransform {
        let w = self.w;
        let theta = (self.cross - (self.x * self.z2 - self.x2 * self.z) / w)
            .atan2(self.dot - (self.x * self.x2 + self.z * self.z2) / w);
        let (sin, cos) = theta.sin_cos();
        GroundTransform {
            theta,
            offset: DVec2::new(
                (self.x - self.x2 * cos - self.z2 * sin) / w,
                (self.z + self.x2 * sin - self.z2 * cos) / w,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn cloud(rng: &mut ChaCha8Rng, n: usize) -> Vec<(f64, DVec3)> {
        (0..n)
            .map(|_| {
                let w = rng.gen_range(0.1..2.0);
                let p = DVec3::new(
                    rng.gen_range(-3.0..3.0),
                    rng.gen_range(0.0..2.0),
                    rng.gen_range(-3.0..3.0),
                );
                (w, p)
            })
            .collect()
    }

    #[test]
    fn recovers_a_known_rigid_motion_exactly() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..50 {
            let truth = GroundTransform {
                theta: rng.gen_range(-3.1..3.1),
                offset: DVec2::new(rng.gen_range(-10.0..10.0), rng.gen_range(-10.0..10.0)),
            };
            // p = T(p′): the alignment of p′ onto p must be T itself, at distance 0.
            let moved = cloud(&mut rng, 12);
            let mut m = Moments::default();
            for (w, q) in &moved {
                m.add(*w, truth.apply(*q), *q);
            }
            let found = m.alignment();
            let dtheta = (found.theta - truth.theta + std::f64::consts::PI)
                .rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(dtheta.abs() < 1e-9, "{found:?} vs {truth:?}");
            assert!((found.offset - truth.offset).length() < 1e-9);
            assert!(m.aligned_distance() < 1e-9, "{}", m.aligned_distance());
        }
    }

    #[test]
    fn aligned_distance_matches_the_direct_sum_and_is_minimal() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let a = cloud(&mut rng, 20);
        let b = cloud(&mut rng, 20);
        let mut m = Moments::default();
        for ((w, p), (_, q)) in a.iter().zip(&b) {
            m.add(*w, *p, *q);
        }
        let direct = |t: &GroundTransform| -> f64 {
            a.iter()
                .zip(&b)
                .map(|((w, p), (_, q))| w * (*p - t.apply(*q)).length_squared())
                .sum()
        };
        let best = m.alignment();
        assert!((m.aligned_distance() - direct(&best)).abs() < 1e-9 * direct(&best));
        // Any perturbation of the optimum does worse.
        for (dt, dx, dz) in [
            (0.01, 0.0, 0.0),
            (0.0, 0.01, 0.0),
            (0.0, 0.0, -0.01),
            (-0.02, 0.01, 0.01),
        ] {
            let t = GroundTransform {
                theta: best.theta + dt,
                offset: best.offset + DVec2::new(dx, dz),
            };
            assert!(direct(&t) > direct(&best));
        }
    }
}
