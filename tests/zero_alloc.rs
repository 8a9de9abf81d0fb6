//! The rolling path allocates nothing per hop: a counting global allocator watches every
//! allocation while a second of samples streams through the rolling envelope spectrum and the
//! fault scorer. (Its own test binary, because a global allocator is per binary.)

use bearingd::analysis::envelope::RollingEnvelope;
use bearingd::analysis::fault_bands::FaultScorer;
use bearingd::analysis::Band;
use bearingd::bearing::BearingGeometry;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
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
    let before = ALLOCATIONS.load(Ordering::SeqCst);
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
    let allocations = ALLOCATIONS.load(Ordering::SeqCst) - before;
    assert!(updates >= 20, "only {updates} updates");
    assert!(best > 0.0);
    assert_eq!(
        allocations, 0,
        "{allocations} allocations in {updates} hops"
    );
}
