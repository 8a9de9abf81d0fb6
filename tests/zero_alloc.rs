//! The rolling path allocates nothing per hop: a counting global allocator watches every
//! allocation while a second of samples streams through the rolling envelope spectrum and the
//! fault scorer, and while a channel monitor takes hops and speed changes between two band
//! selections. (Its own test binary, because a global allocator is per binary; allocations are counted per
//! thread, the analysis runs on the test's.)
#![allow(unsafe_code, clippy::unwrap_used, clippy::expect_used)]

use bearingd::analysis::envelope::RollingEnvelope;
use bearingd::analysis::fault_bands::FaultScorer;
use bearingd::analysis::Band;
use bearingd::bearing::BearingGeometry;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct CountingAllocator;

thread_local! {
    /// Allocations of this thread: the test harness's own threads (printing results while
    /// another test measures) do not count. Const-initialised, so reading it never allocates.
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn rolling_envelope_and_scoring_never_allocate_per_hop() {
    let fs = 25_600.0;
    let freqs = BearingGeometry::from_catalog("skf-6205-2rs")
        .unwrap()
        .fault_frequencies(1772.0 / 60.0);
    let bins = 1_200;
    let bands = [
        Band::new(2_000.0, 6_000.0),
        Band::new(1_000.0, 3_000.0),
        Band::new(3_000.0, 4_000.0),
    ];
    let mut rolling = RollingEnvelope::new(fs, 16_384, 4_096, 8, &bands, bins);
    let mut scorer = FaultScorer::new(0.02, 3, bins);
    let signal: Vec<f32> = (0..(fs as usize * 4))
        .map(|n| ((n as f32) * 0.37).sin() * ((n % 241) as f32 / 241.0))
        .collect();
    // Warm-up: the first window fills the ring.
    rolling.push(&signal[..16_384], |_| {});

    let mut updates = 0;
    let mut best = 0.0;
    let before = allocations();
    for block in signal[16_384..].chunks(256) {
        rolling.push(block, |u| {
            updates += 1;
            for band in u.bands {
                for score in scorer.score_all(band.averaged_amplitude(), u.bin_hz, &freqs) {
                    best = f64::max(best, score.score);
                }
            }
        });
    }
    let allocations = allocations() - before;
    assert!(updates >= 20, "only {updates} updates");
    assert!(best > 0.0);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {updates} hops"
    );
}

#[test]
fn a_monitor_takes_hops_and_speed_changes_without_allocating() {
    use bearingd::analysis::flags::FlagSettings;
    use bearingd::analysis::monitor::{ChannelMonitor, MonitorSettings};
    use bearingd::analysis::speed::SpeedMode;
    use bearingd::analysis::AnalysisSettings;
    use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};

    let params = SimulationParams::example(SimulatedFault::OuterRace);
    let fs = params.fs_hz;
    let shaft = params.rpm / 60.0;
    let settings = MonitorSettings {
        fs_hz: fs,
        analysis: AnalysisSettings::default(),
        // One selection after 4 s, the next far beyond the test.
        band_period_samples: (1e6 * fs) as u64,
        band_phase_samples: 0,
        window_stagger: (0, 1),
        band_history_samples: (4.0 * fs) as usize,
        flags: FlagSettings {
            watch_score: 10.0,
            alarm_score: 15.0,
            clear_ratio: 0.8,
            on_delay_samples: fs as u64,
            off_delay_samples: fs as u64,
        },
        baseline_windows: 5,
        sigma: 3.0,
        clip_count: 32_767,
        flat_line_samples: fs as u64,
        speed: SpeedMode::Given {
            known_at_start: true,
            max_shaft_hz: shaft * 1.5,
        },
        // The velocity severity (ISO zones) and its flag run every half window too.
        // So do the machine-fault detector and its flags, every `averages` windows.
        detectors: bearingd::analysis::detectors::DetectorSettings {
            severity: Some(bearingd::analysis::iso::SeveritySettings::default()),
            machine_faults: Some(Default::default()),
        },
        trend: bearingd::analysis::monitor::TrendSettings::default(),
    };
    let mut monitor = ChannelMonitor::new(settings, params.frequencies(), None);
    let counts: Vec<i16> = Simulator::record(params, 20.0)
        .iter()
        .map(|&g| {
            (f64::from(g) / 0.000_488)
                .round()
                .clamp(-32_768.0, 32_767.0) as i16
        })
        .collect();
    let warm = (6.0 * fs) as usize;
    monitor.push_counts(0, &counts[..warm], 0.000_488, &mut |_| {});
    assert!(
        monitor.bands().is_some(),
        "bands selected during the warm-up"
    );
    assert!(
        allocations() > 0,
        "the counter sees this thread's allocations"
    );

    let mut windows = 0;
    // A window's report comes once its bands are done: in a later block, or at a speed change
    // (which finishes the window's band work first).
    let mut count = |event: bearingd::analysis::monitor::MonitorEvent| {
        if matches!(event, bearingd::analysis::monitor::MonitorEvent::Window(_)) {
            windows += 1;
        }
    };
    let before = allocations();
    for (i, block) in counts[warm..].chunks(1_000).enumerate() {
        let at = (warm + i * 1_000) as u64;
        if i % 12 == 0 {
            let speed = shaft * (1.0 + 0.001 * (i % 5) as f64);
            monitor.set_speed_at(at, Some(speed), &mut count);
        }
        monitor.push_counts(at, block, 0.000_488, &mut count);
    }
    let allocations = allocations() - before;
    assert!(windows >= 15, "only {windows} hops");
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {windows} hops"
    );
}
