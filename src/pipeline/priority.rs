//! Every thread of `bearingd run` but the analysis thread runs at a lower CPU priority, so
//! that the analysis thread (which decides and publishes alerts) is never preempted by the
//! daemon's own background work. On a two-core edge box a trace of the daemon showed the
//! slowest 1 % of alert-deciding blocks off the CPU for 1.3 ms, preempted by a sibling thread
//! (the simulated sensors' generation on the async runtime, the log writer, a band selection,
//! a re-fit); with these threads lowered the analysis ran uninterrupted (docs/PERFORMANCE.md,
//! issue 12).
//!
//! Two levels. The async runtime's workers (the sources) run at nice +10: they must keep up
//! with the transports even on a box busy with other programs. The batch threads (the log
//! writer, the band worker, the twin's re-fit thread, the alert keeper) run in SCHED_IDLE: a
//! waking analysis thread takes their CPU at once, which nice +10 did not guarantee (an
//! alert's p99 over 10,000 windows: 0.87–1.09 ms with nice, 0.80–0.82 ms with SCHED_IDLE).
//! They get every cycle the box leaves idle (the analysis uses about a tenth of one core for 16
//! channels at 25.6 kHz). Should other programs keep every CPU busy, they fall behind: a re-fit
//! is then dropped (counted and said), and the analysis waits for a band result at its due
//! sample or for room in the log queue (1,024 messages); only if that lasts do the sources'
//! buffers overflow, with their gaps counted, as for any overload. The priorities are relative
//! to this process's other threads as far as the scheduler goes; other programs on the box are
//! unaffected.

/// (choice) Nice +10: about a tenth of the CPU share of a normal thread when both want it.
const BACKGROUND_NICE: libc::c_int = 10;

/// Lowers the calling thread's CPU priority by [`BACKGROUND_NICE`] (on Linux the nice value is
/// per thread): for the sources' runtime, which must keep up with the transports. Raising one's
/// own nice value needs no privilege; should the call fail anyway, the thread runs at its
/// normal priority, which is only slower for alerts, never wrong.
pub fn lower_this_thread() {
    #[allow(unsafe_code)]
    // SAFETY: nice(2) changes only the calling thread's scheduling priority; it reads and
    // writes no memory of this program.
    unsafe {
        libc::nice(BACKGROUND_NICE);
    }
}

/// Puts the calling thread in SCHED_IDLE: for batch work (re-fits, band selections, the log
/// writer, the alert keeper) that may wait for a free CPU. A normal thread that wakes up
/// preempts a SCHED_IDLE one at once, where under nice +10 the scheduler may let the lower
/// thread finish its time slice first (up to milliseconds). Needs no privilege; if refused
/// (a seccomp filter), the thread is lowered by nice instead.
pub fn idle_this_thread() {
    #[allow(unsafe_code)]
    // SAFETY: sched_param is a plain C struct of integers (glibc has one field, musl more),
    // valid all zero, which is the priority SCHED_IDLE requires; sched_setscheduler(2)
    // changes only the calling thread's scheduling policy and only reads `param`.
    let refused = unsafe {
        let param: libc::sched_param = std::mem::zeroed();
        libc::sched_setscheduler(0, libc::SCHED_IDLE, &param)
    } != 0;
    if refused {
        lower_this_thread();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn policy_of_this_thread() -> libc::c_int {
        #[allow(unsafe_code)]
        // SAFETY: sched_getscheduler(2) only reads the calling thread's policy.
        unsafe {
            libc::sched_getscheduler(0)
        }
    }

    #[test]
    fn a_batch_thread_is_idle_and_a_source_thread_is_niced() {
        let (batch, source) = std::thread::scope(|scope| {
            let batch = scope.spawn(|| {
                idle_this_thread();
                policy_of_this_thread()
            });
            let source = scope.spawn(|| {
                lower_this_thread();
                #[allow(unsafe_code)]
                // SAFETY: getpriority(2) only reads the calling thread's nice value (tid 0).
                let nice = unsafe { libc::getpriority(libc::PRIO_PROCESS, 0) };
                (policy_of_this_thread(), nice)
            });
            (batch.join(), source.join())
        });
        assert_eq!(batch.ok(), Some(libc::SCHED_IDLE));
        let (policy, nice) = source.unwrap_or((-1, 0));
        assert_eq!(policy, libc::SCHED_OTHER);
        assert!(nice >= BACKGROUND_NICE, "nice {nice}");
    }
}
