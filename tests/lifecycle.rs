//! A clean start and a clean stop of `bearingd run` as a process (issue 11 item 6): a missing
//! source stops the start before any log file exists; retention's deletions are said in the log
//! itself; a file opened by rotation begins with the current state; the embedded default's
//! iceoryx2 root is one the config accepts; dead iceoryx2 nodes of a killed daemon are cleaned.
//! Log files are read back by Python's strict `mcap` reader.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd_testdata::{mcap_files, python_mcap, scratch_dir};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
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

/// The messages of `file` in log-time order, as Python's strict reader sees them
/// (`tests/python/log_topics.py`); `None` outside CI without the Python reader.
fn python_messages(file: &Path) -> Option<Vec<Value>> {
    let py = python_mcap()?;
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/log_topics.py");
    let out = Command::new(py).arg(script).arg(file).output().unwrap();
    assert!(
        out.status.success(),
        "{} does not read strictly: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    Some(summary["messages"].as_array().unwrap().clone())
}

#[test]
fn issue11_a_missing_can_interface_stops_the_start_naming_it_and_leaves_no_log_file() {
    let dir = scratch_dir("lifecycle-can-missing");
    let data = dir.join("data");
    let config = dir.join("can.toml");
    std::fs::write(
        &config,
        format!(
            r#"
[[sensors]]
id = "motor-de"
transport = "can"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"
[sensors.speed]
rpm = 1772
[sensors.can]
interface = "vcan-missing"
node_id = 1
[outputs]
iceoryx2_root = "/dev/shm/bearingd-lifecycle-can-{}"
"#,
            std::process::id()
        ),
    )
    .unwrap();
    for _restart in 0..2 {
        let out = bearingd(&[
            "run",
            "--config",
            config.to_str().unwrap(),
            "--data-dir",
            data.to_str().unwrap(),
            "--duration",
            "1",
            "--quiet",
        ]);
        let stderr = stderr_of(&out);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains("CAN interface vcan-missing")
                && stderr.contains("ip link")
                && stderr.contains("sensors[].can.interface"),
            "the error must name the interface and the fix: {stderr}"
        );
        let logs = mcap_files(&data.join("mcap"));
        assert!(logs.is_empty(), "log files left behind: {logs:?}");
    }
}

#[test]
fn issue11_the_embedded_defaults_iceoryx2_root_is_one_the_config_accepts() {
    let dir = scratch_dir("lifecycle-iox-root");
    // The root of a `--data-dir` run is chosen by the binary; `run` says it when the alerts
    // start.
    let run = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "0.5",
        "--quiet",
        "--data-dir",
        dir.join("data").to_str().unwrap(),
    ]);
    let stderr = stderr_of(&run);
    assert!(run.status.success(), "{stderr}");
    let root = stderr
        .lines()
        .find_map(|l| l.split("(root ").nth(1))
        .map(|r| r.trim_end_matches(')').to_string())
        .unwrap_or_else(|| panic!("no alert root said: {stderr}"));
    // The same root in a config file validates.
    let config = config_file(&dir, |text| {
        text.replace("\"/run/bearingd/iceoryx2\"", &format!("\"{root}\""))
    });
    let validate = bearingd(&["validate", config.to_str().unwrap()]);
    assert!(
        validate.status.success(),
        "the default's root {root} is refused in a config: {}",
        stderr_of(&validate)
    );
}

/// Per channel and kind, the latest message of a family (`/flags/`, `/health/`, `/twin/`).
fn latest(state: &mut BTreeMap<String, Value>, topic: &str, message: &Value) {
    let kind = message
        .get("fault")
        .or_else(|| message.get("kind"))
        .cloned()
        .unwrap_or(Value::Null);
    state.insert(format!("{topic} {kind}"), message.clone());
}

/// `bearingd run --fast` of the embedded default with `edit` applied, for `seconds` of signal,
/// logging under `dir/data` with its own iceoryx2 root (removed after); its output and the
/// data dir.
fn fast_run(dir: &Path, seconds: &str, edit: impl Fn(String) -> String) -> (Output, PathBuf) {
    let data = dir.join("data");
    // The scratch dir's name is unique per test and process.
    let root = format!(
        "/dev/shm/{}-iox",
        dir.file_name().unwrap().to_string_lossy()
    );
    let config = config_file(dir, |text| {
        edit(text).replace("\"/run/bearingd/iceoryx2\"", &format!("\"{root}\""))
    });
    let out = bearingd(&[
        "run",
        "--config",
        config.to_str().unwrap(),
        "--data-dir",
        data.to_str().unwrap(),
        "--fast",
        "--quiet",
        "--duration",
        seconds,
    ]);
    let _ = std::fs::remove_dir_all(&root);
    (out, data)
}

#[test]
fn issue11_a_rotated_file_begins_with_the_current_state_and_nothing_from_before_it() {
    let dir = scratch_dir("lifecycle-rotation");
    let (out, data) = fast_run(&dir, "60", |text| {
        // Twice the default imbalance: ISO zone C, so the zone flag rises early (state too).
        text.replace("mcap_max_file_mb = 256", "mcap_max_file_mb = 1")
            .replace("imbalance_g = 0.05", "imbalance_g = 0.1")
    });
    assert!(out.status.success(), "{}", stderr_of(&out));
    let files = mcap_files(&data.join("mcap"));
    assert!(files.len() >= 3, "no rotation: {files:?}");
    // What was current before each file: the latest flag, health and twin per channel.
    let mut flags = BTreeMap::new();
    let mut health = BTreeMap::new();
    let mut twin = BTreeMap::new();
    let mut zone = BTreeMap::new();
    let mut checked_twin = false;
    let mut checked_zone = false;
    for (i, file) in files.iter().enumerate() {
        let Some(messages) = python_messages(file) else {
            return;
        };
        if i > 0 {
            let first = &messages[0];
            assert_eq!(first["topic"], "/state", "{}: {first}", file.display());
            let start = first["log_time"].as_u64().unwrap();
            let snapshot = &first["json"];
            let as_set = |list: &Value, family: &str| -> BTreeMap<String, Value> {
                let mut set = BTreeMap::new();
                for m in list.as_array().unwrap() {
                    let channel = m["channel"].to_string();
                    latest(&mut set, &format!("{family}{channel}"), m);
                }
                set
            };
            assert_eq!(
                as_set(&snapshot["flags"], "/flags/"),
                flags,
                "{}",
                file.display()
            );
            assert_eq!(as_set(&snapshot["health"], "/health/"), health);
            assert_eq!(as_set(&snapshot["twin"], "/twin/"), twin);
            assert_eq!(
                as_set(&snapshot["velocity_flags"], "/velocity_flags/"),
                zone
            );
            checked_twin |= !twin.is_empty();
            checked_zone |= !zone.is_empty();
            for m in &messages {
                assert!(
                    m["log_time"].as_u64().unwrap() >= start,
                    "{}: {} at {} before the file's start {start}",
                    file.display(),
                    m["topic"],
                    m["log_time"]
                );
            }
        }
        for m in &messages {
            let topic = m["topic"].as_str().unwrap();
            let family = ["/flags/", "/health/", "/twin/", "/velocity_flags/"]
                .into_iter()
                .find(|f| topic.starts_with(f));
            if let Some(family) = family {
                let key = format!("{family}{}", m["json"]["channel"]);
                let set = match family {
                    "/flags/" => &mut flags,
                    "/health/" => &mut health,
                    "/twin/" => &mut twin,
                    _ => &mut zone,
                };
                latest(set, &key, &m["json"]);
            }
        }
    }
    assert!(
        checked_twin,
        "no twin fit before a rotation: nothing checked"
    );
    assert!(
        checked_zone,
        "no ISO zone flag change before a rotation: nothing checked"
    );
    assert!(
        !flags.is_empty(),
        "no flag change in 60 s of the embedded fault"
    );
}

#[test]
fn issue11_each_retention_deletion_is_a_log_message_in_the_mcap_file() {
    let dir = scratch_dir("lifecycle-retention");
    let (out, data) = fast_run(&dir, "120", |text| {
        text.replace("mcap_max_file_mb = 256", "mcap_max_file_mb = 1")
            .replace("mcap_disk_budget_mb = 4096", "mcap_disk_budget_mb = 2")
    });
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    let deleted: Vec<String> = stderr
        .lines()
        .filter_map(|l| l.strip_prefix("bearingd: retention: deleted "))
        .flat_map(|l| l.split(" (").next().unwrap().split(", "))
        .map(String::from)
        .collect();
    assert!(!deleted.is_empty(), "{stderr}");
    for path in &deleted {
        assert!(
            path.contains("bearingd-") && !Path::new(path).exists(),
            "said deleted but still there, or not a log: {path}"
        );
    }
    let mut noted = Vec::new();
    for file in mcap_files(&data.join("mcap")) {
        let Some(messages) = python_messages(&file) else {
            return;
        };
        for m in messages.iter().filter(|m| m["topic"] == "/log") {
            let note = &m["json"];
            assert_eq!(note["level"], 2, "{note}");
            assert_eq!(note["name"], "bearingd");
            let text = note["message"].as_str().unwrap();
            let path = text
                .strip_prefix("retention: deleted ")
                .and_then(|t| t.split(" to keep").next())
                .unwrap_or_else(|| panic!("not a retention note: {text}"));
            assert!(
                deleted.iter().any(|d| d == path),
                "{path} not said: {stderr}"
            );
            let sec = note["timestamp"]["sec"].as_u64().unwrap();
            let nsec = note["timestamp"]["nsec"].as_u64().unwrap();
            assert_eq!(sec * 1_000_000_000 + nsec, m["log_time"].as_u64().unwrap());
            noted.push(path.to_string());
        }
    }
    // The last pass wrote into the file still open at the stop, which no pass deleted.
    let last = deleted.last().unwrap();
    assert!(
        noted.contains(last),
        "the last deletion {last} is not in the surviving logs; noted: {noted:?}"
    );
}

/// Everything under `/dev/shm` named with `prefix`, and every file under `root`.
fn iox_entries(prefix: &str, root: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else {
                out.push(path);
            }
        }
    }
    let mut out: Vec<PathBuf> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .map(|e| e.path())
        .collect();
    walk(root, &mut out);
    out.sort();
    out
}

#[test]
fn issue11_a_killed_daemons_iceoryx2_resources_are_removed_and_said_at_the_next_start() {
    let dir = scratch_dir("lifecycle-dead-node");
    let data = dir.join("data");
    let pid = std::process::id();
    let prefix = format!("bdlc{pid}_");
    let root = PathBuf::from(format!("/dev/shm/bearingd-lifecycle-dead-{pid}"));
    let config = config_file(&dir, |text| {
        text.replace(
            "\"/run/bearingd/iceoryx2\"",
            &format!("\"{}\"", root.display()),
        )
    });
    let run = |extra: &[&str]| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_bearingd"));
        cmd.env("BEARINGD_IOX_PREFIX", &prefix)
            .args(["run", "--config", config.to_str().unwrap(), "--quiet"])
            .args(["--data-dir", data.to_str().unwrap()])
            .args(extra);
        cmd
    };
    let mut first = run(&[])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Up once its log has data (the alert service starts before the sources).
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while mcap_files(&data.join("mcap"))
        .last()
        .is_none_or(|f| std::fs::metadata(f).unwrap().len() < 20_000)
    {
        assert!(
            std::time::Instant::now() < deadline,
            "the first daemon did not start"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    first.kill().unwrap();
    first.wait().unwrap();
    // iceoryx2's global management segment (`…node.<version>.global_mgmt`) is shared by every
    // node of the prefix and kept by iceoryx2 across processes (a clean stop leaves it too): it
    // is not the dead node's.
    let left: Vec<PathBuf> = iox_entries(&prefix, &root)
        .into_iter()
        .filter(|p| !p.to_string_lossy().ends_with(".global_mgmt"))
        .collect();
    assert!(!left.is_empty(), "the killed daemon left nothing to clean?");
    let second = run(&["--fast", "--duration", "1"]).output().unwrap();
    let stderr = stderr_of(&second);
    assert!(second.status.success(), "{stderr}");
    let said: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("removed the stale resources of a dead node"))
        .collect();
    assert!(
        said.iter()
            .any(|l| l.contains(&format!("pid {}", first.id())) && l.contains("bearingd")),
        "the cleanup of pid {} is not said: {stderr}",
        first.id()
    );
    let still: Vec<&PathBuf> = left.iter().filter(|p| p.exists()).collect();
    let _ = std::fs::remove_dir_all(&root);
    assert!(
        still.is_empty(),
        "the killed daemon's iceoryx2 entries are still there: {still:?} (of {left:?})"
    );
}
