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
//! (why) The cap during analysis only: writing 0 when a block is taken wakes every idle CPU at
//! once (the kernel re-selects their idle state), in parallel with the block's FFT, so the CPU
//! the alert's subscriber sleeps on is awake and polling by the time the alert is published;
//! writing the default back when the block is done lets them halt again. The CPUs poll for the
//! analysis alone (1.5 % of the CPUs' time with 16 channels, docs/PERFORMANCE.md), not for
//! the whole run.

use std::fs::{File, OpenOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};

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

/// The request of `outputs.cpu_awake_during_analysis`: idle CPUs polling (0 µs) while a block
/// is analysed, unconstrained between blocks. Dropping it (or a crash) withdraws it.
#[derive(Debug)]
pub struct CpusAwake {
    file: File,
    device: PathBuf,
}

impl CpusAwake {
    /// Opens a request on `device` (normally [`CPU_LATENCY_DEVICE`]), unconstrained until
    /// [`Self::set`].
    pub fn open(device: &Path) -> Result<CpusAwake, CpuLatencyError> {
        Ok(CpusAwake {
            file: open_request(device, CpuLatencyRequest::AwakeDuringAnalysis)?,
            device: device.to_path_buf(),
        })
    }

    /// `true` as a block's analysis starts (idle CPUs are woken and poll), `false` when it is
    /// done (they may halt again).
    pub fn set(&mut self, awake: bool) -> Result<(), CpuLatencyError> {
        let latency_us = if awake { 0 } else { UNCONSTRAINED_US };
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

    #[test]
    fn awake_during_analysis_writes_0_then_the_unconstrained_value() {
        let dir = tempfile::tempdir().expect("temp dir");
        let device = dir.path().join("cpu_dma_latency");
        std::fs::write(&device, b"").expect("stand-in device");
        let mut awake = CpusAwake::open(&device).expect("opened");
        assert!(
            std::fs::read(&device).expect("read").is_empty(),
            "opened unconstrained"
        );
        awake.set(true).expect("awake");
        awake.set(false).expect("released");
        // A regular file keeps both writes one after the other; the device takes each at once.
        let written = std::fs::read(&device).expect("read");
        assert_eq!(written[..4], 0i32.to_ne_bytes());
        assert_eq!(written[4..], 2_000_000_000i32.to_ne_bytes());
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
