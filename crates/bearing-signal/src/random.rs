//! Seeded random numbers, the same for the same seed on every machine, for the simulator and
//! for tests at every level (it sits at the bottom of the layout so that `analysis` tests can use
//! it too): rand_chacha's ChaCha8, whose output for a seed is fixed by its documented algorithm,
//! plus normal draws by Box–Muller.

use rand::{Rng as _, RngCore as _, SeedableRng as _};
use rand_chacha::ChaCha8Rng;

/// A seeded stream of uniform and normal numbers.
#[derive(Debug, Clone)]
pub struct Rng {
    inner: ChaCha8Rng,
    spare_normal: Option<f64>,
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng {
            inner: ChaCha8Rng::seed_from_u64(seed),
            spare_normal: None,
        }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.inner.next_u64()
    }

    /// Uniform in (0, 1] (never 0, so that its logarithm is finite).
    pub fn uniform(&mut self) -> f64 {
        1.0 - self.inner.random::<f64>()
    }

    /// Standard normal.
    pub fn normal(&mut self) -> f64 {
        if let Some(z) = self.spare_normal.take() {
            return z;
        }
        let radius = (-2.0 * self.uniform().ln()).sqrt();
        let angle = std::f64::consts::TAU * self.uniform();
        self.spare_normal = Some(radius * angle.sin());
        radius * angle.cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_has_unit_variance_and_same_seed_same_stream() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let z = a.normal();
            assert_eq!(z, b.normal());
            sum += z;
            sum2 += z * z;
        }
        let mean = sum / n as f64;
        assert!(mean.abs() < 0.01, "{mean}");
        assert!((sum2 / n as f64 - 1.0).abs() < 0.02);
    }
}
