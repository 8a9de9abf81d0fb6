//! Holding the CPUs' wake-up latency down while `bearingd run` runs
//! (`outputs.cpu_wakeup_latency_us`).
//!
//! Why: an alert crosses three threads (the source's, the analysis', the subscriber's), and each
//! one that was idle has to be woken. An idle CPU sleeps in a halt or deeper C-state, and
//! leaving it costs tens of µs on a VM and up to hundreds on hardware with deep C-states: about
//! 0.1 ms of an alert's p50 and p99 on our 2-vCPU VM (docs/PERFORMANCE.md). Linux's PM QoS
//! lets a process cap that latency for as long as it keeps `/dev/cpu_dma_latency` open with the
//! cap written in it; closing the file, also by a crash, lifts the cap. The kernel's cpuidle
//! governor honours it; the price is idle power: with 0, an idle CPU polls instead of halting.

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

/// Why the cap could not be held; the daemon runs on without it.
#[derive(Debug, thiserror::Error)]
#[error(
    "outputs.cpu_wakeup_latency_us = {latency_us}: cannot hold it through {}: {source}; \
     alerts keep the kernel's idle policy (slower wake-ups). {}",
    device.display(),
    fix_for(source.kind())
)]
pub struct CpuLatencyError {
    pub latency_us: u32,
    pub device: PathBuf,
    #[source]
    pub source: std::io::Error,
}

fn fix_for(kind: std::io::ErrorKind) -> &'static str {
    match kind {
        std::io::ErrorKind::NotFound => {
            "Under systemd with PrivateDevices=, the unit must bind it in (the shipped unit \
             has BindPaths=-/dev/cpu_dma_latency); if this kernel has no such device, leave \
             the key out"
        }
        std::io::ErrorKind::PermissionDenied => {
            "Let bearingd's user write it (`make install` puts the rule in \
             /usr/lib/tmpfiles.d/bearingd.conf; apply it with `systemd-tmpfiles --create`), \
             or leave the key out"
        }
        _ => "Leave the key out if this machine cannot hold the cap",
    }
}

impl CpuLatencyCap {
    /// Caps the CPUs' wake-up latency at `latency_us` µs through `device` (normally
    /// [`CPU_LATENCY_DEVICE`]) until the returned cap is dropped.
    pub fn hold(device: &Path, latency_us: u32) -> Result<CpuLatencyCap, CpuLatencyError> {
        let failed = |source| CpuLatencyError {
            latency_us,
            device: device.to_path_buf(),
            source,
        };
        // The kernel takes the cap as a native-endian s32 (or as a hex string).
        let value = i32::try_from(latency_us).map_err(|_| {
            failed(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "more than the kernel's s32",
            ))
        })?;
        let mut file = OpenOptions::new()
            .write(true)
            .open(device)
            .map_err(failed)?;
        file.write_all(&value.to_ne_bytes()).map_err(failed)?;
        Ok(CpuLatencyCap { _device: file })
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
}
