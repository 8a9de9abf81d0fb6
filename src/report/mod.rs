//! What `analyze` tells its user about a record: a JSON document for programs, a text summary
//! for people, and a figure for the eyes (drawn by the lab crate, `bearingd-lab`, from the same
//! report). One [`AnalyzeReport`] feeds all three so that they always say the same thing.

pub mod plain;
mod text;

pub use text::render_text;

use crate::analysis::defect_size::{DefectSize, NotMeasured};
use crate::analysis::diagnosis::{DecisionRule, Diagnosis, Verdict};
use crate::analysis::fault_bands::HarmonicPeak;
use crate::analysis::indicators::Indicators;
use crate::analysis::iso::VelocitySeverity;
use crate::analysis::modulation::Modulation;
use crate::analysis::{BandSelection, RecordAnalysis};
use crate::bearing::BearingGeometry;
use crate::learned::{Basis, Combined, LearnedOpinion};
use crate::messages::FaultKind;
use crate::recording::SampleUnit;
use crate::twin::diagnose::{ResidualSummary, TwinDiagnosis};
use crate::twin::{HypothesisFit, TwinParams};
use serde::Serialize;

/// Where the shaft speed came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SpeedSource {
    /// The recording states it (e.g. CWRU's `XNNNRPM` variable).
    File,
    /// `--rpm` on the command line (or the config).
    Given,
    /// The data set's documented constant speed (e.g. IMS: 2000 rpm).
    DataSetDefault,
    /// The simulated record's speed.
    Simulation,
}

/// The record's identity and operating conditions, as the caller resolved them.
#[derive(Debug, Clone)]
pub struct RecordContext {
    pub file: String,
    pub channel: String,
    pub rpm: f64,
    pub rpm_source: SpeedSource,
    pub bearing: BearingGeometry,
    pub selection: BandSelection,
    /// What the samples are in: g, or fractions of a recorder's full scale.
    pub unit: SampleUnit,
    /// What was assumed (shown as `note:`).
    pub notes: Vec<String>,
    /// What is wrong with the record as read (shown as `warning:`).
    pub warnings: Vec<String>,
}

#[derive(Debug, Clone, Serialize)]
pub struct FaultFrequenciesHz {
    pub shaft: f64,
    pub bpfo: f64,
    pub bpfi: f64,
    pub bsf: f64,
    pub two_bsf: f64,
    pub ftf: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct Scores {
    pub outer_race: f64,
    pub inner_race: f64,
    pub ball: f64,
    pub cage: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct BandSelectionReport {
    /// `kurtogram`, `gk` or `fixed`.
    pub method: &'static str,
    /// The band the method chose.
    pub selected_hz: [f64; 2],
    /// Why the reported band is the one it is.
    pub reason: String,
}

#[derive(Debug, Clone, Serialize)]
pub struct HypothesisReport {
    pub fault: FaultKind,
    pub frequency_hz: f64,
    pub band_hz: [f64; 2],
    /// Geometric-mean peak-to-floor ratio over the comb.
    pub score: f64,
    /// `−log10` of the probability noise alone gives this comb (after the band search).
    pub significance: f64,
    /// The comb's fitted slip, relative.
    pub slip: f64,
    pub sideband_score: Option<f64>,
    /// For an inner race or a ball: shaft-rate against cage-rate sidebands around its peaks.
    pub modulation: Option<Modulation>,
    pub harmonics: Vec<HarmonicPeak>,
    /// What is left of it once the leading hypothesis's comb is explained away (`null` for the
    /// leader itself): what the verdict weighed it on.
    pub explained: Option<ExplainedScore>,
    /// Whether the verdict names this fault.
    pub named: bool,
    /// When not named: why, in a few plain words (see [`plain::why_not`]).
    pub why_not: Option<String>,
}

/// A hypothesis re-scored with the leader's comb explained away.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ExplainedScore {
    /// The leading hypothesis.
    pub by: FaultKind,
    pub score: f64,
    pub significance: f64,
}

/// `SampleUnit` as the analyze JSON names it.
fn unit_name<S: serde::Serializer>(unit: &SampleUnit, serializer: S) -> Result<S::Ok, S::Error> {
    serializer.serialize_str(match unit {
        SampleUnit::G => "g",
        SampleUnit::FullScale => "full_scale",
    })
}

/// The JSON document of `bearingd analyze --format json`.
#[derive(Debug, Clone, Serialize)]
pub struct AnalyzeReport {
    pub file: String,
    pub channel: String,
    pub fs_hz: f64,
    /// What the samples (and so every amplitude of the report) are in: `g`, or `full_scale`
    /// when the recorder's full scale is unknown (an integer WAV): amplitudes are then relative.
    #[serde(serialize_with = "unit_name")]
    pub unit: SampleUnit,
    pub rpm: f64,
    pub rpm_source: SpeedSource,
    pub bearing: String,
    pub bearing_geometry: BearingGeometry,
    pub duration_s: f64,
    pub samples: usize,
    pub window_samples: usize,
    pub windows_averaged: usize,
    pub band_hz: [f64; 2],
    pub band_selection: BandSelectionReport,
    pub fault_frequencies_hz: FaultFrequenciesHz,
    pub scores: Scores,
    /// The verdict in a technician's words: what is wrong, how sure, what to do
    /// ([`plain::summary`]); worded again by the methods that change the verdict or its
    /// confidence (`set_twin`, `set_learned`).
    pub summary: String,
    pub diagnosis: &'static str,
    /// `diagnosis` as the type the plain words are chosen by.
    #[serde(skip)]
    pub verdict: Verdict,
    pub confidence: f64,
    pub reason: String,
    /// With `none`: the faults that were each detected but could not be told apart.
    pub candidates: Vec<FaultKind>,
    pub thresholds: Thresholds,
    pub indicators: Indicators,
    pub hypotheses: Vec<HypothesisReport>,
    /// ISO 10816-3 / 20816-3 velocity severity and zone; `null` when the samples are not in
    /// physical units (`unit` is `full_scale`) or the record is too short.
    pub velocity: Option<VelocitySeverity>,
    /// What the detectors that judge whole records found, each under its own key
    /// (`machine_faults`; [`crate::analysis::detectors`]).
    #[serde(flatten)]
    pub detectors: serde_json::Map<String, serde_json::Value>,
    /// The same for people: lines of the text report.
    #[serde(skip)]
    pub detector_lines: Vec<String>,
    /// The signal-model twin's fit (`analyze --twin`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub twin: Option<TwinReport>,
    /// The learned model's opinion and the combined diagnosis (`analyze --learned`); the
    /// report's `diagnosis` is then the combined one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub learned: Option<LearnedReport>,
    /// The race defect's length from the spacing of its entry and exit events
    /// ([`crate::analysis::defect_size`]): only for an outer- or inner-race verdict on a record
    /// of ≥ 40 kHz whose events are clear; else `null`, and `defect_size_note` says why.
    pub defect_size_mm: Option<DefectSizeReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub defect_size_note: Option<String>,
    /// What the analysis assumed or could not do, and why: information, not a problem.
    pub notes: Vec<String>,
    /// What is wrong with the record as read (e.g. a truncated file read as far as valid).
    pub warnings: Vec<String>,
}

/// The learned model's part of a report.
#[derive(Debug, Clone, Serialize)]
pub struct LearnedReport {
    pub opinion: LearnedOpinion,
    /// What the envelope diagnosis alone said.
    pub envelope_diagnosis: &'static str,
    pub basis: Basis,
    pub learned_agrees: bool,
}

/// The `defect_size_mm` object of the JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct DefectSizeReport {
    /// Circumferential length of the defect, mm.
    pub value: f64,
    /// One standard uncertainty, mm.
    pub uncertainty: f64,
    pub method: &'static str,
    /// The entry-to-exit time it comes from, ms.
    pub delay_ms: f64,
    /// Impacts in the synchronous average.
    pub impacts: usize,
}

/// The twin's errors per hypothesis.
#[derive(Debug, Clone, Serialize)]
pub struct TwinErrors {
    pub outer_race: Option<f64>,
    pub inner_race: Option<f64>,
    pub ball: Option<f64>,
}

/// The `twin` object of the JSON report.
#[derive(Debug, Clone, Serialize)]
pub struct TwinReport {
    /// The hypothesis whose twin fits best.
    pub hypothesis: FaultKind,
    pub params: TwinParams,
    pub error: f64,
    /// Error of the runner-up hypothesis minus the best error.
    pub margin: f64,
    pub errors: TwinErrors,
    /// Compute time of the fits (all hypotheses), milliseconds.
    pub fit_ms: f64,
    pub band_hz: [f64; 2],
    pub residual: ResidualSummary,
    pub agrees_with_scores: bool,
    pub note: String,
    /// Every hypothesis's fit.
    pub fits: Vec<HypothesisFit>,
}

impl TwinReport {
    pub fn new(twin: &TwinDiagnosis, fit_ms: f64, agrees_with_scores: bool, note: String) -> Self {
        let best = twin.best_fit();
        TwinReport {
            hypothesis: best.fault,
            params: best.params,
            error: best.error,
            margin: twin.margin,
            errors: TwinErrors {
                outer_race: twin.error_of(FaultKind::OuterRace),
                inner_race: twin.error_of(FaultKind::InnerRace),
                ball: twin.error_of(FaultKind::Ball),
            },
            fit_ms,
            band_hz: band_pair(best.band),
            residual: twin.residual,
            agrees_with_scores,
            note,
            fits: twin.fits.clone(),
        }
    }
}

/// The decision thresholds the verdict was reached with.
#[derive(Debug, Clone, Serialize)]
pub struct Thresholds {
    pub false_alarm_rate: f64,
    pub min_fault_score: f64,
    pub min_score_ratio: f64,
    pub lone_fault_score: f64,
    pub lone_score_ratio: f64,
    pub fault_tolerance: f64,
    pub harmonics: usize,
}

impl Thresholds {
    /// The decision rule these thresholds make up.
    pub fn rule(&self) -> DecisionRule {
        DecisionRule {
            false_alarm_rate: self.false_alarm_rate,
            min_fault_score: self.min_fault_score,
            min_score_ratio: self.min_score_ratio,
            lone_fault_score: self.lone_fault_score,
            lone_score_ratio: self.lone_score_ratio,
        }
    }
}

fn band_pair(band: crate::analysis::Band) -> [f64; 2] {
    [band.lo_hz, band.hi_hz]
}

impl AnalyzeReport {
    /// Adds the twin's fit; its confidence and reason become the combined ones (see
    /// [`crate::twin::diagnose::combine`]).
    pub fn set_twin(&mut self, twin: TwinReport, combined: &Diagnosis) {
        self.confidence = combined.confidence;
        self.reason = combined.reason.clone();
        self.twin = Some(twin);
        self.settle_plain();
    }

    /// Adds the defect size, or why there is none.
    pub fn set_defect_size(&mut self, size: Result<DefectSize, NotMeasured>) {
        match size {
            Ok(size) => {
                self.defect_size_mm = Some(DefectSizeReport {
                    value: size.value_mm,
                    uncertainty: size.uncertainty_mm,
                    method: size.method,
                    delay_ms: size.delay_s * 1e3,
                    impacts: size.impacts,
                });
                self.defect_size_note = None;
            }
            Err(why) => {
                self.defect_size_mm = None;
                self.defect_size_note = Some(why.to_string());
            }
        }
    }

    /// Adds the learned opinion; the diagnosis becomes the combined one.
    /// The learned model's part, once the verdict (this report's) has heard it as a witness;
    /// `envelope` is what the envelope alone said.
    pub fn set_learned(&mut self, opinion: LearnedOpinion, combined: Combined, envelope: Verdict) {
        if combined.basis == Basis::Envelope {
            self.reason = format!("{}; {}", self.reason, combined.reason);
        }
        self.learned = Some(LearnedReport {
            opinion,
            envelope_diagnosis: envelope.name(),
            basis: combined.basis,
            learned_agrees: combined.learned_agrees,
        });
        self.settle_plain();
    }

    /// The structured fields the plain words are made from.
    pub fn plain_facts(&self) -> plain::Facts<'_> {
        plain::Facts {
            verdict: self.verdict,
            confidence: self.confidence,
            candidates: &self.candidates,
            hypotheses: &self.hypotheses,
            rule: self.thresholds.rule(),
            learned: self
                .learned
                .as_ref()
                .filter(|l| l.opinion.segments > 0)
                .map(|l| plain::LearnedFacts {
                    basis: l.basis,
                    agrees: l.learned_agrees,
                }),
            twin_prefers: self
                .twin
                .as_ref()
                .filter(|t| !t.agrees_with_scores)
                .map(|t| t.hypothesis),
        }
    }

    /// Words the verdict and each fault's part in it again, after anything that changes them.
    fn settle_plain(&mut self) {
        let facts = self.plain_facts();
        let summary = plain::summary(&facts);
        let why: Vec<Option<String>> = self
            .hypotheses
            .iter()
            .map(|h| plain::why_not(&facts, h))
            .collect();
        self.summary = summary;
        for (h, why_not) in self.hypotheses.iter_mut().zip(why) {
            h.named = why_not.is_none();
            h.why_not = why_not;
        }
    }

    pub fn new(
        context: &RecordContext,
        analysis: &RecordAnalysis,
        settings: &crate::analysis::AnalysisSettings,
    ) -> Self {
        let f = &analysis.frequencies;
        let method = match context.selection {
            BandSelection::Kurtogram => "kurtogram",
            BandSelection::GiniKurtosis => "gk",
            BandSelection::Fixed { .. } => "fixed",
        };
        let method_words = match context.selection {
            BandSelection::Kurtogram => "the fast kurtogram",
            BandSelection::GiniKurtosis => "the GK index",
            BandSelection::Fixed { .. } => "the configuration (fixed band)",
        };
        let reason = match analysis.diagnosis.verdict.fault() {
            Some(kind) if analysis.reported_band_index != analysis.selected_band_index => format!(
                "{} shows {} best (fault-band SNR refinement); {} chose {}",
                analysis.band(),
                kind.frequency_label(),
                method_words,
                analysis.selected_band()
            ),
            _ => format!("chosen by {method_words}"),
        };
        let explained = |kind: FaultKind| {
            let by = analysis.leader?;
            let s = analysis.explained.iter().find(|s| s.fault == kind)?;
            Some(ExplainedScore {
                by,
                score: s.score,
                significance: s.significance,
            })
        };
        let mut report = AnalyzeReport {
            file: context.file.clone(),
            channel: context.channel.clone(),
            fs_hz: analysis.fs_hz,
            unit: context.unit,
            rpm: context.rpm,
            rpm_source: context.rpm_source,
            bearing: context.bearing.name.clone(),
            bearing_geometry: context.bearing.clone(),
            duration_s: analysis.duration_s(),
            samples: analysis.samples,
            window_samples: analysis.window,
            windows_averaged: analysis.spectrum().windows_averaged,
            band_hz: band_pair(analysis.band()),
            band_selection: BandSelectionReport {
                method,
                selected_hz: band_pair(analysis.selected_band()),
                reason,
            },
            fault_frequencies_hz: FaultFrequenciesHz {
                shaft: f.shaft,
                bpfo: f.bpfo,
                bpfi: f.bpfi,
                bsf: f.bsf,
                two_bsf: f.two_bsf,
                ftf: f.ftf,
            },
            scores: Scores {
                outer_race: analysis.score(FaultKind::OuterRace),
                inner_race: analysis.score(FaultKind::InnerRace),
                ball: analysis.score(FaultKind::Ball),
                cage: analysis.score(FaultKind::Cage),
            },
            summary: String::new(),
            diagnosis: analysis.diagnosis.verdict.name(),
            verdict: analysis.diagnosis.verdict,
            confidence: analysis.diagnosis.confidence,
            reason: analysis.diagnosis.reason.clone(),
            candidates: analysis.diagnosis.candidates.clone(),
            thresholds: Thresholds {
                false_alarm_rate: settings.false_alarm_rate,
                min_fault_score: settings.min_fault_score,
                min_score_ratio: settings.min_score_ratio,
                lone_fault_score: settings.lone_fault_score,
                lone_score_ratio: settings.lone_score_ratio,
                fault_tolerance: settings.fault_tolerance,
                harmonics: settings.harmonics,
            },
            indicators: analysis.indicators,
            hypotheses: analysis
                .hypotheses
                .iter()
                .map(|h| HypothesisReport {
                    fault: h.score.fault,
                    frequency_hz: h.score.frequency_hz,
                    band_hz: band_pair(analysis.scan.bands[h.band_index].band),
                    score: h.score.score,
                    significance: h.score.significance,
                    slip: h.score.slip,
                    sideband_score: h.score.sideband_score,
                    modulation: h.score.modulation,
                    harmonics: h.score.peaks().to_vec(),
                    explained: explained(h.score.fault),
                    named: false,
                    why_not: None,
                })
                .collect(),
            velocity: None,
            detectors: serde_json::Map::new(),
            detector_lines: Vec::new(),
            twin: None,
            learned: None,
            defect_size_mm: None,
            defect_size_note: None,
            notes: context.notes.clone(),
            warnings: context.warnings.clone(),
        };
        report.settle_plain();
        report
    }
}
