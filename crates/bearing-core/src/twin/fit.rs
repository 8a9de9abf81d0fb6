//! Fitting the twin to a measured envelope spectrum (MODELS.md §4), one fault hypothesis at a
//! time, and comparing the hypotheses: a model-based diagnosis.
//!
//! The error is the envelope-spectrum error of seed 000, `1 − cos(S_meas, S_twin)` over
//! `0 … 10·f_d` (amplitude spectra, DC bins excluded). The twin's power spectrum is
//! `a⁴·U + c·N` ([`super::model`]); for given shape parameters the best `a⁴` and `c` are a
//! two-variable non-negative least-squares problem with a closed-form answer, so the search
//! only runs over the shape:
//!
//! 1. the resonance `f_n` from the band's raw power spectrum, where it is observable (the
//!    envelope spectrum hardly depends on it while the band holds the resonance): a Lorentzian
//!    of half-width `B/2π` plus a floor, fitted on the spectrum smoothed over one `f_d`;
//! 2. the impact rate `f_d` (slip) by a scan over the tolerance, since the harmonics make the
//!    error sharply multimodal in it;
//! 3. a bounded Nelder–Mead over `log B`, the jitter and the noise-to-twin ratio, warm-started
//!    from the previous fit when there is one;
//! 4. `f_n` again with the fitted `B`, and a last golden-section refinement of `f_d`.
//!
//! (choice) The load distribution is fixed (ε = 0.5, n = 3/2, defect on the load line); the
//! defect length is not fitted.

use super::model::{EnvelopeModel, ShapeParams};
use super::optimize::{golden_section, nelder_mead};
use crate::analysis::Band;
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use serde::Serialize;

/// The fault hypotheses a twin can have.
pub const HYPOTHESES: [FaultKind; 3] =
    [FaultKind::OuterRace, FaultKind::InnerRace, FaultKind::Ball];

/// Bounds of the fitted parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitBounds {
    pub decay_per_s: (f64, f64),
    pub jitter: (f64, f64),
    /// Relative slip tolerance of the impact rate around its nominal value.
    pub slip: f64,
}

impl Default for FitBounds {
    fn default() -> Self {
        FitBounds {
            decay_per_s: (50.0, 5_000.0),
            jitter: (0.000_5, 0.05),
            slip: 0.02,
        }
    }
}

/// The twin's parameters for one hypothesis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TwinParams {
    /// Impact amplitude `a` at full load, g.
    pub a: f64,
    /// Decay rate `B`, 1/s.
    #[serde(rename = "B")]
    pub decay_per_s: f64,
    /// Resonance `f_n`, Hz.
    pub f_n: f64,
    /// Impact rate `f_d` (the fault frequency with slip), Hz.
    pub f_d: f64,
    /// Slip: `f_d` relative to the nominal fault frequency, minus one.
    pub slip: f64,
    /// Jitter of the impact times, as a fraction of the impact period.
    pub jitter: f64,
    /// Level of the noise floor of the squared-envelope power spectrum, g⁴ per bin at 0 Hz.
    pub noise_floor: f64,
}

impl TwinParams {
    pub fn shape(&self) -> ShapeParams {
        ShapeParams {
            impact_rate_hz: self.f_d,
            decay_per_s: self.decay_per_s,
            resonance_hz: self.f_n,
            jitter: self.jitter,
        }
    }
}

/// The fit of one hypothesis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HypothesisFit {
    pub fault: FaultKind,
    pub band: Band,
    pub params: TwinParams,
    /// `1 − cos(S_meas, S_twin)` over the range of interest.
    pub error: f64,
    pub evaluations: usize,
}

/// A measured squared-envelope spectrum to fit (amplitude per bin from 0 Hz, as
/// [`crate::analysis::envelope::EnvelopeSpectrum`]).
#[derive(Debug, Clone, Copy)]
pub struct MeasuredEnvelope<'a> {
    pub band: Band,
    pub bin_hz: f64,
    pub amplitude: &'a [f32],
}

/// The raw signal's power spectrum (per bin from 0 Hz), used to place the resonance.
#[derive(Debug, Clone, Copy)]
pub struct MeasuredPowerSpectrum<'a> {
    pub bin_hz: f64,
    pub power: &'a [f32],
}

/// The highest envelope frequency a fit of impact rate `f_d` looks at.
pub fn fit_range_hz(f_d: f64, slip: f64) -> f64 {
    10.0 * f_d * (1.0 + slip)
}

/// Fits twins; owns its scratch buffers so that repeated fits allocate little.
#[derive(Default)]
pub struct TwinFitter {
    bounds: FitBounds,
    twin: Vec<f64>,
    noise: Vec<f64>,
    measured: Vec<f64>,
}

/// What the non-negative least squares found for one shape.
#[derive(Clone, Copy)]
struct Scales {
    /// Weight of the unit twin (`a⁴`) and of the noise shape, in power units.
    twin: f64,
    noise: f64,
    error: f64,
}

impl TwinFitter {
    pub fn new(bounds: FitBounds) -> Self {
        TwinFitter {
            bounds,
            ..Default::default()
        }
    }

    /// Fits the twin of `fault` to `measured`, starting from `previous` when given.
    pub fn fit(
        &mut self,
        fault: FaultKind,
        freqs: &FaultFrequencies,
        measured: &MeasuredEnvelope,
        raw: Option<&MeasuredPowerSpectrum>,
        previous: Option<&TwinParams>,
    ) -> HypothesisFit {
        let nominal = fault.frequency(freqs);
        let top = fit_range_hz(nominal, self.bounds.slip).min(measured.band.width_hz());
        let bins = ((top / measured.bin_hz).floor() as usize + 1).min(measured.amplitude.len());
        let mut model = EnvelopeModel::new(fault, freqs, measured.band, measured.bin_hz, bins);
        self.twin.resize(bins, 0.0);
        self.noise.resize(bins, 0.0);
        self.measured.clear();
        self.measured
            .extend(measured.amplitude[..bins].iter().map(|&a| f64::from(a)));
        let mut evaluations = 0;

        let (lo_b, hi_b) = self.bounds.decay_per_s;
        let (lo_j, hi_j) = self.bounds.jitter;
        let slip = self.bounds.slip;
        let mut shape = match previous {
            Some(p) => p.shape(),
            None => ShapeParams {
                impact_rate_hz: nominal,
                decay_per_s: (lo_b * hi_b)
                    .sqrt()
                    .clamp(lo_b, hi_b)
                    .min(800.0_f64.max(lo_b)),
                resonance_hz: measured.band.centre_hz(),
                jitter: 0.01_f64.clamp(lo_j, hi_j),
            },
        };
        shape.impact_rate_hz = shape
            .impact_rate_hz
            .clamp(nominal * (1.0 - slip), nominal * (1.0 + slip));
        if let Some(raw) = raw {
            shape.resonance_hz = fit_resonance(raw, measured.band, shape.decay_per_s, nominal);
        }

        // Impact rate: scan the tolerance (narrowly around a previous fit).
        let (scan_lo, scan_hi, steps) = match previous {
            Some(_) => (
                shape.impact_rate_hz * (1.0 - 0.1 * slip),
                shape.impact_rate_hz * (1.0 + 0.1 * slip),
                9,
            ),
            None => (nominal * (1.0 - slip), nominal * (1.0 + slip), 41),
        };
        let mut best = (f64::MAX, shape.impact_rate_hz);
        for i in 0..steps {
            let f_d = scan_lo + (scan_hi - scan_lo) * i as f64 / (steps - 1) as f64;
            let e = self
                .evaluate(
                    &mut model,
                    &ShapeParams {
                        impact_rate_hz: f_d,
                        ..shape
                    },
                    None,
                )
                .error;
            evaluations += 1;
            if e < best.0 {
                best = (e, f_d);
            }
        }
        shape.impact_rate_hz = best.1;

        // Decay, jitter and noise ratio on the unit cube.
        let ratio_log_range = (-9.0, 9.0);
        let start_ratio = self.evaluate(&mut model, &shape, None);
        let start_log_ratio = if start_ratio.twin > 0.0 && start_ratio.noise > 0.0 {
            (start_ratio.noise / start_ratio.twin)
                .log10()
                .clamp(ratio_log_range.0, ratio_log_range.1)
        } else {
            0.0
        };
        let to_cube = |s: &ShapeParams, log_ratio: f64| {
            [
                (s.decay_per_s.ln() - lo_b.ln()) / (hi_b.ln() - lo_b.ln()),
                (s.jitter - lo_j) / (hi_j - lo_j),
                (log_ratio - ratio_log_range.0) / (ratio_log_range.1 - ratio_log_range.0),
            ]
        };
        let from_cube = |p: &[f64; 3], s: &ShapeParams| {
            (
                ShapeParams {
                    decay_per_s: (lo_b.ln() + p[0] * (hi_b.ln() - lo_b.ln())).exp(),
                    jitter: lo_j + p[1] * (hi_j - lo_j),
                    ..*s
                },
                ratio_log_range.0 + p[2] * (ratio_log_range.1 - ratio_log_range.0),
            )
        };
        let mut log_ratio = start_log_ratio;
        for round in 0..2 {
            let base = shape;
            let step = if previous.is_some() || round > 0 {
                0.05
            } else {
                0.2
            };
            let budget = if round == 0 { 120 } else { 60 };
            let (p, _, n) = nelder_mead(to_cube(&base, log_ratio), step, budget, 1e-7, |p| {
                let (s, r) = from_cube(p, &base);
                self.evaluate(&mut model, &s, Some(10f64.powf(r))).error
            });
            evaluations += n;
            (shape, log_ratio) = from_cube(&p, &base);
            if let Some(raw) = raw {
                shape.resonance_hz =
                    fit_resonance(raw, measured.band, shape.decay_per_s, shape.impact_rate_hz);
            }
        }
        let ratio = 10f64.powf(log_ratio);
        let (f_d, _) = golden_section(
            shape.impact_rate_hz * (1.0 - 0.002),
            shape.impact_rate_hz * (1.0 + 0.002),
            12,
            |f_d| {
                evaluations += 1;
                self.evaluate(
                    &mut model,
                    &ShapeParams {
                        impact_rate_hz: f_d,
                        ..shape
                    },
                    Some(ratio),
                )
                .error
            },
        );
        shape.impact_rate_hz = f_d.clamp(nominal * (1.0 - slip), nominal * (1.0 + slip));
        let scales = self.evaluate(&mut model, &shape, Some(ratio));
        evaluations += 1;
        HypothesisFit {
            fault,
            band: measured.band,
            params: TwinParams {
                a: scales.twin.max(0.0).powf(0.25),
                decay_per_s: shape.decay_per_s,
                f_n: shape.resonance_hz,
                f_d: shape.impact_rate_hz,
                slip: shape.impact_rate_hz / nominal - 1.0,
                jitter: shape.jitter,
                noise_floor: scales.noise,
            },
            error: scales.error,
            evaluations,
        }
    }

    /// The twin's amplitude spectrum for `params` on the bins of the last fit's model, into `out`.
    pub fn twin_amplitude(
        &mut self,
        fault: FaultKind,
        freqs: &FaultFrequencies,
        band: Band,
        bin_hz: f64,
        params: &TwinParams,
        out: &mut [f64],
    ) {
        let mut model = EnvelopeModel::new(fault, freqs, band, bin_hz, out.len());
        self.noise.resize(out.len(), 0.0);
        model.basis(&params.shape(), out, &mut self.noise);
        let twin_scale = params.a.powi(4);
        for (o, n) in out.iter_mut().zip(&self.noise) {
            *o = (twin_scale * *o + params.noise_floor * n).max(0.0).sqrt();
        }
    }

    /// The error of a shape. With `ratio` (noise weight over twin weight) the amplitude scale is
    /// fitted by least squares; without, both weights come from a non-negative least-squares
    /// fit in the power domain.
    fn evaluate(
        &mut self,
        model: &mut EnvelopeModel,
        shape: &ShapeParams,
        ratio: Option<f64>,
    ) -> Scales {
        model.basis(shape, &mut self.twin, &mut self.noise);
        const FIRST_BIN: usize = 2;
        let range = FIRST_BIN..self.twin.len();
        let ratio = match ratio {
            Some(r) => r,
            None => {
                let (twin, noise) = nonnegative_least_squares(
                    self.measured[range.clone()].iter().map(|a| a * a),
                    &self.twin[range.clone()],
                    &self.noise[range.clone()],
                );
                if twin <= 0.0 {
                    return Scales {
                        twin: 0.0,
                        noise,
                        error: 1.0,
                    };
                }
                noise / twin
            }
        };
        let (mut dot, mut model_norm, mut measured_norm) = (0.0, 0.0, 0.0);
        for k in range {
            let t = (self.twin[k] + ratio * self.noise[k]).max(0.0).sqrt();
            let m = self.measured[k];
            dot += t * m;
            model_norm += t * t;
            measured_norm += m * m;
        }
        if model_norm <= 0.0 || measured_norm <= 0.0 {
            return Scales {
                twin: 0.0,
                noise: 0.0,
                error: 1.0,
            };
        }
        // Amplitude scale s: measured ≈ s·sqrt(U + r·N) = sqrt(s²U + s²r·N).
        let s = dot / model_norm;
        let twin = s * s;
        Scales {
            twin,
            noise: twin * ratio,
            error: 1.0 - dot / (model_norm.sqrt() * measured_norm.sqrt()),
        }
    }
}

/// `min ‖y − x·u − z·v‖²` over `x, z ≥ 0`; returns `(x, z)`.
fn nonnegative_least_squares(
    y: impl Iterator<Item = f64> + Clone,
    u: &[f64],
    v: &[f64],
) -> (f64, f64) {
    let (mut uu, mut vv, mut uv, mut uy, mut vy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for ((y, &u), &v) in y.zip(u).zip(v) {
        uu += u * u;
        vv += v * v;
        uv += u * v;
        uy += u * y;
        vy += v * y;
    }
    let det = uu * vv - uv * uv;
    if det > 1e-300 {
        let x = (uy * vv - vy * uv) / det;
        let z = (vy * uu - uy * uv) / det;
        if x >= 0.0 && z >= 0.0 {
            return (x, z);
        }
    }
    // One of the two at zero: keep the better.
    let only_u = if uu > 0.0 { (uy / uu).max(0.0) } else { 0.0 };
    let only_v = if vv > 0.0 { (vy / vv).max(0.0) } else { 0.0 };
    let residual_u = -2.0 * only_u * uy + only_u * only_u * uu;
    let residual_v = -2.0 * only_v * vy + only_v * only_v * vv;
    if residual_u <= residual_v {
        (only_u, 0.0)
    } else {
        (0.0, only_v)
    }
}

/// The resonance inside `band`: a Lorentzian `1/(B² + 4π²(f − f_n)²)` plus a floor fitted to
/// the raw power spectrum averaged over cells half an impact-rate wide (which turns the comb of
/// impact lines into its envelope and leaves a few hundred points to fit).
pub fn fit_resonance(
    raw: &MeasuredPowerSpectrum,
    band: Band,
    decay: f64,
    impact_rate_hz: f64,
) -> f64 {
    let first = ((band.lo_hz / raw.bin_hz).ceil() as usize).max(1);
    let last = ((band.hi_hz / raw.bin_hz).floor() as usize).min(raw.power.len().saturating_sub(1));
    let cell = ((0.5 * impact_rate_hz / raw.bin_hz).round() as usize).max(1);
    if last < first + 4 * cell {
        return band.centre_hz();
    }
    let (frequencies, averaged): (Vec<f64>, Vec<f64>) = raw.power[first..=last]
        .chunks(cell)
        .enumerate()
        .map(|(i, chunk)| {
            let centre = first as f64 + (i * cell) as f64 + (chunk.len() as f64 - 1.0) / 2.0;
            (
                centre * raw.bin_hz,
                chunk.iter().map(|&p| f64::from(p)).sum::<f64>() / chunk.len() as f64,
            )
        })
        .unzip();
    let ones = vec![1.0; averaged.len()];
    let mut lorentz = vec![0.0; averaged.len()];
    let mut error_at = |f_n: f64| {
        for (l, f) in lorentz.iter_mut().zip(&frequencies) {
            *l = 1.0 / (decay * decay + (std::f64::consts::TAU * (f - f_n)).powi(2));
        }
        let (x, z) = nonnegative_least_squares(averaged.iter().copied(), &lorentz, &ones);
        averaged
            .iter()
            .zip(&lorentz)
            .map(|(s, l)| (s - x * l - z).powi(2))
            .sum::<f64>()
    };
    // Coarse scan, then golden section around the best cell.
    const STEPS: usize = 60;
    let step = band.width_hz() / STEPS as f64;
    let best = (0..=STEPS)
        .map(|i| band.lo_hz + i as f64 * step)
        .map(|f| (error_at(f), f))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(band.centre_hz(), |(_, f)| f);
    golden_section(
        (best - step).max(band.lo_hz),
        (best + step).min(band.hi_hz),
        20,
        error_at,
    )
    .0
}
