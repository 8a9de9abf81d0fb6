//! The identified model and what it says about a record: its free-run simulation, its
//! one-step-ahead prediction, their accuracies.
//!
//! The model works in normalised units (each signal minus its mean over the identification
//! record, over its standard deviation) so that states of order 0 and 12 (ten to the 50 apart in
//! g/sⁱ) give coefficients of similar size; the means and scales are part of the model, so it
//! applies to any later record as it is.
//!
//! Two predictors, two accuracies (both `100·(1 − NRMSE)`,
//! `NRMSE = ‖y − ŷ‖ / ‖y − mean(y)‖`):
//! - **simulation** (free run): `ŷ = h(Σᵢ Bᵢ/Fᵢ·uᵢ + free response)` from the inputs alone.
//!   The HW model is an output-error model (no noise model), so this is also its own optimal
//!   predictor, and what MATLAB's `compare` reports for an `idnlhw` model: the number to set
//!   beside the seed's. Like `compare` (its default `InitialCondition = 'e'`), the linear
//!   blocks' initial state is estimated: the free responses of every `1/Fᵢ` are weighted to
//!   minimise the output error. The zero-state accuracy (from
//!   rest, the identification's own criterion) is reported beside it. Why it matters: with a
//!   pole near 1 a state left at zero decays over thousands of samples, longer than a 0.1 s
//!   snapshot, so "from rest" penalises the start of every record.
//! - **one step ahead**: a predictor that sees the measured past of the output. An
//!   output-error model has none of its own, so the model carries the linear ARX model of the
//!   same orders (the identification's starting point, [`ArxModel`]):
//!   `ŷ[k] = −a₁y[k−1] − … + Σᵢ Σₘ bᵢₘ·uᵢ[k−nk−m]`. On these signals `y[k] ≈ y[k−1] +
//!   a⁽ⁿ⁺¹⁾[k−1]/fs`, so it is near 100 % whatever the bearing does, and says more about the
//!   data than about the model; it is given so that a reader can see which of the two a
//!   published accuracy could be.

use super::linear::TransferFunction;
use super::output::OutputPolynomial;
use super::states::VirtualStates;
use super::HwError;
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Gauss–Newton steps of the initial-state estimate (each kept only if it helps).
const ESTIMATED_STATE_STEPS: usize = 10;
/// Halvings of a Gauss–Newton step before the estimate stops there.
const ESTIMATED_STATE_HALVINGS: usize = 10;

/// A multi-input single-output Hammerstein–Wiener model of virtual state `a⁽ⁿ⁾` from
/// `a⁽ⁿ⁺¹⁾ … a⁽ⁿ⁺ᵐ⁾`: unit-gain input nonlinearity, one transfer function per input, a
/// polynomial on the sum.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HwModel {
    /// `n`: the output is `a⁽ⁿ⁾`, the inputs `a⁽ⁿ⁺¹⁾ …`.
    pub order: usize,
    pub input_mean: Vec<f64>,
    pub input_scale: Vec<f64>,
    pub output_mean: f64,
    pub output_scale: f64,
    /// One per input, in input order.
    pub linear: Vec<TransferFunction>,
    pub output: OutputPolynomial,
    /// The one-step-ahead predictor of the same orders.
    pub arx: ArxModel,
}

/// A linear ARX model with one denominator shared by all inputs:
/// `y[k] = −a₁y[k−1] − … − a_na·y[k−na] + Σᵢ Σₘ bᵢₘ·uᵢ[k−nk−m]` (normalised units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArxModel {
    pub a: Vec<f64>,
    /// Per input, `bᵢ₀ …`.
    pub b: Vec<Vec<f64>>,
    pub delay: usize,
}

impl ArxModel {
    /// The least-squares fit (SVD: a rank-deficient record gives the minimum-norm answer);
    /// `None` if it is not finite.
    pub fn fit(y: &[f64], u: &[Vec<f64>], na: usize, nb: usize, nk: usize) -> Option<Self> {
        let lag = na.max(nk + nb - 1);
        let rows = y.len().checked_sub(lag).filter(|&r| r > 0)?;
        let cols = na + u.len() * nb;
        let regressors = DMatrix::from_fn(rows, cols, |r, c| {
            let k = r + lag;
            if c < na {
                -y[k - 1 - c]
            } else {
                let (i, m) = ((c - na) / nb, (c - na) % nb);
                u[i][k - nk - m]
            }
        });
        let target = DVector::from_column_slice(&y[lag..]);
        let theta = regressors.svd(true, true).solve(&target, 1e-12).ok()?;
        if theta.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let theta = theta.as_slice();
        Some(ArxModel {
            a: theta[..na].to_vec(),
            b: (0..u.len())
                .map(|i| theta[na + i * nb..na + (i + 1) * nb].to_vec())
                .collect(),
            delay: nk,
        })
    }

    /// One-step-ahead prediction of `y` from its measured past and the inputs (samples before
    /// the record count as 0).
    pub fn predict(&self, y: &[f64], u: &[Vec<f64>]) -> Vec<f64> {
        (0..y.len())
            .map(|k| {
                let mut p = 0.0;
                for (j, &a) in self.a.iter().enumerate() {
                    if let Some(i) = k.checked_sub(j + 1) {
                        p -= a * y[i];
                    }
                }
                for (bi, ui) in self.b.iter().zip(u) {
                    for (m, &b) in bi.iter().enumerate() {
                        if let Some(i) = k.checked_sub(self.delay + m) {
                            p += b * ui[i];
                        }
                    }
                }
                p
            })
            .collect()
    }
}

/// How well a model reproduces a record.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Accuracy {
    /// `100·(1 − NRMSE)` of the free-run simulation, from the estimated initial state.
    pub simulation: f64,
    /// The same from rest (zero initial state).
    #[serde(default)]
    pub simulation_zero_state: f64,
    /// `100·(1 − NRMSE)` of the one-step-ahead prediction.
    pub one_step: f64,
}

/// The model's outputs over a record, in normalised units, and the measured output.
#[derive(Debug, Clone, PartialEq)]
pub struct Responses {
    pub measured: Vec<f64>,
    /// From the estimated initial state.
    pub simulated: Vec<f64>,
    /// From rest.
    pub simulated_zero_state: Vec<f64>,
    pub one_step: Vec<f64>,
}

impl Responses {
    pub fn accuracy(&self) -> Accuracy {
        Accuracy {
            simulation: fit_percent(&self.measured, &self.simulated),
            simulation_zero_state: fit_percent(&self.measured, &self.simulated_zero_state),
            one_step: fit_percent(&self.measured, &self.one_step),
        }
    }

    /// Measured minus simulated output (normalised units: a residual of 1 is one standard
    /// deviation of the identification record's output).
    pub fn simulation_residual(&self) -> Vec<f64> {
        residual(&self.measured, &self.simulated)
    }

    pub fn one_step_residual(&self) -> Vec<f64> {
        residual(&self.measured, &self.one_step)
    }
}

fn residual(measured: &[f64], model: &[f64]) -> Vec<f64> {
    measured.iter().zip(model).map(|(y, m)| y - m).collect()
}

/// `100·(1 − ‖y − ŷ‖/‖y − mean(y)‖)`; `-inf` when `ŷ` is not finite, `NaN` for a constant `y`.
pub fn fit_percent(y: &[f64], y_hat: &[f64]) -> f64 {
    let n = y.len().min(y_hat.len());
    if n == 0 {
        return f64::NAN;
    }
    let mean = y[..n].iter().sum::<f64>() / n as f64;
    let spread: f64 = y[..n].iter().map(|v| (v - mean).powi(2)).sum();
    let error: f64 = y[..n]
        .iter()
        .zip(&y_hat[..n])
        .map(|(a, b)| (a - b).powi(2))
        .sum();
    if !error.is_finite() {
        return f64::NEG_INFINITY;
    }
    if spread <= 0.0 {
        return f64::NAN;
    }
    100.0 * (1.0 - (error / spread).sqrt())
}

impl HwModel {
    pub fn inputs(&self) -> usize {
        self.linear.len()
    }

    /// The highest state order the model needs.
    pub fn max_order(&self) -> usize {
        self.order + self.inputs()
    }

    /// The measured output and inputs of `states`, normalised with the model's means and scales.
    pub fn normalise(&self, states: &VirtualStates) -> Result<(Vec<f64>, Vec<Vec<f64>>), HwError> {
        if states.max_order() < self.max_order() {
            return Err(HwError::MissingOrders {
                have: states.max_order(),
                needed: self.max_order(),
            });
        }
        let scale = |x: &[f64], mean: f64, s: f64| x.iter().map(|v| (v - mean) / s).collect();
        let y = scale(
            &states.states[self.order],
            self.output_mean,
            self.output_scale,
        );
        let u = (0..self.inputs())
            .map(|i| {
                scale(
                    &states.states[self.order + 1 + i],
                    self.input_mean[i],
                    self.input_scale[i],
                )
            })
            .collect();
        Ok((y, u))
    }

    /// The model's free-run simulations and one-step prediction of `states`.
    pub fn respond(&self, states: &VirtualStates) -> Result<Responses, HwError> {
        let (measured, u) = self.normalise(states)?;
        Ok(self.responses(measured, &u))
    }

    /// [`Responses`] of normalised `y` and `u`.
    pub fn responses(&self, measured: Vec<f64>, u: &[Vec<f64>]) -> Responses {
        let (w, simulated_zero_state) = self.simulate_normalised(u);
        let simulated = self.simulate_from_estimated_state(&w, &measured);
        let one_step = self.arx.predict(&measured, u);
        Responses {
            measured,
            simulated,
            simulated_zero_state,
            one_step,
        }
    }

    /// `h(w + Z·α)`: the zero-state linear output `w` plus the free responses `Z` of every
    /// `1/Fᵢ` (a basis of `nfᵢ` sequences each), `α` minimising `‖y − h(w + Z·α)‖²` (the output
    /// error, as `compare` does): started from the least-squares fit of `Z·α` to `h⁻¹(y) − w`,
    /// then Gauss–Newton steps, each kept only if it lowers the error (the inversion alone can
    /// pick the wrong branch of a turning `h` where `w` is far from the truth).
    /// Never worse than from rest: where no `α` does better than none, that is `h(w)`.
    fn simulate_from_estimated_state(&self, w: &[f64], y: &[f64]) -> Vec<f64> {
        let n = w.len().min(y.len());
        // One column per pole of every block: an impulse at sample j filtered by 1/Fᵢ.
        let poles: usize = self.linear.iter().map(|tf| tf.f.len()).sum();
        let mut basis = DMatrix::zeros(n, poles);
        let mut column = 0;
        for tf in &self.linear {
            for j in 0..tf.f.len().min(n) {
                let z = basis.column_mut(column + j);
                let z = z.data.into_slice_mut();
                z[j] = 1.0;
                super::linear::filter_denominator(&tf.f, z);
            }
            column += tf.f.len();
        }
        let simulate = |free: &DVector<f64>| -> Vec<f64> {
            (0..n).map(|k| self.output.eval(w[k] + free[k])).collect()
        };
        let error = |simulated: &[f64]| -> f64 {
            let e: f64 = simulated.iter().zip(y).map(|(s, m)| (m - s).powi(2)).sum();
            if e.is_finite() {
                e
            } else {
                f64::INFINITY
            }
        };
        let mut free = DVector::zeros(n);
        let mut best = simulate(&free);
        if basis.ncols() == 0 || n <= basis.ncols() {
            return best;
        }
        let mut best_error = error(&best);
        let solve = |a: DMatrix<f64>, b: &DVector<f64>| a.svd(true, true).solve(b, 1e-9).ok();
        let inverted =
            DVector::from_iterator(n, (0..n).map(|k| self.output.invert(y[k], w[k]) - w[k]));
        // The start: the inversion's least squares, if it does better than no free response.
        if let Some(alpha) = solve(basis.clone(), &inverted) {
            let candidate = &basis * &alpha;
            let simulated = simulate(&candidate);
            let candidate_error = error(&simulated);
            if candidate_error < best_error {
                (free, best, best_error) = (candidate, simulated, candidate_error);
            }
        }
        // Gauss–Newton on the output error, J = diag(h'(w + Zα))·Z, each step halved until it
        // helps.
        for _ in 0..ESTIMATED_STATE_STEPS {
            let jacobian = DMatrix::from_fn(n, basis.ncols(), |k, c| {
                self.output.slope(w[k] + free[k]) * basis[(k, c)]
            });
            let residual = DVector::from_iterator(n, (0..n).map(|k| y[k] - best[k]));
            let Some(step) = solve(jacobian, &residual) else {
                break;
            };
            let mut step = &basis * step;
            let mut improved = None;
            for _ in 0..ESTIMATED_STATE_HALVINGS {
                let candidate = &free + &step;
                let simulated = simulate(&candidate);
                let candidate_error = error(&simulated);
                if candidate_error < best_error {
                    improved = Some((candidate, simulated, candidate_error));
                    break;
                }
                step *= 0.5;
            }
            let Some((candidate, simulated, candidate_error)) = improved else {
                break;
            };
            let gain = best_error - candidate_error;
            (free, best, best_error) = (candidate, simulated, candidate_error);
            if gain <= 1e-12 * (1.0 + best_error) {
                break;
            }
        }
        best
    }

    /// `(w, ŷ)` of the free run from rest over normalised inputs.
    pub fn simulate_normalised(&self, u: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>) {
        let n = u.first().map_or(0, Vec::len);
        let mut w = vec![0.0; n];
        let mut x = vec![0.0; n];
        for (tf, ui) in self.linear.iter().zip(u) {
            tf.simulate(ui, &mut x);
            w.iter_mut().zip(&x).for_each(|(a, b)| *a += b);
        }
        let y = w.iter().map(|&v| self.output.eval(v)).collect();
        (w, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_percent_edges() {
        assert_eq!(fit_percent(&[1.0, 2.0, 3.0], &[1.0, 2.0, 3.0]), 100.0);
        assert_eq!(fit_percent(&[1.0, 2.0, 3.0], &[2.0, 2.0, 2.0]), 0.0);
        assert!(fit_percent(&[1.0, 1.0], &[1.0, 1.0]).is_nan());
        assert_eq!(
            fit_percent(&[1.0, 2.0], &[f64::NAN, 1.0]),
            f64::NEG_INFINITY
        );
    }
}
