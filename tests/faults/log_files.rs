//! The log directory's files: a stranger named like a log is quarantined, a damaged log is
//! recovered through a checked copy, every file describes itself in metadata (also after
//! rotation and recovery), and a log from another configuration is kept as its own.

use super::{
    bearingd, config_file, now_ns, python_metadata, raw_blocks, raw_ranges, short_run,
    start_daemon, stderr_of, wait_for_log,
};
use bearingd_testdata::{check_mcap_with_python, mcap_files, noise, python_mcap, scratch_dir};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

#[test]
fn a_random_file_named_like_a_log_is_moved_to_quarantine_untouched() {
    let dir = scratch_dir("faults-random");
    let data = dir.join("data");
    let logs = data.join("mcap");
    std::fs::create_dir_all(&logs).unwrap();
    let name = "bearingd-20200101T000000Z-000000.mcap";
    let bytes = noise(100_000, 11);
    std::fs::write(logs.join(name), &bytes).unwrap();
    // And a file with a valid start but not one complete record.
    let mut stub = mcap::MAGIC.to_vec();
    stub.extend(noise(50, 3));
    let stub_name = "bearingd-20200101T000001Z-000000.mcap";
    std::fs::write(logs.join(stub_name), &stub).unwrap();

    let out = short_run(&data);
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    for (name, bytes) in [(name, &bytes), (stub_name, &stub)] {
        assert!(!logs.join(name).exists(), "{name} is still among the logs");
        let kept = std::fs::read(logs.join("quarantine").join(name)).unwrap();
        assert_eq!(&kept, bytes, "{name} was changed");
        assert!(
            stderr.contains(name) && stderr.contains("quarantine"),
            "{stderr}"
        );
    }
    // The run's own log is fine.
    let files = mcap_files(&logs);
    assert_eq!(files.len(), 1, "{files:?}");
    if let Some(py) = python_mcap() {
        check_mcap_with_python(&py, &files[0], None);
    }
}

#[test]
fn a_log_damaged_in_the_middle_is_recovered_through_a_checked_copy_and_its_original_kept() {
    let dir = scratch_dir("faults-damaged");
    let data = dir.join("data");
    let logs = data.join("mcap");
    let out = bearingd(&[
        "run",
        "--fast",
        "--duration",
        "20",
        "--quiet",
        "--data-dir",
        data.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let files = mcap_files(&logs);
    assert_eq!(files.len(), 1);
    let path = files[0].clone();
    let intact = raw_blocks(&files);
    // Cut the summary off (as a crash would) and flip a byte in a chunk near the middle.
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.truncate(bytes.len() * 9 / 10);
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x5A;
    std::fs::write(&path, &bytes).unwrap();

    let out = short_run(&data);
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("recovered") && stderr.contains("damaged original kept"),
        "{stderr}"
    );
    let name = path.file_name().unwrap();
    assert_eq!(
        std::fs::read(logs.join("quarantine").join(name)).unwrap(),
        bytes,
        "the damaged original's bytes are kept"
    );
    let recovered = raw_blocks(std::slice::from_ref(&path));
    // The embedded default's simulated sensor sends blocks of 0.1 s.
    eprintln!(
        "damaged + cut log: {recovered} of {intact} raw blocks recovered, {:.1} s of signal lost",
        (intact - recovered) as f64 * 0.1
    );
    assert!(
        recovered > intact / 2 && recovered < intact,
        "{recovered} of {intact} raw blocks recovered"
    );
    if let Some(py) = python_mcap() {
        check_mcap_with_python(&py, &path, None);
    }
}

#[test]
fn every_log_file_describes_itself_in_metadata_that_python_reads_also_after_rotation_and_recovery()
{
    let Some(py) = python_mcap() else { return };
    let dir = scratch_dir("faults-metadata");
    let data = dir.join("data");
    let root = format!("/dev/shm/bearingd-faults-md-{}", std::process::id());
    let config = config_file(&dir, |text| {
        text.replace("mcap_max_file_s = 3600", "mcap_max_file_s = 1")
            .replace("\"/run/bearingd/iceoryx2\"", &format!("\"{root}\""))
    });
    let before = now_ns();
    let out = bearingd(&[
        "run",
        "--config",
        config.to_str().unwrap(),
        "--data-dir",
        data.to_str().unwrap(),
        "--fast",
        "--quiet",
        "--duration",
        "3.5",
    ]);
    let _ = std::fs::remove_dir_all(&root);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let files = mcap_files(&data.join("mcap"));
    assert!(
        files.len() >= 3,
        "rotation every second of log time: {files:?}"
    );
    let mut run_ids = Vec::new();
    for (i, file) in files.iter().enumerate() {
        let read = python_metadata(&py, file);
        let md = &read["metadata"];
        let run = &md["bearingd.run"][0];
        assert_eq!(run["version"], env!("CARGO_PKG_VERSION"), "{read}");
        assert!(!run["host"].as_str().unwrap().is_empty());
        run_ids.push(run["run_id"].clone());
        let origin: u64 = run["log_time_origin_ns"].as_str().unwrap().parse().unwrap();
        assert!(origin >= before && origin <= now_ns(), "{read}");
        assert!(run["log_time_origin_utc"].as_str().unwrap().ends_with('Z'));
        // Log times are real UTC: at or after the origin, within the run's 3.5 s of signal.
        let first = read["first_log_time"].as_u64().unwrap();
        let last = read["last_log_time"].as_u64().unwrap();
        assert!(first >= origin && last <= origin + 4_000_000_000, "{read}");
        let channel = &md["bearingd.channel"][0];
        assert_eq!(channel["channel"], "motor-de/radial", "{read}");
        assert_eq!(channel["topic"], "/raw/motor-de/radial");
        assert_eq!(channel["sample_rate_hz"], "25600");
        assert_eq!(channel["unit"], "g");
        assert_eq!(channel["bearing"], "skf-6205-2rs");
        let geometry: serde_json::Value =
            serde_json::from_str(channel["bearing_geometry"].as_str().unwrap()).unwrap();
        assert_eq!(geometry["rolling_elements"], 9, "{geometry}");
        let config: serde_json::Value =
            serde_json::from_str(md["bearingd.config"][0]["json"].as_str().unwrap()).unwrap();
        assert_eq!(config["sensors"][0]["sample_rate_hz"], 25600.0);
        assert_eq!(
            md["bearingd.file"][0]["sequence"],
            (i + 1).to_string(),
            "{read}"
        );
    }
    assert!(run_ids.windows(2).all(|w| w[0] == w[1]), "{run_ids:?}");

    // A file recovered after a kill -9 keeps its metadata.
    let killed_data = dir.join("killed");
    let mut child = start_daemon(&killed_data);
    wait_for_log(&killed_data, 20_000);
    child.kill().unwrap();
    child.wait().unwrap();
    let killed = mcap_files(&killed_data.join("mcap"));
    let out = short_run(&killed_data);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let read = python_metadata(&py, &killed[0]);
    assert_eq!(
        read["metadata"]["bearingd.file"][0]["sequence"], "1",
        "{read}"
    );
    assert_eq!(
        read["metadata"]["bearingd.channel"][0]["sample_rate_hz"],
        "25600"
    );
}

/// A log written with another config (another sample rate, another run) in the data
/// directory: a finished one is left byte for byte; an unfinished one (its daemon killed) is
/// recovered as it was written, with its own run id and sample rate, never today's.
#[test]
fn issue11_a_log_from_another_config_is_left_as_it_is_or_recovered_as_its_own() {
    let dir = scratch_dir("faults-other-config");
    let data = dir.join("data");
    let logs = data.join("mcap");
    let root = format!("/dev/shm/bearingd-faults-other-{}", std::process::id());
    let other = config_file(&dir, |text| {
        text.replace("sample_rate_hz = 25600", "sample_rate_hz = 12800")
            .replace("\"/run/bearingd/iceoryx2\"", &format!("\"{root}\""))
    });
    let run_other = |extra: &[&str]| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_bearingd"));
        cmd.args(["run", "--config", other.to_str().unwrap(), "--quiet"])
            .args(["--data-dir", data.to_str().unwrap()])
            .args(extra);
        cmd
    };
    let finished = run_other(&["--fast", "--duration", "3"]).output().unwrap();
    assert!(finished.status.success(), "{}", stderr_of(&finished));
    let finished_file = mcap_files(&logs).pop().unwrap();
    let finished_bytes = std::fs::read(&finished_file).unwrap();
    let mut killed = run_other(&[])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let unfinished = loop {
        let files = mcap_files(&logs);
        let newest = files.last().unwrap().clone();
        if newest != finished_file && std::fs::metadata(&newest).unwrap().len() > 50_000 {
            break newest;
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    killed.kill().unwrap();
    killed.wait().unwrap();
    let _ = std::fs::remove_dir_all(&root);
    // Today's daemon: the embedded default (25600 Hz) on the same directory.
    let today = short_run(&data);
    let stderr = stderr_of(&today);
    assert!(today.status.success(), "{stderr}");
    assert_eq!(
        std::fs::read(&finished_file).unwrap(),
        finished_bytes,
        "the finished file of another config was changed"
    );
    assert!(
        stderr.contains(&format!("recovered {}", unfinished.display())),
        "{stderr}"
    );
    let Some(py) = python_mcap() else {
        return;
    };
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/log_metadata.py");
    let metadata = |file: &Path| -> serde_json::Value {
        let out = Command::new(&py).arg(&script).arg(file).output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let run_id = |m: &serde_json::Value| m["metadata"]["bearingd.run"][0]["run_id"].clone();
    let rate = |m: &serde_json::Value| {
        m["metadata"]["bearingd.channel"][0]["sample_rate_hz"]
            .as_str()
            .unwrap()
            .parse::<f64>()
            .unwrap()
    };
    let recovered = metadata(&unfinished);
    let newest = metadata(mcap_files(&logs).last().unwrap());
    assert_eq!(rate(&recovered), 12800.0, "{recovered}");
    assert_eq!(rate(&newest), 25600.0, "{newest}");
    assert_ne!(run_id(&recovered), run_id(&newest));
    assert_ne!(run_id(&recovered), run_id(&metadata(&finished_file)));
    let (_, raw_rate) = raw_ranges(std::slice::from_ref(&unfinished));
    assert_eq!(raw_rate, 12800.0);
}
