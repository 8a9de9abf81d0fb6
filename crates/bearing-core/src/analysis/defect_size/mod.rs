//! The length of a race defect from the time between its entry and exit events (issue 30),
//! measured only where the record can resolve them: at 40 kHz and above.
//!
//! A rolling element crossing a race defect of length `L` makes two events `Δt = Z·L/(2π r f_d)`
//! apart (MODELS.md §4; [`BearingGeometry::defect_length_mm`] is the inverse): it unloads as it
//! enters and is reloaded, or strikes, as it leaves (Sawalhi & Randall 2011). For the SKF 6205 at
//! 1800 rpm that is 0.57 ms per mm; at 12 kHz a 0.2 mm defect's events lie 1.4 samples apart,
//! inside one ring of the resonance (docs/DIAGNOSIS.md §5), which is why we do not try below
//! [`MIN_SAMPLE_RATE_HZ`].
//!
//! # How (each step chosen by measurement on the physics twin, DIAGNOSIS.md §5)
//!
//! 1. **Find the impacts**: the analytic signal of the record (its first 20 s) in the fault's
//!    band; its envelope's maximum in each fault period (searched ±¼ period around the last one
//!    plus a period, so slip is followed). Only the strong ones (≥ half the 90th percentile) are kept: an
//!    inner-race defect strikes hard only in the load zone.
//! 2. **Synchronous average**: a segment of 0.9 periods around each impact, aligned to the
//!    average by the sub-sample peak of their cross-correlation in the band (two passes), then
//!    averaged: the hundreds or thousands of impacts add coherently, the noise does not. Averaging at the
//!    nominal period instead smears: 1 % slip walks the impacts by many samples over a record.
//! 3. **Whitening**: an AR model of order `fs/3000` (16 at 48 kHz; Yule–Walker) of the
//!    *average* removes the structure's ringing, so what remains is where force enters: the
//!    entry and the exit. Fitted on the whole record instead, the model whitens the noise floor
//!    more than the resonance, and the ringing left over made a false "exit" 0.4 ms after a
//!    single event (0.3 mm read as 0.53 mm, 0.2 mm as 1.25 mm).
//! 4. **Events**: the envelope of the whitened average, each frequency weighted by how far the
//!    average stands above the impact-to-impact spread there (a Wiener weight: the whitening
//!    would otherwise lift the bare noise of the high frequencies), above 1 kHz, smoothed over
//!    ±1 sample at 48 kHz. The two most prominent peaks are the entry and the exit.
//! 5. **Only when clear**: the second event's prominence must be ≥ ¼ of the first's and ≥ 3×
//!    the envelope's median; no third peak may come within 0.7 of the second (else which pair
//!    is meant is a guess); in each of 4 interleaved sub-averages both events must stand ≥ 2.5×
//!    that sub-average's median, and the 4 spacings must agree within 25 %.
//!
//! The uncertainty combines the spread of the sub-averages' spacings (standard error of their
//! mean), the sample grid, and half the main event's half-width at half maximum: the peaks of
//! two events closer than about their width pull towards each other, which is where the
//! twin's largest errors (−10 … −23 %) are.
//!
//! What we tried and dropped: the power cepstrum of the average (its echo peak drowns in the
//! resonance's own cepstrum: no clear peak at the spacing for 0.1–1 mm at a 3 kHz resonance), and
//! the whitened envelope without the Wiener weight (the prototype sized 34 of the 96 grid
//! records instead of 48, with the same errors).
//!
//! Sans-IO: samples in, a size or the reason there is none out; no clock, no file.

mod average;
mod events;

use super::band::Band;
use super::diagnosis::Verdict;
use super::record::RecordAnalysis;
use crate::bearing::{BearingGeometry, FaultKind, Race};
use average::Average;
use events::Events;
use rustfft::num_complex::Complex64;
use rustfft::FftPlannerScalar;
use serde::Serialize;
use std::f64::consts::TAU;

/// Below this sample rate the entry and exit of a defect under about 1 mm lie within a few
/// samples and one ring of the resonance: no size is reported.
pub const MIN_SAMPLE_RATE_HZ: f64 = 40_000.0;

/// What [`measure_defect_size`] reports in `method`.
pub const METHOD: &str = "entry-exit spacing in the AR-whitened synchronous average";

/// Impacts needed: 4 sub-averages of at least 4.
const MIN_IMPACTS: usize = 16;
/// Sub-averages the spacing is checked on.
const SUB_AVERAGES: usize = 4;
/// The longest stretch of record used, s: some 2,000 impacts of a 6205's outer race at
/// 1,800 rpm, and a whole-record FFT of 0.96 M points at 48 kHz (15 MB).
const MAX_RECORD_S: f64 = 20.0;
/// The longest defect searched for, mm.
const MAX_LENGTH_MM: f64 = 3.0;
/// Frequencies below this carry the structure's slow modes, not the events, Hz.
const HIGH_PASS_HZ: f64 = 1_000.0;
/// The second event's prominence against the first's and against the envelope's median.
const MIN_PROMINENCE_RATIO: f64 = 0.25;
const MIN_PROMINENCE_OVER_MEDIAN: f64 = 3.0;
/// A third peak this close (in prominence) to the second makes the pair ambiguous.
const MAX_THIRD_RATIO: f64 = 0.7;
/// Each sub-average's events against its envelope's median.
const MIN_SUB_EVENT_OVER_MEDIAN: f64 = 2.5;
/// The sub-averages' spacings may scatter by this fraction of the spacing (std).
const MAX_SUB_SPREAD: f64 = 0.25;

/// A measured defect length.
#[derive(Debug, Clone, Serialize)]
pub struct DefectSize {
    /// Circumferential length of the defect, mm.
    pub value_mm: f64,
    /// One standard uncertainty, mm.
    pub uncertainty_mm: f64,
    /// The entry-to-exit time it comes from, s.
    pub delay_s: f64,
    /// Impacts averaged.
    pub impacts: usize,
    pub method: &'static str,
}

/// Why no size is reported. Each message says what would make one possible.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NotMeasured {
    #[error("needs ≥ 40 kHz; this record is {} kHz", fmt_khz(*.fs_hz))]
    SampleRateTooLow { fs_hz: f64 },
    #[error(
        "the verdict is {0}: only an outer- or inner-race defect has an entry and an exit to time"
    )]
    NotARaceFault(&'static str),
    #[error("{0} is not usable for sizing")]
    BadInput(String),
    #[error("only {found} clear impacts in the record, {needed} needed; give a longer record")]
    TooFewImpacts { found: usize, needed: usize },
    #[error("the entry and exit events are not found clearly: {0}")]
    NotResolved(String),
}

fn fmt_khz(fs_hz: f64) -> String {
    let khz = fs_hz / 1e3;
    if (khz - khz.round()).abs() < 0.05 {
        format!("{khz:.0}")
    } else {
        format!("{khz:.1}")
    }
}

/// The defect size of the race fault `verdict` names (the analysis's, or the one a second
/// opinion made of it), in the band and at the fitted fault frequency the analysis found for it.
pub fn measure_for_verdict(
    signal: &[f32],
    analysis: &RecordAnalysis,
    verdict: Verdict,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    match verdict {
        Verdict::OuterRace => measure_for_fault(signal, analysis, FaultKind::OuterRace, bearing),
        Verdict::InnerRace => measure_for_fault(signal, analysis, FaultKind::InnerRace, bearing),
        other => Err(NotMeasured::NotARaceFault(other.name())),
    }
}

/// The defect size of `fault`, whatever the verdict, in the band and at the fitted frequency
/// of its hypothesis (the validation on the twin sizes every race defect it simulates).
pub fn measure_for_fault(
    signal: &[f32],
    analysis: &RecordAnalysis,
    fault: FaultKind,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    let hypothesis = analysis
        .hypotheses
        .iter()
        .find(|h| h.score.fault == fault)
        .ok_or(NotMeasured::NotARaceFault(fault.name()))?;
    measure_defect_size(
        signal,
        analysis.fs_hz,
        fault,
        hypothesis.score.frequency_hz,
        analysis.scan.bands[hypothesis.band_index].band,
        bearing,
    )
}

/// Measures the length of the `fault` (outer or inner race) defect whose impacts repeat at
/// `fault_hz` and show in `band`. See the module documentation for how and when.
pub fn measure_defect_size(
    signal: &[f32],
    fs_hz: f64,
    fault: FaultKind,
    fault_hz: f64,
    band: Band,
    bearing: &BearingGeometry,
) -> Result<DefectSize, NotMeasured> {
    let race = match fault {
        FaultKind::OuterRace => Race::Outer,
        FaultKind::InnerRace => Race::Inner,
        other => return Err(NotMeasured::NotARaceFault(other.name())),
    };
    if !(fs_hz.is_finite() && fs_hz > 0.0) {
        return Err(NotMeasured::BadInput(format!("sample rate {fs_hz} Hz")));
    }
    if fs_hz < MIN_SAMPLE_RATE_HZ {
        return Err(NotMeasured::SampleRateTooLow { fs_hz });
    }
    if !(fault_hz.is_finite() && fault_hz > 0.0 && fault_hz < fs_hz / 64.0) {
        return Err(NotMeasured::BadInput(format!(
            "fault frequency {fault_hz} Hz"
        )));
    }
    if !(band.lo_hz >= 0.0 && band.hi_hz > band.lo_hz && band.hi_hz <= fs_hz / 2.0 + 1e-9) {
        return Err(NotMeasured::BadInput(format!("band {band}")));
    }
    let mut fft = Fft::default();
    // The first MAX_RECORD_S only: enough impacts, and the whole-record FFT stays bounded.
    let signal = &signal[..signal.len().min((MAX_RECORD_S * fs_hz) as usize)];
    let period = fs_hz / fault_hz;
    let len = (0.9 * period) as usize;
    let averaged = Average::of(&mut fft, signal, fs_hz, band, period, len)?;
    let whitened = averaged.whitened(fs_hz);
    let events = Events {
        fs_hz,
        weights: &averaged.wiener_weights(&mut fft),
        max_delay: (bearing.entry_exit_delay_s(race, MAX_LENGTH_MM, fault_hz) * fs_hz)
            .min(0.4 * len as f64) as usize,
        min_separation: ((3.0 * fs_hz / 48_000.0).round() as usize).max(2),
    };
    let envelope = events.envelope(&mut fft, &mean_of(whitened.iter()));
    let pair = events.pair(&envelope)?;
    let spacings = events.sub_average_spacings(&mut fft, &whitened, pair)?;
    let delay = (pair.exit - pair.entry) / fs_hz;
    let delays: Vec<f64> = spacings.iter().map(|s| s / fs_hz).collect();
    let (mean, std) = mean_std(&delays);
    if std > MAX_SUB_SPREAD * delay {
        return Err(NotMeasured::NotResolved(format!(
            "the spacing in {SUB_AVERAGES} sub-averages scatters by {:.0} % ({:.3} ± {:.3} ms)",
            100.0 * std / delay,
            mean * 1e3,
            std * 1e3
        )));
    }
    let k = delays.len() as f64;
    let sample_s = 1.0 / fs_hz;
    let variance = std * std * k / (k - 1.0) / k
        + sample_s * sample_s / 6.0
        + (0.5 * pair.half_width / fs_hz).powi(2);
    let to_mm = |delay_s: f64| bearing.defect_length_mm(race, delay_s, fault_hz);
    Ok(DefectSize {
        value_mm: to_mm(delay),
        uncertainty_mm: to_mm(variance.sqrt()),
        delay_s: delay,
        impacts: whitened.len(),
        method: METHOD,
    })
}

/// Complex FFTs of any length, planned once per length. The scalar planner: this runs once per
/// `analyze`, off the window path, and rustfft's SSE and AVX kernels in `f64` would be about
/// 0.4 MB of the service binary for it (docs/PERFORMANCE.md "Service binary").
struct Fft {
    planner: FftPlannerScalar<f64>,
}

impl Default for Fft {
    fn default() -> Self {
        Fft {
            planner: FftPlannerScalar::new(),
        }
    }
}

impl Fft {
    fn forward(&mut self, buf: &mut [Complex64]) {
        self.planner.plan_fft_forward(buf.len()).process(buf);
    }

    /// Inverse, scaled by 1/n.
    fn inverse(&mut self, buf: &mut [Complex64]) {
        self.planner.plan_fft_inverse(buf.len()).process(buf);
        let scale = 1.0 / buf.len() as f64;
        buf.iter_mut().for_each(|v| *v *= scale);
    }

    fn of_real(&mut self, x: &[f64]) -> Vec<Complex64> {
        let mut buf: Vec<Complex64> = x.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        self.forward(&mut buf);
        buf
    }
}

/// Signed frequency of bin `k` of an `n`-point FFT, in cycles per sample.
fn bin_frequency(k: usize, n: usize) -> f64 {
    if k <= (n - 1) / 2 {
        k as f64 / n as f64
    } else {
        k as f64 / n as f64 - 1.0
    }
}

/// `x` delayed by `delay` samples (fractional, circular), in the frequency domain.
fn delayed(fft: &mut Fft, x: &[Complex64], delay: f64) -> Vec<Complex64> {
    let n = x.len();
    let mut buf = x.to_vec();
    fft.forward(&mut buf);
    for (k, v) in buf.iter_mut().enumerate() {
        *v *= Complex64::from_polar(1.0, -TAU * bin_frequency(k, n) * delay);
    }
    fft.inverse(&mut buf);
    buf
}

fn mean_of<'a>(rows: impl Iterator<Item = &'a Vec<f64>>) -> Vec<f64> {
    let mut sum: Vec<f64> = Vec::new();
    let mut count = 0usize;
    for row in rows {
        if sum.is_empty() {
            sum = vec![0.0; row.len()];
        }
        sum.iter_mut().zip(row).for_each(|(s, v)| *s += v);
        count += 1;
    }
    sum.iter_mut().for_each(|s| *s /= count.max(1) as f64);
    sum
}

fn mean_std(values: &[f64]) -> (f64, f64) {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n;
    (mean, var.sqrt())
}

fn median(values: &[f64]) -> f64 {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.get(sorted.len() / 2).copied().unwrap_or(0.0)
}

/// Index of the largest value in `values[range]` (clamped to the slice).
fn argmax(values: &[f64], from: usize, to: usize) -> usize {
    let to = to.min(values.len());
    (from.min(to)..to)
        .max_by(|&a, &b| values[a].total_cmp(&values[b]))
        .unwrap_or(from)
}

/// Sub-sample position of the peak at `i`: the vertex of the parabola through its neighbours.
fn vertex(values: &[f64], i: usize) -> f64 {
    if i == 0 || i + 1 >= values.len() {
        return i as f64;
    }
    let (a, b, c) = (values[i - 1], values[i], values[i + 1]);
    let curvature = a - 2.0 * b + c;
    if curvature == 0.0 {
        i as f64
    } else {
        i as f64 + 0.5 * (a - c) / curvature
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bearing_signal::simulate::{SimulatedFault, SimulationParams, Simulator};

    /// Two seconds of the signal model's race defect with entry and exit impacts `length_mm`
    /// apart (0: one impact per passage), resonance 3 kHz.
    fn signal_model(fault: SimulatedFault, fs_hz: f64, length_mm: f64) -> (Vec<f32>, f64) {
        let mut params = SimulationParams::example(fault);
        params.fs_hz = fs_hz;
        params.defect_length_mm = length_mm;
        params.noise_g = 0.1;
        let rate = params.impact_rate_hz();
        (Simulator::record(params, 2.0), rate)
    }

    fn size(
        signal: &[f32],
        fs_hz: f64,
        fault: FaultKind,
        rate: f64,
    ) -> Result<DefectSize, NotMeasured> {
        let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
        measure_defect_size(
            signal,
            fs_hz,
            fault,
            rate,
            Band::new(2_000.0, 4_000.0),
            &bearing,
        )
    }

    #[test]
    fn sizes_the_entry_and_exit_the_signal_model_draws() {
        let mut sized = 0;
        for (fault, kind) in [
            (SimulatedFault::OuterRace, FaultKind::OuterRace),
            (SimulatedFault::InnerRace, FaultKind::InnerRace),
        ] {
            for length_mm in [0.5, 1.0, 2.0] {
                let (signal, rate) = signal_model(fault, 48_000.0, length_mm);
                match size(&signal, 48_000.0, kind, rate) {
                    Ok(found) => {
                        let error = (found.value_mm - length_mm) / length_mm;
                        assert!(
                            error.abs() < 0.1 && found.uncertainty_mm > 0.0,
                            "{kind:?} {length_mm} mm: {found:?}"
                        );
                        assert_eq!(found.method, METHOD);
                        sized += 1;
                    }
                    // Refusing is allowed (0.5 mm on the outer race: a third peak as strong
                    // as the exit); a wrong number is not.
                    Err(NotMeasured::NotResolved(_)) => {}
                    Err(other) => panic!("{kind:?} {length_mm} mm: {other}"),
                }
            }
        }
        assert!(sized >= 5, "only {sized} of 6 sized");
    }

    #[test]
    fn one_event_per_passage_is_not_sized() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 48_000.0, 0.0);
        let found = size(&signal, 48_000.0, FaultKind::OuterRace, rate);
        assert!(
            matches!(found, Err(NotMeasured::NotResolved(_))),
            "{found:?}"
        );
    }

    #[test]
    fn noise_alone_is_not_sized() {
        let mut rng = crate::random::Rng::new(3);
        let signal: Vec<f32> = (0..96_000).map(|_| (0.2 * rng.normal()) as f32).collect();
        let found = size(&signal, 48_000.0, FaultKind::OuterRace, 107.0);
        assert!(found.is_err(), "{found:?}");
    }

    #[test]
    fn below_40_khz_the_reason_says_so() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 12_000.0, 2.0);
        let found = size(&signal, 12_000.0, FaultKind::OuterRace, rate);
        assert_eq!(
            found.unwrap_err().to_string(),
            "needs ≥ 40 kHz; this record is 12 kHz"
        );
    }

    #[test]
    fn only_race_defects_have_a_size() {
        let (signal, rate) = signal_model(SimulatedFault::Ball, 48_000.0, 1.0);
        for fault in [FaultKind::Ball, FaultKind::Cage] {
            let found = size(&signal, 48_000.0, fault, rate);
            assert!(
                matches!(found, Err(NotMeasured::NotARaceFault(_))),
                "{found:?}"
            );
        }
    }

    #[test]
    fn unusable_inputs_are_errors_not_panics() {
        let (signal, rate) = signal_model(SimulatedFault::OuterRace, 48_000.0, 1.0);
        for (fs, f, band) in [
            (f64::NAN, rate, Band::new(2e3, 4e3)),
            (48e3, 0.0, Band::new(2e3, 4e3)),
            (48e3, rate, Band::new(4e3, 2e3)),
            (48e3, rate, Band::new(2e3, 40e3)),
        ] {
            let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
            let found = measure_defect_size(&signal, fs, FaultKind::OuterRace, f, band, &bearing);
            assert!(matches!(found, Err(NotMeasured::BadInput(_))), "{found:?}");
        }
        let short = size(&signal[..1_000], 48_000.0, FaultKind::OuterRace, rate);
        assert!(
            matches!(short, Err(NotMeasured::TooFewImpacts { .. })),
            "{short:?}"
        );
        assert!(size(&[], 48_000.0, FaultKind::OuterRace, rate).is_err());
    }
}
