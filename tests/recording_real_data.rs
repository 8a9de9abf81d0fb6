//! The readers against the real shared data sets (../shared/data, never committed).
//! Missing data: a loud skip locally, a failure with CI=true (see `bearingd_testdata::shared_data_dir`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

use bearingd::recording::{list_channels, read_recording, ReadOptions, RecordingFormat};
use bearingd_testdata::shared_data_dir;
use std::path::Path;

fn channel(name: &str) -> ReadOptions {
    ReadOptions {
        channel: Some(name.to_string()),
        column: None,
        unit: None,
    }
}

fn manifest(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    bearingd_testdata::read_manifest(dir)
}

#[test]
fn every_cwru_file_matches_its_manifest_row() {
    let Some(dir) = shared_data_dir("cwru") else {
        return;
    };
    let rows = manifest(&dir);
    assert_eq!(rows.len(), 19, "manifest rows");
    for row in rows {
        let path = dir.join(&row["file"]);
        let r = read_recording(&path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let what = &row["file"];
        assert_eq!(r.format, RecordingFormat::Matlab);
        assert_eq!(r.channel, row["channel_var"], "{what}");
        assert_eq!(
            r.samples.len(),
            row["n_samples"].parse::<usize>().unwrap(),
            "{what}"
        );
        assert_eq!(
            r.fs_hz,
            Some(row["fs_hz"].parse::<f64>().unwrap()),
            "{what}"
        );
        // Every one of these files has an XNNNRPM variable (checked by listing them).
        let want_rpm: f64 = row["rpm"].parse().unwrap();
        let rpm = r.rpm.unwrap_or_else(|| panic!("{what}: no rpm"));
        assert!(
            (rpm - want_rpm).abs() <= 1.0,
            "{what}: rpm {rpm} vs {want_rpm}"
        );
        assert!(r.warnings.is_empty(), "{what}: {:?}", r.warnings);
        assert!(r.samples.iter().all(|v| v.is_finite() && v.abs() < 100.0));
    }
}

#[test]
fn cwru_channels_by_keyword_and_name() {
    let Some(dir) = shared_data_dir("cwru") else {
        return;
    };
    let path = dir.join("12k_Drive_End_IR007_0_105.mat");
    assert_eq!(
        list_channels(&path).unwrap(),
        ["X105_DE_time", "X105_FE_time", "X105_BA_time", "X105RPM"]
    );
    let fe = read_recording(&path, &channel("fe")).unwrap();
    assert_eq!(fe.channel, "X105_FE_time");
    let by_name = read_recording(&path, &channel("X105_FE_time")).unwrap();
    assert_eq!(fe.samples, by_name.samples);
    assert_eq!(
        read_recording(&path, &channel("BA")).unwrap().channel,
        "X105_BA_time"
    );

    // The normal baseline has no base accelerometer: the error lists what is there.
    let normal = dir.join("normal_0_97.mat");
    let e = read_recording(&normal, &channel("BA"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("no variable 'X097_BA_time'"), "{e}");
    assert!(e.contains("X097_DE_time, X097_FE_time, X097RPM"), "{e}");
}

#[test]
fn pronostia_snapshots() {
    let Some(dir) = shared_data_dir("femto") else {
        return;
    };
    for file in [
        "Bearing1_2/acc_00001.csv",
        "Bearing1_2/acc_00011.csv",
        "Bearing3_1/acc_00001.csv",
    ] {
        let path = dir.join(file);
        let h = read_recording(&path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(h.format, RecordingFormat::PronostiaCsv);
        assert_eq!(
            (h.channel.as_str(), h.samples.len()),
            ("horizontal", 2560),
            "{file}"
        );
        assert_eq!(h.fs_hz, Some(25_600.0));
        assert!(h.warnings.is_empty(), "{file}: {:?}", h.warnings);
        let v = read_recording(&path, &channel("vertical")).unwrap();
        assert_eq!(v.samples.len(), 2560);
        assert_ne!(h.samples, v.samples);
    }
    // First row of Bearing1_2/acc_00001.csv: 8,47,5,1.9691e+05,0.05,-0.253
    let first = dir.join("Bearing1_2/acc_00001.csv");
    assert_eq!(
        read_recording(&first, &ReadOptions::default())
            .unwrap()
            .samples[0],
        0.05
    );
    assert_eq!(
        read_recording(&first, &channel("vertical"))
            .unwrap()
            .samples[0],
        -0.253
    );
}

#[test]
fn ims_snapshots() {
    let Some(dir) = shared_data_dir("ims") else {
        return;
    };
    let rows = manifest(&dir);
    assert_eq!(rows.len(), 5);
    for row in rows {
        let path = dir.join(&row["file"]);
        let channels = list_channels(&path).unwrap();
        assert_eq!(
            channels,
            ["B1x", "B1y", "B2x", "B2y", "B3x", "B3y", "B4x", "B4y"]
        );
        let r = read_recording(&path, &ReadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.format, RecordingFormat::ImsText);
        assert_eq!((r.channel.as_str(), r.samples.len()), ("B1x", 20_480));
        assert_eq!((r.fs_hz, r.rpm), (Some(20_000.0), None));
        for (i, name) in channels.iter().enumerate() {
            let by_name = read_recording(&path, &channel(&name.to_lowercase())).unwrap();
            let by_index = read_recording(&path, &channel(&(i + 1).to_string())).unwrap();
            assert_eq!(by_name.samples.len(), 20_480);
            assert_eq!(by_name.samples, by_index.samples);
        }
    }
    // First row of 2003.10.22.12.14.13: -0.054 -0.049 -0.208 -0.081 -0.122 -0.222 ...
    let first = dir.join("2003.10.22.12.14.13");
    let b3x = read_recording(&first, &channel("B3x")).unwrap();
    assert_eq!(b3x.samples[0], -0.122);
}
