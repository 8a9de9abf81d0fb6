//! `[analysis]`: window, hop, band selection and fixed bands, checked against the sensors' rates.

use super::*;
use crate::analysis::agreement::Agreement;

/// (choice) The longest evidence horizon: a channel keeps its horizon as 16-bit counts, 2 bytes
/// per sample (10 minutes at 25.6 kHz: 31 MB per channel).
const MAX_EVIDENCE_HORIZON_S: f64 = 600.0;

impl Checker {
    pub(super) fn analysis(
        &mut self,
        raw: &RawAnalysis,
        sensors: &[CheckedSensor],
    ) -> Option<(AnalysisSettings, f64, f64)> {
        let d = AnalysisSettings::default();
        let window_s = self.number(
            "analysis.window_s",
            &raw.window_s,
            d.window_s,
            Limits::above_to(0.05, 10.0),
            "give the envelope-spectrum window length in seconds, e.g. window_s = 1.0",
        );
        let overlap = self.number(
            "analysis.overlap",
            &raw.overlap,
            d.overlap,
            Limits::within(0.0, 0.9),
            "give the overlap of successive windows as a fraction, e.g. overlap = 0.5 for 50 %",
        );
        let averages = self
            .integer(
                "analysis.averages",
                &raw.averages,
                i64::try_from(d.averages).unwrap_or(8),
                1,
                64,
                "give how many window spectra are averaged, e.g. averages = 8",
            )
            .and_then(|n| usize::try_from(n).ok());
        let band_selection = self.band_selection(raw, sensors);
        let refine_band_by_snr = self.or_default(
            "analysis.refine_band_by_snr",
            &raw.refine_band_by_snr,
            d.refine_band_by_snr,
            "use true to refine the band by fault-band SNR, or false to keep the first choice",
        );
        let band_period_s = self.number(
            "analysis.band_period_s",
            &raw.band_period_s,
            DEFAULT_BAND_PERIOD_S,
            Limits::above_to(0.0, DAY_S),
            "give how often the band is chosen again, in seconds, e.g. band_period_s = 20.0",
        );
        let evidence_horizon_s = self.number(
            "analysis.evidence_horizon_s",
            &raw.evidence_horizon_s,
            DEFAULT_EVIDENCE_HORIZON_S,
            Limits::above_to(0.0, MAX_EVIDENCE_HORIZON_S),
            "give how many seconds of signal a channel's verdict rests on, e.g. \
             evidence_horizon_s = 10.0",
        );
        let min_band_hz = self.min_band(&raw.min_band_hz, sensors);
        let fault_tolerance = self.number(
            "analysis.fault_tolerance",
            &raw.fault_tolerance,
            d.fault_tolerance,
            Limits::above_to(0.0, 0.1),
            "give the relative search tolerance around each fault frequency, e.g. \
             fault_tolerance = 0.02 for ±2 %",
        );
        let harmonics = self
            .integer(
                "analysis.harmonics",
                &raw.harmonics,
                i64::try_from(d.harmonics).unwrap_or(5),
                1,
                10,
                "give how many harmonics of each fault frequency count, e.g. harmonics = 5",
            )
            .and_then(|n| usize::try_from(n).ok());
        let false_alarm_rate = self.number(
            "analysis.false_alarm_rate",
            &raw.false_alarm_rate,
            d.false_alarm_rate,
            Limits::above_to(0.0, 0.5),
            "give the probability noise alone may name a fault per decision, e.g. \
             false_alarm_rate = 0.001",
        );
        let min_fault_score = self.number(
            "analysis.min_fault_score",
            &raw.min_fault_score,
            d.min_fault_score,
            Limits::within(1.0, f64::INFINITY),
            "give the smallest comb score (peak-to-floor ratio, at least 1) that makes a \
             diagnosis, e.g. min_fault_score = 5.0",
        );
        let min_score_ratio = self.number(
            "analysis.min_score_ratio",
            &raw.min_score_ratio,
            d.min_score_ratio,
            Limits::within(1.0, f64::INFINITY),
            "give how many times the best fault score must exceed the runner-up, at least 1, \
             e.g. min_score_ratio = 1.5",
        );
        let lone_fault_score = self.number(
            "analysis.lone_fault_score",
            &raw.lone_fault_score,
            d.lone_fault_score,
            Limits::within(1.0, f64::INFINITY),
            "give the smallest comb score (at least 1) that makes a diagnosis when no other \
             fault comes near it, e.g. lone_fault_score = 2.5",
        );
        let lone_score_ratio = self.number(
            "analysis.lone_score_ratio",
            &raw.lone_score_ratio,
            d.lone_score_ratio,
            Limits::within(1.0, f64::INFINITY),
            "give how many times every other fault a comb below min_fault_score must be to \
             stand alone, at least 1, e.g. lone_score_ratio = 2.0",
        );
        let agreement = self.agreement(raw, false_alarm_rate);
        Some((
            AnalysisSettings {
                window_s: window_s?,
                overlap: overlap?,
                averages: averages?,
                band_selection: band_selection?,
                refine_band_by_snr: refine_band_by_snr?,
                min_band_hz: min_band_hz?,
                fault_tolerance: fault_tolerance?,
                harmonics: harmonics?,
                false_alarm_rate: false_alarm_rate?,
                min_fault_score: min_fault_score?,
                min_score_ratio: min_score_ratio?,
                lone_fault_score: lone_fault_score?,
                lone_score_ratio: lone_score_ratio?,
                agreement: agreement?,
            },
            band_period_s?,
            evidence_horizon_s?,
        ))
    }

    /// The learned model's agreement (`analysis.agreement_*`): off unless given, and then all
    /// four keys, for none has a calibrated default yet.
    fn agreement(
        &mut self,
        raw: &RawAnalysis,
        false_alarm_rate: Option<f64>,
    ) -> Option<Option<Agreement>> {
        let keys: [(&str, &Field<f64>, Limits, &str); 4] = [
            (
                "analysis.agreement_probability",
                &raw.agreement_probability,
                Limits::within(0.5, 1.0),
                "give how sure the learned model must be of the envelope's first-ranked fault, \
                 0.5 to 1, e.g. agreement_probability = 0.9",
            ),
            (
                "analysis.agreement_fault_score",
                &raw.agreement_fault_score,
                Limits::within(1.0, f64::INFINITY),
                "give the smallest comb score (at least 1) the first-ranked fault needs when the \
                 learned model names it too, e.g. agreement_fault_score = 3.0",
            ),
            (
                "analysis.agreement_score_ratio",
                &raw.agreement_score_ratio,
                Limits::within(1.0, f64::INFINITY),
                "give how many times every other fault, once it is explained away, an agreed \
                 fault must be, at least 1, e.g. agreement_score_ratio = 2.0",
            ),
            (
                "analysis.agreement_significance_relief",
                &raw.agreement_significance_relief,
                Limits::within(0.0, f64::INFINITY),
                "give by how many decades an agreed fault's significance may fall short of \
                 false_alarm_rate's, 0 or more, e.g. agreement_significance_relief = 1.0",
            ),
        ];
        let mut values = [None; 4];
        let mut missing = Vec::new();
        for (value, &(key, field, limits, fix)) in values.iter_mut().zip(&keys) {
            match self.get(key, field, fix) {
                Got::Missing => missing.push((key, fix)),
                Got::Invalid => {}
                Got::Value(v) => *value = self.in_limits(key, v, limits, fix),
            }
        }
        if missing.len() == keys.len() {
            return Some(None);
        }
        for (key, fix) in missing {
            self.problem(
                key,
                format!(
                    "missing: the learned model's agreement has no defaults yet, so its four \
                     keys go together; {fix}, or remove the other agreement_* keys"
                ),
            );
        }
        let [Some(min_probability), Some(min_score), Some(min_lead), Some(relief)] = values else {
            return None;
        };
        // A relief of the whole significance would name what noise gives at any probability.
        let needed = -false_alarm_rate?.log10();
        if relief >= needed {
            self.problem(
                "analysis.agreement_significance_relief",
                format!(
                    "{relief} decades would waive all of the {needed:.1} that false_alarm_rate \
                     asks, so noise could be named; lower it below {needed:.1}, e.g. \
                     agreement_significance_relief = 1.0"
                ),
            );
            return None;
        }
        Some(Some(Agreement {
            min_probability,
            min_score,
            min_lead,
            significance_relief_decades: relief,
        }))
    }

    pub(super) fn band_selection(
        &mut self,
        raw: &RawAnalysis,
        sensors: &[CheckedSensor],
    ) -> Option<BandSelection> {
        let key = "analysis.band_selection";
        let fix = "use \"kurtogram\", \"gk\" or \"fixed\", e.g. band_selection = \"gk\"";
        #[derive(Clone, Copy, PartialEq)]
        enum Method {
            Kurtogram,
            Gk,
            Fixed,
        }
        let method = self
            .or_default(
                key,
                &raw.band_selection,
                match AnalysisSettings::default().band_selection {
                    BandSelection::Kurtogram => "kurtogram",
                    BandSelection::GiniKurtosis => "gk",
                    BandSelection::Fixed { .. } => "fixed",
                }
                .to_string(),
                fix,
            )
            .and_then(|name| {
                self.choice(
                    key,
                    &name,
                    "band selection",
                    &[
                        ("kurtogram", Method::Kurtogram),
                        ("gk", Method::Gk),
                        ("fixed", Method::Fixed),
                    ],
                    fix,
                )
            });

        let band_key = "analysis.band_hz";
        let band_fix = "give [low, high] in Hz with low < high, e.g. band_hz = [2000.0, 4000.0]";
        let band = match self.get(band_key, &raw.band_hz, band_fix) {
            Got::Missing => None,
            Got::Invalid => return None,
            Got::Value(band) => Some(band),
        };
        match (method?, band) {
            (Method::Kurtogram, None) => Some(BandSelection::Kurtogram),
            (Method::Gk, None) => Some(BandSelection::GiniKurtosis),
            (Method::Kurtogram | Method::Gk, Some(_)) => {
                self.problem(
                    band_key,
                    "band_hz is only used with band_selection = \"fixed\", and this file \
                     chooses the band automatically; remove band_hz, or set band_selection = \
                     \"fixed\" to use it",
                );
                None
            }
            (Method::Fixed, None) => {
                self.problem(
                    band_key,
                    format!("missing: band_selection = \"fixed\" needs the band; {band_fix}"),
                );
                None
            }
            (Method::Fixed, Some(band)) => {
                let (lo_hz, hi_hz) = self.fixed_band(band_key, &band, band_fix, sensors)?;
                Some(BandSelection::Fixed { lo_hz, hi_hz })
            }
        }
    }

    pub(super) fn fixed_band(
        &mut self,
        key: &str,
        band: &[f64],
        fix: &str,
        sensors: &[CheckedSensor],
    ) -> Option<(f64, f64)> {
        let &[lo, hi] = band else {
            self.problem(
                key,
                format!(
                    "has {} numbers, not 2 (low and high edge); {fix}",
                    band.len()
                ),
            );
            return None;
        };
        if !lo.is_finite() || !hi.is_finite() {
            self.problem(key, format!("[{lo}, {hi}] has a non-finite edge; {fix}"));
            return None;
        }
        if lo < 0.0 || lo >= hi {
            self.problem(
                key,
                format!("[{lo}, {hi}] is not a band: it needs 0 <= low < high; {fix}"),
            );
            return None;
        }
        let mut below_nyquist = true;
        for sensor in sensors {
            let Some(rate) = sensor.sample_rate_hz else {
                continue;
            };
            let nyquist = rate / 2.0;
            if hi >= nyquist {
                self.problem(
                    key,
                    format!(
                        "the upper edge {hi} Hz is not below the Nyquist frequency {nyquist} Hz \
                         of {}; lower it below {nyquist} Hz, e.g. band_hz = [{lo}, {}]",
                        sensor.named(&format!("sampled at {rate} Hz")),
                        suggest_below(lo, nyquist),
                    ),
                );
                below_nyquist = false;
            }
        }
        below_nyquist.then_some((lo, hi))
    }

    pub(super) fn min_band(
        &mut self,
        field: &Field<f64>,
        sensors: &[CheckedSensor],
    ) -> Option<Option<f64>> {
        let key = "analysis.min_band_hz";
        let fix = "give the narrowest band the kurtogram may choose, in Hz, e.g. min_band_hz = \
                   600.0, or leave it out for three times the highest fault frequency";
        let value = match self.get(key, field, fix) {
            Got::Missing => return Some(None),
            Got::Invalid => return None,
            Got::Value(v) => v,
        };
        let value = self.in_limits(key, value, Limits::above_to(0.0, f64::INFINITY), fix)?;
        let mut fits = true;
        for sensor in sensors {
            let Some(rate) = sensor.sample_rate_hz else {
                continue;
            };
            let nyquist = rate / 2.0;
            if value >= nyquist {
                self.problem(
                    key,
                    format!(
                        "{value} Hz is not below the Nyquist frequency {nyquist} Hz of {}, so \
                         no band would fit; lower it below {nyquist} Hz or leave it out",
                        sensor.named(&format!("sampled at {rate} Hz"))
                    ),
                );
                fits = false;
            }
        }
        fits.then_some(Some(value))
    }

    // ------------------------------------------------------------------------ twin, flags
}
