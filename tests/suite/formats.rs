//! Issue 16 item 3: every recording format people bring analyses with default options, taking
//! from the file what it states (sample rate, speed, bearing) and asking only for what it does
//! not. Fixtures are synthetic: the simulator's outer-race fault, written as a nested MATLAB
//! struct by `scipy.io.savemat`, logged to MCAP by `bearingd run`, cut to a 2,560-sample
//! PRONOSTIA snapshot, and written as WAV. No third-party data is committed or needed.

use bearingd_testdata::{python_scipy, scratch_dir, shared_data_dir};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

/// `bearingd analyze FILE ARGS --format json`, which must succeed.
fn analyze_json(file: &Path, args: &[&str]) -> Value {
    let mut all = vec!["analyze", file.to_str().unwrap()];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--format", "json"]);
    let out = bearingd(&all);
    assert!(
        out.status.success(),
        "{all:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("analyze JSON")
}

/// `bearingd analyze FILE ARGS`, which must fail with one line naming the file.
fn analyze_error(file: &Path, args: &[&str]) -> String {
    let mut all = vec!["analyze", file.to_str().unwrap()];
    all.extend_from_slice(args);
    let out = bearingd(&all);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{all:?}: {err}");
    assert_eq!(err.trim_end().lines().count(), 1, "not one line: {err}");
    let name = file.file_name().unwrap().to_string_lossy();
    assert!(err.contains(&*name), "does not name the file: {err}");
    err
}

/// A simulated outer-race record written by `bearingd simulate` (`.csv`: one column in g).
fn simulate(out: &Path, bearing: &str, rpm: f64, fs: f64, seconds: f64) {
    let made = bearingd(&[
        "simulate",
        "--fault",
        "outer",
        "--bearing",
        bearing,
        "--rpm",
        &rpm.to_string(),
        "--fs",
        &fs.to_string(),
        "--duration",
        &format!("{seconds}s"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
}

/// Writes a MATLAB fixture with `tests/python/make_mat.py` (scipy.io.savemat).
fn make_mat(py: &Path, layout: &str, samples: &Path, out: &Path, fs: f64, rpm: f64) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/make_mat.py");
    let made = Command::new(py)
        .arg(script)
        .args([layout, samples.to_str().unwrap(), out.to_str().unwrap()])
        .args([fs.to_string(), rpm.to_string()])
        .output()
        .expect("run make_mat.py");
    assert!(
        made.status.success(),
        "make_mat.py {layout}: {}",
        String::from_utf8_lossy(&made.stderr)
    );
}

fn assert_outer_race(report: &Value) {
    assert_eq!(report["diagnosis"], "outer_race", "{report:#}");
}

#[test]
fn issue16_mfpt_struct_mat_reads_rate_and_speed_from_the_file() {
    let Some(py) = python_scipy() else { return };
    let dir = scratch_dir("formats-mfpt");
    let samples = dir.join("sim.csv");
    // The MFPT set's rate is 48,828 Hz for its fault records, its shaft 25 Hz.
    simulate(&samples, "mfpt", 1500.0, 48_828.0, 3.0);
    let mat = dir.join("OuterRaceFault_1.mat");
    make_mat(&py, "mfpt", &samples, &mat, 48_828.0, 1500.0);

    // Only --bearing is missing from the file, and the MFPT layout names it.
    let report = analyze_json(&mat, &[]);
    assert_eq!(report["channel"], "bearing.gs");
    assert_eq!(report["fs_hz"], 48_828.0);
    assert_eq!(report["rpm"], 1500.0);
    assert_eq!(report["rpm_source"], "file");
    assert_eq!(report["samples"], 3 * 48_828);
    assert!(report["bearing"].as_str().unwrap().starts_with("mfpt"));
    let warnings = report["warnings"].to_string();
    assert!(warnings.contains("bearing.rate"), "{warnings}");
    assert_outer_race(&report);
}

#[test]
fn issue16_nested_compressed_struct_mat_is_read_by_field_path() {
    let Some(py) = python_scipy() else { return };
    let dir = scratch_dir("formats-nested");
    let samples = dir.join("sim.csv");
    simulate(&samples, "skf-6205-2rs", 1772.0, 12_000.0, 4.0);
    let mat = dir.join("my_rig.mat");
    make_mat(&py, "nested", &samples, &mat, 12_000.0, 1772.0);

    // Several signals: the error lists their paths and names the option.
    let err = analyze_error(&mat, &["--bearing", "skf-6205-2rs"]);
    for needle in ["test.sensors.de", "test.sensors.fe", "--channel"] {
        assert!(err.contains(needle), "'{needle}' missing: {err}");
    }
    // A field path picks one; the rate and speed come from the enclosing struct.
    for channel in ["test.sensors.de", "test.sensors.fe"] {
        let report = analyze_json(&mat, &["--channel", channel, "--bearing", "skf-6205-2rs"]);
        assert_eq!(report["channel"], channel);
        assert_eq!(report["fs_hz"], 12_000.0);
        assert_eq!(report["rpm"], 1772.0);
        assert_eq!(report["rpm_source"], "file");
        assert_eq!(report["samples"], 4 * 12_000);
        assert_outer_race(&report);
    }
    // A path that is not there: the error lists what is, text and cells included.
    let err = analyze_error(&mat, &["--channel", "test.sensors.nde"]);
    for needle in [
        "test.sensors.nde",
        "test.sensors.de",
        "operator (1x17 text)",
        "extras{2}",
    ] {
        assert!(err.contains(needle), "'{needle}' missing: {err}");
    }
    // A file that does not state what is needed says which option gives it.
    let err = analyze_error(&mat, &["--channel", "extras{2}"]);
    assert!(err.contains("--fs"), "{err}");
}

/// Every `/raw` topic in the log files of a data directory.
fn only_log(data: &Path) -> PathBuf {
    let mut logs: Vec<PathBuf> = std::fs::read_dir(data.join("mcap"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
        .collect();
    assert_eq!(logs.len(), 1, "{logs:?}");
    logs.pop().unwrap()
}

#[test]
fn issue16_a_log_written_by_run_analyzes_with_default_options() {
    let dir = scratch_dir("formats-mcap");
    let data = dir.join("data");
    // The embedded default: a simulated sensor whose outer-race fault starts at 30 s.
    let out = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "60",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let log = only_log(&data);

    let report = analyze_json(&log, &[]);
    assert_eq!(report["channel"], "motor-de/radial");
    assert_eq!(report["fs_hz"], 25_600.0);
    assert_eq!(report["samples"], 60 * 25_600);
    // The speed the log states (the simulated node's 1772 rpm), not a default.
    assert_eq!(report["rpm_source"], "file");
    assert!(
        (report["rpm"].as_f64().unwrap() - 1772.0).abs() < 1.0,
        "{report:#}"
    );
    assert!(report["bearing"]
        .as_str()
        .unwrap()
        .starts_with("skf-6205-2rs"));
    assert_outer_race(&report);

    // --channel picks the raw channel, with or without the topic prefix.
    let by_topic = analyze_json(&log, &["--channel", "/raw/motor-de/radial"]);
    assert_eq!(by_topic["channel"], "motor-de/radial");
    let err = analyze_error(&log, &["--channel", "motor-nde/radial"]);
    for needle in ["motor-nde/radial", "motor-de/radial", "--channel"] {
        assert!(err.contains(needle), "'{needle}' missing: {err}");
    }
}

/// A PRONOSTIA `acc_NNNNN.csv` snapshot (hour, minute, second, µs, horizontal, vertical) of
/// `horizontal` and a quieter vertical axis.
fn write_pronostia(path: &Path, horizontal: &[f64]) {
    let text: String = horizontal
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let micros = i as f64 / 25_600.0 * 1e6;
            format!("9,39,39,{:.0},{h},{}\n", micros, 0.3 * h)
        })
        .collect();
    std::fs::write(path, text).unwrap();
}

fn read_samples(csv: &Path) -> Vec<f64> {
    std::fs::read_to_string(csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.trim().parse().unwrap())
        .collect()
}

#[test]
fn issue16_a_2560_sample_snapshot_analyzes_with_default_options() {
    let dir = scratch_dir("formats-snapshot");
    let samples = dir.join("sim.csv");
    simulate(&samples, "pronostia", 1800.0, 25_600.0, 0.1);
    let x = read_samples(&samples);
    assert_eq!(x.len(), 2560);
    let snapshot = dir.join("acc_00001.csv");
    write_pronostia(&snapshot, &x);

    // The file states its rate (25.6 kHz by its format) but not the speed, and its directory
    // names no operating condition: the error says where PRONOSTIA's speeds come from.
    let err = analyze_error(&snapshot, &[]);
    assert!(
        err.contains("--rpm RPM")
            && err.contains("1800 rpm for Bearing1_N")
            && !err.contains("1797"),
        "{err}"
    );
    let report = analyze_json(&snapshot, &["--rpm", "1800"]);
    assert_eq!(report["samples"], 2560);
    assert_eq!(report["fs_hz"], 25_600.0);
    // The window adapts: the largest power of two the record holds.
    assert_eq!(report["window_samples"], 2048);
    assert_eq!(report["windows_averaged"], 1);
    assert!(report["bearing"].as_str().unwrap().starts_with("pronostia"));

    // The real snapshots read the same way, when the data set is here.
    let Some(femto) = shared_data_dir("femto") else {
        return;
    };
    let real = femto.join("Bearing1_2/acc_00001.csv");
    let report = analyze_json(&real, &["--rpm", "1800"]);
    assert_eq!(report["window_samples"], 2048);
    // Without --rpm, the speed of the condition its directory names; what was assumed is a
    // note, not a warning.
    let report = analyze_json(&real, &[]);
    assert_eq!(report["rpm"], 1800.0);
    assert_eq!(report["rpm_source"], "data_set_default");
    let notes = report["notes"].to_string();
    assert!(
        notes.contains(
            "assumed 1800 rpm, PRONOSTIA's operating condition 1 (the directory Bearing1_2)"
        ) && notes.contains("bearing not given: assumed pronostia"),
        "{notes}"
    );
    assert_eq!(report["warnings"], serde_json::json!([]), "{report:#}");
    let text = bearingd(&["analyze", real.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains("note: bearing not given") && !text.contains("warning:"),
        "{text}"
    );
    // The header's band (GK's, for a record with no fault) is not the one the faults are
    // scored in here, and says so.
    assert!(
        text.contains("each fault below is scored in the band that shows it best"),
        "{text}"
    );
    let bearing3 = femto.join("Bearing3_1/acc_00001.csv");
    assert_eq!(analyze_json(&bearing3, &[])["rpm"], 1500.0);
}

#[test]
fn issue16_a_wav_analyzes_given_the_speed_and_bearing_it_does_not_state() {
    let dir = scratch_dir("formats-wav");
    let wav = dir.join("recorder.wav");
    simulate(&wav, "skf-6205-2rs", 1772.0, 12_000.0, 4.0);
    let err = analyze_error(&wav, &["--bearing", "skf-6205-2rs"]);
    // Not CWRU's speed: a WAV file's machine is anyone's.
    assert!(
        err.contains("--rpm RPM") && err.contains("nameplate") && !err.contains("1797"),
        "{err}"
    );
    let err = analyze_error(&wav, &["--rpm", "1772"]);
    assert!(err.contains("--bearing"), "{err}");
    let report = analyze_json(&wav, &["--rpm", "1772", "--bearing", "skf-6205-2rs"]);
    assert_eq!(report["fs_hz"], 12_000.0);
    assert_eq!(report["samples"], 4 * 12_000);
    assert_outer_race(&report);
}

#[test]
fn issue16_a_table_with_several_columns_names_the_column_option() {
    let dir = scratch_dir("formats-table");
    let table = dir.join("export.csv");
    let rows: String = std::iter::once("time,acc_x,acc_y\n".to_string())
        .chain((0..5000).map(|i| format!("{},{},{}\n", i, (i % 7) as f64, (i % 5) as f64)))
        .collect();
    std::fs::write(&table, rows).unwrap();
    let err = analyze_error(
        &table,
        &[
            "--fs",
            "12000",
            "--rpm",
            "1772",
            "--bearing",
            "skf-6205-2rs",
        ],
    );
    for needle in ["--column", "acc_x", "acc_y"] {
        assert!(err.contains(needle), "'{needle}' missing: {err}");
    }
}

/// The velocity RMS (mm/s) of a report, which must have one.
fn velocity_mm_s(report: &Value) -> f64 {
    report["velocity"]["rms_mm_s"]
        .as_f64()
        .unwrap_or_else(|| panic!("no velocity: {report:#}"))
}

fn notes_of(report: &Value) -> String {
    format!("{} {}", report["notes"], report["warnings"])
}

/// A 16-bit PCM WAV of `samples` scaled so that `full_scale` is ±32768 counts, written with
/// hound (the recorder's counts: a file that states no unit).
fn write_pcm16(path: &Path, samples: &[f64], full_scale: f64, fs: u32) {
    let spec = hound::WavSpec {
        channels: 1,
        sample_rate: fs,
        bits_per_sample: 16,
        sample_format: hound::SampleFormat::Int,
    };
    let mut w = hound::WavWriter::create(path, spec).unwrap();
    for s in samples {
        w.write_sample((s / full_scale * 32768.0).round().clamp(-32768.0, 32767.0) as i16)
            .unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn issue33_what_simulate_writes_as_wav_is_read_in_g_with_its_channel_name() {
    let dir = scratch_dir("formats-wav-units");
    let (wav, csv) = (dir.join("sim.wav"), dir.join("sim.csv"));
    simulate(&wav, "skf-6205-2rs", 1772.0, 12_000.0, 4.0);
    simulate(&csv, "skf-6205-2rs", 1772.0, 12_000.0, 4.0);
    let given = ["--rpm", "1772", "--bearing", "skf-6205-2rs"];
    let from_wav = analyze_json(&wav, &given);
    let from_csv = analyze_json(&csv, &[&given[..], &["--fs", "12000"]].concat());

    // The same values, the same unit, the same channel name as the CSV column.
    assert_eq!(from_wav["channel"], "accel_g");
    assert_eq!(from_csv["channel"], "accel_g");
    assert_eq!(from_wav["unit"], "g");
    assert_eq!(from_csv["unit"], "g");
    let (v_wav, v_csv) = (velocity_mm_s(&from_wav), velocity_mm_s(&from_csv));
    assert!(
        (v_wav - v_csv).abs() <= 1e-6 * v_csv,
        "WAV {v_wav} mm/s, CSV {v_csv} mm/s"
    );
    assert!(
        notes_of(&from_wav).contains("float WAV samples taken as g"),
        "{}",
        notes_of(&from_wav)
    );
    // The channel by its name or its number.
    for channel in ["accel_g", "ACCEL_G", "1"] {
        let report = analyze_json(&wav, &[&given[..], &["--channel", channel]].concat());
        assert_eq!(report["channel"], "accel_g", "--channel {channel}");
    }

    // --unit restates the values: m/s² are divided by standard gravity, full scale has no
    // velocity, and the format's own assumption is replaced, not kept beside.
    let in_ms2 = analyze_json(&wav, &[&given[..], &["--unit", "m/s2"]].concat());
    let ratio = v_wav / velocity_mm_s(&in_ms2);
    assert!((ratio - 9.80665).abs() < 1e-6, "ratio {ratio}");
    let notes = notes_of(&in_ms2);
    assert!(notes.contains("divided by 9.80665"), "{notes}");
    assert!(!notes.contains("taken as g"), "{notes}");
    let relative = analyze_json(&wav, &[&given[..], &["--unit", "full-scale"]].concat());
    assert!(relative["velocity"].is_null(), "{relative:#}");
    assert!(
        notes_of(&relative).contains("no ISO 10816-3 velocity"),
        "{}",
        notes_of(&relative)
    );
    // The diagnosis does not depend on the unit.
    for report in [&from_wav, &in_ms2, &relative] {
        assert_outer_race(report);
    }
}

#[test]
fn issue33_an_integer_wav_is_relative_until_its_unit_is_stated() {
    let dir = scratch_dir("formats-wav-int");
    let (csv, wav) = (dir.join("sim.csv"), dir.join("recorder.wav"));
    simulate(&csv, "skf-6205-2rs", 1772.0, 12_000.0, 4.0);
    let samples = read_samples(&csv);
    let full_scale = samples.iter().fold(0.0f64, |m, s| m.max(s.abs())) * 1.25;
    write_pcm16(&wav, &samples, full_scale, 12_000);
    let given = ["--rpm", "1772", "--bearing", "skf-6205-2rs"];

    let relative = analyze_json(&wav, &given);
    assert_eq!(relative["channel"], "1", "no iXML chunk: numbered");
    assert!(relative["velocity"].is_null(), "{relative:#}");
    assert_eq!(
        relative["unit"], "full_scale",
        "the JSON says the amplitudes are relative"
    );
    assert!(
        notes_of(&relative).contains("fractions of full scale"),
        "{}",
        notes_of(&relative)
    );
    assert_outer_race(&relative);

    // Stated in g: ±1.0 full scale is 1 g, so the velocity is the CSV's over the full scale.
    let csv_v = velocity_mm_s(&analyze_json(
        &csv,
        &[&given[..], &["--fs", "12000"]].concat(),
    ));
    let stated = analyze_json(&wav, &[&given[..], &["--unit", "g"]].concat());
    assert_eq!(stated["unit"], "g");
    let expected = csv_v / full_scale;
    let got = velocity_mm_s(&stated);
    assert!(
        (got - expected).abs() < 0.01 * expected,
        "{got} mm/s, expected {expected} (16-bit rounding aside)"
    );
    assert!(
        notes_of(&stated).contains("--unit g"),
        "{}",
        notes_of(&stated)
    );
    assert!(!notes_of(&stated).contains("fractions of full scale"));

    // import says what it does with relative values.
    let out = bearingd(&[
        "import",
        wav.to_str().unwrap(),
        "--out",
        dir.join("imported").to_str().unwrap(),
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("will be read as g"), "{err}");
}

#[test]
fn issue33_unit_is_refused_where_the_data_set_documents_it_and_choices_are_listed() {
    let dir = scratch_dir("formats-unit-refused");
    let snapshot = dir.join("acc_00001.csv");
    write_pronostia(&snapshot, &vec![0.1; 2560]);
    let err = analyze_error(&snapshot, &["--unit", "m/s2"]);
    assert!(
        err.contains("--unit does not apply") && err.contains("PRONOSTIA"),
        "{err}"
    );
    // clap's own error lists the same choices the help does.
    let out = bearingd(&["analyze", "--demo", "--unit", "volts"]);
    let err = String::from_utf8_lossy(&out.stderr);
    for choice in ["g", "m/s2", "full-scale"] {
        assert!(err.contains(choice), "'{choice}' missing: {err}");
    }
}
