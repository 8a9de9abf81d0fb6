//! Every thread of `bearingd run` but the analysis thread runs at a lower CPU priority, so
//! that the analysis thread (which decides and publishes alerts) is never preempted by the
//! daemon's own background work. On a two-core edge box a trace of the daemon showed the
//! slowest 1 % of alert-deciding blocks off the CPU for 1.3 ms, preempted by a sibling thread
//! (the simulated sensors' generation on the async runtime, the log writer, a band selection,
//! a re-fit); with these threads lowered the analysis ran uninterrupted (docs/PERFORMANCE.md,
//! issue 12).
//!
//! Lowered: the async runtime's workers (sources, status), the log writer, the band worker,
//! the twin's re-fit thread and the alert keeper. Each still gets every cycle the analysis
//! leaves idle (it uses about a tenth of one core for 16 channels at 25.6 kHz); the analysis
//! waits for the band worker and the log writer only when they fall seconds behind (a band
//! result at its due sample, a full log queue of 1,024 messages), which lowering did not cause
//! in the measurements. The priority is relative to this process's other threads only as far
//! as the scheduler goes; other programs on the box are unaffected.

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
