//! The Hammerstein–Wiener (HW) model on virtual states (seed 003, MODELS.md §6), sans-IO.
//!
//! Why: seed 003 models a bearing's vibration as a small nonlinear dynamic system whose
//! "virtual states" are the acceleration and its derivatives; how well such a model fits, and
//! how its parameters drift, describe the bearing's dynamics beyond what RMS and kurtosis say.
//! The seed identified it with MATLAB's System Identification Toolbox in 135–445 s; the
//! identification here takes milliseconds, so the daemon can re-identify it online.
//!
//! The model (the seed's best configuration, every part configurable in [`HwConfig`]):
//! output `y = a⁽ⁿ⁾`, inputs `uᵢ = a⁽ⁿ⁺ⁱ⁾`, `i = 1…3`, unit-gain input nonlinearity, one
//! transfer function per input (3 poles, 0 zeros, delay 1), a one-dimensional polynomial
//! output nonlinearity:
//!
//! ```text
//! y[k] = h( Σᵢ Bᵢ(q)/Fᵢ(q) · q^{−nk} · uᵢ[k] ),   h(w) = c₀ + w + c₂w² + … + c_d·w^d
//! ```
//!
//! - [`states`]: the virtual states (finite differences, median filter of width 5, where in
//!   the chain set by [`StateFilter`]);
//! - [`linear`]: one input's transfer function, its poles, the stability guard;
//! - [`output`]: the output polynomial and its inverse;
//! - [`model`]: the identified model, its free-run simulation and one-step prediction, the
//!   accuracy `100·(1 − NRMSE)` of each;
//! - [`identify`]: ARX start, polynomial by least squares, Levenberg–Marquardt on the
//!   output error; a previous model as a warm start (the daemon's periodic re-fit);
//! - [`online`]: one channel's model over time, warm-started, and its drift against the
//!   channel's healthy baseline (the daemon's `/hw` topic).
//!
//! No clock, no file, no panic on any input: NaN samples, a constant record, a record too short
//! for the model are [`HwError`]s naming what is wrong.

pub mod identify;
pub mod linear;
pub mod model;
pub mod online;
pub mod output;
pub mod states;

pub use identify::{identify, HwFit};
pub use model::{Accuracy, HwModel, Responses};
pub use online::{HwTracker, HwUpdate};
pub use states::{StateFilter, VirtualStates};

use serde::{Deserialize, Serialize};

/// The structure of the model and how hard to work at identifying it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HwConfig {
    /// `n`: the output is the virtual state `a⁽ⁿ⁾`.
    pub order: usize,
    /// Where the median filter sits in the chain of differences.
    #[serde(default)]
    pub states: StateFilter,
    /// Inputs `a⁽ⁿ⁺¹⁾ … a⁽ⁿ⁺ⁱⁿᵖᵘᵗˢ⁾`.
    pub inputs: usize,
    /// Poles of each input's transfer function (`nf`).
    pub poles: usize,
    /// Zeros of each input's transfer function (`nb − 1`).
    pub zeros: usize,
    /// Input delay in samples (`nk`).
    pub delay: usize,
    /// Degree of the output polynomial.
    pub poly_degree: usize,
    /// Levenberg–Marquardt iterations at most.
    pub max_iterations: usize,
    /// Relative decrease of the cost below which the iterations stop.
    pub tolerance: f64,
    /// Poles are kept at or inside this radius (the stability guard).
    pub max_pole_radius: f64,
}

impl Default for HwConfig {
    /// Seed 003's best configuration: `[a⁽ⁿ⁺¹⁾, a⁽ⁿ⁺²⁾, a⁽ⁿ⁺³⁾] → a⁽ⁿ⁾`, 3 poles, 0 zeros,
    /// delay 1, polynomial output. (choice) Degree 3: the lowest odd degree that can bend both
    /// ends of the range (the seed does not give its degree; 2 and 5 are compared in
    /// docs/HW.md). (choice) Poles within 0.9995: a time constant of at most 2000 samples
    /// (78 ms at 25.6 kHz), near a pure integrator but never one.
    fn default() -> Self {
        HwConfig {
            order: 0,
            states: StateFilter::default(),
            inputs: 3,
            poles: 3,
            zeros: 0,
            delay: 1,
            poly_degree: 3,
            max_iterations: 40,
            tolerance: 1e-7,
            max_pole_radius: 0.9995,
        }
    }
}

impl HwConfig {
    /// The seed's configuration for output order `n`.
    pub fn for_order(order: usize) -> Self {
        HwConfig {
            order,
            ..HwConfig::default()
        }
    }

    /// Every problem of the configuration at once.
    pub fn validate(&self) -> Result<(), HwError> {
        let mut problems = Vec::new();
        let mut check = |ok: bool, text: &str| {
            if !ok {
                problems.push(text.to_string());
            }
        };
        check(self.order <= 20, "order must be 0…20");
        check((1..=8).contains(&self.inputs), "inputs must be 1…8");
        check(self.poles <= 10, "poles must be 0…10");
        check(self.zeros <= 10, "zeros must be 0…10");
        check(self.delay <= 10, "delay must be 0…10 samples");
        check(
            (1..=7).contains(&self.poly_degree),
            "poly_degree must be 1…7",
        );
        check(
            self.max_iterations <= 10_000,
            "max_iterations must be ≤ 10000",
        );
        check(
            self.tolerance.is_finite() && self.tolerance >= 0.0,
            "tolerance must be a number ≥ 0",
        );
        check(
            self.max_pole_radius > 0.0 && self.max_pole_radius < 1.0,
            "max_pole_radius must be in (0, 1)",
        );
        if problems.is_empty() {
            Ok(())
        } else {
            Err(HwError::Config {
                problems: problems.join("; "),
            })
        }
    }

    /// Parameters identified.
    pub fn parameters(&self) -> usize {
        self.inputs * (self.zeros + 1 + self.poles) + self.poly_degree
    }

    /// Shortest record (after differencing) the identification accepts: ten samples per
    /// parameter and at least 64.
    pub fn min_samples(&self) -> usize {
        (10 * self.parameters()).max(64) + self.poles.max(self.delay + self.zeros)
    }

    /// Whether `model` has this structure (so it can warm-start an identification).
    pub fn matches(&self, model: &HwModel) -> bool {
        model.order == self.order
            && model.inputs() == self.inputs
            && model.output.degree() == self.poly_degree
            && model.linear.iter().all(|tf| {
                tf.b.len() == self.zeros + 1 && tf.f.len() == self.poles && tf.delay == self.delay
            })
    }
}

/// Why a model could not be identified or applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HwError {
    #[error("sample {index} is NaN or infinite; repair the record or cut that part out")]
    NonFinite { index: usize },
    #[error("{got} samples, but the model needs at least {needed}; give a longer record")]
    TooShort { got: usize, needed: usize },
    #[error("sample rate {fs_hz} Hz is not usable; give the rate in Hz, e.g. 25600")]
    SampleRate { fs_hz: f64 },
    #[error("virtual state of order {order} is constant: a flat record has no dynamics to identify; check the sensor")]
    Flat { order: usize },
    #[error("the model needs virtual states up to order {needed}, these go up to {have}")]
    MissingOrders { have: usize, needed: usize },
    #[error("HW model configuration: {problems}")]
    Config { problems: String },
}

/// Builds the states a model of `config` needs from raw samples and identifies it: the
/// one-call form for a record.
pub fn identify_record(
    samples: &[f64],
    fs_hz: f64,
    config: &HwConfig,
    warm: Option<&HwModel>,
) -> Result<HwFit, HwError> {
    config.validate()?;
    let states = VirtualStates::new(
        samples,
        fs_hz,
        config.order + config.inputs,
        config.min_samples(),
        config.states,
    )?;
    identify(&states, config, warm)
}
