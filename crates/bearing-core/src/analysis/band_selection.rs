//! A channel's band selection and evidence as a job: cut from the history at the sample it is
//! due, computed anywhere, used at a sample fixed in advance.
//!
//! The job is `bearingd analyze` on the channel's history (the horizon since its last gap or
//! restart, at most the configured length): it chooses the bands the rolling spectra follow and
//! gives the verdict on all of that evidence, which the channel's flags follow. One analysis for
//! both paths is what makes the daemon's flags on a complete recording equal `analyze`'s verdict.
//!
//! Why: a band selection (the whole-record analysis of the last 10 s, plus the speed estimate)
//! costs 30–100 ms per 25.6 kHz channel. Run inline it holds the analysis thread, and every block
//! that arrives meanwhile (and any alert it decides) waits. As a job it can run on another thread
//! ([`BandSelector`]) while the monitor goes on; the monitor uses the result at `due` = start +
//! a delay in samples, and waits for it there if it is late. So the result takes effect at the
//! same sample whatever thread ran it and however long it took: a replay repeats every event.

use super::agreement::{Witness, WitnessOpinion};
use super::diagnosis::{Named, Verdict};
use super::envelope::FftPlans;
use super::fault_bands::FaultScore;
use super::record::{analyze_with_plans, RecordAnalysis};
use super::speed::estimate_shaft_hz;
use super::speed::SpeedMode;
use super::{AnalysisSettings, Band};
use crate::bearing::FaultFrequencies;
use crate::messages::FaultKind;
use std::collections::VecDeque;
use std::sync::Arc;

/// What a band selection needs, copied out of the monitor when it is due.
#[derive(Debug, Clone)]
pub struct BandJob {
    /// The history, oldest first, as the sensor's counts.
    pub counts: Vec<i16>,
    /// g per count.
    pub scale: f64,
    pub fs_hz: f64,
    /// The fault frequencies the channel scores with now.
    pub freqs: FaultFrequencies,
    /// Fault frequencies per Hz of shaft rate (to scale to an estimated speed).
    pub orders: FaultFrequencies,
    /// Whether `freqs` may be used (the speed is known).
    pub speed_known: bool,
    /// The highest usable shaft rate, Hz.
    pub max_shaft_hz: f64,
    pub speed: SpeedMode,
    pub analysis: AnalysisSettings,
    /// The second witness the verdict hears, when `analysis.agreement` is set.
    pub witness: Option<Arc<dyn Witness>>,
}

/// What a band selection found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BandResult {
    /// The speed estimate, Hz, when the channel estimates its speed and one was found.
    pub estimated_shaft_hz: Option<f64>,
    /// One band per fault kind ([`FaultKind::ALL`] order) and the method's choice; `None` when
    /// no speed was usable or the analysis failed (the bands stay as they are).
    pub bands: Option<([Band; 4], Band)>,
    /// The verdict on the job's history; `None` with `bands`.
    pub evidence: Option<Evidence>,
}

/// The verdict of the whole-record analysis of a channel's history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evidence {
    /// Every fault's score in its best band ([`FaultKind::ALL`] order), as `analyze` reports
    /// them.
    pub scores: [FaultScore; 4],
    /// The verdict (its faults are the ones whose flags it raises) and how it was named.
    pub verdict: Verdict,
    pub named: Option<Named>,
    /// What the second witness said, when it was asked.
    pub witness: Option<WitnessHeard>,
    /// Samples the history held.
    pub samples: usize,
}

/// What a second witness said of a band job's history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WitnessHeard {
    Opinion(WitnessOpinion),
    /// It had nothing to say (the history is shorter than it needs).
    Silent,
    /// It failed; the verdict is the envelope's.
    Failed,
}

impl Evidence {
    /// One line for the log: what the verdict rests on and says, e.g. `verdict on 10.0 s:
    /// outer_race (outer_race 6.2 at p = 10^-9.1, inner_race 3.3, ball 2.0, cage 1.8)`.
    pub fn describe(&self, seconds: f64) -> String {
        let said = match self.verdict {
            Verdict::None => "no clear fault",
            verdict => verdict.name(),
        };
        let scores: Vec<String> = self
            .scores
            .iter()
            .map(|s| {
                format!(
                    "{} {:.1} at p = 10^-{:.1}",
                    s.fault.name(),
                    s.score,
                    s.significance
                )
            })
            .collect();
        let witness = match self.witness {
            None => String::new(),
            Some(WitnessHeard::Opinion(o)) => format!(
                "; the witness says {} ({:.0} %)",
                o.fault.map_or("none", FaultKind::name),
                100.0 * o.probability
            ),
            Some(WitnessHeard::Silent) => "; the witness has no opinion (too short)".into(),
            Some(WitnessHeard::Failed) => "; the witness failed".into(),
        };
        format!(
            "verdict on {seconds:.1} s: {said} ({}){witness}",
            scores.join(", ")
        )
    }

    /// The largest score of the faults other than `fault` (at least 1e-9).
    pub fn runner_up(&self, fault: FaultKind) -> f64 {
        self.scores
            .iter()
            .filter(|s| s.fault != fault)
            .map(|s| s.score)
            .fold(1e-9, f64::max)
    }
}

/// A shaft rate given or estimated, if usable: finite, positive, at most `max_shaft_hz`.
pub fn usable_shaft_hz(given: Option<f64>, max_shaft_hz: f64) -> Option<f64> {
    given.filter(|&hz| hz.is_finite() && hz > 0.0 && hz <= max_shaft_hz * (1.0 + 1e-9))
}

/// `freqs` with every frequency multiplied by `factor` (they are all proportional to the shaft
/// rate, MODELS.md §1).
pub fn scaled(freqs: &FaultFrequencies, factor: f64) -> FaultFrequencies {
    FaultFrequencies {
        shaft: freqs.shaft * factor,
        ftf: freqs.ftf * factor,
        bpfo: freqs.bpfo * factor,
        bpfi: freqs.bpfi * factor,
        bsf: freqs.bsf * factor,
        two_bsf: freqs.two_bsf * factor,
    }
}

impl BandJob {
    /// Runs the selection: the speed estimate (when estimating), then the whole-record analysis
    /// with the frequencies at the speed the monitor will have once it takes the result.
    pub fn run(&self, plans: &mut FftPlans) -> BandResult {
        let signal: Vec<f32> = self
            .counts
            .iter()
            .map(|&c| (f64::from(c) * self.scale) as f32)
            .collect();
        let mut freqs = self.freqs;
        let mut known = self.speed_known;
        let mut estimated_shaft_hz = None;
        if let SpeedMode::Estimate(search) = self.speed {
            // A failed estimate keeps the last one; without any, nothing is scored yet.
            if let Some(estimate) = estimate_shaft_hz(plans, &signal, self.fs_hz, search) {
                estimated_shaft_hz = Some(estimate.shaft_hz);
                let usable = usable_shaft_hz(Some(estimate.shaft_hz), self.max_shaft_hz);
                if let Some(hz) = usable {
                    freqs = scaled(&self.orders, hz);
                }
                known = usable.is_some();
            }
        }
        if !known {
            return BandResult {
                estimated_shaft_hz,
                bands: None,
                evidence: None,
            };
        }
        let mut analysis =
            analyze_with_plans(plans, &signal, self.fs_hz, &freqs, &self.analysis).ok();
        let witness = self.hear_witness(analysis.as_mut(), &signal, &freqs);
        let evidence = analysis.as_ref().map(|analysis| Evidence {
            scores: FaultKind::ALL.map(|kind| {
                analysis
                    .hypotheses
                    .iter()
                    .find(|h| h.score.fault == kind)
                    .map_or(FaultScore::unscored(kind, &freqs), |h| h.score)
            }),
            verdict: analysis.diagnosis.verdict,
            named: analysis.diagnosis.named,
            witness,
            samples: signal.len(),
        });
        let bands = analysis.map(|analysis| {
            let band_of = |kind: FaultKind| {
                analysis
                    .hypotheses
                    .iter()
                    .find(|h| h.score.fault == kind)
                    .map_or(analysis.selected_band(), |h| {
                        analysis.scan.bands[h.band_index].band
                    })
            };
            (FaultKind::ALL.map(band_of), analysis.selected_band())
        });
        BandResult {
            estimated_shaft_hz,
            bands,
            evidence,
        }
    }
}

impl BandJob {
    /// Asks the witness (when there is one and an agreement to weigh it by) of `signal`, and
    /// lets the analysis's verdict hear it.
    fn hear_witness(
        &self,
        analysis: Option<&mut RecordAnalysis>,
        signal: &[f32],
        freqs: &FaultFrequencies,
    ) -> Option<WitnessHeard> {
        let (Some(analysis), Some(witness), Some(_)) =
            (analysis, &self.witness, self.analysis.agreement)
        else {
            return None;
        };
        let heard = match witness.witness(signal, self.fs_hz, freqs) {
            Ok(Some(opinion)) => WitnessHeard::Opinion(opinion),
            Ok(None) => WitnessHeard::Silent,
            Err(_) => WitnessHeard::Failed,
        };
        let opinion = match heard {
            WitnessHeard::Opinion(opinion) => Some(opinion),
            _ => None,
        };
        analysis.hear_witness(opinion, &self.analysis);
        Some(heard)
    }
}

/// Runs a monitor's band selections: [`start`](Self::start) hands over a job,
/// [`finish`](Self::finish) returns the oldest unfinished job's result, waiting for it if
/// needed. Jobs finish in the order they started.
pub trait BandSelector: Send {
    fn start(&mut self, job: Arc<BandJob>);
    /// `None` only if no job was started.
    fn finish(&mut self) -> Option<BandResult>;
}

/// Runs each job on the calling thread when it starts (`bearingd analyze`, tests, and a
/// monitor whose results are used at once).
#[derive(Default)]
pub struct InlineSelector {
    done: VecDeque<BandResult>,
}

impl BandSelector for InlineSelector {
    fn start(&mut self, job: Arc<BandJob>) {
        self.done.push_back(job.run(&mut FftPlans::shared()));
    }

    fn finish(&mut self) -> Option<BandResult> {
        self.done.pop_front()
    }
}
