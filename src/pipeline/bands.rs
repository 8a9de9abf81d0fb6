//! The pipeline's band selections on a thread of their own ([`BandWorker`]), so that the
//! analysis thread never holds a block (and the alert it may decide) for the 30–100 ms of a
//! selection.
//!
//! Each channel's monitor gets a [`WorkerSelector`]: it hands its jobs to the worker and, at the
//! sample where the result is due (a fixed delay after the start, in sample time), takes the
//! result, waiting for it only if the worker is late. What the monitor does therefore depends
//! on the samples alone, never on how fast the worker was: `run` and `replay` agree.
//!
//! Bounds: each channel has at most one job under way (the monitor starts none while one is),
//! so the job queue holds at most one per channel.

use crate::analysis::band_selection::{BandJob, BandResult, BandSelector};
use crate::analysis::envelope::FftPlans;
use std::collections::VecDeque;
use std::sync::mpsc;
use std::sync::Arc;

/// A job and where its result goes.
type Request = (Arc<BandJob>, mpsc::SyncSender<BandResult>);

/// The band-selection thread; it ends when every [`WorkerSelector`] is gone.
pub struct BandWorker {
    jobs: mpsc::SyncSender<Request>,
}

impl BandWorker {
    /// Starts the thread, for at most `channels` jobs under way; `None` if the thread cannot
    /// be started (the monitors then select inline).
    pub fn start(channels: usize) -> Option<BandWorker> {
        let (jobs, requests) = mpsc::sync_channel::<Request>(channels.max(1));
        std::thread::Builder::new()
            .name("bearingd-bands".into())
            .spawn(move || {
                super::priority::idle_this_thread();
                // Its own plans: the shared cache's lock is then never held for a selection.
                let mut plans = FftPlans::default();
                while let Ok((job, result)) = requests.recv() {
                    let _ = result.send(job.run(&mut plans));
                }
            })
            .ok()?;
        Some(BandWorker { jobs })
    }

    /// A selector for one channel's monitor.
    pub fn selector(&self) -> WorkerSelector {
        WorkerSelector {
            jobs: self.jobs.clone(),
            under_way: VecDeque::new(),
        }
    }
}

/// One channel's end of the [`BandWorker`].
pub struct WorkerSelector {
    jobs: mpsc::SyncSender<Request>,
    under_way: VecDeque<(Arc<BandJob>, mpsc::Receiver<BandResult>)>,
}

impl BandSelector for WorkerSelector {
    fn start(&mut self, job: Arc<BandJob>) {
        let (tx, rx) = mpsc::sync_channel(1);
        // A worker that is gone (it cannot panic on input, but still) leaves the job to
        // `finish`, which then runs it here.
        let _ = self.jobs.send((job.clone(), tx));
        self.under_way.push_back((job, rx));
    }

    fn finish(&mut self) -> Option<BandResult> {
        let (job, result) = self.under_way.pop_front()?;
        Some(
            result
                .recv()
                .unwrap_or_else(|_| job.run(&mut FftPlans::shared())),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::band_selection::InlineSelector;
    use crate::analysis::speed::SpeedMode;
    use crate::analysis::AnalysisSettings;
    use crate::twin::{SimulatedFault, SimulationParams, Simulator};

    #[test]
    fn the_worker_finds_what_the_inline_selection_finds() {
        let mut params = SimulationParams::example(SimulatedFault::OuterRace);
        params.onset_s = 0.0;
        let mut signal = vec![0f32; (params.fs_hz * 2.0) as usize];
        Simulator::new(params.clone()).fill(&mut signal);
        let scale = 1.0 / 2048.0;
        let freqs = params.frequencies();
        let job = Arc::new(BandJob {
            counts: signal
                .iter()
                .map(|&g| (f64::from(g) / scale).round() as i16)
                .collect(),
            scale,
            fs_hz: params.fs_hz,
            freqs,
            orders: crate::analysis::band_selection::scaled(&freqs, 1.0 / freqs.shaft),
            speed_known: true,
            max_shaft_hz: freqs.shaft,
            speed: SpeedMode::Fixed,
            analysis: AnalysisSettings::default(),
            witness: None,
        });
        let worker = BandWorker::start(2).unwrap();
        let mut threaded = worker.selector();
        let mut inline = InlineSelector::default();
        threaded.start(job.clone());
        threaded.start(job.clone());
        inline.start(job);
        let expected = inline.finish().unwrap();
        assert!(expected.bands.is_some());
        assert_eq!(threaded.finish(), Some(expected));
        assert_eq!(threaded.finish(), Some(expected));
        assert_eq!(threaded.finish(), None);
    }
}
