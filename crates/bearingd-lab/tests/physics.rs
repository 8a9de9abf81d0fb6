//! The physics twin through the lab's command line (issue 14): `simulate --model physics` writes
//! records `analyze` reads and diagnoses; `calibrate` fits a real CWRU record, prints the
//! parameters and the fit error, draws the spectra and saves parameters that `simulate
//! --calibrated` uses.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd_testdata::{scratch_dir, shared_data_dir};
use std::process::Output;

fn lab(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd-lab"), args)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Simulates `fault` with the physics twin into `path`, analyses it, returns the diagnosis.
fn simulate_and_diagnose(extra: &[&str], path: &str) -> String {
    let mut args = vec![
        "simulate",
        "--model",
        "physics",
        "--rpm",
        "1797",
        "--duration",
        "3s",
        "--noise",
        "0.05",
        "--out",
        path,
    ];
    args.extend_from_slice(extra);
    let made = lab(&args);
    assert!(made.status.success(), "{args:?}: {}", stderr(&made));
    let out = lab(&[
        "analyze",
        path,
        "--rpm",
        "1797",
        "--bearing",
        "skf-6205-2rs",
        "--fs",
        "12000",
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    json["diagnosis"].as_str().unwrap_or_default().to_string()
}

#[test]
fn physics_records_are_read_and_diagnosed_by_analyze() {
    let dir = scratch_dir("physics-simulate");
    for (fault, file, expected) in [
        ("outer", "outer.wav", "outer_race"),
        ("inner", "inner.csv", "inner_race"),
    ] {
        let path = dir.join(file);
        let diagnosis = simulate_and_diagnose(
            &["--fault", fault, "--resonance", "3200"],
            path.to_str().unwrap(),
        );
        assert_eq!(diagnosis, expected, "{fault}");
    }
    // The 5-DOF variant too.
    let path = dir.join("outer5.wav");
    let diagnosis = simulate_and_diagnose(
        &["--fault", "outer", "--resonance", "3200", "--dof", "five"],
        path.to_str().unwrap(),
    );
    assert_eq!(diagnosis, "outer_race");
}

#[test]
fn calibrate_fits_a_cwru_record_and_its_parameters_simulate() {
    let Some(cwru) = shared_data_dir("cwru") else {
        return;
    };
    let dir = scratch_dir("physics-calibrate");
    let record = cwru.join("12k_Drive_End_OR007@6_0_130.mat");
    let plot = dir.join("calibration.png");
    let saved = dir.join("cwru130.json");
    // A small budget: CI checks the command, docs/PHYSICS.md has the full calibration.
    let out = lab(&[
        "calibrate",
        record.to_str().unwrap(),
        "--population",
        "10",
        "--generations",
        "4",
        "--plot",
        plot.to_str().unwrap(),
        "--save",
        saved.to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    let text = String::from_utf8_lossy(&out.stdout);
    for needle in ["k_r", "c_r", "k_b", "defect width", "fit error", "dB"] {
        assert!(text.contains(needle), "{text} lacks {needle}");
    }
    // The envelope diagnosis chose the fault; progress was shown per generation.
    assert!(err.contains("outer_race"), "{err}");
    assert!(err.contains("generation   4/4"), "{err}");
    // The fit beats the literature defaults.
    let numbers: Vec<f64> = text
        .lines()
        .find(|l| l.contains("fit error"))
        .unwrap()
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter_map(|w| w.parse().ok())
        .collect();
    assert!(numbers[0] < numbers[1], "{text}");
    let png = std::fs::read(&plot).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000);
    let wav = dir.join("what-if.wav");
    let diagnosis = simulate_and_diagnose(
        &["--calibrated", saved.to_str().unwrap(), "--fault", "outer"],
        wav.to_str().unwrap(),
    );
    assert_eq!(diagnosis, "outer_race");
}

#[test]
fn calibrate_refuses_bad_input_in_one_line() {
    let dir = scratch_dir("physics-calibrate-bad");
    for (args, needle) in [
        (
            vec!["calibrate", "/nonexistent/x.mat"],
            "/nonexistent/x.mat",
        ),
        (
            vec!["calibrate", "/nonexistent/x.mat", "--band", "4000-2000"],
            "--band 4000-2000",
        ),
    ] {
        let out = lab(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    }
    let bad = dir.join("bad.json");
    std::fs::write(&bad, "{not json").unwrap();
    let out = lab(&[
        "simulate",
        "--model",
        "physics",
        "--calibrated",
        bad.to_str().unwrap(),
        "--out",
        dir.join("x.wav").to_str().unwrap(),
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bad.json") && err.contains("calibrate --save"),
        "{err}"
    );
}
