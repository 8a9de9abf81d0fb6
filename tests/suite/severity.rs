//! Issue 16 item 4: `bearingd analyze` reports the ISO 10816-3 / 20816-3 velocity severity
//! and zone for the machine group and foundation given, and draws the velocity spectrum. The
//! record is an analytic sine, whose velocity RMS is known in closed form: a peak
//! acceleration `a` g at `f` Hz is `a·g₀/(2πf)/√2` m/s RMS.

use bearingd_testdata::scratch_dir;
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output};

fn bearingd(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(args)
        .output()
        .expect("run bearingd")
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
    let text: String = (0..120_000)
        .map(|n| {
            let t = n as f64 / 12_000.0;
            format!("{}\n", 0.5 * (std::f64::consts::TAU * 80.0 * t).sin())
        })
        .collect();
    std::fs::write(&file, text).unwrap();
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

    // The text names value and zone; the plot draws the velocity spectrum.
    slow.truncate(8);
    let plot = dir.join("sine.svg");
    slow.extend_from_slice(&["--plot", plot.to_str().unwrap()]);
    let out = bearingd(&slow);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("ISO 10816-3 velocity 6.9") && text.contains("zone D"),
        "{text}"
    );
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(
        svg.contains("velocity RMS per bin (mm/s)"),
        "no velocity panel"
    );
    assert!(svg.contains("zone D"), "the plot does not show the zone");
}

#[test]
fn issue16_a_wav_has_no_velocity_and_says_why() {
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
        "--format",
        "json",
    ]);
    assert!(out.status.success());
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(report["velocity"].is_null());
    assert!(
        report["warnings"]
            .to_string()
            .contains("no ISO 10816-3 velocity"),
        "{report:#}"
    );
}
