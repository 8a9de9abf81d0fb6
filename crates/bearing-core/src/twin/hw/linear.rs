//! The linear block of one input: a discrete transfer function with `nb = zeros + 1` numerator
//! coefficients, `nf = poles` denominator coefficients and an input delay `nk` (MATLAB's
//! `idnlhw` orders `[nb nf nk]`):
//!
//! ```text
//! x[k] = b₀·u[k−nk] + … + b_{nb−1}·u[k−nk−nb+1] − f₁·x[k−1] − … − f_nf·x[k−nf]
//! ```
//!
//! Its poles are the roots of `zⁿᶠ + f₁·zⁿᶠ⁻¹ + … + f_nf`. A pole on or outside the unit circle
//! makes the free-run simulation grow without bound, so [`TransferFunction::stabilise`] moves
//! every pole beyond a radius back inside (reflection `p → 1/p̄`, which keeps the magnitude
//! response's shape, then a clamp to the radius).

use nalgebra::linalg::Schur;
use nalgebra::{Complex, DMatrix};
use serde::{Deserialize, Serialize};

/// `B(q)/F(q)·q^{−delay}`; `b` holds `b₀…`, `f` holds `f₁…` (the leading 1 is implied).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransferFunction {
    pub b: Vec<f64>,
    pub f: Vec<f64>,
    pub delay: usize,
}

impl TransferFunction {
    /// `x = B/F·q^{−delay}·u` from rest (zero initial conditions); `x.len() == u.len()`.
    pub fn simulate(&self, u: &[f64], x: &mut [f64]) {
        for (k, out) in x.iter_mut().enumerate() {
            let mut acc = 0.0;
            for (m, &b) in self.b.iter().enumerate() {
                if let Some(i) = k.checked_sub(self.delay + m) {
                    acc += b * u[i];
                }
            }
            *out = acc;
        }
        filter_denominator(&self.f, x);
    }

    /// Poles, in no particular order; `None` when the coefficients are not finite or the
    /// eigenvalue iteration does not converge.
    pub fn poles(&self) -> Option<Vec<Complex<f64>>> {
        roots(&self.f)
    }

    /// Largest pole radius (0 without poles, infinite when the poles cannot be found).
    pub fn spectral_radius(&self) -> f64 {
        self.poles().map_or(f64::INFINITY, |poles| {
            poles.iter().map(|p| p.norm()).fold(0.0, f64::max)
        })
    }

    /// Moves every pole beyond `max_radius` inside it; returns whether any moved. Coefficients
    /// whose poles cannot be found (not finite, or no convergence) are reset to a pole-free
    /// block.
    pub fn stabilise(&mut self, max_radius: f64) -> bool {
        let Some(mut poles) = self.poles() else {
            self.f.iter_mut().for_each(|v| *v = 0.0);
            return true;
        };
        let mut moved = false;
        for p in &mut poles {
            let r = p.norm();
            if r > max_radius {
                let reflected = if r > 1.0 { 1.0 / r } else { r };
                *p = Complex::from_polar(reflected.min(max_radius), p.arg());
                moved = true;
            }
        }
        if moved {
            self.f = monic_from_roots(&poles);
        }
        moved
    }

    /// Gain at zero frequency, `B(1)/F(1)` (infinite for a pole at 1).
    pub fn dc_gain(&self) -> f64 {
        self.b.iter().sum::<f64>() / (1.0 + self.f.iter().sum::<f64>())
    }
}

/// `x ← x / F(q)` in place, from rest: `x[k] −= f₁·x[k−1] + … + f_n·x[k−n]`.
pub fn filter_denominator(f: &[f64], x: &mut [f64]) {
    for k in 0..x.len() {
        let mut acc = x[k];
        for (j, &fj) in f.iter().enumerate() {
            if let Some(i) = k.checked_sub(j + 1) {
                acc -= fj * x[i];
            }
        }
        x[k] = acc;
    }
}

/// Iterations the Schur decomposition may take before a root search gives up (nalgebra's
/// `complex_eigenvalues` iterates without bound and never returned on some companion matrices
/// met during identification).
const SCHUR_ITERATIONS: usize = 500;

/// Roots of `zⁿ + c₁·zⁿ⁻¹ + … + c_n`: the eigenvalues of its companion matrix; `None` if a
/// coefficient is not finite or the iteration does not converge.
pub fn roots(c: &[f64]) -> Option<Vec<Complex<f64>>> {
    let n = c.len();
    if n == 0 {
        return Some(Vec::new());
    }
    if c.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let companion = DMatrix::from_fn(n, n, |i, j| {
        if i == 0 {
            -c[j]
        } else if i == j + 1 {
            1.0
        } else {
            0.0
        }
    });
    let schur = Schur::try_new(companion, f64::EPSILON, SCHUR_ITERATIONS)?;
    let poles: Vec<Complex<f64>> = schur.complex_eigenvalues().iter().copied().collect();
    poles
        .iter()
        .all(|p| p.re.is_finite() && p.im.is_finite())
        .then_some(poles)
}

/// `c₁…c_n` of `Π (z − pᵢ)` (real parts: complex poles come in conjugate pairs).
pub fn monic_from_roots(poles: &[Complex<f64>]) -> Vec<f64> {
    let mut c = vec![Complex::new(1.0, 0.0)];
    for &p in poles {
        let mut next = vec![Complex::new(0.0, 0.0); c.len() + 1];
        for (i, &ci) in c.iter().enumerate() {
            next[i] += ci;
            next[i + 1] -= ci * p;
        }
        c = next;
    }
    c[1..].iter().map(|v| v.re).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_and_back() {
        let poles = [
            Complex::new(0.9, 0.0),
            Complex::from_polar(0.8, 0.5),
            Complex::from_polar(0.8, -0.5),
        ];
        let f = monic_from_roots(&poles);
        let mut found: Vec<f64> = roots(&f).unwrap().iter().map(|p| p.norm()).collect();
        found.sort_by(f64::total_cmp);
        assert!((found[0] - 0.8).abs() < 1e-9 && (found[2] - 0.9).abs() < 1e-9);
    }

    #[test]
    fn stabilise_reflects_and_clamps() {
        let mut tf = TransferFunction {
            b: vec![1.0],
            f: monic_from_roots(&[Complex::new(1.25, 0.0), Complex::new(0.5, 0.0)]),
            delay: 1,
        };
        assert!(tf.stabilise(0.999));
        assert!((tf.spectral_radius() - 0.8).abs() < 1e-9);
        let mut edge = TransferFunction {
            b: vec![1.0],
            f: vec![-1.0],
            delay: 1,
        };
        assert!(edge.stabilise(0.99));
        assert!((edge.f[0] + 0.99).abs() < 1e-12);
        let mut broken = TransferFunction {
            b: vec![1.0],
            f: vec![f64::NAN, 0.1],
            delay: 1,
        };
        assert!(broken.stabilise(0.99));
        assert_eq!(broken.f, [0.0, 0.0]);
    }

    #[test]
    fn simulate_first_order() {
        // x[k] = u[k-1] + 0.5 x[k-1], impulse at 0.
        let tf = TransferFunction {
            b: vec![1.0],
            f: vec![-0.5],
            delay: 1,
        };
        let mut x = [0.0; 4];
        tf.simulate(&[1.0, 0.0, 0.0, 0.0], &mut x);
        assert_eq!(x, [0.0, 1.0, 0.5, 0.25]);
        assert!((tf.dc_gain() - 2.0).abs() < 1e-12);
    }
}
