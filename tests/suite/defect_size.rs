//! The defect size in `analyze` (issue 30 item 6): reported from a 48 kHz record of the physics
//! twin, `null` with the reason on every CWRU record (12 kHz, or no race fault named), and no
//! size on CWRU's healthy 48 kHz record even when asked for one of either race.

use crate::cli::{bearingd, stderr};
use bearingd::analysis::defect_size::{measure_for_fault, NotMeasured};
use bearingd::analysis::record::RecordAnalyzer;
use bearingd::analysis::AnalysisSettings;
use bearingd::bearing::{BearingGeometry, FaultKind};
use bearingd::recording::{read_recording, ReadOptions};
use bearingd_testdata::{scratch_dir, shared_data_dir};
use std::path::Path;

fn analyze_json(path: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["analyze", path.to_str().unwrap(), "--format", "json"];
    args.extend_from_slice(extra);
    let out = bearingd(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn analyze_reports_the_size_of_a_48_khz_physics_twin_defect() {
    let dir = scratch_dir("defect-size");
    let wav = dir.join("outer-1mm.wav");
    let made = bearingd(&[
        "simulate",
        "--model",
        "physics",
        "--fault",
        "outer",
        "--rpm",
        "1797",
        "--fs",
        "48000",
        "--duration",
        "2s",
        "--defect-width",
        "1.0",
        "--load",
        "2000",
        "--resonance",
        "3000",
        "--noise",
        "0.05",
        "--seed",
        "5",
        "--out",
        wav.to_str().unwrap(),
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    let condition = ["--rpm", "1797", "--bearing", "skf-6205-2rs"];
    let json = analyze_json(&wav, &condition);
    assert_eq!(json["diagnosis"], "outer_race");
    let size = &json["defect_size_mm"];
    let value = size["value"].as_f64().unwrap();
    assert!((value - 1.0).abs() <= 0.5, "{size}");
    assert!(size["uncertainty"].as_f64().unwrap() > 0.0, "{size}");
    assert!(
        size["method"].as_str().unwrap().contains("entry-exit"),
        "{size}"
    );
    assert!(json.get("defect_size_note").is_none(), "{json}");
    let out = bearingd(&[
        "analyze",
        wav.to_str().unwrap(),
        "--rpm",
        "1797",
        "--bearing",
        "skf-6205-2rs",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("defect size: {value:.2} ± ")),
        "{text}"
    );
}

#[test]
fn no_size_on_any_cwru_record_and_the_note_says_why() {
    let Some(cwru) = shared_data_dir("cwru") else {
        return;
    };
    let mut files: Vec<_> = std::fs::read_dir(&cwru)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mat"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 19,
        "{} records in {}",
        files.len(),
        cwru.display()
    );
    let mut twelve_khz_race = 0;
    for file in &files {
        let json = analyze_json(file, &[]);
        assert!(
            json["defect_size_mm"].is_null(),
            "{}: {json}",
            file.display()
        );
        let note = json["defect_size_note"].as_str().unwrap();
        let diagnosis = json["diagnosis"].as_str().unwrap();
        if json["fs_hz"] == 12_000.0 && diagnosis.ends_with("_race") {
            assert_eq!(
                note,
                "needs ≥ 40 kHz; this record is 12 kHz",
                "{}",
                file.display()
            );
            twelve_khz_race += 1;
        } else {
            assert!(
                note.starts_with(&format!("the verdict is {diagnosis}")),
                "{note}"
            );
        }
    }
    assert!(
        twelve_khz_race >= 8,
        "only {twelve_khz_race} race verdicts at 12 kHz"
    );
}

/// CWRU's healthy baseline is sampled at 48 kHz: sized as if it had a defect of either race,
/// it must give no number (there are no entry and exit events to find).
#[test]
fn the_healthy_48_khz_cwru_record_has_no_defect_size() {
    let Some(cwru) = shared_data_dir("cwru") else {
        return;
    };
    let recording = read_recording(&cwru.join("normal_0_97.mat"), &ReadOptions::default()).unwrap();
    let fs = recording.fs_hz.unwrap();
    assert_eq!(fs, 48_000.0);
    let rpm = recording.rpm.unwrap_or(1797.0);
    let bearing = BearingGeometry::from_catalog("skf-6205-2rs").unwrap();
    let samples: Vec<f32> = recording.samples.iter().map(|&v| v as f32).collect();
    let analysis = RecordAnalyzer::default()
        .analyze(
            &samples,
            fs,
            &bearing.fault_frequencies(rpm / 60.0),
            &AnalysisSettings::default(),
        )
        .unwrap();
    for fault in [FaultKind::OuterRace, FaultKind::InnerRace] {
        let size = measure_for_fault(&samples, &analysis, fault, &bearing);
        assert!(
            matches!(
                size,
                Err(NotMeasured::NotResolved(_) | NotMeasured::TooFewImpacts { .. })
            ),
            "{fault:?}: {size:?}"
        );
    }
}
