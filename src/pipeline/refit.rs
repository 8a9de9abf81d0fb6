//! The twin's periodic re-fit, on its own thread (FFT-heavy work never runs on the async
//! side), warm-started per channel from the previous fit.

use super::TwinRequest;
use crate::analysis::envelope::{window_samples, FftPlans};
use crate::messages::{ChannelId, TwinMessage};
use crate::twin::diagnose::fit_record;
use crate::twin::{TwinFitter, TwinParams};
use std::collections::BTreeMap;

/// Re-fits the twins of every channel, keeping each channel's last parameters.
#[derive(Default)]
pub struct TwinWorker {
    plans: FftPlans,
    fitter: TwinFitter,
    previous: BTreeMap<ChannelId, Vec<TwinParams>>,
}

/// Welch windows per re-fit: the re-fit's signal is cut into windows a quarter of its length.
const WINDOW_FRACTION: f64 = 0.25;

impl TwinWorker {
    pub fn refit(&mut self, request: &TwinRequest) -> Option<TwinMessage> {
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
        })
    }
}
