//! Calibration of the physics twin to a measured record (seed 001's step, MODELS.md §5): find
//! the resonator stiffness `k_r`, its damping `c_r`, the contact stiffness `k_b` and the defect
//! width whose simulated spectrum best matches the measured one inside the resonance band.
//!
//! Why these four: `k_r` and `c_r` place the resonance the defect's impacts excite and set its
//! bandwidth; `k_b` and the defect width set how hard the impacts are. The masses, the support
//! stiffnesses and the load stay at their defaults: they move the low-frequency modes, which
//! the band does not see.
//!
//! The misfit: the Welch amplitude spectra (Hann, [`SPECTRUM_WINDOW`] samples, half overlap)
//! of the measured record and of a short simulated record, compared bin by bin inside the band
//! in decibels: the RMS of `20·log10(simulated / measured)`. Decibels because that is how people
//! read a spectrum (the plot has a log axis) and so that the resonance's hump and the valleys
//! beside it both count, not only the highest bins. The simulated power gets a white noise floor
//! (the sensor's and the machine's other sources), its level found for each candidate by a
//! golden-section search. 0 dB is a perfect fit.
//!
//! The search: differential evolution over the four parameters in log coordinates
//! ([`super::evolve::differential_evolution`]), each generation's candidates simulated
//! in parallel. Seed 001 used Beluga Whale Optimization at 27–175 s per iteration; here a whole
//! calibration takes seconds (docs/PHYSICS.md has the measured times).

use super::evolve::{differential_evolution, EvolutionProgress, EvolutionSettings};
use super::model::simulate;
use super::params::{hertz_contact_stiffness, PhysicsError, PhysicsParams};
use crate::analysis::band::Band;
use crate::analysis::envelope::{welch_power_spectrum, FftPlans};
use crate::twin::optimize::golden_section;
use crate::twin::SimulatedFault;
use serde::Serialize;

/// Samples per Welch segment of the compared spectra: 256 at 12 kHz is 47 Hz per bin, fine
/// enough for the resonance's shape, coarse enough that a short simulation gives a smooth
/// spectrum.
pub const SPECTRUM_WINDOW: usize = 256;

/// The search box and budget of a calibration.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CalibrationSettings {
    /// Range of the resonance `√(k_r/m_r)/2π`, Hz (searched on a log scale).
    pub resonance_hz: (f64, f64),
    /// Range of the resonator's damping ratio `c_r/(2√(k_r·m_r))` (log scale).
    pub damping_ratio: (f64, f64),
    /// Range of `k_b` as a multiple of the Hertz value for the bearing (log scale).
    pub contact_factor: (f64, f64),
    /// Range of the defect width, mm (log scale). Unused for a healthy bearing.
    pub defect_width_mm: (f64, f64),
    /// Length of each candidate's simulation, s.
    pub simulated_s: f64,
    pub population: usize,
    pub generations: usize,
    pub seed: u64,
}

impl CalibrationSettings {
    /// The default box for a record sampled at `fs_hz` whose resonance band is `band`: the
    /// resonance anywhere from half the band's lower edge to twice its upper edge (at most
    /// 0.45·fs), damping 0.5–30 %, `k_b` from a fifth to five times the Hertz value, defect
    /// 0.05–1.5 mm; 0.2 s per candidate, 20 candidates × 25 generations (520 simulations).
    pub fn for_band(band: Band, fs_hz: f64) -> Self {
        CalibrationSettings {
            resonance_hz: (
                (band.lo_hz / 2.0).max(100.0),
                (band.hi_hz * 2.0).min(0.45 * fs_hz),
            ),
            damping_ratio: (0.005, 0.3),
            contact_factor: (0.2, 5.0),
            defect_width_mm: (0.05, 1.5),
            simulated_s: 0.2,
            population: 20,
            generations: 25,
            seed: 1,
        }
    }
}

/// The outcome: the fitted parameters, the error before and after, and the spectra for a plot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// The starting parameters with `k_r`, `c_r`, `k_b` and the defect width replaced.
    pub params: PhysicsParams,
    /// In-band spectral RMSE of the fit, dB (see the module documentation).
    pub error_db: f64,
    /// The same error with the starting parameters, dB.
    pub initial_error_db: f64,
    /// White noise floor fitted beside the model, g per √Hz.
    pub noise_floor_g_per_sqrt_hz: f64,
    pub band: Band,
    pub evaluations: usize,
    pub generations: usize,
    /// Best error after each generation (0: the initial population).
    pub history: Vec<f64>,
    /// Bin spacing of the spectra, Hz; the spectra run from 0 Hz to fs/2.
    pub bin_hz: f64,
    /// Amplitude spectra (g per √Hz) of the measured record, the fitted model (noise floor
    /// included) and the starting parameters (with their own best floor).
    pub measured: Vec<f64>,
    pub fitted: Vec<f64>,
    pub initial: Vec<f64>,
}

/// Where `value` sits in `range` on a log scale, 0 to 1 (clamped).
fn unit_log((lo, hi): (f64, f64), value: f64) -> f64 {
    if hi > lo {
        ((value / lo).ln() / (hi / lo).ln()).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// The four calibrated values of a point of the unit cube.
fn apply(base: &PhysicsParams, settings: &CalibrationSettings, point: &[f64; 4]) -> PhysicsParams {
    let log_between = |(lo, hi): (f64, f64), u: f64| (lo.ln() + u * (hi / lo).ln()).exp();
    let mut params = base.clone();
    let s = &mut params.structure;
    let resonance = log_between(settings.resonance_hz, point[0]);
    let zeta = log_between(settings.damping_ratio, point[1]);
    s.resonator_stiffness = s.resonator_mass_kg * (std::f64::consts::TAU * resonance).powi(2);
    s.resonator_damping = 2.0 * zeta * (s.resonator_stiffness * s.resonator_mass_kg).sqrt();
    s.contact_stiffness =
        hertz_contact_stiffness(&base.bearing) * log_between(settings.contact_factor, point[2]);
    if base.fault != SimulatedFault::None {
        let (lo, hi) = settings.defect_width_mm;
        // Never wider than the ball allows (the model's own limit).
        let hi = hi.min(0.9 * base.bearing.element_diameter_mm);
        params.defect_width_mm = log_between((lo.min(hi), hi), point[3]);
    }
    params
}

/// A measured spectrum and the band it is compared in.
struct Target {
    /// Power per bin (g²), 0 Hz to fs/2.
    power: Vec<f64>,
    bins: (usize, usize),
    bin_hz: f64,
}

/// Power below which a bin counts as this (g²): keeps the logarithm finite on a silent bin.
const TINY_POWER: f64 = 1e-30;

impl Target {
    /// The in-band RMS of `10·log10(simulated + floor) − 10·log10(measured)`, dB.
    fn error_db(&self, simulated: &[f64], floor: f64) -> f64 {
        let (first, last) = self.bins;
        let squared: f64 = (first..last)
            .map(|k| {
                let ratio = (simulated[k] + floor).max(TINY_POWER) / self.power[k].max(TINY_POWER);
                (10.0 * ratio.log10()).powi(2)
            })
            .sum();
        (squared / (last - first).max(1) as f64).sqrt()
    }

    /// The misfit of a simulated power spectrum (dB), its best floor (power per bin) and the
    /// amplitude spectrum with the floor.
    fn misfit(&self, simulated: &[f64]) -> (f64, f64, Vec<f64>) {
        let (first, last) = self.bins;
        let top = (first..last)
            .map(|k| self.power[k])
            .fold(TINY_POWER, f64::max)
            .log10();
        let (log_floor, error) = golden_section(top - 10.0, top, 40, |l| {
            self.error_db(simulated, 10f64.powf(l))
        });
        let floor = 10f64.powf(log_floor);
        let amplitude = simulated.iter().map(|p| (p + floor).sqrt()).collect();
        (error, floor, amplitude)
    }
}

/// The Welch power spectrum per bin (g²), 0 Hz to fs/2.
fn power_spectrum(signal: &[f32]) -> Vec<f64> {
    welch_power_spectrum(&mut FftPlans::default(), signal, SPECTRUM_WINDOW, 0.5)
        .into_iter()
        .map(f64::from)
        .collect()
}

/// Fits `k_r`, `c_r`, `k_b` and the defect width of `base` (bearing, speed, load, fault as the
/// record was taken) to `measured` (g at `base.fs_hz`) inside `band`. `progress` is called
/// after every generation. Errors: unusable `base`, a record shorter than a few Welch segments
/// or a band outside the spectrum.
pub fn calibrate(
    measured: &[f32],
    base: &PhysicsParams,
    band: Band,
    settings: &CalibrationSettings,
    progress: impl FnMut(&EvolutionProgress<4>),
) -> Result<Calibration, PhysicsError> {
    base.validate()?;
    let mut problems = Vec::new();
    if measured.len() < 4 * SPECTRUM_WINDOW {
        problems.push(format!(
            "the measured record has {} samples; calibration needs at least {}",
            measured.len(),
            4 * SPECTRUM_WINDOW
        ));
    }
    let nyquist = base.fs_hz / 2.0;
    if !(band.lo_hz >= 0.0 && band.hi_hz <= nyquist && band.width_hz() > 0.0) {
        problems.push(format!(
            "band {:.0}–{:.0} Hz must lie inside 0–{nyquist:.0} Hz",
            band.lo_hz, band.hi_hz
        ));
    }
    let ordered = |(lo, hi): (f64, f64)| lo.is_finite() && lo > 0.0 && hi.is_finite() && hi >= lo;
    for (name, range) in [
        ("resonance range (Hz)", settings.resonance_hz),
        ("damping-ratio range", settings.damping_ratio),
        ("contact-stiffness factor range", settings.contact_factor),
        ("defect-width range (mm)", settings.defect_width_mm),
    ] {
        if !ordered(range) {
            problems.push(format!(
                "{name} {range:?} must be positive and ordered (lo ≤ hi)"
            ));
        }
    }
    if settings.resonance_hz.1 >= nyquist {
        problems.push(format!(
            "resonance range up to {} Hz must stay below fs/2 = {nyquist} Hz",
            settings.resonance_hz.1
        ));
    }
    let simulated_samples = settings.simulated_s * base.fs_hz;
    if simulated_samples.is_nan() || simulated_samples < 4.0 * SPECTRUM_WINDOW as f64 {
        problems.push(format!(
            "simulated length {} s gives fewer than {} samples",
            settings.simulated_s,
            4 * SPECTRUM_WINDOW
        ));
    }
    if !problems.is_empty() {
        return Err(PhysicsError::Invalid {
            problems: problems.join("; "),
        });
    }
    let power = power_spectrum(measured);
    let bin_hz = base.fs_hz / SPECTRUM_WINDOW as f64;
    let bins = band.bins(base.fs_hz, SPECTRUM_WINDOW);
    let (first, last) = bins;
    // The heuristic start: the resonance at the strongest bin of the band, 5 % damping, the
    // Hertz contact and the starting defect width.
    let strongest = (first..last)
        .max_by(|&a, &b| power[a].total_cmp(&power[b]))
        .unwrap_or(first);
    let target = Target {
        power,
        bins,
        bin_hz,
    };
    let guess = [
        unit_log(settings.resonance_hz, strongest as f64 * bin_hz),
        unit_log(settings.damping_ratio, 0.05),
        unit_log(settings.contact_factor, 1.0),
        unit_log(settings.defect_width_mm, base.defect_width_mm),
    ];
    let mut short = base.clone();
    short.duration_s = settings.simulated_s;
    short.noise_g = 0.0;
    let spectrum_of = |params: &PhysicsParams| simulate(params).map(|x| power_spectrum(&x));
    let objective = |point: &[f64; 4]| match spectrum_of(&apply(&short, settings, point)) {
        Ok(simulated) => target.misfit(&simulated).0,
        // A candidate the integrator cannot handle is simply a bad candidate.
        Err(_) => f64::INFINITY,
    };
    let initial_spectrum = spectrum_of(&short)?;
    let (initial_error_db, _, initial) = target.misfit(&initial_spectrum);
    let mut history = Vec::new();
    let mut progress = progress;
    let result = differential_evolution(
        &EvolutionSettings {
            population: settings.population,
            generations: settings.generations,
            crossover: 0.9,
            tolerance: 1e-4,
            seed: settings.seed,
        },
        &[guess],
        objective,
        |p| {
            history.push(p.best_value);
            progress(p);
        },
    );
    let fitted_short = apply(&short, settings, &result.best);
    let (error_db, floor, fitted) = target.misfit(&spectrum_of(&fitted_short)?);
    let mut params = apply(base, settings, &result.best);
    params.noise_g = base.noise_g;
    Ok(Calibration {
        params,
        error_db,
        initial_error_db,
        noise_floor_g_per_sqrt_hz: (floor / target.bin_hz).sqrt(),
        band,
        evaluations: result.evaluations,
        generations: result.generation,
        history,
        bin_hz: target.bin_hz,
        measured: target.power.iter().map(|p| p.sqrt()).collect(),
        fitted,
        initial,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A record made by the model itself with known parameters: the calibration must find
    /// parameters whose spectrum matches it (the fit error near what the estimate's noise
    /// allows), much better than the defaults, with the resonance where it was put.
    #[test]
    fn calibration_recovers_a_known_resonance_from_a_simulated_record() {
        let mut truth = PhysicsParams::cwru(SimulatedFault::OuterRace).unwrap();
        truth.duration_s = 2.0;
        truth.noise_g = 0.002;
        let s = &mut truth.structure;
        s.resonator_stiffness = s.resonator_mass_kg * (std::f64::consts::TAU * 3_200.0f64).powi(2);
        s.resonator_damping = 2.0 * 0.04 * (s.resonator_stiffness * s.resonator_mass_kg).sqrt();
        s.contact_stiffness *= 1.5;
        truth.defect_width_mm = 0.3;
        let measured = simulate(&truth).unwrap();
        let band = Band::new(2_000.0, 4_500.0);
        let mut settings = CalibrationSettings::for_band(band, truth.fs_hz);
        settings.generations = 15;
        let base = PhysicsParams::cwru(SimulatedFault::OuterRace).unwrap();
        let mut calls = 0;
        let fit = calibrate(&measured, &base, band, &settings, |_| calls += 1).unwrap();
        assert_eq!(calls, fit.history.len());
        assert!(fit.history.windows(2).all(|w| w[1] <= w[0]));
        // The truth's own spectrum misses by the noise of a 0.2 s Welch estimate: about 1 dB.
        assert!(fit.error_db < 2.0, "fit error {} dB", fit.error_db);
        assert!(
            fit.initial_error_db > 3.0 * fit.error_db,
            "defaults {} dB",
            fit.initial_error_db
        );
        let resonance = fit.params.structure.resonance_hz();
        assert!(
            (resonance / 3_200.0 - 1.0).abs() < 0.05,
            "resonance {resonance} Hz"
        );
    }

    #[test]
    fn a_bad_band_or_a_short_record_is_an_error() {
        let base = PhysicsParams::cwru(SimulatedFault::OuterRace).unwrap();
        let settings = CalibrationSettings::for_band(Band::new(2_000.0, 4_000.0), 12_000.0);
        let message = calibrate(
            &[0.0; 100],
            &base,
            Band::new(5_000.0, 9_000.0),
            &settings,
            |_| {},
        )
        .unwrap_err()
        .to_string();
        assert!(message.contains("100 samples"), "{message}");
        assert!(message.contains("band 5000–9000"), "{message}");
    }
}
