//! The lab's command-line conventions (issue 33 item 3): every command honours `--format json`
//! (one JSON document on stdout carrying the result's key fields), and a long command shows its
//! progress on stderr only: plain lines in a pipe, an indicatif bar on a terminal.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd_testdata::{python_pty, scratch_dir};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

const LAB: &str = env!("CARGO_BIN_EXE_bearingd-lab");

fn lab(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(LAB, args)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `args` with `--format json`, expects success and one JSON document on stdout.
fn json_of(args: &[&str]) -> Value {
    let mut all = args.to_vec();
    all.extend(["--format", "json"]);
    let out = lab(&all);
    assert!(out.status.success(), "{all:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "{all:?}: stdout is not one JSON document ({e}): {}",
            String::from_utf8_lossy(&out.stdout)
        )
    })
}

/// Six records of 2 s: small enough for seconds, enough for a training epoch.
const SPEC: &str = r#"
seed = 3
faults = ["none", "outer_race"]
records_per_fault = 5
model = "signal"
duration_s = 2.0
fs_hz = 12000
bearing = "skf-6205-2rs"
rpm = [1700, 1800]
noise_g = [0.05, 0.1]
amplitude_g = [1.0, 1.5]
defect_width_mm = [0.178, 0.533]
load_n = [500, 2000]
"#;

fn s(path: &Path) -> &str {
    path.to_str().unwrap()
}

#[test]
fn simulate_dataset_train_and_calibrate_print_json_with_their_key_fields() {
    let dir = scratch_dir("cli-json");
    let record = dir.join("outer.csv");
    let sim = json_of(&["simulate", "--duration", "1s", "--out", s(&record)]);
    assert_eq!(sim["samples"], 12_000, "{sim}");
    assert_eq!(sim["fs_hz"], 12_000.0, "{sim}");
    assert!(
        sim["analyze"].as_str().unwrap().contains("--fs 12000"),
        "{sim}"
    );
    assert!(record.is_file());

    let spec = dir.join("spec.toml");
    std::fs::write(&spec, SPEC).unwrap();
    let set = dir.join("set");
    let made = json_of(&["dataset", "--spec", s(&spec), "--out", s(&set)]);
    assert_eq!(made["records"], 10, "{made}");
    assert_eq!(made["classes"], 2, "{made}");
    assert_eq!(made["model"], "signal", "{made}");
    assert!(set.join("dataset.npz").is_file());

    let model = dir.join("model.safetensors");
    let trained = json_of(&[
        "train",
        "--dataset",
        s(&set),
        "--out",
        s(&model),
        "--epochs",
        "2",
    ]);
    assert_eq!(trained["epochs"].as_array().unwrap().len(), 2, "{trained}");
    assert_eq!(
        trained["classes"],
        serde_json::json!(["none", "outer_race"])
    );
    let accuracy = trained["validation_accuracy"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&accuracy), "{trained}");
    assert!(model.is_file());

    let fit = json_of(&[
        "calibrate",
        s(&record),
        "--fs",
        "12000",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--fault",
        "outer",
        "--population",
        "4",
        "--generations",
        "1",
        "--simulated",
        "0.1",
    ]);
    assert!(fit["error_db"].as_f64().unwrap().is_finite(), "{fit}");
    assert_eq!(fit["band_hz"].as_array().unwrap().len(), 2, "{fit}");
    assert!(fit["params"].is_object(), "{fit}");
    // The notes are in the object, not on stderr.
    assert!(
        fit["notes"].is_array() && fit["warnings"].is_array(),
        "{fit}"
    );
}

/// The physics twin's record of `seconds`: long enough for a few progress steps.
fn physics_args(out: &Path, seconds: &str) -> Vec<String> {
    [
        "simulate",
        "--model",
        "physics",
        "--duration",
        seconds,
        "--fs",
        "12000",
        "--out",
    ]
    .iter()
    .map(|a| a.to_string())
    .chain([s(out).to_string()])
    .collect()
}

#[test]
fn progress_in_a_pipe_is_plain_lines_on_stderr_and_nothing_on_stdout() {
    let dir = scratch_dir("cli-pipe");
    let args = physics_args(&dir.join("p.wav"), "4s");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = lab(&args);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(out.stdout.is_empty(), "progress leaked to stdout");
    assert!(!err.contains('\r'), "a bar was drawn into a pipe: {err:?}");
    let counts: Vec<u64> = err
        .lines()
        .filter_map(|l| l.strip_prefix("simulate: "))
        .map(|rest| {
            let (count, tail) = rest.split_once(' ').unwrap();
            assert!(tail.starts_with("s of signal, physics twin, "), "{rest}");
            let (done, total) = count.split_once('/').unwrap();
            assert_eq!(total, "4", "{rest}");
            done.parse().unwrap()
        })
        .collect();
    assert!(counts.len() >= 2, "too few progress lines: {err}");
    assert_eq!(counts.last(), Some(&4), "{err}");
    assert!(counts.windows(2).all(|w| w[0] < w[1]), "{counts:?}");
}

#[test]
fn progress_on_a_terminal_is_an_indicatif_bar_and_no_plain_lines() {
    let Some(py) = python_pty() else { return };
    let dir = scratch_dir("cli-pty");
    let args = physics_args(&dir.join("p.wav"), "3s");
    // Runs the lab under a pseudo-terminal (stdout and stderr both on it) and prints what the
    // terminal received, escapes and carriage returns included.
    let script = r#"
import os, pty, sys
pid, fd = pty.fork()
if pid == 0:
    os.execv(sys.argv[1], sys.argv[1:])
seen = b""
while True:
    try:
        chunk = os.read(fd, 4096)
    except OSError:
        break
    if not chunk:
        break
    seen += chunk
_, status = os.waitpid(pid, 0)
sys.stdout.write(seen.decode("utf-8", "replace"))
sys.exit(os.waitstatus_to_exitcode(status))
"#;
    let out = Command::new(py)
        .args(["-c", script, LAB])
        .args(&args)
        .env("TERM", "xterm")
        .output()
        .unwrap();
    let seen = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{seen} {}", stderr(&out));
    // indicatif redraws its line in place: a carriage return and the erase-line escape.
    assert!(
        seen.contains("\r\u{1b}[2K"),
        "no bar redrawn in place: {seen:?}"
    );
    assert!(
        seen.contains("s of signal") && seen.contains("simulate "),
        "no bar of the template: {seen:?}"
    );
    assert!(
        !seen.contains("simulate: "),
        "plain lines on a terminal: {seen:?}"
    );
}

#[test]
fn evaluate_prints_its_summary_and_the_files_written_as_json() {
    let dir = scratch_dir("cli-json-evaluate");
    let out = dir.join("fa");
    let said = json_of(&[
        "evaluate",
        "--false-alarm-hours",
        "0.01",
        "--jobs",
        "2",
        "--out",
        s(&out),
    ]);
    assert_eq!(said["evaluation"], "false alarms", "{said}");
    assert!(
        said["summary"]["all"]["decisions"].as_u64().unwrap() > 0,
        "{said}"
    );
    let written: Vec<&str> = said["written"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    assert_eq!(written.len(), 2, "{said}");
    assert!(written.iter().all(|w| Path::new(w).is_file()), "{said}");
}
