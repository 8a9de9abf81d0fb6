//! `bearingd-lab trend` (`bearingd trend`) on run-to-failure data (issue 13 item 4): on both FEMTO/PRONOSTIA dev
//! bearings the health stage never leaves "healthy" in the first half of life and the failure
//! stage is entered before the end; on the IMS files (healthy, five snapshots) it never leaves
//! healthy; unreadable snapshots are skipped, counted and named, never silently.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd_testdata::{read_manifest, scratch_dir, shared_data_dir};
use serde_json::Value;
use std::collections::HashMap;
use std::path::Path;
use std::process::Output;

fn lab(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd-lab"), args)
}

/// The service binary, for `import`.
fn bearingd(args: &[&str]) -> Output {
    let service = bearingd_testdata::binary_beside(env!("CARGO_BIN_EXE_bearingd-lab"), "bearingd");
    bearingd_testdata::run_binary(service.to_str().unwrap(), args)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs `trend` with `extra` options and returns its JSON report.
fn trend_json(dir: &Path, extra: &[&str]) -> Value {
    let mut args = vec!["trend", dir.to_str().unwrap(), "--format", "json"];
    args.extend_from_slice(extra);
    let out = lab(&args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("trend --format json prints JSON")
}

fn stage_at(event: &Value) -> (String, String) {
    (
        event["to"].as_str().unwrap().to_string(),
        event["source"].as_str().unwrap().to_string(),
    )
}

/// Checks item 4's criteria on one FEMTO bearing against the manifest's life fraction;
/// returns the report (`None`: no data outside CI).
fn check_femto(bearing: &str, rpm: &str, extra: &[&str]) -> Option<Value> {
    let femto = shared_data_dir("femto")?;
    let life_frac: HashMap<String, f64> = read_manifest(&femto)
        .into_iter()
        .filter(|row| row["bearing"] == bearing)
        .map(|row| {
            let name = row["file"].rsplit('/').next().unwrap().to_string();
            (name, row["life_frac"].parse().unwrap())
        })
        .collect();
    let dir = femto.join(bearing);
    let plot = scratch_dir("trend").join(format!("{bearing}.svg"));
    let mut options = vec!["--rpm", rpm, "--plot", plot.to_str().unwrap()];
    options.extend_from_slice(extra);
    let report = trend_json(&dir, &options);

    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), life_frac.len(), "every snapshot used");
    assert!(report["skipped"].as_array().unwrap().is_empty());
    let events: Vec<(String, String)> = report["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(stage_at)
        .collect();
    let frac = |source: &str| life_frac[source];
    let left_healthy: Vec<_> = events
        .iter()
        .filter(|(to, _)| to == "degrading" || to == "failing")
        .filter(|(_, source)| frac(source) < 0.5)
        .collect();
    assert!(
        left_healthy.is_empty(),
        "{bearing}: left the healthy stage in the first half of life: {left_healthy:?} (all: {events:?})"
    );
    assert!(
        events.iter().any(|(to, _)| to == "healthy"),
        "{bearing}: never learned its baseline: {events:?}"
    );
    let failing = events
        .iter()
        .find(|(to, _)| to == "failing")
        .unwrap_or_else(|| panic!("{bearing}: never entered the failure stage: {events:?}"));
    assert!(
        frac(&failing.1) < 1.0,
        "{bearing}: the failure stage came only at the last snapshot: {failing:?}"
    );
    // The stages only move forward, in order.
    let order: Vec<&str> = events.iter().map(|(to, _)| to.as_str()).collect();
    assert_eq!(order, ["healthy", "degrading", "failing"], "{bearing}");

    // The trend: estimates once degrading with a learned limit, and a hindsight judgement.
    let hindsight = &report["hindsight"];
    assert!(
        hindsight["estimates"].as_u64().unwrap() > 0,
        "{bearing}: no trend estimate before the crossing: {hindsight}"
    );
    assert!(hindsight["crossed_s"].as_f64().unwrap() > 0.0);
    let svg = std::fs::read_to_string(&plot).unwrap();
    assert!(
        svg.starts_with("<svg") || svg.starts_with("<?xml"),
        "{}",
        plot.display()
    );
    assert!(svg.contains("failing") && svg.contains("time to threshold"));
    Some(report)
}

#[test]
fn issue13_femto_bearing1_2_stays_healthy_in_the_first_half_and_fails_before_the_end() {
    // Without the HW model (the stages do not use it) to keep the suite short.
    check_femto("Bearing1_2", "1800", &["--no-hw"]);
}

#[test]
fn issue13_femto_bearing3_1_stays_healthy_in_the_first_half_and_fails_before_the_end() {
    let Some(report) = check_femto("Bearing3_1", "1500", &[]) else {
        return;
    };
    // With the HW model: every snapshot has its residual.
    let residuals: Vec<f64> = report["points"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["hw_residual_percent"].as_f64().expect("HW residual"))
        .collect();
    assert!(residuals.iter().all(|r| (0.0..=100.0).contains(r)));
}

#[test]
fn ims_snapshots_stay_healthy_and_the_manifest_is_ignored_not_hidden() {
    let Some(ims) = shared_data_dir("ims") else {
        return;
    };
    // Five 1 s snapshots, each one window: a baseline of 3, then 2 snapshots judged.
    let report = trend_json(&ims, &["--baseline", "3", "--window", "1", "--no-hw"]);
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 5, "{report}");
    let events: Vec<_> = report["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(stage_at)
        .collect();
    assert_eq!(events.len(), 1, "{events:?}");
    assert_eq!(events[0].0, "healthy");
    assert_eq!(points[4]["stage"], "healthy");
    assert_eq!(report["ignored"], serde_json::json!(["manifest.csv"]));
    // IMS runs at 2000 rpm: the fault score is there.
    assert!(points.iter().all(|p| p["fault_score"].is_number()));
}

#[test]
fn unreadable_snapshots_are_skipped_counted_and_named() {
    let Some(femto) = shared_data_dir("femto") else {
        return;
    };
    let dir = scratch_dir("trend-bad");
    for i in [1, 11, 21, 31, 41, 51] {
        let name = format!("acc_{i:05}.csv");
        std::fs::copy(femto.join("Bearing1_2").join(&name), dir.join(&name)).unwrap();
    }
    std::fs::write(dir.join("acc_00061.csv"), "not,a,pronostia\nfile\n").unwrap();
    std::fs::write(dir.join("notes.txt"), "written by hand").unwrap();
    let out = lab(&["trend", dir.to_str().unwrap(), "--baseline", "3", "--no-hw"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(text.contains("6 snapshots"), "{text}");
    assert!(
        text.contains("skipped 1 file(s) that could not be used"),
        "{text}"
    );
    assert!(text.contains("acc_00061.csv"), "{text}");
    assert!(
        text.contains("ignored 1 file(s) that are not snapshots: notes.txt"),
        "{text}"
    );
    assert!(
        text.contains("give --rpm"),
        "no speed: says how to get the fault score: {text}"
    );

    // A directory with nothing usable is an input error naming the files.
    let empty = scratch_dir("trend-empty");
    std::fs::write(empty.join("acc_00001.csv"), "1,2\n").unwrap();
    let out = lab(&["trend", empty.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let err = stderr(&out);
    assert!(
        err.contains("no usable snapshot") && err.contains("acc_00001.csv"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_bearingd_log_is_cut_into_windows_in_sample_time() {
    let Some(ims) = shared_data_dir("ims") else {
        return;
    };
    let dir = scratch_dir("trend-log");
    let out = bearingd(&[
        "import",
        ims.join("2003.10.22.12.14.13").to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = bearingd_testdata::mcap_files(&dir)
        .pop()
        .expect("import wrote a log");
    // 20,480 samples at 20 kHz in windows of 0.25 s: 4 snapshots, 0.25 s apart.
    let report = trend_json(
        &log,
        &[
            "--window",
            "0.25",
            "--baseline",
            "2",
            "--no-hw",
            "--rpm",
            "2000",
            "--bearing",
            "rexnord-za-2115",
        ],
    );
    let points = report["points"].as_array().unwrap();
    let times: Vec<f64> = points
        .iter()
        .map(|p| p["time_s"].as_f64().unwrap())
        .collect();
    assert_eq!(times, [0.0, 0.25, 0.5, 0.75], "{report}");
    assert!(points[3]["source"].as_str().unwrap().ends_with(".mcap#3"));
    assert!(points.iter().all(|p| p["fault_score"].is_number()));
}

/// `bearingd run --fast` of `seconds` of the embedded default (a simulated sensor that
/// develops an outer-race fault), `config` replacing it when given; returns the log's path.
fn daemon_log(tag: &str, seconds: u32, config: Option<&Path>) -> std::path::PathBuf {
    let data = scratch_dir(tag);
    let duration = seconds.to_string();
    let mut args = vec![
        "run",
        "--fast",
        "--duration",
        &duration,
        "--data-dir",
        data.to_str().unwrap(),
        "--quiet",
    ];
    if let Some(config) = config {
        args.extend(["--config", config.to_str().unwrap()]);
    }
    let out = bearingd(&args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    bearingd_testdata::mcap_files(&data.join("mcap"))
        .pop()
        .expect("bearingd run wrote a log")
}

fn note_with<'a>(report: &'a Value, text: &str) -> Option<&'a str> {
    report["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .find(|n| n.contains(text))
}

/// Issue 33 item 5: on a daemon log the HW residual is the daemon's own (`/hw`), not
/// identified again per window (0.8 s of CPU each); progress lines go to stderr in a pipe.
#[test]
fn a_daemon_log_s_hw_fits_are_used_not_identified_again() {
    let log = daemon_log("trend-hw-log", 40, None);
    let dir = log.parent().unwrap();
    let args = ["trend", dir.to_str().unwrap(), "--format", "json"];
    let out = lab(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: Value = serde_json::from_slice(&out.stdout).unwrap();
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 40, "{report}");
    let with_hw: Vec<&Value> = points
        .iter()
        .filter(|p| p["hw_residual_percent"].is_number())
        .collect();
    // One fit per twin re-fit (every 10 s of sample time), each from the log.
    assert!((2..=5).contains(&with_hw.len()), "{}", with_hw.len());
    assert!(with_hw.iter().all(|p| p["hw_from"] == "log"), "{with_hw:?}");
    assert!(
        note_with(&report, "the daemon's own fits").is_some(),
        "{report}"
    );
    // In a pipe: plain progress lines, the last one complete.
    let err = stderr(&out);
    assert!(err.contains("trend: 1/1 files, 40 snapshots"), "{err}");
}

/// Without `/hw` in the log (HW off) the model is identified on each snapshot, said once.
#[test]
fn a_log_without_hw_fits_falls_back_to_identifying_and_says_so() {
    let out = bearingd(&["config", "default"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("hw_enabled = true"));
    let config = scratch_dir("trend-hw-off").join("bearingd.toml");
    std::fs::write(
        &config,
        text.replace("hw_enabled = true", "hw_enabled = false"),
    )
    .unwrap();
    let log = daemon_log("trend-hw-off-log", 4, Some(&config));
    let report = trend_json(&log, &["--baseline", "2"]);
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 4, "{report}");
    assert!(
        points.iter().all(|p| p["hw_from"] == "fit"),
        "every snapshot identified: {report}"
    );
    let notes: Vec<&str> = report["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_str)
        .filter(|n| n.contains("hold no HW fit"))
        .collect();
    assert_eq!(notes.len(), 1, "said once: {report}");
}

/// Imports an IMS file as a log and copies it into `dir` under `name`.
fn imported_as(ims: &Path, file: &str, dir: &Path, name: &str) {
    let out_dir = scratch_dir("trend-import");
    let out = bearingd(&[
        "import",
        ims.join(file).to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let log = bearingd_testdata::mcap_files(&out_dir)
        .pop()
        .expect("import wrote a log");
    std::fs::copy(log, dir.join(name)).unwrap();
}

/// Issue 33 item 5: logs are placed by their anchor (`log_time_origin_ns`), not their names;
/// the 50 min between two of them is a gap, said in the JSON and the table.
#[test]
fn logs_are_ordered_by_their_anchor_and_a_gap_between_them_is_shown() {
    let Some(ims) = shared_data_dir("ims") else {
        return;
    };
    let dir = scratch_dir("trend-anchor");
    // The earlier recording under the later name, and the other way round.
    let (early, late) = (
        "bearingd-20300101T000000Z-000000.mcap",
        "bearingd-20000101T000000Z-000000.mcap",
    );
    imported_as(&ims, "2003.10.22.12.14.13", &dir, early);
    imported_as(&ims, "2003.10.22.13.04.13", &dir, late);
    let options = [
        "--window",
        "0.25",
        "--baseline",
        "2",
        "--no-hw",
        "--rpm",
        "2000",
        "--bearing",
        "rexnord-za-2115",
    ];
    let report = trend_json(&dir, &options);
    assert!(report["skipped"].as_array().unwrap().is_empty(), "{report}");
    let points = report["points"].as_array().unwrap();
    let sources: Vec<&str> = points
        .iter()
        .map(|p| p["source"].as_str().unwrap())
        .collect();
    assert_eq!(sources.len(), 8, "{sources:?}");
    assert!(
        sources[..4].iter().all(|s| s.starts_with(early)),
        "{sources:?}"
    );
    assert!(
        sources[4..].iter().all(|s| s.starts_with(late)),
        "{sources:?}"
    );
    let times: Vec<f64> = points
        .iter()
        .map(|p| p["time_s"].as_f64().unwrap())
        .collect();
    assert_eq!(&times[..4], [0.0, 0.25, 0.5, 0.75]);
    assert!((times[4] - 3000.0).abs() < 1.0, "{times:?}");
    let gaps = report["gaps"].as_array().unwrap();
    assert_eq!(gaps.len(), 1, "{report}");
    // Each IMS file: 20,480 samples at 20 kHz.
    assert!(
        (gaps[0]["from_s"].as_f64().unwrap() - 1.024).abs() < 1e-6,
        "{gaps:?}"
    );
    assert_eq!(gaps[0]["to_s"].as_f64().unwrap(), times[4]);
    assert!(gaps[0]["before"].as_str().unwrap().starts_with(late));

    let mut args = vec!["trend", dir.to_str().unwrap(), "--format", "table"];
    args.extend_from_slice(&options);
    let out = lab(&args);
    let table = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<&str> = table.lines().skip(2).collect();
    assert!(rows[4].starts_with("| (gap) | 1.0 to 3000.0 |"), "{table}");
}

/// Issue 33 item 5: two `run --fast` logs (dated in sample time, so the second starts before
/// the first ends) are read one after the other, none skipped, whatever their names.
#[test]
fn fast_runs_overlapping_in_time_are_placed_one_after_the_other() {
    let first = daemon_log("trend-fast-1", 6, None);
    let second = daemon_log("trend-fast-2", 6, None);
    let dir = scratch_dir("trend-fast");
    std::fs::copy(&first, dir.join("bearingd-20991231T000000Z-000000.mcap")).unwrap();
    std::fs::copy(&second, dir.join("bearingd-20000101T000000Z-000000.mcap")).unwrap();
    let report = trend_json(&dir, &["--baseline", "2", "--no-hw"]);
    assert!(report["skipped"].as_array().unwrap().is_empty(), "{report}");
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 12, "{report}");
    assert!(points[0]["source"]
        .as_str()
        .unwrap()
        .starts_with("bearingd-2099"));
    let times: Vec<f64> = points
        .iter()
        .map(|p| p["time_s"].as_f64().unwrap())
        .collect();
    for (i, t) in times.iter().enumerate() {
        assert!((t - i as f64).abs() < 1e-6, "{times:?}");
    }
    assert!(
        note_with(&report, "placed right after").is_some(),
        "{report}"
    );
}

/// Issue 33 item 5: without `--rpm` the FEMTO manifest's speed (1800 rpm) is used, so every
/// snapshot has its fault score, and the note says where the speed came from.
#[test]
fn the_manifest_s_speed_gives_the_fault_score_without_rpm() {
    let Some(femto) = shared_data_dir("femto") else {
        return;
    };
    let dir = scratch_dir("trend-manifest").join("Bearing1_2");
    std::fs::create_dir_all(&dir).unwrap();
    let mut manifest = String::new();
    for (i, line) in std::fs::read_to_string(femto.join("manifest.csv"))
        .unwrap()
        .lines()
        .enumerate()
    {
        // The header and the first 6 snapshots of Bearing1_2, beside copies of their files.
        if i == 0 || (line.starts_with("Bearing1_2/") && manifest.lines().count() < 7) {
            manifest.push_str(line);
            manifest.push('\n');
            if i > 0 {
                let file = line.split(',').next().unwrap();
                std::fs::copy(femto.join(file), dir.parent().unwrap().join(file)).unwrap();
            }
        }
    }
    std::fs::write(dir.parent().unwrap().join("manifest.csv"), &manifest).unwrap();
    let report = trend_json(&dir, &["--baseline", "3", "--no-hw"]);
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 6, "{report}");
    assert!(
        points.iter().all(|p| p["fault_score"].is_number()),
        "{report}"
    );
    let note = note_with(&report, "the data set's manifest").unwrap_or_default();
    assert!(note.contains("1800 rpm"), "{report}");
    assert!(note_with(&report, "give --rpm").is_none(), "{report}");

    // A manifest that cannot be read is said, with the reason and the way out, not skipped
    // in silence.
    std::fs::write(
        dir.parent().unwrap().join("manifest.csv"),
        "name,rpm\nBearing1_2/acc_00001.csv,1800\n",
    )
    .unwrap();
    let report = trend_json(&dir, &["--baseline", "3", "--no-hw"]);
    let note = note_with(&report, "not a readable data set manifest").unwrap_or_default();
    assert!(
        note.contains("manifest.csv")
            && note.contains("no `file` column")
            && note.contains("give --rpm"),
        "{report}"
    );
    assert!(
        note_with(&report, "the data set's manifest:").is_none(),
        "{report}"
    );
}

/// A log whose daemon fits the HW model but holds no fit yet (4 s, before the first re-fit
/// at 10 s) is not identified again: its snapshots have no HW residual.
#[test]
fn a_log_of_a_daemon_with_hw_on_is_never_identified_again() {
    let log = daemon_log("trend-hw-none-yet", 4, None);
    let report = trend_json(&log, &["--baseline", "2"]);
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 4, "{report}");
    assert!(points.iter().all(|p| p["hw_from"].is_null()), "{report}");
    assert!(note_with(&report, "hold no HW fit").is_none(), "{report}");
}

/// Issue 33 item 4: a folder of what `simulate` writes as WAV trends in g, its channel named,
/// with the same RMS as the same record written as CSV; an integer WAV is said to be relative.
#[test]
fn simulated_wavs_trend_in_g_and_integer_wavs_are_said_to_be_relative() {
    let dir = scratch_dir("trend-wav-units");
    let (wavs, csvs) = (dir.join("wav"), dir.join("csv"));
    for (folder, ext) in [(&wavs, "wav"), (&csvs, "csv")] {
        std::fs::create_dir_all(folder).unwrap();
        for k in 1..=3 {
            let out = folder.join(format!("snapshot{k}.{ext}"));
            let made = lab(&[
                "simulate",
                "--fault",
                "outer",
                "--rpm",
                "1772",
                "--duration",
                "1s",
                "--out",
                out.to_str().unwrap(),
            ]);
            assert!(made.status.success(), "{}", stderr(&made));
        }
    }
    // Their names state no time: without --interval the WAVs are skipped, each named.
    let out = lab(&["trend", wavs.to_str().unwrap(), "--rpm", "1772"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("snapshot1.wav") && stderr(&out).contains("--interval"),
        "{}",
        stderr(&out)
    );
    let given = [
        "--baseline",
        "2",
        "--window",
        "1",
        "--no-hw",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--interval",
        "60",
    ];
    let from_wav = trend_json(&wavs, &given);
    let from_csv = trend_json(&csvs, &[&given[..], &["--fs", "12000"]].concat());
    assert_eq!(from_wav["channel"], "accel_g");
    let notes = from_wav["notes"].to_string();
    assert!(notes.contains("float WAV samples taken as g"), "{notes}");
    assert!(!notes.contains("full scale, not g"), "{notes}");
    let rms = |report: &Value| -> Vec<f64> {
        let points = report["points"].as_array().unwrap();
        points.iter().map(|p| p["rms"].as_f64().unwrap()).collect()
    };
    let (rms_wav, rms_csv) = (rms(&from_wav), rms(&from_csv));
    assert_eq!(rms_wav.len(), 3);
    assert_eq!(rms_wav.len(), rms_csv.len());
    for (w, c) in rms_wav.iter().zip(&rms_csv) {
        assert!((w - c).abs() <= 1e-6 * c, "WAV RMS {w} g, CSV {c} g");
    }

    // The same folder as 16-bit counts: relative, and the note says what does not apply.
    let ints = dir.join("int");
    std::fs::create_dir_all(&ints).unwrap();
    for k in 1..=3 {
        let mut reader = hound::WavReader::open(wavs.join(format!("snapshot{k}.wav"))).unwrap();
        let spec = hound::WavSpec {
            bits_per_sample: 16,
            sample_format: hound::SampleFormat::Int,
            ..reader.spec()
        };
        let mut w = hound::WavWriter::create(ints.join(format!("snapshot{k}.wav")), spec).unwrap();
        for s in reader.samples::<f32>() {
            w.write_sample((s.unwrap() * 3000.0) as i16).unwrap();
        }
        w.finalize().unwrap();
    }
    let relative = trend_json(&ints, &given);
    let notes = relative["notes"].to_string();
    assert!(notes.contains("fractions of full scale, not g"), "{notes}");
    assert!(
        notes.contains("failure threshold in g does not apply"),
        "{notes}"
    );
}
