//! The output nonlinearity: a one-dimensional polynomial `h(w) = c₀ + c₁·w + … + c_d·w^d`
//! (seed 003's "1-DP"). The identification fixes `c₁ = 1` (the gain lives in the linear
//! blocks; otherwise `h` and the blocks could trade it freely).

use serde::{Deserialize, Serialize};

/// `h(w) = Σ cᵢ·wⁱ`, `coefficients[i] = cᵢ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputPolynomial {
    pub coefficients: Vec<f64>,
}

impl OutputPolynomial {
    /// `h(w) = w`, the starting point of an identification.
    pub fn identity(degree: usize) -> Self {
        let mut coefficients = vec![0.0; degree.max(1) + 1];
        coefficients[1] = 1.0;
        OutputPolynomial { coefficients }
    }

    pub fn degree(&self) -> usize {
        self.coefficients.len().saturating_sub(1)
    }

    pub fn eval(&self, w: f64) -> f64 {
        self.coefficients
            .iter()
            .rev()
            .fold(0.0, |acc, &c| acc * w + c)
    }

    /// `h'(w)`.
    pub fn slope(&self, w: f64) -> f64 {
        self.coefficients
            .iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (i, &c)| acc * w + i as f64 * c)
    }

    /// A `w` with `h(w) = y`, the one nearest `guess` that Newton's method finds from there;
    /// where `h` does not reach `y` (or turns back), the `w` of the smallest `|h(w) − y|` found.
    pub fn invert(&self, y: f64, guess: f64) -> f64 {
        if self.degree() <= 1 {
            let slope = self.coefficients.get(1).copied().unwrap_or(0.0);
            return if slope != 0.0 {
                (y - self.coefficients[0]) / slope
            } else {
                guess
            };
        }
        let mut w = guess;
        let mut best = (f64::INFINITY, guess);
        for _ in 0..30 {
            let err = self.eval(w) - y;
            if err.abs() < best.0 {
                best = (err.abs(), w);
            }
            let slope = self.slope(w);
            if err == 0.0 || slope == 0.0 || !slope.is_finite() {
                break;
            }
            let step = err / slope;
            w -= step;
            if step.abs() <= 1e-12 * (1.0 + w.abs()) {
                break;
            }
        }
        if self.eval(w).is_finite() && (self.eval(w) - y).abs() < best.0 {
            w
        } else {
            best.1
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eval_slope_invert() {
        let h = OutputPolynomial {
            coefficients: vec![0.5, 1.0, 0.0, 0.2],
        };
        assert!((h.eval(2.0) - (0.5 + 2.0 + 1.6)).abs() < 1e-12);
        assert!((h.slope(2.0) - (1.0 + 3.0 * 0.2 * 4.0)).abs() < 1e-12);
        let w = h.invert(h.eval(-1.3), 0.0);
        assert!((w + 1.3).abs() < 1e-9, "{w}");
        assert_eq!(OutputPolynomial::identity(1).invert(2.0, 0.0), 2.0);
        // A square never reaches −1: the closest point, no panic, no NaN.
        let square = OutputPolynomial {
            coefficients: vec![0.0, 0.0, 1.0],
        };
        assert!(square.invert(-1.0, 0.5).is_finite());
    }
}
