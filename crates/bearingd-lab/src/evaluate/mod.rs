//! `bearingd-lab evaluate` (or `bearingd evaluate`): the detector-evaluation harness (seed
//! 002's method: a twin generates faults under controlled conditions, and the
//! condition-monitoring algorithm is judged on them).
//!
//! Why: a detector tuned on a handful of recordings says nothing about the faults, speeds,
//! bearings and noise levels it has not seen. The simulator knows the truth, so a sweep over
//! fault type × severity × SNR × speed × bearing (with healthy records, and with the nuisance
//! a real machine adds) measures what matters: how often each fault is found at each noise
//! level, how often a healthy machine is flagged, and whether the detector ever names the
//! wrong fault. It runs the real pipeline, both ways users meet it ([`run`]): the record path
//! of `bearingd analyze` and the daemon's channel monitor in sample time.
//!
//! - [`sweep`]: the axes and the cases they make, each with its own derived seed.
//! - [`run`]: one case through both paths.
//! - [`summary`]: Pd tables, false-alarm rates, confusion matrices, CSV.
//! - [`figure`]: Pd vs SNR per fault type.
//! - [`agreement`]: the learned model's agreement decided at every point of a parameter grid
//!   on the same records, to calibrate it.
//! - [`false_alarms`]: hours of healthy signal through the monitor path, its flag rises per
//!   hour of operation (`bearingd evaluate --false-alarm-hours H`).
//! - [`recordings`]: real recordings of a manifest through `analyze` and through the daemon
//!   (`bearingd import` + `bearingd replay`, in-process), with the truth the manifest states
//!   (`bearingd evaluate --recordings`).
//!
//! Deterministic: a case's result depends only on the sweep seed and the case, never on the
//! thread that ran it or the order; results are kept in case order.

pub mod agreement;
pub mod false_alarms;
pub mod figure;
pub mod outcome;
pub mod recordings;
pub mod run;
pub mod summary;
pub mod sweep;

pub use figure::pd_figure;
pub use outcome::{CaseResult, Predicted};
pub use run::{run_case, Bench};
pub use summary::{render_csv, render_tables, summarize, Path, Summary};
pub use sweep::{Case, Machine, NoiseLevel, Sweep};

use crate::analysis::record::RecordAnalyzer;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Runs every case of `sweep` on `threads` threads; `progress(done, total)` is called after
/// each case (from the worker threads). Results come back in case order.
pub fn run_sweep(
    bench: &Bench,
    sweep: &Sweep,
    threads: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Vec<CaseResult> {
    let cases = sweep.cases();
    in_order(
        &cases,
        threads,
        RecordAnalyzer::default,
        |analyzer, case| run_case(bench, sweep, case, analyzer),
        &|done, total, _| progress(done, total),
    )
}

/// `work` on every item on `threads` threads, each thread with its own `state` (an analyzer's
/// buffers); `progress(done, total, result)` after each item (from the worker threads). The
/// results come back in the items' order, whichever thread ran each.
pub fn in_order<T: Sync, S, R: Send>(
    items: &[T],
    threads: usize,
    state: impl Fn() -> S + Sync,
    work: impl Fn(&mut S, &T) -> R + Sync,
    progress: &(dyn Fn(usize, usize, &R) + Sync),
) -> Vec<R> {
    let total = items.len();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let slots: Mutex<Vec<Option<R>>> = Mutex::new((0..total).map(|_| None).collect());
    std::thread::scope(|scope| {
        for _ in 0..threads.clamp(1, total.max(1)) {
            scope.spawn(|| {
                let mut state = state();
                loop {
                    let index = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(index) else {
                        break;
                    };
                    let result = work(&mut state, item);
                    progress(done.fetch_add(1, Ordering::Relaxed) + 1, total, &result);
                    slots.lock().unwrap_or_else(|e| e.into_inner())[index] = Some(result);
                }
            });
        }
    });
    slots
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .flatten()
        .collect()
}
