//! Background threads yield to the analysis: the band-selection worker, the twin's re-fit and
//! the sink thread run at a lower scheduling priority (nice +10) than the analysis and alert
//! threads, so that a 30–100 ms selection or fit never delays a block (and an alert) when the
//! cores are busy. Only lowering is asked for, which needs no privilege.

/// How much lower than the process a background thread runs (nice increment).
const BACKGROUND_NICE: libc::c_int = 10;

/// Lowers the calling thread's priority (Linux: the nice value is per thread). A refusal is
/// harmless (the thread keeps its priority), so it is not reported.
#[allow(
    unsafe_code,
    reason = "setpriority has no safe std API; on Linux who = 0 names the calling thread"
)]
pub fn lower_this_threads_priority() {
    // SAFETY: a plain system call on integers, no memory is passed.
    unsafe {
        let current = libc::getpriority(libc::PRIO_PROCESS, 0);
        let _ = libc::setpriority(libc::PRIO_PROCESS, 0, (current + BACKGROUND_NICE).min(19));
    }
}
