//! The twin over a whole record: fit every fault hypothesis in the band where the band-score
//! analysis found it best, compare the fits (a model-based diagnosis), describe what the best
//! twin does not explain (residuals), and combine its verdict with the band scores.

use super::fit::{
    fit_range_hz, HypothesisFit, MeasuredEnvelope, MeasuredPowerSpectrum, TwinFitter, TwinParams,
    HYPOTHESES,
};
use super::model::{stribeck_load, LOAD_EXPONENT, LOAD_ZONE};
use crate::analysis::diagnosis::{Diagnosis, Verdict};
use crate::analysis::envelope::{
    hop_samples, welch_envelope_spectrum, welch_power_spectrum, window_starts, BandEnvelope,
    FftPlans, WindowTransform,
};
use crate::analysis::Band;
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use serde::Serialize;

/// What the best twin leaves unexplained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ResidualSummary {
    /// `‖S_meas − S_twin‖² / ‖S_meas‖²` of the amplitude envelope spectra over the fit range.
    pub energy_ratio: f64,
    /// The largest excess of the measured envelope spectrum over the twin's: where something
    /// the twin does not model (another fault, a machine line) shows.
    pub largest_peak_hz: f64,
    pub largest_peak_amplitude: f64,
    /// In-band time residual: `‖e_meas − e_twin‖² / ‖e_meas − mean‖²` of the squared envelope
    /// over the first windows, the twin's impacts aligned to the measured ones.
    pub time_energy_ratio: f64,
}

/// The twin's fits of one record and what follows from them.
#[derive(Debug, Clone)]
pub struct TwinDiagnosis {
    /// One fit per hypothesis, in [`HYPOTHESES`] order.
    pub fits: Vec<HypothesisFit>,
    /// Index of the best (lowest error) fit.
    pub best: usize,
    /// Error of the runner-up minus error of the best.
    pub margin: f64,
    pub residual: ResidualSummary,
    /// The best hypothesis's measured and twin amplitude spectra (bins from 0 Hz).
    pub bin_hz: f64,
    pub measured: Vec<f64>,
    pub twin: Vec<f64>,
}

impl TwinDiagnosis {
    pub fn best_fit(&self) -> &HypothesisFit {
        &self.fits[self.best]
    }

    pub fn error_of(&self, kind: FaultKind) -> Option<f64> {
        self.fits.iter().find(|f| f.fault == kind).map(|f| f.error)
    }
}

/// Fits the twin of every hypothesis to `signal`, each in its band; `previous` warm-starts
/// the fits (same order as [`HYPOTHESES`]).
#[allow(clippy::too_many_arguments)]
pub fn fit_record(
    plans: &mut FftPlans,
    fitter: &mut TwinFitter,
    signal: &[f32],
    fs_hz: f64,
    freqs: &FaultFrequencies,
    bands: &[Band; 3],
    window: usize,
    overlap: f64,
    previous: Option<&[TwinParams]>,
) -> TwinDiagnosis {
    let bin_hz = fs_hz / window as f64;
    let raw = welch_power_spectrum(plans, signal, window, overlap);
    let raw = MeasuredPowerSpectrum {
        bin_hz,
        power: &raw,
    };
    let mut spectra = Vec::with_capacity(3);
    let fits: Vec<HypothesisFit> = HYPOTHESES
        .iter()
        .zip(bands)
        .enumerate()
        .map(|(i, (&kind, &band))| {
            let bins = ((fit_range_hz(kind.frequency(freqs), 0.02) / bin_hz).ceil() as usize + 2)
                .min(window / 2);
            let spectrum =
                welch_envelope_spectrum(plans, signal, fs_hz, band, window, overlap, bins);
            let measured = MeasuredEnvelope {
                band,
                bin_hz,
                amplitude: &spectrum.amplitude,
            };
            let fit = fitter.fit(
                kind,
                freqs,
                &measured,
                Some(&raw),
                previous.and_then(|p| p.get(i)),
            );
            spectra.push(spectrum.amplitude);
            fit
        })
        .collect();
    let best = (0..fits.len())
        .min_by(|&a, &b| fits[a].error.total_cmp(&fits[b].error))
        .unwrap_or(0);
    let margin = fits
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != best)
        .map(|(_, f)| f.error - fits[best].error)
        .fold(f64::INFINITY, f64::min);
    let margin = if margin.is_finite() { margin } else { 0.0 };

    let fit = &fits[best];
    let measured: Vec<f64> = spectra[best].iter().map(|&a| f64::from(a)).collect();
    let bins = ((fit_range_hz(fit.fault.frequency(freqs), 0.02) / bin_hz).floor() as usize + 1)
        .min(measured.len());
    let mut twin = vec![0.0; bins];
    fitter.twin_amplitude(fit.fault, freqs, fit.band, bin_hz, &fit.params, &mut twin);
    let residual = ResidualSummary {
        time_energy_ratio: time_residual(plans, signal, fs_hz, freqs, fit, window, overlap),
        ..spectral_residual(&measured[..bins], &twin, bin_hz)
    };
    TwinDiagnosis {
        fits,
        best,
        margin,
        residual,
        bin_hz,
        measured: measured[..bins].to_vec(),
        twin,
    }
}

fn spectral_residual(measured: &[f64], twin: &[f64], bin_hz: f64) -> ResidualSummary {
    const FIRST_BIN: usize = 2;
    let (mut residual, mut total, mut peak) = (0.0, 0.0, (0.0, 0usize));
    for k in FIRST_BIN..measured.len().min(twin.len()) {
        let r = measured[k] - twin[k];
        residual += r * r;
        total += measured[k] * measured[k];
        if r > peak.0 {
            peak = (r, k);
        }
    }
    ResidualSummary {
        energy_ratio: if total > 0.0 { residual / total } else { 0.0 },
        largest_peak_hz: peak.1 as f64 * bin_hz,
        largest_peak_amplitude: peak.0,
        time_energy_ratio: f64::NAN,
    }
}

/// Windows the time residual is averaged over.
const TIME_RESIDUAL_WINDOWS: usize = 3;

/// The squared envelope of the band over the first windows against the twin's, with the twin's
/// impact phase (and, for inner-race and ball faults, the modulation phase) chosen to match.
/// (choice) The twin's impact envelope is taken as `e^{−2Bt}`, ignoring the band's clipping.
fn time_residual(
    plans: &mut FftPlans,
    signal: &[f32],
    fs_hz: f64,
    freqs: &FaultFrequencies,
    fit: &HypothesisFit,
    window: usize,
    overlap: f64,
) -> f64 {
    let mut transform = WindowTransform::new(window, plans);
    let mut band = BandEnvelope::new(fit.band, fs_hz, window, 2, plans);
    let modulation_hz = match fit.fault {
        FaultKind::InnerRace => freqs.shaft,
        FaultKind::Ball => freqs.ftf,
        FaultKind::OuterRace | FaultKind::Cage => 0.0,
    };
    let (impact_phases, modulation_phases) = (24, if modulation_hz > 0.0 { 8 } else { 1 });
    // q² on a table of angles: the inner loop then needs no trigonometry.
    const ANGLES: usize = 360;
    let load_table: Vec<f64> = (0..ANGLES)
        .map(|i| {
            stribeck_load(
                std::f64::consts::TAU * i as f64 / ANGLES as f64,
                LOAD_ZONE,
                LOAD_EXPONENT,
            )
            .powi(2)
        })
        .collect();
    let p = &fit.params;
    let mut ratios = Vec::new();
    let mut twin = vec![0f64; band.analytic_len()];
    for start in window_starts(signal.len(), window, hop_samples(window, overlap))
        .take(TIME_RESIDUAL_WINDOWS)
    {
        let measured: Vec<f64> = band
            .analytic_from(transform.transform(&signal[start..start + window], &[]))
            .iter()
            .map(|c| f64::from(c.norm_sqr()))
            .collect();
        let rate = fs_hz * measured.len() as f64 / window as f64;
        let mean = measured.iter().sum::<f64>() / measured.len() as f64;
        let spread: f64 = measured.iter().map(|e| (e - mean).powi(2)).sum();
        if spread <= 0.0 {
            continue;
        }
        let decay_per_sample = (-2.0 * p.decay_per_s / rate).exp();
        let mut best = f64::INFINITY;
        for impact_phase in 0..impact_phases {
            for modulation_phase in 0..modulation_phases {
                let phase = impact_phase as f64 / impact_phases as f64;
                let theta0 =
                    std::f64::consts::TAU * modulation_phase as f64 / modulation_phases as f64;
                let mut next_impact = 0usize;
                let mut level = 0.0;
                for (n, t) in twin.iter_mut().enumerate() {
                    level *= decay_per_sample;
                    let now = n as f64 / rate;
                    loop {
                        let t_k = (phase + next_impact as f64) / p.f_d;
                        if t_k > now {
                            break;
                        }
                        let turns =
                            (theta0 / std::f64::consts::TAU + modulation_hz * t_k).rem_euclid(1.0);
                        let weight = p.a
                            * p.a
                            * load_table[((turns * ANGLES as f64) as usize).min(ANGLES - 1)];
                        // The impact falls between two samples: decay it to this sample.
                        level += weight * (-2.0 * p.decay_per_s * (now - t_k)).exp();
                        next_impact += 1;
                    }
                    *t = level;
                }
                let offset = mean - twin.iter().sum::<f64>() / twin.len() as f64;
                let error: f64 = measured
                    .iter()
                    .zip(&twin)
                    .map(|(m, t)| (m - t - offset).powi(2))
                    .sum();
                best = best.min(error / spread);
            }
        }
        ratios.push(best);
    }
    if ratios.is_empty() {
        f64::NAN
    } else {
        ratios.iter().sum::<f64>() / ratios.len() as f64
    }
}

/// The confidence of a fault found by the band scores once the twin has a say: its best fit
/// agreeing raises it toward 1, disagreeing lowers it toward 0.5, each in proportion to how
/// decisive the twin is (a `margin` of 0.1 in error or more counts fully).
pub fn twin_adjusted_confidence(confidence: f64, twin_agrees: bool, margin: f64) -> f64 {
    let weight = (margin / 0.1).clamp(0.0, 1.0);
    if twin_agrees {
        confidence + (1.0 - confidence) * 0.5 * weight
    } else {
        confidence - (confidence - 0.5) * weight
    }
}

/// How the twin changes the verdict of the band scores.
///
/// (choice) The band scores decide and the twin adjusts the confidence. The scores are
/// calibrated on real records (no false class on the developer set) and say plainly which
/// lines stand out; the twin's error is relative (a wrong hypothesis can still fit a noisy
/// spectrum's floor well), so it is supporting evidence: agreement raises the confidence,
/// disagreement lowers it and is said in the reason. A twin that favours a fault where the
/// scores see none is reported but raises no fault.
pub fn combine(scores: &Diagnosis, twin: &TwinDiagnosis) -> (Diagnosis, bool, String) {
    let twin_fault = twin.best_fit().fault;
    let mut combined = scores.clone();
    let (agrees, note) = match scores.verdict {
        Verdict::None => (
            true,
            format!(
                "the twin fits {} best (error {:.3}, margin {:.3}); the band scores see no clear fault, so none is raised",
                twin_fault.name(),
                twin.best_fit().error,
                twin.margin
            ),
        ),
        verdict if verdict.faults().contains(&twin_fault) => {
            combined.confidence = twin_adjusted_confidence(scores.confidence, true, twin.margin);
            (true, format!("the twin agrees: {} fits best (error {:.3}, margin {:.3})", twin_fault.name(), twin.best_fit().error, twin.margin))
        }
        verdict => {
            combined.confidence = twin_adjusted_confidence(scores.confidence, false, twin.margin);
            (
                false,
                format!(
                    "the twin DISAGREES: it fits {} best (error {:.3}, margin {:.3}), not {}",
                    twin_fault.name(),
                    twin.best_fit().error,
                    twin.margin,
                    verdict.name()
                ),
            )
        }
    };
    combined.reason = format!("{}; {note}", scores.reason);
    (combined, agrees, note)
}
