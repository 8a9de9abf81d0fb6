//! The squared-envelope spectrum against a naive-DFT oracle, the rolling form against the
//! batch form, and the rolling form's band work spread over the hop against it done at once.

use bearingd::analysis::envelope::{
    welch_envelope_spectrum, BandEnvelope, FftPlans, HopStage, RollingEnvelope, WindowTransform,
};
use bearingd::analysis::Band;
use bearingd::random::Rng;
use std::f64::consts::TAU;

/// Amplitude-modulated resonance: carrier `carrier_hz`, modulation `mod_hz`, plus noise.
fn am_signal(len: usize, fs: f64, carrier_hz: f64, mod_hz: f64, noise: f64, seed: u64) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    (0..len)
        .map(|n| {
            let t = n as f64 / fs;
            ((1.0 + 0.8 * (TAU * mod_hz * t).cos()) * (TAU * carrier_hz * t).sin()
                + noise * rng.normal()) as f32
        })
        .collect()
}

/// Direct O(N²) evaluation of the definition: DFT, keep the band's positive bins doubled,
/// inverse DFT at full rate, squared magnitude, mean removed, Hann, DFT, scaled power.
fn naive_squared_envelope_power(x: &[f32], fs: f64, band: Band, bins: usize) -> Vec<f64> {
    let n = x.len();
    let dft = |k: usize, signal: &dyn Fn(usize) -> f64| -> (f64, f64) {
        let (mut re, mut im) = (0.0, 0.0);
        for (i, phase) in (0..n).map(|i| (i, -TAU * (k * i % n) as f64 / n as f64)) {
            let v = signal(i);
            re += v * phase.cos();
            im += v * phase.sin();
        }
        (re, im)
    };
    let first = ((band.lo_hz * n as f64 / fs).round() as usize).max(1);
    let last = ((band.hi_hz * n as f64 / fs).round() as usize).min(n / 2 + 1);
    let spectrum: Vec<(usize, (f64, f64))> = (first..last)
        .map(|k| (k, dft(k, &|i| f64::from(x[i]))))
        .collect();
    let envelope: Vec<f64> = (0..n)
        .map(|i| {
            let (mut re, mut im) = (0.0, 0.0);
            for &(k, (xr, xi)) in &spectrum {
                let phase = TAU * (k * i % n) as f64 / n as f64;
                re += xr * phase.cos() - xi * phase.sin();
                im += xr * phase.sin() + xi * phase.cos();
            }
            let scale = 2.0 / n as f64;
            (re * scale).powi(2) + (im * scale).powi(2)
        })
        .collect();
    let mean = envelope.iter().sum::<f64>() / n as f64;
    let hann: Vec<f64> = (0..n)
        .map(|i| 0.5 - 0.5 * (TAU * i as f64 / n as f64).cos())
        .collect();
    let hann_sum: f64 = hann.iter().sum();
    (0..bins)
        .map(|k| {
            let (re, im) = dft(k, &|i| (envelope[i] - mean) * hann[i]);
            (re * re + im * im) * (2.0 / hann_sum).powi(2)
        })
        .collect()
}

#[test]
fn one_window_matches_the_naive_dft_oracle() {
    let (fs, window, bins) = (12_000.0, 1024, 64);
    let band = Band::new(2_500.0, 3_500.0);
    let x = am_signal(window, fs, 3_000.0, 105.0, 0.3, 11);
    let mut plans = FftPlans::default();
    let mut transform = WindowTransform::new(window, &mut plans);
    let mut envelope = BandEnvelope::new(band, fs, window, bins, &mut plans);
    let mut fast = vec![0f32; bins];
    envelope.process(transform.transform(&x, &[]), &mut fast);
    let oracle = naive_squared_envelope_power(&x, fs, band, bins);
    let peak = oracle.iter().cloned().fold(0.0, f64::max);
    for (k, (f, o)) in fast.iter().zip(&oracle).enumerate() {
        assert!(
            (f64::from(*f) - o).abs() <= 2e-4 * peak,
            "bin {k}: fast {f} vs oracle {o} (peak {peak})"
        );
    }
    let peak_bin = (1..bins)
        .max_by(|&a, &b| fast[a].total_cmp(&fast[b]))
        .unwrap();
    assert_eq!(
        peak_bin,
        (105.0 * window as f64 / fs).round() as usize,
        "envelope peak at the modulation frequency"
    );
}

#[test]
fn welch_spectrum_peaks_at_the_modulation_frequency_and_its_harmonic() {
    let fs = 12_000.0;
    let x = am_signal(120_000, fs, 3_000.0, 107.3, 1.0, 3);
    let s = welch_envelope_spectrum(
        &mut FftPlans::default(),
        &x,
        fs,
        Band::new(2_000.0, 4_000.0),
        16_384,
        0.5,
        2_000,
    );
    let peak_hz = |lo: f64, hi: f64| {
        s.frequencies()
            .zip(&s.amplitude)
            .filter(|(f, _)| *f > lo && *f < hi)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(f, _)| f)
            .unwrap()
    };
    assert!(
        (peak_hz(20.0, 150.0) - 107.3).abs() <= s.bin_hz,
        "fundamental at {}",
        peak_hz(20.0, 150.0)
    );
    assert!(
        (peak_hz(150.0, 260.0) - 214.6).abs() <= s.bin_hz,
        "second harmonic at {}",
        peak_hz(150.0, 260.0)
    );
    assert_eq!(s.windows_averaged, 13);
}

#[test]
fn rolling_average_equals_batch_welch_whatever_the_block_sizes() {
    let (fs, window, hop, bins) = (12_000.0, 4096, 2048, 400);
    let band = Band::new(2_000.0, 4_000.0);
    let x = am_signal(40_960, fs, 3_000.0, 105.0, 0.5, 5);
    let batch = welch_envelope_spectrum(&mut FftPlans::default(), &x, fs, band, window, 0.5, bins);
    let mut rolling = RollingEnvelope::new(fs, window, hop, 1_000, &[band], bins);
    let mut rng = Rng::new(9);
    let mut rest = &x[..];
    let mut last: Option<(u64, Vec<f32>, usize)> = None;
    while !rest.is_empty() {
        let take = ((rng.uniform() * 3_000.0) as usize + 1).min(rest.len());
        rolling.push(&rest[..take], |u| {
            last = Some((
                u.end_sample,
                u.bands[0].averaged_amplitude().to_vec(),
                u.windows_averaged,
            ))
        });
        rest = &rest[take..];
    }
    let (end_sample, averaged, count) = last.expect("updates");
    assert_eq!(count, batch.windows_averaged);
    assert_eq!(end_sample, ((count - 1) * hop + window) as u64);
    let peak = batch.amplitude.iter().cloned().fold(0.0, f32::max);
    for (k, (r, b)) in averaged.iter().zip(&batch.amplitude).enumerate() {
        assert!(
            (r - b).abs() <= 1e-4 * peak,
            "bin {k}: rolling {r} vs batch {b}"
        );
    }
}

/// What a rolling envelope hands out, stage by stage: the window's end and, for a band stage,
/// the engine and its average; for the whole update, every engine's average.
#[derive(Debug, PartialEq)]
enum Seen {
    Window(u64),
    Band(usize, Vec<f32>),
    Update(u64, usize, Vec<Vec<f32>>),
}

fn seen(stage: HopStage) -> Seen {
    match stage {
        HopStage::Window(ready) => Seen::Window(ready.end_sample),
        HopStage::Band { engine, band, .. } => {
            Seen::Band(engine, band.averaged_amplitude().to_vec())
        }
        HopStage::Bands(update) => Seen::Update(
            update.end_sample,
            update.windows_averaged,
            update
                .bands
                .iter()
                .map(|b| b.averaged_amplitude().to_vec())
                .collect(),
        ),
    }
}

#[test]
fn spread_band_work_is_the_same_work_at_fixed_samples_whatever_the_blocks() {
    let (fs, window, hop, bins) = (12_000.0, 4096, 2048, 400);
    // Three bands asked for, one of them twice: three engines.
    let bands = [
        Band::new(2_000.0, 4_000.0),
        Band::new(1_000.0, 2_500.0),
        Band::new(2_000.0, 4_000.0),
        Band::new(3_500.0, 5_500.0),
    ];
    // The last window ends at 39,212 (300 + 4096 + 17 hops), its bands due after 39,500.
    let x = am_signal(39_500, fs, 3_000.0, 105.0, 0.5, 11);
    let make = || RollingEnvelope::new(fs, window, hop, 4, &bands, bins).with_phase(300);
    let mut at_once = Vec::new();
    make().push_staged(&x, |stage| at_once.push(seen(stage)));
    assert_eq!(
        at_once.len(),
        18 * 5,
        "18 windows of a window, 3 bands and an update"
    );

    let step = (hop / 5) as u64;
    let mut rng = Rng::new(3);
    for largest in [1, 700, 5_000] {
        let mut spread = make().spread_bands();
        let (mut rest, mut pushed) = (&x[..], 0u64);
        let mut stages: Vec<(Seen, u64, u64)> = Vec::new();
        while !rest.is_empty() {
            let take = ((rng.uniform() * largest as f64) as usize + 1).min(rest.len());
            let from = pushed;
            pushed += take as u64;
            spread.push_staged(&rest[..take], |stage| {
                stages.push((seen(stage), from, pushed))
            });
            rest = &rest[take..];
        }
        assert!(
            spread.bands_pending(),
            "the last window's bands wait for their samples"
        );
        spread.finish_bands(|stage| stages.push((seen(stage), pushed, pushed)));
        assert!(!spread.bands_pending());
        let values: Vec<&Seen> = stages.iter().map(|s| &s.0).collect();
        assert_eq!(
            values,
            at_once.iter().collect::<Vec<_>>(),
            "blocks up to {largest}"
        );
        // Each band stage comes in the block holding its sample: engine k at the window's end
        // plus (k + 1) steps, the update with the last engine; the last window's at the end.
        let mut window_end = 0;
        for (stage, from, to) in &stages {
            let due = match stage {
                Seen::Window(end) => {
                    window_end = *end;
                    *end
                }
                Seen::Band(engine, _) => window_end + (*engine as u64 + 1) * step,
                Seen::Update(..) => window_end + 3 * step,
            };
            if due > pushed {
                assert_eq!(
                    (*from, *to),
                    (pushed, pushed),
                    "{stage:?} finished at the end"
                );
            } else {
                assert!(
                    *from < due && due <= *to,
                    "{stage:?} due at {due}, in [{from}, {to}]"
                );
            }
        }
    }
}
