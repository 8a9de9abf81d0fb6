//! Faults injected into `bearingd run` as a process, each checked for what it must not cost:
//! two daemons on one data directory, a daemon killed with `kill -9` (its lock left behind),
//! a random file named like a log, a log damaged in the middle. Every log file that is left is
//! read back strictly by Python's `mcap` reader. (Issue 11.)
//!
//! One binary, one module per kind of fault: `process` (daemons killed, a second daemon, a
//! junk replay), `log_files` (quarantine, recovery, metadata), `disk` (a full disk). The
//! helpers below start the daemon and read what it left.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod disk;
mod log_files;
mod process;

use bearingd::mcap_log::read_messages;
use bearingd::messages::PipelineMessage;
use bearingd_testdata::mcap_files;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

/// A one-second `--fast` run of the embedded default on `data`.
fn short_run(data: &Path) -> Output {
    bearingd(&[
        "run",
        "--fast",
        "--duration",
        "1",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ])
}

/// The embedded default in real time on `data`, until stopped.
fn start_daemon(data: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["run", "--quiet", "--data-dir", data.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits until the daemon's log file holds at least `bytes` (its first flushes are on disk).
fn wait_for_log(data: &Path, bytes: u64) -> PathBuf {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(file) = mcap_files(&data.join("mcap")).pop() {
            if std::fs::metadata(&file).map(|m| m.len()).unwrap_or(0) >= bytes {
                return file;
            }
        }
        assert!(Instant::now() < deadline, "no log in {}", data.display());
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn raw_blocks(files: &[PathBuf]) -> usize {
    read_messages(files)
        .filter(|m| matches!(m.as_ref().map(|m| &m.message), Ok(PipelineMessage::Raw(_))))
        .count()
}

fn terminate(child: &mut Child) {
    let status = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// The embedded default's file with `edit` applied, written to `dir/bearingd.toml`.
fn config_file(dir: &Path, edit: impl Fn(String) -> String) -> PathBuf {
    let out = bearingd(&["config", "default"]);
    assert!(out.status.success());
    let text = edit(String::from_utf8(out.stdout).unwrap());
    let path = dir.join("bearingd.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// What `tests/python/log_metadata.py` (Python `mcap`, strict) reads from `file`.
fn python_metadata(py: &Path, file: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/log_metadata.py");
    let out = Command::new(py).arg(script).arg(file).output().unwrap();
    assert!(
        out.status.success(),
        "{}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn now_ns() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64
}

/// Sample ranges `[first, end)` of the raw blocks of `files`, in sample order.
fn raw_ranges(files: &[PathBuf]) -> (Vec<(u64, u64)>, f64) {
    let mut ranges = Vec::new();
    let mut rate = 0.0;
    for message in read_messages(files) {
        if let Ok(PipelineMessage::Raw(block)) = message.map(|m| m.message) {
            rate = block.sample_rate_hz;
            ranges.push((
                block.first_sample,
                block.first_sample + block.counts.len() as u64,
            ));
        }
    }
    ranges.sort_unstable();
    (ranges, rate)
}
