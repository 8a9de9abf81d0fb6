//! The monitor's own state, checked from inside: the history a band selection reads, the scale
//! it is kept in, and a restart that goes back in sample time. What the monitor tells its
//! driver (flags, gaps, block sizes, speeds) is tested from outside in `tests/suite/monitor.rs`.

use super::*;
use crate::analysis::flags::FlagSettings;
use crate::analysis::indicators::Indicators;
use crate::analysis::AnalysisSettings;
use bearing_signal::simulate::{SimulatedFault, SimulationParams};

const FS: f64 = 2_560.0;
/// Shorter than a chunk of [`CHUNK`] samples, so that one chunk can overrun the whole history.
const HISTORY: usize = 3_000;

/// A small channel: 2048-sample windows, a 3000-sample history and no band selection within
/// the tests' few seconds, so that what is checked is the per-block path alone.
fn monitor() -> ChannelMonitor {
    let settings = MonitorSettings {
        fs_hz: FS,
        analysis: AnalysisSettings::default(),
        band_period_samples: 1_000_000,
        band_phase_samples: 0,
        window_stagger: (0, 1),
        band_history_samples: HISTORY,
        flags: FlagSettings {
            watch_score: 10.0,
            alarm_score: 15.0,
            clear_ratio: 0.8,
            on_delay_samples: 0,
            off_delay_samples: 0,
        },
        baseline_windows: 20,
        sigma: 3.0,
        clip_count: 32_767,
        flat_line_samples: FS as u64,
        speed: SpeedMode::Fixed,
        detectors: Default::default(),
        trend: TrendSettings::default(),
    };
    let freqs = SimulationParams::example(SimulatedFault::OuterRace).frequencies();
    let mut monitor = ChannelMonitor::new(settings, freqs, None);
    // Never reached: the tests look at the history, not at a selection of it.
    monitor.next_band_selection = u64::MAX;
    monitor
}

/// Counts that differ from sample to sample (no flat line) with a seed.
fn counts(len: usize, seed: i32) -> Vec<i16> {
    (0..len as i32)
        .map(|i| ((i * 7_919 + seed * 104_729) % 2_001 - 1_000) as i16)
        .collect()
}

/// The end sample and indicators of every window the counts close.
fn windows(monitor: &mut ChannelMonitor, at: u64, counts: &[i16]) -> Vec<(u64, Indicators)> {
    let mut seen = Vec::new();
    monitor.push_counts(at, counts, 0.001, &mut |event| {
        if let MonitorEvent::Window(report) = event {
            seen.push((report.end_sample, report.indicators));
        }
    });
    seen
}

#[test]
fn the_history_holds_the_newest_counts_in_order_whatever_the_blocks() {
    let all = counts(3 * HISTORY + 77, 1);
    // Blocks of one sample, of a few, of more than the history, and every size between.
    for sizes in [
        vec![1],
        vec![7, 4_096, 13],
        vec![HISTORY + 3],
        vec![2 * HISTORY + 1, 1],
    ] {
        let mut monitor = monitor();
        let mut at = 0;
        for (i, &size) in sizes.iter().cycle().enumerate() {
            if at >= all.len() {
                break;
            }
            let block = &all[at..(at + size).min(all.len())];
            monitor.push_counts(at as u64, block, 0.001, &mut |_| {});
            at += block.len();
            let kept = &all[at.saturating_sub(HISTORY)..at];
            assert_eq!(
                monitor.history_counts(),
                kept,
                "blocks {sizes:?}, after block {i}"
            );
        }
    }
}

#[test]
fn a_new_scale_drops_the_history_kept_in_the_old_one() {
    let mut monitor = monitor();
    let first = counts(2_500, 2);
    monitor.push_counts(0, &first, 0.001, &mut |_| {});
    assert_eq!(monitor.history_counts(), first);
    let second = counts(1_000, 3);
    monitor.push_counts(2_500, &second, 0.002, &mut |_| {});
    assert_eq!(monitor.history_counts(), second);
    assert_eq!(monitor.history_scale, 0.002);
}

/// A replay that starts again at sample 0 with other samples: the windows after it are those
/// of a monitor that never saw the first samples (no window mixes the two, and no window's
/// indicators reuse sums of the samples it replaced).
#[test]
fn going_back_in_sample_time_starts_the_windows_again() {
    // One window before: its segments' sums are what a forgotten restart would reuse.
    let (before, after) = (counts(2_500, 4), counts(8_000, 5));
    let mut replayed = monitor();
    assert!(!windows(&mut replayed, 0, &before).is_empty());
    let again = windows(&mut replayed, 0, &after);
    let fresh = windows(&mut monitor(), 0, &after);
    assert!(fresh.len() >= 3, "{} windows", fresh.len());
    assert_eq!(again.len(), fresh.len());
    for ((end, got), (fresh_end, want)) in again.iter().zip(&fresh) {
        assert_eq!(end, fresh_end);
        assert_eq!(got, want, "window ending at {end}");
    }
}

/// The indicators of each window are those of its samples summed whole, however the blocks
/// cut it (the monitor sums each sample once, in segments shared by overlapping windows).
#[test]
fn each_windows_indicators_are_those_of_its_samples() {
    let all = counts(12_000, 6);
    let mut monitor = monitor();
    let mut seen = Vec::new();
    let mut at = 0;
    for block in all.chunks(333) {
        seen.extend(windows(&mut monitor, at, block));
        at += block.len() as u64;
    }
    let window = window_samples(AnalysisSettings::default().window_s, FS);
    assert!(seen.len() >= 5, "{} windows", seen.len());
    for (end, got) in seen {
        let samples: Vec<f32> = all[end as usize - window..end as usize]
            .iter()
            .map(|&c| (f64::from(c) * 0.001) as f32)
            .collect();
        let want = Indicators::of(&samples);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        assert!(close(got.rms, want.rms), "at {end}: {got:?} {want:?}");
        assert!(close(got.kurtosis, want.kurtosis), "at {end}");
        assert_eq!(got.peak, want.peak, "at {end}");
    }
}

/// A window's report waits for its band stages ([`RollingEnvelope::spread_bands`]); a gap
/// comes before them: the report still comes, with that window's end, before the gap's event
/// and before any window after the gap.
#[test]
fn a_gap_finishes_the_report_of_the_window_before_it() {
    let window = window_samples(AnalysisSettings::default().window_s, FS);
    let mut monitor = monitor();
    // One sample past the window's end: its report is due a fifth of a hop later.
    let before = counts(window + 1, 7);
    assert!(windows(&mut monitor, 0, &before).is_empty());
    assert!(monitor.rolling.bands_pending());

    let mut events = Vec::new();
    let after = counts(3 * window, 8);
    monitor.push_counts(10 * window as u64, &after, 0.001, &mut |event| {
        events.push(match event {
            MonitorEvent::Window(report) => format!("window {}", report.end_sample),
            MonitorEvent::Gap { at_sample, .. } => format!("gap {at_sample}"),
            _ => return,
        })
    });
    assert_eq!(
        events.get(..2),
        Some(&[format!("window {window}"), format!("gap {}", window + 1)][..]),
        "{events:?}"
    );
    assert!(
        events[2..].iter().all(|e| e.starts_with("window ")) && events.len() > 2,
        "windows after the gap: {events:?}"
    );
}

/// A speed change while a window's band stages wait: the window's report comes first, scored
/// with the fault frequencies the window was taken at, then the speed's event.
#[test]
fn a_speed_change_finishes_the_report_of_the_window_before_it() {
    let window = window_samples(AnalysisSettings::default().window_s, FS);
    let mut monitor = monitor();
    let shaft = monitor.freqs.shaft;
    monitor.settings.speed = SpeedMode::Given {
        known_at_start: true,
        max_shaft_hz: 2.0 * shaft,
    };
    assert!(windows(&mut monitor, 0, &counts(window + 1, 9)).is_empty());
    assert!(monitor.rolling.bands_pending());

    let mut events = Vec::new();
    monitor.set_speed_at(window as u64 + 1, Some(1.5 * shaft), &mut |event| {
        events.push(match event {
            MonitorEvent::Window(report) => format!("window {}", report.end_sample),
            MonitorEvent::Speed { at_sample, .. } => format!("speed {at_sample}"),
            _ => return,
        })
    });
    assert_eq!(
        events,
        [format!("window {window}"), format!("speed {}", window + 1)],
    );
    assert!(!monitor.rolling.bands_pending());
}
