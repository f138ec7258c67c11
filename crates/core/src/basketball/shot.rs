//! Shot success against distance. The paper takes it inversely proportional to the
//! distance to the basket; a pure 1/d would exceed 1 near the ring, so it is capped.

use serde::{Deserialize, Serialize};

/// The chance a shot goes in against its distance to the basket: `scale_m / d`, capped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ShotModel {
    /// Success at distance d is `scale_m / d`, metres: 1.5 gives 50 % from 3 m and 25 %
    /// from 6 m.
    pub scale_m: f64,
    /// The most a shot can succeed, however close.
    pub cap: f64,
}

impl Default for ShotModel {
    fn default() -> Self {
        ShotModel {
            scale_m: 1.5,
            cap: 0.6,
        }
    }
}

impl ShotModel {
    /// Probability that a shot from `distance_m` from the basket goes in.
    pub fn success(&self, distance_m: f64) -> f64 {
        if distance_m <= 0.0 {
            return self.cap;
        }
        (self.scale_m / distance_m).min(self.cap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn success_is_inverse_in_distance_under_the_cap() {
        let m = ShotModel::default();
        assert_eq!(m.success(3.0), 0.5);
        assert_eq!(m.success(6.0), 0.25);
        // Doubling the distance halves the chance wherever the cap does not bind.
        for d in [2.6, 4.0, 7.5] {
            assert!((m.success(2.0 * d) - 0.5 * m.success(d)).abs() < 1e-12);
        }
        assert_eq!(m.success(0.5), 0.6);
        assert_eq!(m.success(0.0), 0.6);
    }
}
