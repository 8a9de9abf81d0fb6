//! Issue 16 item 4: `bearingd analyze` reports the ISO 10816-3 / 20816-3 velocity severity
//! and zone for the machine group and foundation given, and draws the velocity spectrum. The
//! record is an analytic sine, whose velocity RMS is known in closed form: a peak
//! acceleration `a` g at `f` Hz is `a·g₀/(2πf)/√2` m/s RMS.

use bearingd_testdata::{iox_root, scratch_dir};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

fn analyze(file: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "analyze",
        file.to_str().unwrap(),
        "--fs",
        "12000",
        "--rpm",
        "1800",
        "--bearing",
        "skf-6205-2rs",
        "--format",
        "json",
    ];
    args.extend_from_slice(extra);
    let out = bearingd(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// Velocity RMS in mm/s of a sine of peak acceleration `a_g` at `f_hz`.
fn analytic_mm_s(a_g: f64, f_hz: f64) -> f64 {
    a_g * 9.806_65 / (std::f64::consts::TAU * f_hz) / 2f64.sqrt() * 1e3
}

#[test]
fn issue16_analyze_reports_velocity_rms_and_zone_of_an_analytic_sine() {
    let dir = scratch_dir("severity-sine");
    let file = dir.join("sine.csv");
    // 0.5 g at 80 Hz for 10 s at 12 kHz: 6.90 mm/s RMS.
    bearingd_testdata::write_csv(
        &file,
        bearingd_testdata::sine_g(0.5, 80.0, 12_000.0, 120_000),
    );
    let want = analytic_mm_s(0.5, 80.0);

    let report = analyze(&file, &[]);
    let v = &report["velocity"];
    let got = v["rms_mm_s"].as_f64().unwrap();
    assert!((got - want).abs() / want < 0.01, "{got} vs {want} mm/s");
    assert_eq!(v["band_hz"], serde_json::json!([10.0, 1000.0]));
    // Group 2 (the default) on a rigid foundation: D from 4.5 mm/s.
    assert_eq!(v["zone"], "D");
    assert_eq!(v["settings"]["group"], "medium");
    assert_eq!(v["limits"]["cd_mm_s"], 4.5);

    // Group 1 on a flexible foundation: B from 3.5, C from 7.1 mm/s.
    let report = analyze(&file, &["--machine-group", "1", "--foundation", "flexible"]);
    assert_eq!(report["velocity"]["zone"], "B");
    assert_eq!(report["velocity"]["settings"]["foundation"], "flexible");

    // Below 600 rpm the band starts at 2 Hz.
    let mut slow = vec![
        "analyze",
        file.to_str().unwrap(),
        "--fs",
        "12000",
        "--rpm",
        "300",
        "--bearing",
        "skf-6205-2rs",
        "--format",
        "json",
    ];
    let out = bearingd(&slow);
    assert!(out.status.success());
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        report["velocity"]["band_hz"],
        serde_json::json!([2.0, 1000.0])
    );

    // The text names value and zone (the plot of the velocity spectrum: the lab's tests).
    slow.truncate(8);
    let out = bearingd(&slow);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("ISO 10816-3 velocity 6.9") && text.contains("zone D"),
        "{text}"
    );
}

/// Samples in fractions of full scale have no scale to g: no velocity, and the report says why
/// and how to state the unit. (A float WAV as `simulate` writes it is g since issue 33 item 4;
/// `--unit full-scale` makes it relative, as an integer WAV is: tests/suite/formats.rs.)
#[test]
fn issue16_a_record_in_full_scale_units_has_no_velocity_and_says_why() {
    let dir = scratch_dir("severity-wav");
    let wav = dir.join("rec.wav");
    let made = bearingd(&[
        "simulate",
        "--out",
        wav.to_str().unwrap(),
        "--duration",
        "2s",
    ]);
    assert!(made.status.success());
    let out = bearingd(&[
        "analyze",
        wav.to_str().unwrap(),
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--unit",
        "full-scale",
        "--format",
        "json",
    ]);
    assert!(out.status.success());
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["velocity"].is_null());
    let notes = report["notes"].to_string();
    assert!(
        notes.contains("no ISO 10816-3 velocity") && notes.contains("--unit g"),
        "{report:#}"
    );
}

/// What `tests/python/velocity_log.py` (Python `mcap`, strict reader) finds in the logs.
pub(crate) fn velocity_log(py: &Path, files: &[std::path::PathBuf]) -> Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/velocity_log.py");
    let out = Command::new(py)
        .arg(script)
        .args(files)
        .output()
        .expect("run velocity_log.py");
    assert!(
        out.status.success(),
        "velocity_log.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// A config of the simulated node with `imbalance_g` of once-per-revolution tone and no
/// bearing fault, logging under `dir`, its iceoryx2 root named by `iox_tag` (one per test),
/// with `extra` (TOML) at its end.
pub(crate) fn imbalance_config(
    dir: &Path,
    imbalance_g: f64,
    iox_tag: &str,
    extra: &str,
) -> std::path::PathBuf {
    // Outside /tmp (the config refuses it there), short enough for iceoryx2's socket paths.
    let iox = iox_root(env!("CARGO_TARGET_TMPDIR"), iox_tag);
    let text = format!(
        r#"[[sensors]]
id = "motor-de"
transport = "sim"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"
[sensors.speed]
source = "fixed"
rpm = 1772
[sensors.sim]
fault = "none"
imbalance_g = {imbalance_g}

[severity]
machine_group = 2
foundation = "rigid"

[outputs]
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"
{extra}
"#,
        state = dir.join("state").display(),
        mcap = dir.join("mcap").display(),
        iox = iox.display(),
    );
    let path = dir.join("bearingd.toml");
    std::fs::write(&path, text).unwrap();
    path
}

pub(crate) fn run_ok(args: &[&str]) -> String {
    let out = bearingd(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{args:?}: {stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// (from, to, end_sample) of every velocity zone flag change.
fn zone_flags(log: &Value) -> Vec<(String, String, u64)> {
    log["velocity_flags"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            (
                f["from"].as_str().unwrap().to_string(),
                f["to"].as_str().unwrap().to_string(),
                f["end_sample"].as_u64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn issue16_the_daemon_logs_velocity_and_raises_the_zone_flag_after_its_delay() {
    let Some(py) = bearingd_testdata::python_mcap() else {
        return;
    };
    let dir = scratch_dir("severity-daemon");
    // 0.1 g at the shaft rate (29.53 Hz): 3.74 mm/s, zone C of group 2 on a rigid foundation
    // (C from 2.8, D from 4.5 mm/s); the 0.05 g of noise adds 0.2 mm/s in quadrature.
    let config = imbalance_config(&dir, 0.1, "is", "");
    let stdout = run_ok(&[
        "run",
        "--config",
        config.to_str().unwrap(),
        "--fast",
        "--duration",
        "30",
        "--quiet",
    ]);
    assert!(
        stdout.contains("FLAG motor-de/radial: iso_zone ok -> watch"),
        "{stdout}"
    );
    assert!(stdout.contains("flags=iso_zone=watch"), "{stdout}");
    let live = bearingd_testdata::mcap_files(&dir.join("mcap"));
    let log = velocity_log(&py, &live);
    assert_eq!(
        log["schemas"]["/velocity/motor-de/radial"]["name"],
        "bearingd.Velocity"
    );
    assert_eq!(
        log["schemas"]["/velocity_flags/motor-de/radial"]["name"],
        "bearingd.VelocityFlag"
    );
    let readings = log["velocity"].as_array().unwrap();
    // 32,768-sample windows (10 Hz is 8 bins up at 25.6 kHz), a reading every half window.
    let hop = 16_384;
    assert!(
        readings.len() as u64 >= 30 * 25_600 / hop - 2,
        "{}",
        readings.len()
    );
    let want = analytic_mm_s(0.1, 1772.0 / 60.0);
    for r in readings {
        let v = r["rms_mm_s"].as_f64().unwrap();
        assert!((v - want).abs() / want < 0.03, "{r}: want {want:.3} mm/s");
        assert_eq!(r["zone"], "C", "{r}");
        assert_eq!(r["band_hz"], serde_json::json!([10.0, 1000.0]));
    }
    // The flag rises at the first reading 5 s (on_delay_s, in samples) after the first
    // reading in zone C, not before, and never changes again (the level holds).
    let first_c = readings[0]["end_sample"].as_u64().unwrap();
    let on_delay = 5 * 25_600;
    let raised_at = readings
        .iter()
        .map(|r| r["end_sample"].as_u64().unwrap())
        .find(|&s| s - first_c >= on_delay)
        .unwrap();
    assert_eq!(
        zone_flags(&log),
        [("ok".to_string(), "watch".to_string(), raised_at)]
    );
    for r in readings {
        let want_flag = if r["end_sample"].as_u64().unwrap() >= raised_at {
            "watch"
        } else {
            "ok"
        };
        assert_eq!(r["flag"], want_flag, "{r}");
    }
    // No bearing fault is simulated: no fault flag.
    assert_eq!(log["fault_flags"].as_array().unwrap().len(), 0);

    // A replay of the log through the same config raises the same zone flag at the same sample.
    let replay_dir = dir.join("replay");
    run_ok(&[
        "replay",
        live[0].to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--out",
        replay_dir.to_str().unwrap(),
        "--quiet",
    ]);
    let replayed = velocity_log(&py, &bearingd_testdata::mcap_files(&replay_dir));
    assert_eq!(zone_flags(&replayed), zone_flags(&log));
}

#[test]
fn issue16_the_healthy_embedded_default_stays_in_zone_b_without_a_zone_flag() {
    let Some(py) = bearingd_testdata::python_mcap() else {
        return;
    };
    let dir = scratch_dir("severity-default");
    let data = dir.join("data");
    // The embedded default, 0.05 g of imbalance (1.87 mm/s), with its outer-race fault from
    // 30 s: the impacts ring at 3 kHz, outside the band, and leave the velocity as it was.
    let stdout = run_ok(&[
        "run",
        "--fast",
        "--duration",
        "60",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    assert!(!stdout.contains("iso_zone"), "{stdout}");
    assert!(stdout.contains("iso=B("), "{stdout}");
    let log = velocity_log(&py, &bearingd_testdata::mcap_files(&data.join("mcap")));
    let readings = log["velocity"].as_array().unwrap();
    assert!(readings.len() >= 90, "{}", readings.len());
    let want = analytic_mm_s(0.05, 1772.0 / 60.0);
    for r in readings {
        let v = r["rms_mm_s"].as_f64().unwrap();
        assert!((v - want).abs() / want < 0.03, "{r}: want {want:.3} mm/s");
        assert_eq!((&r["zone"], &r["flag"]), (&"B".into(), &"ok".into()), "{r}");
    }
    assert!(zone_flags(&log).is_empty());
}
