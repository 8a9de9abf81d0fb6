//! Holding the CPUs' wake-up latency down for `bearingd run`: always, while it runs
//! (`outputs.cpu_wakeup_latency_us`), or only while a block is analysed
//! (`outputs.cpu_awake_during_analysis`, on by default).
//!
//! Why: an alert crosses three threads (the source's, the analysis', the subscriber's), and each
//! one that was idle has to be woken. An idle CPU sleeps in a halt or deeper C-state, and
//! leaving it costs tens of µs on a VM and up to hundreds on hardware with deep C-states: about
//! 0.1 ms of an alert's p50 and p99 on our 2-vCPU VM (docs/PERFORMANCE.md). Linux's PM QoS
//! lets a process cap that latency for as long as it keeps `/dev/cpu_dma_latency` open with the
//! cap written in it; closing the file, also by a crash, lifts the cap. The kernel's cpuidle
//! governor honours it; the price is idle power: with 0, an idle CPU polls instead of halting.
//!
//! (why) The cap during analysis only: writing 0 when a block is handed over wakes every idle
//! CPU at once (the kernel re-selects their idle state), in parallel with the block's FFT, so
//! the CPU the alert's subscriber sleeps on is awake and polling by the time the alert is
//! published; writing the default back when the block is analysed lets them halt again. The
//! CPUs poll for the analysis alone (1.5 % of the CPUs' time with 16 channels,
//! docs/PERFORMANCE.md), not for the whole run. The source that hands the block over writes the
//! 0, not the analysis thread: waking the CPUs costs the writer tens of µs, which the alert
//! would otherwise wait for ([`CpusAwake`]).

use crate::sources::HandOverWatch;
use std::fs::{File, OpenOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, MutexGuard, PoisonError};

/// The kernel's PM QoS device for the CPUs' wake-up latency.
pub const CPU_LATENCY_DEVICE: &str = "/dev/cpu_dma_latency";

/// A held cap on the CPUs' wake-up latency; dropping it lifts the cap.
#[derive(Debug)]
pub struct CpuLatencyCap {
    /// Open for as long as the cap holds.
    _device: File,
}

/// The value the kernel takes for "no constraint" (`PM_QOS_DEFAULT_VALUE`, 2,000 s): a request
/// at this value no longer holds the CPUs awake.
const UNCONSTRAINED_US: i32 = 2_000_000_000;

/// What the config asked of the PM QoS device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CpuLatencyRequest {
    /// `outputs.cpu_wakeup_latency_us`: this cap for as long as bearingd runs.
    Cap { latency_us: u32 },
    /// `outputs.cpu_awake_during_analysis`: 0 while a block is analysed.
    AwakeDuringAnalysis,
}

impl std::fmt::Display for CpuLatencyRequest {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CpuLatencyRequest::Cap { latency_us } => {
                write!(f, "outputs.cpu_wakeup_latency_us = {latency_us}")
            }
            CpuLatencyRequest::AwakeDuringAnalysis => {
                write!(f, "outputs.cpu_awake_during_analysis = true")
            }
        }
    }
}

impl CpuLatencyRequest {
    /// How to do without it: the key's neutral setting.
    fn without(self) -> &'static str {
        match self {
            CpuLatencyRequest::Cap { .. } => "leave the key out",
            CpuLatencyRequest::AwakeDuringAnalysis => "set it to false",
        }
    }
}

/// Why the request could not be held; the daemon runs on without it.
#[derive(Debug, thiserror::Error)]
#[error(
    "{request}: cannot hold it through {}: {source}; alerts keep the kernel's idle policy \
     (slower wake-ups). {}",
    device.display(),
    fix_for(source.kind(), *request)
)]
pub struct CpuLatencyError {
    pub request: CpuLatencyRequest,
    pub device: PathBuf,
    #[source]
    pub source: std::io::Error,
}

fn fix_for(kind: std::io::ErrorKind, request: CpuLatencyRequest) -> String {
    let without = request.without();
    match kind {
        std::io::ErrorKind::NotFound => format!(
            "Under systemd with PrivateDevices=, the unit must bind it in (the shipped unit \
             has BindPaths=-/dev/cpu_dma_latency); if this kernel has no such device, {without}"
        ),
        std::io::ErrorKind::PermissionDenied => format!(
            "Let bearingd's user write it (`make install` puts the rule in \
             /usr/lib/tmpfiles.d/bearingd.conf; apply it with `systemd-tmpfiles --create`), \
             or {without}"
        ),
        _ => format!("If this machine cannot hold it, {without}"),
    }
}

/// The error of `request` on `device`, for `map_err`.
fn refused(
    request: CpuLatencyRequest,
    device: &Path,
) -> impl Fn(std::io::Error) -> CpuLatencyError + '_ {
    move |source| CpuLatencyError {
        request,
        device: device.to_path_buf(),
        source,
    }
}

/// Opens the PM QoS device: a new request of this process, unconstrained until written.
fn open_request(device: &Path, request: CpuLatencyRequest) -> Result<File, CpuLatencyError> {
    OpenOptions::new()
        .write(true)
        .open(device)
        .map_err(refused(request, device))
}

/// Sets this process's request on an open device to `latency_us` (the kernel takes a
/// native-endian s32, or a hex string).
fn write_request(file: &mut File, latency_us: i32) -> std::io::Result<()> {
    file.write_all(&latency_us.to_ne_bytes())
}

impl CpuLatencyCap {
    /// Caps the CPUs' wake-up latency at `latency_us` µs through `device` (normally
    /// [`CPU_LATENCY_DEVICE`]) until the returned cap is dropped.
    pub fn hold(device: &Path, latency_us: u32) -> Result<CpuLatencyCap, CpuLatencyError> {
        let request = CpuLatencyRequest::Cap { latency_us };
        let failed = refused(request, device);
        let value = i32::try_from(latency_us).map_err(|_| {
            failed(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "more than the kernel's s32",
            ))
        })?;
        let mut file = open_request(device, request)?;
        write_request(&mut file, value).map_err(failed)?;
        Ok(CpuLatencyCap { _device: file })
    }
}

/// The request of `outputs.cpu_awake_during_analysis`: idle CPUs polling (0 µs) from a block's
/// hand-over to the analysis until every block handed over is analysed, unconstrained between.
/// Dropping the last handle (or a crash) withdraws it.
///
/// (why) Shared by the two ends of the analysis queue. Tightening the request wakes every idle
/// CPU, and the writer waits for that: 12–52 µs on one VM, 0.1 ms at the median on another
/// (docs/PERFORMANCE.md). So the source that handed a block over tightens it, while the
/// analysis thread already works on the block; the analysis thread only relaxes it (under
/// 1 µs). Two counts, of the blocks handed over and of those analysed, keep a block analysed
/// before its source got to tighten from holding the CPUs awake with nothing to analyse.
#[derive(Debug, Clone)]
pub struct CpusAwake {
    request: Arc<Mutex<AwakeRequest>>,
}

#[derive(Debug)]
struct AwakeRequest {
    file: File,
    device: PathBuf,
    handed_over: u64,
    analysed: u64,
    /// 0 µs written and not relaxed since.
    tight: bool,
    /// A write failed: no request is made after it.
    refused: bool,
    /// That failure, until the analysis thread says it.
    unsaid: Option<CpuLatencyError>,
}

impl CpusAwake {
    /// Opens a request on `device` (normally [`CPU_LATENCY_DEVICE`]), unconstrained until a
    /// block is handed over.
    pub fn open(device: &Path) -> Result<CpusAwake, CpuLatencyError> {
        let request = AwakeRequest {
            file: open_request(device, CpuLatencyRequest::AwakeDuringAnalysis)?,
            device: device.to_path_buf(),
            handed_over: 0,
            analysed: 0,
            tight: false,
            refused: false,
            unsaid: None,
        };
        Ok(CpusAwake {
            request: Arc::new(Mutex::new(request)),
        })
    }

    /// A block is analysed: the CPUs may halt again once every block handed over is. Returns
    /// the first refused write, of either end, once: the caller says it.
    pub fn analysed(&self) -> Option<CpuLatencyError> {
        let mut request = self.lock();
        request.unless_refused(|request| {
            request.analysed += 1;
            if request.tight && request.analysed >= request.handed_over {
                request.write(UNCONSTRAINED_US)?;
                request.tight = false;
            }
            Ok(())
        });
        request.unsaid.take()
    }

    /// The request. A thread that panicked holding it left it usable (each step writes
    /// before it records), so the lock is taken over.
    fn lock(&self) -> MutexGuard<'_, AwakeRequest> {
        self.request.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

impl HandOverWatch for CpusAwake {
    /// A block is in the analysis queue: the idle CPUs are woken unless it is analysed already.
    fn handed_over(&self) {
        self.lock().unless_refused(|request| {
            request.handed_over += 1;
            if !request.tight && request.analysed < request.handed_over {
                request.write(0)?;
                request.tight = true;
            }
            Ok(())
        });
    }
}

impl AwakeRequest {
    /// Runs `step` unless a write was refused before; a refusal ends the requests and waits
    /// to be said.
    fn unless_refused(&mut self, step: impl FnOnce(&mut Self) -> Result<(), CpuLatencyError>) {
        if self.refused {
            return;
        }
        if let Err(error) = step(self) {
            self.refused = true;
            self.unsaid = Some(error);
        }
    }

    fn write(&mut self, latency_us: i32) -> Result<(), CpuLatencyError> {
        write_request(&mut self.file, latency_us).map_err(refused(
            CpuLatencyRequest::AwakeDuringAnalysis,
            &self.device,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_device_names_the_key_the_device_and_the_fix() {
        let device = Path::new("/nonexistent/cpu_dma_latency");
        let error = CpuLatencyCap::hold(device, 0).expect_err("no such device");
        let text = error.to_string();
        assert!(text.contains("outputs.cpu_wakeup_latency_us = 0"), "{text}");
        assert!(text.contains("/nonexistent/cpu_dma_latency"), "{text}");
        assert!(text.contains("leave the key out"), "{text}");
    }

    #[test]
    fn the_cap_is_written_as_a_native_s32() {
        let dir = tempfile::tempdir().expect("temp dir");
        let device = dir.path().join("cpu_dma_latency");
        std::fs::write(&device, b"").expect("stand-in device");
        let cap = CpuLatencyCap::hold(&device, 20).expect("held");
        assert_eq!(std::fs::read(&device).expect("read"), 20i32.to_ne_bytes());
        drop(cap);
    }

    /// A stand-in device (a regular file keeps every write, one after the other) and the
    /// request opened on it.
    fn awake_on_a_file() -> (tempfile::TempDir, PathBuf, CpusAwake) {
        let dir = tempfile::tempdir().expect("temp dir");
        let device = dir.path().join("cpu_dma_latency");
        std::fs::write(&device, b"").expect("stand-in device");
        let awake = CpusAwake::open(&device).expect("opened");
        (dir, device, awake)
    }

    /// What the device was told, in order.
    fn told(device: &Path) -> Vec<i32> {
        let written = std::fs::read(device).expect("read");
        written
            .chunks_exact(4)
            .map(|v| i32::from_ne_bytes([v[0], v[1], v[2], v[3]]))
            .collect()
    }

    #[test]
    fn a_handed_over_block_wakes_the_cpus_until_it_is_analysed() {
        let (_dir, device, awake) = awake_on_a_file();
        assert!(told(&device).is_empty(), "opened unconstrained");
        awake.handed_over();
        assert_eq!(told(&device), [0]);
        assert!(awake.analysed().is_none());
        assert_eq!(told(&device), [0, UNCONSTRAINED_US]);
    }

    #[test]
    fn the_cpus_stay_awake_until_every_block_handed_over_is_analysed() {
        let (_dir, device, awake) = awake_on_a_file();
        awake.handed_over();
        awake.handed_over();
        awake.analysed();
        assert_eq!(told(&device), [0], "one block still waits");
        awake.analysed();
        assert_eq!(told(&device), [0, UNCONSTRAINED_US]);
    }

    #[test]
    fn a_block_analysed_before_its_source_tightened_wakes_nothing() {
        let (_dir, device, awake) = awake_on_a_file();
        // The analysis thread took the block and was done before the source, back from the
        // queue, got to say it handed the block over.
        awake.analysed();
        awake.handed_over();
        assert!(told(&device).is_empty(), "{:?}", told(&device));
        // The next block is woken for as before.
        awake.handed_over();
        assert_eq!(told(&device), [0]);
        awake.analysed();
        assert_eq!(told(&device), [0, UNCONSTRAINED_US]);
    }

    #[test]
    fn a_refused_write_of_the_source_is_said_once_by_the_analysis() {
        // Every write to /dev/full fails (no space).
        let awake = CpusAwake::open(Path::new("/dev/full")).expect("opened");
        awake.handed_over();
        let said = awake
            .analysed()
            .expect("the refusal, for the analysis thread to say");
        assert!(said.to_string().contains("/dev/full"), "{said}");
        awake.handed_over();
        assert!(awake.analysed().is_none(), "said once, no request after it");
    }

    #[test]
    fn a_refused_awake_request_says_how_to_turn_it_off() {
        let device = Path::new("/nonexistent/cpu_dma_latency");
        let text = CpusAwake::open(device)
            .expect_err("no such device")
            .to_string();
        assert!(
            text.contains("outputs.cpu_awake_during_analysis = true"),
            "{text}"
        );
        assert!(text.contains("/nonexistent/cpu_dma_latency"), "{text}");
        assert!(text.contains("set it to false"), "{text}");
    }
}
