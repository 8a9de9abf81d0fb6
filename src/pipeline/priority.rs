//! The twin's re-fit thread gives the CPU to the analysis thread. On a two-core edge box a
//! re-fit (the twin's three hypotheses, the HW model, the learned opinion: tens of ms) sharing a
//! core with the analysis thread delays the window that raises an alert; at a lower priority
//! the scheduler lets the analysis thread preempt it. The re-fit still gets every idle cycle
//! and nothing waits for it (a newer request replaces an older one), so nothing is lost.
//!
//! Only the re-fit thread: the band worker and the log writer stay at normal priority, because
//! the analysis *does* wait for them (a band selection's result at its due sample, a full log
//! queue); starved under load they made the tail worse (docs/PERFORMANCE.md, issue 12).

/// (choice) Nice +10: about a tenth of the CPU share of a normal thread when both want it.
const BACKGROUND_NICE: libc::c_int = 10;

/// Lowers the calling thread's CPU priority by [`BACKGROUND_NICE`] (on Linux the nice value is
/// per thread). Raising one's own nice value needs no privilege; should the call fail anyway,
/// the thread runs at its normal priority, which is only slower for alerts, never wrong.
pub fn lower_this_thread() {
    #[allow(unsafe_code)]
    // SAFETY: nice(2) changes only the calling thread's scheduling priority; it reads and
    // writes no memory of this program.
    unsafe {
        libc::nice(BACKGROUND_NICE);
    }
}
