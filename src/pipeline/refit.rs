//! The twin's periodic re-fit, on its own thread (FFT-heavy work never runs on the async
//! side), warm-started per channel from the previous fit: the signal-model twin on the
//! envelope spectrum and, on the newest samples of the same signal, the Hammerstein–Wiener
//! model of seed 003 with its drift against the channel's baseline (`twin::hw::online`); and,
//! when a learned model is configured, its opinion of the same signal combined with the
//! envelope evidence the request carries (`learned`), logged with the twin's fit.

use super::TwinRequest;
use crate::analysis::envelope::{window_samples, FftPlans};
use crate::config::TwinConfig;
use crate::learned::{ModelError, ModelSet};
use crate::messages::{
    ChannelId, ClassProbability, HwMessage, LearnedOpinionMessage, PipelineMessage, TwinMessage,
};
use crate::twin::diagnose::fit_record;
use crate::twin::hw::{HwConfig, HwError, HwTracker, HwUpdate};
use crate::twin::{TwinFitter, TwinParams};
use std::collections::BTreeMap;
use std::sync::Arc;

/// `twin.learned_model`, loaded once per process: the twin's re-fits log its opinion, and the
/// band jobs' verdicts hear it as their second witness (`analysis.agreement_*`).
pub fn load_learned(config: &TwinConfig) -> Result<Option<Arc<ModelSet>>, ModelError> {
    Ok(config
        .learned_model
        .as_deref()
        .map(ModelSet::load)
        .transpose()?
        .map(Arc::new))
}

/// Re-fits the twins of every channel, keeping each channel's last parameters.
pub struct TwinWorker {
    plans: FftPlans,
    fitter: TwinFitter,
    previous: BTreeMap<ChannelId, Vec<TwinParams>>,
    /// The HW model's settings; `None`: off (`twin.hw_enabled = false`).
    hw: Option<HwSettings>,
    hw_trackers: BTreeMap<ChannelId, HwTracker>,
    /// `twin.learned_model`, loaded: a model per bearing.
    learned: Option<Arc<ModelSet>>,
}

#[derive(Debug, Clone, Copy)]
struct HwSettings {
    config: HwConfig,
    samples: usize,
    baseline_fits: u64,
}

/// Welch windows per re-fit: the re-fit's signal is cut into windows a quarter of its length.
const WINDOW_FRACTION: f64 = 0.25;

impl TwinWorker {
    /// The worker, with the learned model (`twin.learned_model`, loaded once by the caller with
    /// [`load_learned`]; every sensor's bearing was found a model when the config was
    /// validated).
    pub fn new(config: &TwinConfig, learned: Option<Arc<ModelSet>>) -> Self {
        TwinWorker {
            plans: FftPlans::default(),
            fitter: TwinFitter::default(),
            previous: BTreeMap::new(),
            hw: config.hw_enabled.then(|| HwSettings {
                config: HwConfig::for_order(config.hw_order),
                samples: config.hw_samples,
                baseline_fits: config.hw_baseline_fits,
            }),
            hw_trackers: BTreeMap::new(),
            learned,
        }
    }

    /// Both models on one request, each handed to `out` as soon as it is made: the twin's fit
    /// (none when the signal is shorter than one Welch window), then the HW model's (none when
    /// it is off), so that the HW identification never delays the twin's fit.
    pub fn refit(&mut self, request: &TwinRequest, out: &mut impl FnMut(PipelineMessage)) {
        if let Some(twin) = self.refit_twin(request) {
            out(PipelineMessage::Twin(twin));
        }
        if let Some(hw) = self.reidentify_hw(request) {
            out(PipelineMessage::Hw(hw));
        }
    }

    /// The HW model of the request's channel, re-identified on the newest samples; a signal it
    /// cannot be identified on gives a message that says why.
    fn reidentify_hw(&mut self, request: &TwinRequest) -> Option<HwMessage> {
        let settings = self.hw?;
        let tracker = self
            .hw_trackers
            .entry(request.channel.clone())
            .or_insert_with(|| {
                HwTracker::new(settings.config, settings.samples, settings.baseline_fits)
            });
        let signal: Vec<f64> = request.samples.iter().map(|&x| f64::from(x)).collect();
        let start = request
            .end_sample
            .saturating_sub(request.samples.len() as u64);
        let update = tracker.update(&signal, request.fs_hz);
        Some(hw_message(request, &settings.config, start, update))
    }

    fn refit_twin(&mut self, request: &TwinRequest) -> Option<TwinMessage> {
        let seconds = request.samples.len() as f64 / request.fs_hz;
        let window = window_samples(seconds * WINDOW_FRACTION, request.fs_hz);
        if request.samples.len() < window {
            return None;
        }
        let previous = self.previous.get(&request.channel).map(Vec::as_slice);
        let twin = fit_record(
            &mut self.plans,
            &mut self.fitter,
            &request.samples,
            request.fs_hz,
            &request.freqs,
            &request.bands,
            window,
            0.5,
            previous,
        );
        self.previous.insert(
            request.channel.clone(),
            twin.fits.iter().map(|f| f.params).collect(),
        );
        let best = twin.best_fit();
        let error_of = |kind| twin.error_of(kind).unwrap_or(f64::NAN);
        use crate::messages::FaultKind::{Ball, InnerRace, OuterRace};
        Some(TwinMessage {
            channel: request.channel.clone(),
            end_sample: request.end_sample,
            hypothesis: best.fault,
            error: best.error,
            margin: twin.margin,
            error_outer_race: error_of(OuterRace),
            error_inner_race: error_of(InnerRace),
            error_ball: error_of(Ball),
            a: best.params.a,
            decay_per_s: best.params.decay_per_s,
            f_n: best.params.f_n,
            f_d: best.params.f_d,
            jitter: best.params.jitter,
            residual_energy_ratio: twin.residual.energy_ratio,
            residual_peak_hz: twin.residual.largest_peak_hz,
            residual_bin_hz: twin.bin_hz,
            residual: twin
                .measured
                .iter()
                .zip(&twin.twin)
                .map(|(m, t)| (m - t) as f32)
                .collect(),
            learned: self.learned_opinion(request),
        })
    }

    /// The learned model's opinion of the request's signal, combined with its envelope
    /// evidence; `None` when no model is configured or the signal is shorter than a segment.
    fn learned_opinion(&self, request: &TwinRequest) -> Option<LearnedOpinionMessage> {
        let model = self.learned.as_ref()?;
        let opinion = match model.opinion_of(&request.samples, request.fs_hz, &request.freqs) {
            Ok(opinion) if opinion.segments > 0 => opinion,
            Ok(_) => return None,
            Err(e) => {
                return Some(LearnedOpinionMessage {
                    segments: 0,
                    probabilities: Vec::new(),
                    confirms: None,
                    agrees: false,
                    problem: Some(e.to_string()),
                })
            }
        };
        let top = opinion.top().0.kind();
        Some(LearnedOpinionMessage {
            segments: opinion.segments,
            probabilities: opinion
                .probabilities
                .iter()
                .map(|&(class, probability)| ClassProbability {
                    fault: class.kind(),
                    probability,
                })
                .collect(),
            confirms: request.agreed,
            agrees: top == request.flagged,
            problem: None,
        })
    }
}

fn hw_message(
    request: &TwinRequest,
    config: &HwConfig,
    signal_start: u64,
    update: Result<HwUpdate, HwError>,
) -> HwMessage {
    let mut message = HwMessage {
        channel: request.channel.clone(),
        end_sample: request.end_sample,
        first_sample: signal_start,
        fs_hz: request.fs_hz,
        order: config.order,
        states: config.states.name().into(),
        problem: None,
        warm_start: false,
        iterations: 0,
        accuracy_simulation: f64::NAN,
        accuracy_one_step: f64::NAN,
        numerators: Vec::new(),
        denominators: Vec::new(),
        pole_radius: Vec::new(),
        output_polynomial: Vec::new(),
        output_mean: f64::NAN,
        output_scale: f64::NAN,
        residual_simulation: Vec::new(),
        residual_one_step: Vec::new(),
        baseline_fits: 0,
        residual_drift_sigma: None,
        parameter_drift: None,
    };
    let update = match update {
        Ok(update) => update,
        Err(problem) => {
            message.problem = Some(problem.to_string());
            return message;
        }
    };
    let model = &update.fit.model;
    let to_f32 = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect();
    HwMessage {
        first_sample: signal_start + update.first_sample as u64,
        warm_start: update.fit.warm_start,
        iterations: update.fit.iterations,
        accuracy_simulation: update.fit.accuracy.simulation,
        accuracy_one_step: update.fit.accuracy.one_step,
        numerators: model.linear.iter().map(|tf| tf.b.clone()).collect(),
        denominators: model.linear.iter().map(|tf| tf.f.clone()).collect(),
        pole_radius: model.linear.iter().map(|tf| tf.spectral_radius()).collect(),
        output_polynomial: model.output.coefficients.clone(),
        output_mean: model.output_mean,
        output_scale: model.output_scale,
        residual_simulation: to_f32(update.responses.simulation_residual()),
        residual_one_step: to_f32(update.responses.one_step_residual()),
        baseline_fits: update.baseline_fits,
        residual_drift_sigma: update.residual_drift_sigma,
        parameter_drift: update.parameter_drift,
        ..message
    }
}
