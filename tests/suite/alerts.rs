//! Alerts over iceoryx2 across real processes: the daemon publishes, `bearingd alerts` and the
//! Python example (`examples/alerts_subscriber.py`, the `iceoryx2` package from PyPI)
//! subscribe.

use bearingd_testdata::{iox_root, python_iceoryx2, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Instant;

fn bearingd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_bearingd"))
}

fn json_lines(text: &str) -> Vec<serde_json::Value> {
    text.lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// The sample of the daemon's `FLAG <channel>: outer_race ok -> ...` line.
fn raised_at(stdout: &str) -> u64 {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("FLAG motor-de/radial: outer_race ok ->"))
        .unwrap_or_else(|| panic!("no outer-race flag raised:\n{stdout}"));
    line.rsplit(' ').next().unwrap().parse().unwrap()
}

/// The Python example subscriber (`examples/alerts_subscriber.py`) on `root`, waiting up to
/// 180 s for the daemon's service and then for `count` alerts. Start it before the daemon.
///
/// (why) A daemon it listens to runs in real time, not `--fast`: a fast run of these configs
/// lives well under a second, and the subscriber, polling every 0.5 s on a loaded 2-core
/// machine, can miss the service altogether (CI of f8e0a7b: `DoesNotExist` after 180 s). The
/// service's history covers alerts raised before it connects, as long as the daemon lives.
pub(crate) fn spawn_python_subscriber(python: &Path, root: &Path, count: usize) -> Child {
    Command::new(python)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/alerts_subscriber.py"))
        .arg("--root")
        .arg(root)
        .args(["--count", &count.to_string(), "--timeout", "180"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

#[test]
fn a_python_subscriber_receives_the_raised_alert_of_a_simulated_fault() {
    let Some(python) = python_iceoryx2() else {
        return;
    };
    let dir = scratch_dir("alerts-python");
    let config = fault_from_start_config(&dir, "ip");
    let root = bearingd::config::load(&config)
        .unwrap()
        .outputs
        .iceoryx2_root;
    // The subscriber first: it waits for the daemon to create the service.
    let subscriber = spawn_python_subscriber(&python, &root, 1);
    // An outer-race fault from the start, in real time (see `spawn_python_subscriber`): raised
    // at about 14 s of 16.
    let daemon = bearingd()
        .args(["run", "--duration", "16", "--quiet", "--config"])
        .arg(&config)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&daemon.stdout);
    assert!(
        daemon.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&daemon.stderr)
    );
    let sample = raised_at(&stdout);
    // Raised once the band selection's evidence names the fault: at watch or straight at alarm,
    // then perhaps escalated; the subscriber asked for the first.
    assert!(
        stdout.contains("1 alerts published") || stdout.contains("2 alerts published"),
        "{stdout}"
    );
    // The daemon's own part of their latency, before the subscriber's wake-up.
    assert!(
        stdout.contains(", each in the service p50 ") && stdout.contains("after its input arrived"),
        "{stdout}"
    );

    let received = subscriber.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&received.stdout);
    assert!(
        received.status.success(),
        "Python subscriber failed:\n{text}\n{}",
        String::from_utf8_lossy(&received.stderr)
    );
    let alerts = json_lines(&text);
    assert_eq!(alerts.len(), 1, "{text}");
    let alert = &alerts[0];
    assert_eq!(alert["type"], "alert");
    assert_eq!(alert["state"], "raised");
    assert_eq!(alert["fault"], "outer_race");
    assert_eq!(alert["sensor"], "motor-de");
    assert_eq!(alert["axis"], "radial");
    assert_eq!(alert["sequence"], 1);
    assert_eq!(alert["previous_severity"], "ok");
    assert_eq!(alert["end_sample"], sample, "the same window as the flag");
    let confidence = alert["confidence"].as_f64().unwrap();
    assert!((0.5..=1.0).contains(&confidence), "{alert}");
    // BPFO of a 6205-2RS at 1772 rpm is 105.9 Hz.
    let bpfo = alert["fault_frequency_hz"].as_f64().unwrap();
    assert!((bpfo - 105.9).abs() < 0.5, "{alert}");
    let latency_ns = alert["received_wall_ns"].as_u64().unwrap() as i128
        - alert["wall_time_ns"].as_u64().unwrap() as i128;
    assert!(latency_ns > 0, "received before it was decided? {alert}");
}

/// A config with one simulated sensor whose outer race is faulty from the start, files in
/// `dir`, the iceoryx2 root under the target dir (the config refuses /tmp), one per `iox_tag`
/// (tests running at once must not share an alert service).
fn fault_from_start_config(dir: &Path, iox_tag: &str) -> PathBuf {
    // Short: iceoryx2's socket paths below it must fit in 108 bytes.
    let iox = iox_root(env!("CARGO_TARGET_TMPDIR"), iox_tag);
    let text = format!(
        r#"
[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 12800
axes = ["radial"]
bearing = "skf-6205-2rs"
[sensors.speed]
source = "fixed"
rpm = 1772
[sensors.sim]
fault = "outer"
onset_s = 0.0
severity = 2.0

[analysis]
band_period_s = 4.0

[thresholds]
on_delay_s = 1.0

[outputs]
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"
"#,
        state = dir.join("state").display(),
        mcap = dir.join("mcap").display(),
        iox = iox.display(),
    );
    let path = dir.join("bearingd.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// Stops the daemon with SIGTERM as systemd would, and returns its output.
fn terminate(daemon: Child) -> std::process::Output {
    let pid = daemon.id().to_string();
    let _ = Command::new("kill").args(["-TERM", &pid]).status();
    daemon.wait_with_output().unwrap()
}

#[test]
fn bearingd_alerts_prints_live_alerts_and_a_late_subscriber_gets_the_active_ones() {
    let dir = scratch_dir("alerts-cli");
    let config = fault_from_start_config(&dir, "ia");
    let daemon = bearingd()
        .args(["run", "--quiet", "--config"])
        .arg(&config)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    let live = bearingd()
        .args([
            "alerts",
            "--json",
            "--count",
            "1",
            "--timeout",
            "120",
            "--config",
        ])
        .arg(&config)
        .output()
        .unwrap();
    let live_text = String::from_utf8_lossy(&live.stdout).into_owned();
    if !live.status.success() {
        let out = terminate(daemon);
        panic!(
            "bearingd alerts: {live_text}\n{}\ndaemon: {}\n{}",
            String::from_utf8_lossy(&live.stderr),
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let first = json_lines(&live_text);
    assert_eq!(first.len(), 1, "{live_text}");
    assert_eq!(first[0]["fault"], "outer_race");
    assert_eq!(first[0]["state"], "raised");
    assert_eq!(first[0]["active_at_start"], false);
    eprintln!(
        "first alert after {:.1} s of real time",
        started.elapsed().as_secs_f64()
    );

    // A subscriber that comes later learns the active alert from the service's history.
    let late = bearingd()
        .args([
            "alerts",
            "--json",
            "--count",
            "1",
            "--timeout",
            "20",
            "--config",
        ])
        .arg(&config)
        .output()
        .unwrap();
    let late_text = String::from_utf8_lossy(&late.stdout).into_owned();
    // The Python example, as late, prints what `bearingd alerts --json` printed.
    let python_late = python_iceoryx2().map(|python| {
        let root = bearingd::config::load(&config)
            .unwrap()
            .outputs
            .iceoryx2_root;
        Command::new(python)
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/alerts_subscriber.py"))
            .arg("--root")
            .arg(root)
            .args(["--count", "1", "--timeout", "20"])
            .output()
            .unwrap()
    });
    let out = terminate(daemon);
    let daemon_stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        late.status.success(),
        "{late_text}\n{}",
        String::from_utf8_lossy(&late.stderr)
    );
    let active = json_lines(&late_text);
    assert_eq!(active.len(), 1, "{late_text}");
    assert_eq!(active[0]["active_at_start"], true);
    assert_eq!(active[0]["fault"], "outer_race");
    assert_eq!(active[0]["run_id"], first[0]["run_id"]);
    assert!(active[0]["sequence"].as_u64() >= first[0]["sequence"].as_u64());
    if let Some(python) = python_late {
        let text = String::from_utf8_lossy(&python.stdout);
        assert!(
            python.status.success(),
            "{text}\n{}",
            String::from_utf8_lossy(&python.stderr)
        );
        let mut from_python = json_lines(&text);
        assert_eq!(from_python.len(), 1, "{text}");
        // Everything but the moment each subscriber received it.
        let mut from_rust = active[0].clone();
        for line in [&mut from_python[0], &mut from_rust] {
            line.as_object_mut().unwrap().remove("received_wall_ns");
        }
        assert_eq!(from_python[0], from_rust);
    }

    assert!(
        out.status.success(),
        "daemon after SIGTERM: {daemon_stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(raised_at(&daemon_stdout), first[0]["end_sample"]);
    assert!(
        daemon_stdout.contains("alerts published"),
        "{daemon_stdout}"
    );
}

/// With no daemon where it looks, `bearingd alerts` says which daemon it looked for (the data
/// dir, made absolute, or the config) and how to point it at another.
#[test]
fn bearingd_alerts_without_a_daemon_names_where_it_looked_and_how_to_point_it() {
    let dir = scratch_dir("alerts-nowhere");
    let data = dir.join("no-daemon-here");
    let out = bearingd()
        .args(["alerts", "--timeout", "0", "--data-dir"])
        .arg(&data)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "looked for the daemon of `bearingd run` without a config and with the data dir {}",
            data.display()
        )) && err.contains("give its --data-dir DIR")
            && err.contains("--config /etc/bearingd/bearingd.toml"),
        "{err}"
    );
    let out = bearingd()
        .current_dir(&dir)
        .args(["alerts", "--timeout", "0"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("(the default ./bearingd-data, from this directory)"),
        "{err}"
    );
}
