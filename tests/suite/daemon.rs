//! `bearingd run` and `bearingd replay` as processes: the embedded default logs to MCAP, the
//! log is read by Python's strict reader, a replay raises the same flags at the same samples,
//! a `kill -9` loses at most the open chunk, and a bad config refuses to start.

use crate::replay::replay_json;
use bearingd::mcap_log::read_messages;
use bearingd::messages::PipelineMessage;
use bearingd_testdata::{check_mcap_with_python, iox_root, mcap_files, python_mcap, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

/// What `tests/python/<script> FILE` prints (JSON), asserting that it succeeded.
fn python_json(py: &Path, script: &str, file: &Path) -> serde_json::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/python")
        .join(script);
    let out = Command::new(py).arg(path).arg(file).output().unwrap();
    assert!(
        out.status.success(),
        "{script} {}: {}{}",
        file.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The committed config with `replacements` made (each must apply), an iceoryx2 root of the
/// test's own, written to `dir/<name>.toml`.
fn config_with(dir: &Path, name: &str, replacements: &[(&str, &str)]) -> PathBuf {
    let committed =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/bearingd.toml"))
            .unwrap();
    let mut text = committed.replace(
        "\"/run/bearingd/iceoryx2\"",
        &format!("\"/dev/shm/bearingd-{name}-{}\"", std::process::id()),
    );
    for (from, to) in replacements {
        assert!(text.contains(from), "{from} is not in config/bearingd.toml");
        text = text.replace(from, to);
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `bearingd run --fast` of `config` for `seconds`, logging under `data`; its log files.
fn fast_run_logs(config: &Path, data: &Path, seconds: &str) -> Vec<PathBuf> {
    crate::replay::fast_run(config, data, seconds);
    mcap_files(&data.join("mcap"))
}

/// (channel, fault, from, to, sample) of every flag change in the logs.
fn logged_flags(files: &[PathBuf]) -> Vec<(String, String, String, String, u64)> {
    read_messages(files)
        .filter_map(|m| match m.expect("readable log").message {
            PipelineMessage::Flag(f) => Some((
                f.channel.to_string(),
                f.fault.to_string(),
                f.from.to_string(),
                f.to.to_string(),
                f.end_sample,
            )),
            _ => None,
        })
        .collect()
}

#[test]
fn run_logs_to_mcap_and_a_replay_raises_the_same_flags_at_the_same_samples() {
    let dir = scratch_dir("daemon-replay");
    let data = dir.join("data");
    let out = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "90",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The embedded fault ramps in from 30 s: its flag rises to watch once its comb stands
    // alone (docs/DIAGNOSIS.md), then to alarm.
    assert!(
        stdout.contains("FLAG motor-de/radial: outer_race ok -> watch")
            || stdout.contains("FLAG motor-de/radial: outer_race ok -> alarm"),
        "{stdout}"
    );
    assert!(stdout.contains("flags=outer_race=alarm"), "{stdout}");

    let live = mcap_files(&data.join("mcap"));
    assert_eq!(live.len(), 1, "{live:?}");
    let live_flags = logged_flags(&live);
    assert!(!live_flags.is_empty());
    // The simulated fault starts at 30 s; no flag before it.
    assert!(
        live_flags.iter().all(|f| f.4 > 30 * 25_600),
        "{live_flags:?}"
    );
    if let Some(py) = python_mcap() {
        let summary = check_mcap_with_python(&py, &live[0], None);
        let text = summary.to_string();
        for topic in [
            "/raw/motor-de/radial",
            "/indicators/motor-de/radial",
            "/flags/motor-de/radial",
            "/spectrum/motor-de/radial",
            "/twin/motor-de/radial",
        ] {
            assert!(text.contains(topic), "{topic} missing from {text}");
        }
    }

    let replay_dir = dir.join("replay");
    let (summary, _) = replay_json(&live[..1], &replay_dir, &[]);
    assert_eq!(summary["samples"], 90 * 25_600);
    let replayed = logged_flags(&mcap_files(&replay_dir));
    assert_eq!(
        replayed, live_flags,
        "the replay's flags differ from the live run's"
    );
}

#[test]
fn kill_9_while_logging_loses_at_most_the_open_chunk_and_restart_recovers_the_file() {
    let dir = scratch_dir("daemon-kill");
    let data = dir.join("data");
    let mut child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["run", "--quiet", "--data-dir", data.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(4_500));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    let files = mcap_files(&data.join("mcap"));
    assert_eq!(files.len(), 1);
    let killed_bytes = std::fs::metadata(&files[0]).unwrap().len();

    let out = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "1",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("recovered")
            && stderr.contains(files[0].file_name().unwrap().to_str().unwrap()),
        "{stderr}"
    );
    // About 4 s were logged, flushed every second: at least 2.5 s of raw blocks (0.1 s each) survive.
    let raw = read_messages(&files[..1])
        .filter(|m| matches!(m.as_ref().map(|m| &m.message), Ok(PipelineMessage::Raw(_))))
        .count();
    assert!(
        raw >= 25,
        "only {raw} raw blocks recovered from {killed_bytes} bytes"
    );
    if let Some(py) = python_mcap() {
        check_mcap_with_python(&py, &files[0], None);
    }
}

#[test]
fn a_config_error_refuses_to_start_and_lists_every_problem() {
    let dir = scratch_dir("daemon-config");
    let committed =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/bearingd.toml"))
            .unwrap();
    let bad = committed
        .replace("sample_rate_hz = 25600", "sample_rate_hz = -5")
        .replace("averages = 8", "averages = 0");
    let path = dir.join("bad.toml");
    std::fs::write(&path, bad).unwrap();
    let out = bearingd(&["run", "--config", path.to_str().unwrap(), "--duration", "1"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("sensors[0].sample_rate_hz") && stderr.contains("analysis.averages"),
        "{stderr}"
    );
}

/// The firmware simulator as a separate process publishing over iceoryx2, `bearingd run`
/// subscribing, logging to MCAP; then a replay of that log raises the same flags at the same
/// samples. The speed comes from the node's speed frames (no nominal speed: nothing is scored
/// before the first), is logged and fed back by the replay; the source's counters are logged
/// at the status interval and read back by Python.
#[test]
fn a_simulated_node_over_iceoryx2_through_the_daemon_and_its_replay_give_the_same_flags() {
    let dir = scratch_dir("daemon-iox");
    // iceoryx2's root must not sit under /tmp (the config refuses it): use the target dir.
    let iox_root = iox_root(env!("CARGO_TARGET_TMPDIR"), "iox");
    std::fs::create_dir_all(&iox_root).unwrap();
    let prefix = format!("bdtest{}_", std::process::id());
    let config = format!(
        r#"
[[sensors]]
id = "node1"
transport = "shm"
sample_rate_hz = 25600
scale_g_per_count = 0.00048828125
axes = ["radial"]
bearing = "skf-6205-2rs"
[sensors.speed]
source = "can"
max_rpm = 2500
[sensors.shm]
service = "bearingd/accel/node1"

[outputs]
status_interval_s = 2
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"
"#,
        state = dir.join("state").display(),
        mcap = dir.join("mcap").display(),
        iox = iox_root.display()
    );
    let config_path = dir.join("node1.toml");
    std::fs::write(&config_path, config).unwrap();

    let daemon = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args([
            "run",
            "--config",
            config_path.to_str().unwrap(),
            "--duration",
            "24",
            "--quiet",
        ])
        .env("BEARINGD_IOX_PREFIX", &prefix)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let firmware_sim = Path::new(env!("CARGO_BIN_EXE_bearingd")).with_file_name("firmware-sim");
    assert!(
        firmware_sim.exists(),
        "{} missing: build the workspace (cargo test --workspace)",
        firmware_sim.display()
    );
    let node = Command::new(&firmware_sim)
        .args([
            "--transport",
            "shm",
            "--sensor",
            "node1",
            "--node",
            "1",
            "--fault",
            "outer",
            "--onset",
            "20",
            "--rpm",
            "1772",
        ])
        .args([
            "--fs",
            "25600",
            "--duration",
            "60",
            "--speed-factor",
            "4",
            "--seed",
            "3",
            "--noise",
            "0.1",
        ])
        .args([
            "--iox-prefix",
            &prefix,
            "--iox-root",
            iox_root.to_str().unwrap(),
            "--wait-ready",
            "20",
        ])
        .output()
        .unwrap();
    assert!(
        node.status.success(),
        "firmware-sim: {}",
        String::from_utf8_lossy(&node.stderr)
    );
    let out = daemon.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("FLAG node1/radial: outer_race"), "{stdout}");

    let live = mcap_files(&dir.join("mcap"));
    let live_flags = logged_flags(&live);
    let raw_samples: usize = read_messages(&live)
        .filter_map(|m| match m.unwrap().message {
            PipelineMessage::Raw(b) => Some(b.counts.len()),
            _ => None,
        })
        .sum();
    assert_eq!(
        raw_samples,
        60 * 25_600,
        "every sample sent was logged; daemon said:\n{stdout}"
    );
    assert!(
        live_flags
            .iter()
            .all(|f| f.1 == "outer_race" && f.4 > 20 * 25_600),
        "{live_flags:?}"
    );

    // The speed frames (one per second of sample time, 1772 rpm) were used and logged.
    let speeds: Vec<(u64, Option<f64>)> = read_messages(&live)
        .filter_map(|m| match m.unwrap().message {
            PipelineMessage::Speed(s) => Some((s.end_sample, s.rpm)),
            _ => None,
        })
        .collect();
    assert!(speeds.len() >= 50, "{speeds:?}");
    assert_eq!(speeds[0], (0, Some(1772.0)), "{speeds:?}");
    assert!(speeds.iter().all(|s| s.1 == Some(1772.0)), "{speeds:?}");
    // The source's counters, periodically and at the end: every sample, no loss.
    let ingest: Vec<_> = read_messages(&live)
        .filter_map(|m| match m.unwrap().message {
            PipelineMessage::Ingest(i) => Some(i),
            _ => None,
        })
        .collect();
    assert!(ingest.len() >= 5, "{ingest:?}");
    let last = ingest.last().unwrap();
    assert_eq!(last.source, "shm-node1");
    assert_eq!(last.samples, 60 * 25_600, "{last:?}");
    assert!(last.speed_frames >= 60, "{last:?}");
    assert_eq!(
        (
            last.gaps,
            last.missing_samples,
            last.malformed,
            last.dropped_blocks
        ),
        (0, 0, 0, 0),
        "{last:?}"
    );
    assert!(ingest.windows(2).all(|w| w[0].frames <= w[1].frames));
    if let Some(py) = python_mcap() {
        let summary = check_mcap_with_python(&py, &live[0], None);
        let topics = &summary["topics"];
        assert!(
            topics["/ingest/shm-node1"].as_u64().unwrap_or(0) >= 5,
            "{summary}"
        );
        assert!(
            topics["/speed/node1/radial"].as_u64().unwrap_or(0) >= 50,
            "{summary}"
        );
    }

    let replay_dir = dir.join("replay");
    replay_json(
        &live[..1],
        &replay_dir,
        &["--config", config_path.to_str().unwrap()],
    );
    assert_eq!(logged_flags(&mcap_files(&replay_dir)), live_flags);
    let _ = std::fs::remove_dir_all(&iox_root);
}

/// `bearingd import` of every CWRU record, then `bearingd replay` with the settings its log carries:
/// the diagnosable records (inner and outer race, 0.007 and 0.021 in) raise their fault's flag
/// and no other; no record raises a flag of a wrong fault.
#[test]
fn imported_cwru_records_replayed_raise_the_right_flags() {
    let Some(data) = bearingd_testdata::shared_data_dir("cwru") else {
        return;
    };
    let dir = scratch_dir("daemon-import");
    let mut problems = Vec::new();
    for row in bearingd_testdata::read_manifest(&data) {
        let out = dir.join(row["file"].replace(['@', '.'], "_"));
        let imported = bearingd(&[
            "import",
            data.join(&row["file"]).to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            imported.status.success(),
            "{}",
            String::from_utf8_lossy(&imported.stderr)
        );
        let log = mcap_files(&out);
        let replayed = bearingd(&[
            "replay",
            log[0].to_str().unwrap(),
            "--quiet",
            "--json",
            "--out",
            out.join("replay").to_str().unwrap(),
        ]);
        assert!(
            replayed.status.success(),
            "{}",
            String::from_utf8_lossy(&replayed.stderr)
        );
        let summary: serde_json::Value = serde_json::from_slice(&replayed.stdout).unwrap();
        // The imported log carries the settings it is replayed with.
        assert_eq!(summary["settings_from"], "log", "{summary}");
        let raised: Vec<String> = summary["flags"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|f| f["from"] == "ok")
            .map(|f| f["fault"].as_str().unwrap().to_string())
            .collect();
        let expected = match row["fault"].as_str() {
            "inner" => "inner_race",
            "outer" => "outer_race",
            "ball" => "ball",
            _ => "none",
        };
        let must = matches!(row["fault"].as_str(), "inner" | "outer")
            && matches!(row["fault_size_in"].as_str(), "0.007" | "0.021");
        if must && !raised.iter().any(|f| f == expected) {
            problems.push(format!(
                "{}: no {expected} flag (raised {raised:?})",
                row["file"]
            ));
        }
        if let Some(wrong) = raised.iter().find(|f| *f != expected) {
            problems.push(format!(
                "{}: a {wrong} flag on a {expected} record",
                row["file"]
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The Hammerstein–Wiener model online (issue 13 item 3): `bearingd run` re-identifies it with
/// each twin fit and logs it to `/hw/<sensor>/<axis>`; Python's strict reader reads it back and
/// recomputes each model's free-run accuracy from its logged time residual and the log's own
/// raw samples; the replay (which serves every re-fit request) learns the baseline and then
/// reports the drift on every fit.
#[test]
fn the_hw_model_is_logged_with_its_time_residuals_and_python_recomputes_its_accuracy() {
    let dir = scratch_dir("daemon-hw");
    let config = config_with(
        &dir,
        "hw",
        &[
            ("refit_period_s = 10.0", "refit_period_s = 2.0"),
            ("hw_baseline_fits = 10", "hw_baseline_fits = 4"),
        ],
    );
    let live = fast_run_logs(&config, &dir.join("data"), "40");
    let replay_dir = dir.join("replay");
    replay_json(&live[..1], &replay_dir, &[]);
    let replayed = mcap_files(&replay_dir);

    let Some(py) = python_mcap() else {
        return;
    };
    let read = |file: &Path| python_json(&py, "hw_log.py", file);
    for file in [&live[0], &replayed[0]] {
        let log = read(file);
        assert_eq!(log["schema"]["name"], "bearingd.Hw", "{log}");
        let models = log["hw"].as_array().unwrap();
        assert!(!models.is_empty(), "no /hw message in {}", file.display());
        for m in models {
            assert!(m["problem"].is_null(), "{m}");
            // 2,560 samples less the three differences of the inputs a⁽¹⁾…a⁽³⁾.
            assert_eq!(m["residual_len"], 2557, "{m}");
            assert_eq!(m["one_step_len"], 2557, "{m}");
            assert!(m["recomputed_accuracy"].is_f64(), "{m}");
        }
    }
    // The replay serves every request (the fast live run drops the ones that arrive while the
    // re-fit thread is busy): one model per 2 s from the first fit, the baseline after four.
    let log = read(&replayed[0]);
    let models = log["hw"].as_array().unwrap();
    assert!(models.len() >= 12, "{} models", models.len());
    for (k, m) in models.iter().enumerate() {
        assert_eq!(m["warm_start"], k > 0, "{m}");
        let learned = k >= 4;
        assert_eq!(m["baseline_fits"], (k + 1).min(4), "{m}");
        assert_eq!(m["residual_drift_sigma"].is_f64(), learned, "{m}");
        assert_eq!(m["parameter_drift"].is_f64(), learned, "{m}");
    }
}

/// The RMS trend with the health stage (issue 13 item 5), read back by Python: the embedded
/// default's fault ramps in from 30 s, so the stage goes healthy → degrading; a point every
/// `trend_point_s`; the trend and its time to the failure limit only once the limit is learned
/// in the degrading stage.
#[test]
fn the_rms_trend_is_published_with_the_stage_and_predicts_only_once_the_limit_is_known() {
    let dir = scratch_dir("daemon-trend");
    let config = config_with(
        &dir,
        "trend",
        &[("trend_point_s = 60.0", "trend_point_s = 5.0")],
    );
    let live = fast_run_logs(&config, &dir.join("data"), "120");
    let Some(py) = python_mcap() else {
        return;
    };
    let log = python_json(&py, "log_topics.py", &live[0]);
    let trend: Vec<&serde_json::Value> = log["messages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["topic"] == "/trend/motor-de/radial")
        .map(|m| &m["json"])
        .collect();
    // 120 s at a point per 5 s (the first span starts at the first window's end).
    assert!((22..=24).contains(&trend.len()), "{} points", trend.len());
    let stage_rank = |m: &serde_json::Value| {
        ["learning", "healthy", "degrading", "failing"]
            .iter()
            .position(|s| m["stage"] == *s)
            .unwrap()
    };
    assert!(trend
        .windows(2)
        .all(|w| stage_rank(w[0]) <= stage_rank(w[1])));
    let rms = |m: &serde_json::Value| m["rms"].as_f64().unwrap();
    let healthy: Vec<f64> = trend
        .iter()
        .filter(|m| stage_rank(m) <= 1)
        .map(|m| rms(m))
        .collect();
    let degrading: Vec<&&serde_json::Value> =
        trend.iter().filter(|m| m["stage"] == "degrading").collect();
    assert!(!healthy.is_empty() && degrading.len() >= 10, "{trend:?}");
    // Before the fault the points sit at the machine's level; the fault triples it.
    assert!(
        healthy.iter().all(|&r| (0.05..0.08).contains(&r)),
        "{healthy:?}"
    );
    assert!(
        rms(degrading.last().unwrap()) > 2.5 * healthy[0],
        "{trend:?}"
    );
    // No prediction before the failure limit is learned, one after.
    for m in trend.iter().filter(|m| stage_rank(m) <= 1) {
        assert!(
            m["threshold"].is_null() && m["time_to_threshold_s"].is_null(),
            "{m}"
        );
    }
    let predicted: Vec<&&&serde_json::Value> = degrading
        .iter()
        .filter(|m| m["threshold"].is_f64())
        .collect();
    assert!(!predicted.is_empty(), "{trend:?}");
    let first = predicted[0];
    assert!(first["threshold"].as_f64().unwrap() > rms(first), "{first}");
    assert!(first["rate_per_s"].as_f64().unwrap() > 0.0, "{first}");
    assert!(first["time_to_threshold_s"].is_f64(), "{first}");
}

/// The files `pid` holds open.
fn open_files(pid: u32) -> Vec<PathBuf> {
    std::fs::read_dir(format!("/proc/{pid}/fd"))
        .map(|dir| {
            dir.filter_map(|entry| std::fs::read_link(entry.ok()?.path()).ok())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn the_cpu_wakeup_latency_is_capped_while_the_daemon_runs_and_only_when_asked() {
    let device = Path::new(bearingd::daemon::cpu_latency::CPU_LATENCY_DEVICE);
    if std::fs::OpenOptions::new()
        .write(true)
        .open(device)
        .is_err()
    {
        let missing = format!(
            "{} is not writable here (the kernel's PM QoS device; run the tests as root)",
            device.display()
        );
        assert!(std::env::var("CI").as_deref() != Ok("true"), "{missing}");
        eprintln!("skipping: {missing}");
        return;
    }
    let dir = scratch_dir("daemon-cpu-latency");
    // (outputs.cpu_wakeup_latency_us = 0, outputs.cpu_awake_during_analysis): each is a
    // request of its own on the device, held open for the whole run.
    for (capped, awake) in [(false, false), (true, true), (false, true)] {
        let cap = if capped {
            "cpu_wakeup_latency_us = 0"
        } else {
            "# cpu_wakeup_latency_us = 0"
        };
        let awake_line = if awake {
            "# cpu_awake_during_analysis = true"
        } else {
            "cpu_awake_during_analysis = false"
        };
        let name = format!("cap-{capped}-awake-{awake}");
        let config = config_with(
            &dir,
            &name,
            &[
                ("# cpu_wakeup_latency_us = 0", cap),
                ("# cpu_awake_during_analysis = true", awake_line),
            ],
        );
        let data = dir.join(format!("data-{name}"));
        let child = Command::new(env!("CARGO_BIN_EXE_bearingd"))
            .args(["run", "--quiet", "--duration", "3", "--config"])
            .arg(&config)
            .arg("--data-dir")
            .arg(&data)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // Looked at every 50 ms from the start to the exit: a run that asks for neither must
        // never hold the device.
        let expected = usize::from(capped) + usize::from(awake);
        let mut child = child;
        let mut most_held = 0;
        while child.try_wait().unwrap().is_none() && !(expected > 0 && most_held == expected) {
            let held = open_files(child.id())
                .iter()
                .filter(|f| *f == device)
                .count();
            most_held = most_held.max(held);
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let out = child.wait_with_output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert_eq!(most_held, expected, "{name}: {stderr}");
        assert_eq!(
            stderr.contains("CPU wake-up latency capped at 0 µs"),
            capped,
            "{stderr}"
        );
        assert!(!stderr.contains("cannot hold it"), "{name}: {stderr}");
    }
}
