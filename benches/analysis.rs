//! Speed of the analysis core (issue 2 targets, reported in docs/PERFORMANCE.md):
//! - `analyze` of a 10 s, 12 kHz record: ≤ 10 ms on one core;
//! - one rolling envelope-spectrum update with a 16384-sample window: ≤ 150 µs;
//! - (issue 16) the ISO velocity severity, per record and per daemon reading.
//!
//! Run: `cargo bench --bench analysis`. The record is CWRU 105 when ../shared/data is there,
//! else 10 s of the twin's simulated outer-race fault (the same size).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::analysis::envelope::{FftPlans, RollingEnvelope};
use bearingd::analysis::iso::{record_severity, SeveritySettings, VelocityTracker};
use bearingd::analysis::record::{analyze_record, RecordAnalyzer};
use bearingd::analysis::{AnalysisSettings, Band, BandSelection};
use bearingd::bearing::BearingGeometry;
use bearingd::recording::{read_recording, ReadOptions};
use bearingd::twin::diagnose::fit_record;
use bearingd::twin::fit::{TwinFitter, HYPOTHESES};
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;

fn ten_second_record() -> (Vec<f32>, f64, f64, &'static str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/cwru/12k_Drive_End_IR007_0_105.mat");
    match read_recording(&path, &ReadOptions::default()) {
        Ok(r) => (
            r.samples.iter().map(|&x| x as f32).collect(),
            12_000.0,
            r.rpm.unwrap_or(1797.0),
            "CWRU 105",
        ),
        Err(_) => {
            let params = SimulationParams::example(SimulatedFault::OuterRace);
            (
                Simulator::record(params.clone(), 10.0),
                params.fs_hz,
                params.rpm,
                "simulated",
            )
        }
    }
}

fn analyze(c: &mut Criterion) {
    let (signal, fs, rpm, name) = ten_second_record();
    let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
        .unwrap()
        .fault_frequencies(rpm / 60.0);
    let mut group = c.benchmark_group(format!("analyze 10 s at 12 kHz ({name})"));
    for (label, selection) in [
        ("gk", BandSelection::GiniKurtosis),
        ("kurtogram", BandSelection::Kurtogram),
    ] {
        let settings = AnalysisSettings {
            band_selection: selection,
            ..AnalysisSettings::default()
        };
        let mut analyzer = RecordAnalyzer::default();
        group.bench_function(format!("{label}, plans reused"), |b| {
            b.iter(|| {
                analyzer
                    .analyze(black_box(&signal), fs, &freqs, &settings)
                    .unwrap()
            })
        });
    }
    let settings = AnalysisSettings::default();
    group.bench_function("gk, first call (plans made)", |b| {
        b.iter(|| analyze_record(black_box(&signal), fs, &freqs, &settings).unwrap())
    });
    group.finish();
}

fn rolling_update(c: &mut Criterion) {
    let fs = 25_600.0;
    let (window, hop) = (16_384, 4_096);
    let bins = 1_200;
    let params = SimulationParams {
        fs_hz: fs,
        ..SimulationParams::example(SimulatedFault::OuterRace)
    };
    let signal = Simulator::record(params, 4.0);
    let mut rolling =
        RollingEnvelope::new(fs, window, hop, 8, &[Band::new(2_000.0, 6_000.0)], bins);
    rolling.push(&signal[..window], |_| {});
    let mut at = window;
    c.bench_function(
        "rolling update, 16384-sample window, 2-6 kHz band, 8 averages",
        |b| {
            b.iter(|| {
                if at + hop > signal.len() {
                    at = window;
                }
                let mut peak = 0f32;
                rolling.push(&signal[at..at + hop], |u| {
                    peak = u.bands[0].averaged_amplitude()[100]
                });
                at += hop;
                black_box(peak)
            })
        },
    );
}

/// Issue 3 target: one refit, all three hypotheses, on a 1 s window at 12 kHz: ≤ 10 ms.
/// The 1 s of samples is cut into 50 %-overlapping windows of 4096 samples (0.34 s, 2.9 Hz
/// bins); the bands are the ones the band-score analysis picks for each hypothesis.
fn twin_refit(c: &mut Criterion) {
    let (signal, fs, rpm, name) = ten_second_record();
    let second = &signal[..fs as usize];
    let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
        .unwrap()
        .fault_frequencies(rpm / 60.0);
    let settings = AnalysisSettings {
        window_s: 4096.0 / fs,
        ..AnalysisSettings::default()
    };
    let analysis = RecordAnalyzer::default()
        .analyze(second, fs, &freqs, &settings)
        .unwrap();
    let band_of = |kind| {
        let h = analysis
            .hypotheses
            .iter()
            .find(|h| h.score.fault == kind)
            .unwrap();
        analysis.scan.bands[h.band_index].band
    };
    let bands = HYPOTHESES.map(band_of);
    let mut plans = FftPlans::default();
    let mut fitter = TwinFitter::default();
    let mut group = c.benchmark_group(format!("twin refit, 3 hypotheses, 1 s at 12 kHz ({name})"));
    group.bench_function("cold start", |b| {
        b.iter(|| {
            fit_record(
                &mut plans,
                &mut fitter,
                black_box(second),
                fs,
                &freqs,
                &bands,
                4096,
                0.5,
                None,
            )
        })
    });
    let previous: Vec<_> = fit_record(
        &mut plans,
        &mut fitter,
        second,
        fs,
        &freqs,
        &bands,
        4096,
        0.5,
        None,
    )
    .fits
    .iter()
    .map(|f| f.params)
    .collect();
    group.bench_function("warm start from the previous fit", |b| {
        b.iter(|| {
            fit_record(
                &mut plans,
                &mut fitter,
                black_box(second),
                fs,
                &freqs,
                &bands,
                4096,
                0.5,
                Some(&previous),
            )
        })
    });
    group.finish();
}

/// Issue 16 item 4: what the ISO 10816-3 velocity costs. `bearingd analyze` measures it once per
/// record beside the envelope analysis (the same plans); the daemon once per half velocity
/// window per channel.
fn iso_velocity(c: &mut Criterion) {
    let (signal, fs, rpm, name) = ten_second_record();
    let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
        .unwrap()
        .fault_frequencies(rpm / 60.0);
    let severity = SeveritySettings::default();
    let mut group = c.benchmark_group(format!("ISO velocity, 10 s at 12 kHz ({name})"));
    let mut analyzer = RecordAnalyzer::default();
    group.bench_function("velocity severity of the record, plans reused", |b| {
        b.iter(|| {
            record_severity(&mut analyzer.plans, black_box(&signal), fs, rpm, severity).unwrap()
        })
    });
    let settings = AnalysisSettings::default();
    group.bench_function("analyze (gk) + velocity severity, plans reused", |b| {
        b.iter(|| {
            let analysis = analyzer
                .analyze(black_box(&signal), fs, &freqs, &settings)
                .unwrap();
            let velocity =
                record_severity(&mut analyzer.plans, black_box(&signal), fs, rpm, severity);
            (analysis, velocity)
        })
    });
    group.finish();

    // The daemon's rolling tracker at 25.6 kHz: 32,768-sample windows, a reading every 16,384
    // samples; one iteration pushes one hop (one reading).
    let fs = 25_600.0;
    let params = SimulationParams {
        fs_hz: fs,
        ..SimulationParams::example(SimulatedFault::OuterRace)
    };
    let signal = Simulator::record(params, 8.0);
    let mut tracker = VelocityTracker::new(fs, 1772.0, severity, 8, &mut FftPlans::default());
    let hop = tracker.window() / 2;
    tracker.push(&signal[..tracker.window()], |_| {});
    let mut at = 0;
    c.bench_function(
        "velocity tracker, one reading (hop 16384 samples of a 32768 window at 25.6 kHz, 8 averages)",
        |b| {
            b.iter(|| {
                if at + hop > signal.len() {
                    at = 0;
                }
                let mut rms = 0.0;
                tracker.push(black_box(&signal[at..at + hop]), |r| rms = r.rms_mm_s);
                at += hop;
                black_box(rms)
            })
        },
    );
}

criterion_group!(benches, analyze, rolling_update, iso_velocity, twin_refit);
criterion_main!(benches);
