//! systemd's notify protocol, end to end: `bearingd run` under a `NOTIFY_SOCKET` this test
//! listens on, as systemd would with `Type=notify` and `WatchdogSec=`.
//!
//! Why a real process and a real socket: what matters is what systemd would receive (the
//! datagrams, their order, the watchdog pings while the pipeline runs), not the calls inside.
#![allow(unsafe_code, clippy::unwrap_used, clippy::expect_used)]

use std::os::unix::net::UnixDatagram;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

type TestResult = Result<(), Box<dyn std::error::Error>>;

/// One simulated sensor, status every 0.5 s, state and logs in `dir`.
fn write_config(dir: &Path) -> std::io::Result<std::path::PathBuf> {
    let path = dir.join("bearingd.toml");
    let text = format!(
        r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 25600
axes = ["radial"]
bearing = "skf-6205-2rs"
[sensors.speed]
source = "fixed"
rpm = 1772

[outputs]
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"
status_interval_s = 0.5
"#,
        state = dir.join("state").display(),
        mcap = dir.join("mcap").display(),
        // iceoryx2's root for the alert service: not under /tmp (the config refuses it).
        iox = bearingd_testdata::iox_root(
            env!("CARGO_TARGET_TMPDIR"),
            &format!(
                "sd-{}",
                dir.file_name().unwrap_or_default().to_string_lossy()
            )
        )
        .display(),
    );
    std::fs::write(&path, text)?;
    Ok(path)
}

#[test]
fn run_notifies_ready_status_watchdog_then_stopping() -> TestResult {
    let dir = tempfile::tempdir()?;
    let socket_path = dir.path().join("notify.sock");
    let listener = UnixDatagram::bind(&socket_path)?;
    listener.set_read_timeout(Some(Duration::from_millis(200)))?;
    let config = write_config(dir.path())?;

    // 4 s of sample time in real time: long enough for several STATUS (every 0.5 s) and
    // WATCHDOG (every 1 s, half of WATCHDOG_USEC) datagrams.
    let mut child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .arg("run")
        .arg("--config")
        .arg(&config)
        .args(["--duration", "4", "--quiet"])
        .env("NOTIFY_SOCKET", &socket_path)
        .env("WATCHDOG_USEC", "2000000")
        .env_remove("WATCHDOG_PID")
        .stdout(Stdio::null())
        .spawn()?;

    let deadline = Instant::now() + Duration::from_secs(60);
    let mut messages: Vec<String> = Vec::new();
    let mut buffer = [0u8; 4096];
    let exit = loop {
        match listener.recv(&mut buffer) {
            Ok(n) => messages.push(String::from_utf8_lossy(&buffer[..n]).into_owned()),
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) => {}
            Err(e) => return Err(e.into()),
        }
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if Instant::now() > deadline {
            child.kill()?;
            child.wait()?;
            return Err(format!("bearingd still running after 60 s; got {messages:?}").into());
        }
    };
    // What was sent just before the exit is still queued on the socket.
    listener.set_nonblocking(true)?;
    while let Ok(n) = listener.recv(&mut buffer) {
        messages.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
    }

    assert!(exit.success(), "bearingd exited with {exit}");
    assert_eq!(
        messages.first().map(String::as_str),
        Some("READY=1"),
        "READY=1 comes first: {messages:?}"
    );
    assert_eq!(
        messages.iter().filter(|m| *m == "READY=1").count(),
        1,
        "{messages:?}"
    );
    let statuses: Vec<&String> = messages
        .iter()
        .filter(|m| m.starts_with("STATUS="))
        .collect();
    assert!(
        statuses
            .iter()
            .any(|m| m.starts_with("STATUS=1 channel; ") && m.contains("motor-de/radial")),
        "a STATUS= naming the channel: {messages:?}"
    );
    assert!(
        statuses.iter().all(|m| !m.contains('\n')),
        "one line per STATUS: {statuses:?}"
    );
    assert!(
        messages.iter().any(|m| m == "WATCHDOG=1"),
        "the running pipeline pings the watchdog: {messages:?}"
    );
    assert_eq!(
        messages.last().map(String::as_str),
        Some("STOPPING=1"),
        "STOPPING=1 comes last: {messages:?}"
    );
    Ok(())
}

#[test]
fn run_without_notify_socket_is_unchanged() -> TestResult {
    // No NOTIFY_SOCKET: no notifications, no complaint on stderr, a normal exit.
    let dir = tempfile::tempdir()?;
    let config = write_config(dir.path())?;
    let output = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .arg("run")
        .arg("--config")
        .arg(&config)
        .args(["--duration", "2", "--fast", "--quiet"])
        .env_remove("NOTIFY_SOCKET")
        .env_remove("WATCHDOG_USEC")
        .output()?;
    assert!(output.status.success(), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("notify"), "{stderr}");
    Ok(())
}

#[test]
fn run_stops_cleanly_on_sigterm() -> TestResult {
    // `systemctl stop` sends SIGTERM to a run without --duration. Regression: the simulated
    // source ignored the stop and the run went on until systemd's SIGKILL, leaving an
    // unfinished MCAP file. Expected: STOPPING=1, exit 0, the log finished (it ends with the
    // MCAP magic, which only the finishing writer writes).
    let dir = tempfile::tempdir()?;
    let socket_path = dir.path().join("notify.sock");
    let listener = UnixDatagram::bind(&socket_path)?;
    listener.set_read_timeout(Some(Duration::from_millis(200)))?;
    let config = write_config(dir.path())?;
    let mut child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .arg("run")
        .arg("--config")
        .arg(&config)
        .arg("--quiet")
        .env("NOTIFY_SOCKET", &socket_path)
        .env_remove("WATCHDOG_USEC")
        .stdout(Stdio::null())
        .spawn()?;

    // The first STATUS= after READY=1: the run is in its main loop, signals are handled.
    let deadline = Instant::now() + Duration::from_secs(60);
    let mut messages: Vec<String> = Vec::new();
    let mut buffer = [0u8; 4096];
    while !messages.iter().any(|m| m.starts_with("STATUS=")) {
        if let Ok(n) = listener.recv(&mut buffer) {
            messages.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
        }
        if Instant::now() > deadline || child.try_wait()?.is_some() {
            let _ = child.kill();
            child.wait()?;
            return Err(format!("no STATUS= within 60 s, or an early exit: {messages:?}").into());
        }
    }
    // SAFETY: kill(2) on our own child's pid; no memory involved.
    let rc = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(rc, 0, "kill(SIGTERM) failed");
    let stop_deadline = Instant::now() + Duration::from_secs(20);
    let exit = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if Instant::now() > stop_deadline {
            child.kill()?;
            child.wait()?;
            return Err("bearingd still running 20 s after SIGTERM".into());
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    listener.set_nonblocking(true)?;
    while let Ok(n) = listener.recv(&mut buffer) {
        messages.push(String::from_utf8_lossy(&buffer[..n]).into_owned());
    }
    assert!(exit.success(), "bearingd exited with {exit} after SIGTERM");
    assert_eq!(
        messages.last().map(String::as_str),
        Some("STOPPING=1"),
        "{messages:?}"
    );
    let logs: Vec<_> = std::fs::read_dir(dir.path().join("mcap"))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    assert_eq!(logs.len(), 1, "one log file: {logs:?}");
    let bytes = std::fs::read(&logs[0])?;
    assert!(
        bytes.ends_with(b"\x89MCAP0\r\n"),
        "{}: not finished (no MCAP magic at the end)",
        logs[0].display()
    );
    Ok(())
}
