//! Faithful replay (issue 11 item 3): `bearingd replay` takes the sample rate, geometry and
//! settings from the log's metadata, reads files by run and sequence whatever order they are
//! given in, restarts the pipeline at a run boundary (a crash and restart) and says so, reports
//! a gap inside a run with its length, dates its own log with the original run's UTC time base
//! (read back by Python's strict `mcap` reader), and writes the same bytes when run twice.

use bearingd::mcap_log::read_messages;
use bearingd::messages::PipelineMessage;
use bearingd_testdata::{mcap_files, python_mcap, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn bearingd(args: &[&str]) -> Output {
    bearingd_testdata::run_binary(env!("CARGO_BIN_EXE_bearingd"), args)
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The embedded default at `rate_hz`, files rotated every `file_s` of log time, an iceoryx2
/// root of its own (numbered per call: two tests may run the same `name` at once); written to
/// `dir/<name>.toml`.
fn config_at(dir: &Path, name: &str, rate_hz: u32, file_s: u32) -> PathBuf {
    static CONFIGS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let number = CONFIGS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let out = bearingd(&["config", "default"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout)
        .unwrap()
        .replace(
            "sample_rate_hz = 25600",
            &format!("sample_rate_hz = {rate_hz}"),
        )
        .replace(
            "mcap_max_file_s = 3600",
            &format!("mcap_max_file_s = {file_s}"),
        )
        .replace(
            "\"/run/bearingd/iceoryx2\"",
            &format!(
                "\"/dev/shm/bearingd-replay-{name}-{}-{number}\"",
                std::process::id()
            ),
        );
    assert!(text.contains(&format!("sample_rate_hz = {rate_hz}")));
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `bearingd run --fast` of `config` on `data` for `seconds` of signal.
pub(crate) fn fast_run(config: &Path, data: &Path, seconds: &str) {
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
    assert!(out.status.success(), "{}", stderr_of(&out));
}

/// (channel, fault, from, to, sample) of every flag change in the logs.
fn logged_flags(files: &[PathBuf]) -> Vec<(String, String, String, u64)> {
    read_messages(files)
        .filter_map(|m| match m.expect("readable log").message {
            PipelineMessage::Flag(f) => Some((
                f.channel.to_string(),
                f.fault.to_string(),
                f.to.to_string(),
                f.end_sample,
            )),
            _ => None,
        })
        .collect()
}

/// What `tests/python/log_metadata.py` (Python `mcap`, strict) reads from `file`.
fn python_metadata(py: &Path, file: &Path) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/log_metadata.py");
    let out = Command::new(py).arg(script).arg(file).output().unwrap();
    assert!(
        out.status.success(),
        "{}: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// `bearingd replay --quiet --json` of `files` into `out`; it must succeed. (Summary, stderr.)
pub fn replay_json(files: &[PathBuf], out: &Path, extra: &[&str]) -> (serde_json::Value, String) {
    let mut args = vec![
        "replay",
        "--out",
        out.to_str().unwrap(),
        "--quiet",
        "--json",
    ];
    args.extend_from_slice(extra);
    args.extend(files.iter().map(|f| f.to_str().unwrap()));
    let result = bearingd(&args);
    let stderr = stderr_of(&result);
    assert!(result.status.success(), "{stderr}");
    (serde_json::from_slice(&result.stdout).unwrap(), stderr)
}

/// Regression test of issue 11 item 3: a run at 12.8 kHz (not the default 25.6 kHz) rotated
/// every 20 s, then a restart killed with `kill -9`; the files replayed newest first, without
/// `--config`.
#[test]
fn issue_11_replay_takes_rate_order_and_run_boundaries_from_the_log() {
    let dir = scratch_dir("replay-faithful");
    let data = dir.join("data");
    let config = config_at(&dir, "slow", 12_800, 20);
    fast_run(&config, &data, "60");
    let first_run = mcap_files(&data.join("mcap"));
    // Three files of 20 s, and a fourth from 60.0 s, the rotation's boundary, holding the last
    // verdict the clean stop made on the samples not yet analysed.
    assert_eq!(first_run.len(), 4, "{first_run:?}");

    // The restart, killed: a crash boundary, its file left unfinished.
    let mut killed = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["run", "--config", config.to_str().unwrap()])
        .args(["--data-dir", data.to_str().unwrap(), "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    let second_run = loop {
        let new: Vec<PathBuf> = mcap_files(&data.join("mcap"))
            .into_iter()
            .filter(|f| !first_run.contains(f))
            .collect();
        if new
            .first()
            .is_some_and(|f| std::fs::metadata(f).unwrap().len() > 20_000)
        {
            break new;
        }
        assert!(Instant::now() < deadline, "the restart logged nothing");
        std::thread::sleep(Duration::from_millis(100));
    };
    killed.kill().unwrap(); // SIGKILL
    killed.wait().unwrap();

    let mut given: Vec<PathBuf> = first_run.iter().chain(&second_run).cloned().collect();
    given.reverse();
    let out = dir.join("replay");
    let (summary, stderr) = replay_json(&given, &out, &[]);

    // Settings from the log: its rate, said on stderr.
    assert_eq!(summary["settings_from"], "log", "{summary}");
    assert!(
        stderr.contains("settings from the log: motor-de at 12800 Hz"),
        "{stderr}"
    );
    // Order: by run, then sequence; said because it is not the order given.
    let expected: Vec<String> = first_run
        .iter()
        .chain(&second_run)
        .map(|p| p.display().to_string())
        .collect();
    let order: Vec<String> = summary["order"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p.as_str().unwrap().to_string())
        .collect();
    assert_eq!(order, expected);
    assert_eq!(summary["reordered"], true);
    assert!(stderr.contains("not in the order given"), "{stderr}");
    // One run boundary, at the restart's file, said and in the summary.
    assert_eq!(summary["run_boundaries"], 1, "{summary}");
    let runs = summary["runs"].as_array().unwrap();
    let restart = &expected[first_run.len()];
    assert_eq!(runs[1]["first_file"], restart.as_str());
    assert!(
        stderr.contains(&format!("run boundary at {restart}")),
        "{stderr}"
    );
    assert_eq!(summary["gap_count"], 0, "{summary}");
    assert_eq!(summary["unfinished_files"], 1, "{summary}");

    // The rate came from the log: every replayed block at 12.8 kHz, and the flags of the live
    // run at the same samples.
    let replayed = mcap_files(&out);
    let live: Vec<PathBuf> = first_run.iter().chain(&second_run).cloned().collect();
    let live_flags = logged_flags(&live);
    assert!(
        live_flags.iter().any(|f| f.1 == "outer_race"),
        "{live_flags:?}"
    );
    assert_eq!(logged_flags(&replayed), live_flags);
    for m in read_messages(&replayed) {
        if let PipelineMessage::Raw(b) = m.unwrap().message {
            assert_eq!(b.sample_rate_hz, 12_800.0);
        }
    }

    // Each run's output is dated with that run's UTC origin, read back by Python.
    if let Some(py) = python_mcap() {
        let mut seen = Vec::new();
        for file in &replayed {
            let read = python_metadata(&py, file);
            let run = &read["metadata"]["bearingd.run"][0];
            let origin: u64 = run["log_time_origin_ns"].as_str().unwrap().parse().unwrap();
            let run_id: u64 = run["run_id"].as_str().unwrap().parse().unwrap();
            let original = runs
                .iter()
                .find(|r| r["run_id"].as_u64() == Some(run_id))
                .unwrap_or_else(|| panic!("{}: run {run_id} was not replayed", file.display()));
            assert_eq!(original["origin_ns"].as_u64(), Some(origin));
            let first = read["first_log_time"].as_u64().unwrap();
            let last = read["last_log_time"].as_u64().unwrap();
            // 2020-01-01 or later: real UTC, not 1970.
            assert!(first >= 1_577_836_800_000_000_000, "{read}");
            assert!(first >= origin && last <= origin + 61_000_000_000, "{read}");
            seen.push(run_id);
        }
        // (File names sort by opening time, which interleaves the runs' files.)
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), 2, "{seen:?}");
    }

    // The same replay again writes the same bytes.
    let first_out = dir.join("replay-first");
    std::fs::rename(&out, &first_out).unwrap();
    replay_json(&given, &out, &[]);
    let again = mcap_files(&out);
    assert_eq!(again.len(), replayed.len());
    for (a, b) in mcap_files(&first_out).iter().zip(&again) {
        assert_eq!(a.file_name(), b.file_name());
        assert!(
            std::fs::read(a).unwrap() == std::fs::read(b).unwrap(),
            "{} differs between two replays",
            b.display()
        );
    }

    // Without the middle file of the first run: a gap of its length, and the file named.
    let (summary, stderr) = replay_json(
        &[first_run[2].clone(), first_run[0].clone()],
        &dir.join("replay-gap"),
        &[],
    );
    assert_eq!(summary["run_boundaries"], 0, "{summary}");
    assert_eq!(summary["gap_count"], 1, "{summary}");
    let gap = &summary["gaps"][0];
    let seconds = gap["seconds"].as_f64().unwrap();
    assert_eq!(seconds, gap["missing_samples"].as_f64().unwrap() / 12_800.0);
    assert!((15.0..=25.0).contains(&seconds), "{gap}");
    assert_eq!(summary["missing_files"][0]["sequence"], 2, "{summary}");
    assert!(
        stderr.contains("gap in motor-de/radial") && stderr.contains("file 2 of the run"),
        "{stderr}"
    );
}

#[test]
fn replay_of_logs_with_different_settings_exits_2_naming_them_unless_config_is_given() {
    let dir = scratch_dir("replay-disagree");
    let slow = config_at(&dir, "slow", 12_800, 3600);
    let fast = config_at(&dir, "fast", 25_600, 3600);
    fast_run(&slow, &dir.join("a"), "1");
    fast_run(&fast, &dir.join("b"), "1");
    let files = [
        mcap_files(&dir.join("a/mcap"))[0].clone(),
        mcap_files(&dir.join("b/mcap"))[0].clone(),
    ];
    let names: Vec<&str> = files
        .iter()
        .map(|f| f.file_name().unwrap().to_str().unwrap())
        .collect();
    let out = bearingd(&[
        "replay",
        "--out",
        dir.join("out").to_str().unwrap(),
        "--quiet",
        files[0].to_str().unwrap(),
        files[1].to_str().unwrap(),
    ]);
    let stderr = stderr_of(&out);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("recorded with different settings")
            && names.iter().all(|n| stderr.contains(n))
            && stderr.contains("--config"),
        "{stderr}"
    );

    // With --config: allowed, said, and what differs from the (first) log is named.
    let (summary, stderr) = replay_json(
        &files[..1],
        &dir.join("out"),
        &["--config", fast.to_str().unwrap()],
    );
    assert_eq!(summary["settings_from"], "config");
    assert!(
        stderr.contains("analysing with --config")
            && stderr.contains("sample_rate_hz 25600 (log: 12800)"),
        "{stderr}"
    );
    assert_eq!(summary["config_differences"].as_array().unwrap().len(), 1);
}

/// `bearingd import` writes a log that describes itself as the daemon's do: replay needs no
/// `--config`, finds the same flags as with the settings file import also writes, and the log
/// is dated by the recording (here the CSV's modification time), not 1970.
#[test]
fn an_imported_recording_carries_its_settings_and_date_and_replays_without_a_config() {
    let dir = scratch_dir("replay-import");
    let csv = dir.join("record.csv");
    let simulated = bearingd(&[
        "simulate",
        "--duration",
        "8",
        "--fs",
        "12800",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(simulated.status.success(), "{}", stderr_of(&simulated));
    let imported = bearingd(&[
        "import",
        csv.to_str().unwrap(),
        "--fs",
        "12800",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--out",
        dir.join("log").to_str().unwrap(),
    ]);
    assert!(imported.status.success(), "{}", stderr_of(&imported));
    let log = mcap_files(&dir.join("log"));
    let mtime_ns = std::fs::metadata(&csv)
        .unwrap()
        .modified()
        .unwrap()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos() as u64;
    if let Some(py) = python_mcap() {
        let read = python_metadata(&py, &log[0]);
        let run = &read["metadata"]["bearingd.run"][0];
        assert_eq!(run["log_time_origin_ns"], mtime_ns.to_string(), "{read}");
        assert_eq!(read["first_log_time"], mtime_ns, "{read}");
        let import = &read["metadata"]["bearingd.import"][0];
        assert_eq!(import["source"], csv.to_str().unwrap(), "{read}");
        assert_eq!(import["time_source"], "file modification time", "{read}");
        let channel = &read["metadata"]["bearingd.channel"][0];
        assert_eq!(channel["sample_rate_hz"], "12800", "{read}");
        assert!(read["metadata"]["bearingd.config"][0]["json"]
            .as_str()
            .unwrap()
            .contains("\"imported\""));
    }

    let (summary, stderr) = replay_json(&log, &dir.join("out"), &[]);
    assert_eq!(summary["settings_from"], "log", "{summary}\n{stderr}");
    assert_eq!(summary["samples"], 8 * 12_800, "{summary}");
    assert!(!stderr.contains("carries no settings"), "{stderr}");
    let from_log = logged_flags(&mcap_files(&dir.join("out")));
    assert!(
        from_log.iter().any(|f| f.1 == "outer_race"),
        "the simulated outer-race fault was not flagged: {from_log:?}"
    );
    let (summary, _) = replay_json(
        &log,
        &dir.join("out2"),
        &["--config", dir.join("log/replay.toml").to_str().unwrap()],
    );
    assert_eq!(summary["settings_from"], "config", "{summary}");
    assert_eq!(logged_flags(&mcap_files(&dir.join("out2"))), from_log);
}

/// A log without the metadata records (as an older bearingd wrote) is replayed with the
/// embedded default, and that is said.
#[test]
fn replay_of_a_log_without_metadata_says_it_falls_back_to_the_embedded_default() {
    use bearingd::messages::{ChannelId, RawBlock};
    use bearingd::sinks::mcap::{LoggerConfig, McapLogger};
    let dir = scratch_dir("replay-bare");
    let origin = 1_700_000_000_000_000_000u64;
    let mut logger = McapLogger::create(LoggerConfig::new(dir.join("log")), origin).unwrap();
    for k in 0..20u64 {
        let block = PipelineMessage::Raw(RawBlock {
            channel: ChannelId {
                sensor: "older".into(),
                axis: "radial".into(),
            },
            first_sample: k * 1280,
            sample_rate_hz: 12_800.0,
            scale_g_per_count: 1e-4,
            counts: vec![0; 1280],
        });
        let at = origin + k * 100_000_000;
        logger.log(&block, at, at).unwrap();
    }
    logger.finish().unwrap();
    let log = mcap_files(&dir.join("log"));
    let (summary, stderr) = replay_json(&log, &dir.join("out"), &[]);
    assert_eq!(summary["settings_from"], "embedded_default", "{summary}");
    assert!(
        stderr.contains("carries no settings") && stderr.contains("give --config"),
        "{stderr}"
    );
    // The embedded default has no sensor `older`: skipped, and said.
    assert_eq!(summary["unknown_channels"][0], "older/radial", "{summary}");
}

/// (channel, kind, stage, sample) of every health message in the logs.
fn logged_health(files: &[PathBuf]) -> Vec<(String, String, String, u64)> {
    read_messages(files)
        .filter_map(|m| match m.expect("readable log").message {
            PipelineMessage::Health(h) => Some((
                h.channel.to_string(),
                format!("{:?}", h.kind),
                format!("{:?}", h.stage),
                h.end_sample,
            )),
            _ => None,
        })
        .collect()
}

/// A restarted daemon starts from the baselines it loaded (`baselines.json`); its log records
/// them (`bearingd.state`), so a replay of that run alone starts from the same state and
/// writes the live run's health messages, not a relearning.
#[test]
fn the_replay_of_a_restarted_run_starts_from_the_baselines_the_daemon_loaded() {
    use bearingd::mcap_log::header::read_header;
    let dir = scratch_dir("replay-state");
    let data = dir.join("data");
    let config = config_at(&dir, "state", 12_800, 3600);
    fast_run(&config, &data, "40");
    let first_run = mcap_files(&data.join("mcap"));
    let first = read_header(&first_run[0]).unwrap();
    assert_eq!(
        first.start_baselines_json.as_deref(),
        Some("[]"),
        "{first:?}"
    );
    fast_run(&config, &data, "20");
    let second_run: Vec<PathBuf> = mcap_files(&data.join("mcap"))
        .into_iter()
        .filter(|f| !first_run.contains(f))
        .collect();
    let header = read_header(&second_run[0]).unwrap();
    let loaded = std::fs::read_to_string(data.join("state/baselines.json")).ok();
    let logged = header.start_baselines_json.clone().unwrap_or_default();
    assert!(
        logged.contains("motor-de"),
        "the restart's log records no baselines: {logged} (baselines.json: {loaded:?})"
    );

    let (summary, _) = replay_json(&second_run, &dir.join("replay"), &[]);
    assert_eq!(summary["runs"][0]["baselines_from"], "log", "{summary}");
    let live = logged_health(&second_run);
    let replayed = logged_health(&mcap_files(&dir.join("replay")));
    assert!(
        !live.is_empty(),
        "the restarted run logged no health message"
    );
    assert_eq!(replayed, live);
    // The replay's own log records the same starting state.
    let again = read_header(&mcap_files(&dir.join("replay"))[0]).unwrap();
    assert_eq!(again.start_baselines_json.as_deref(), Some(logged.as_str()));
}

/// A `bearingd.state` record that does not read is said on stderr and in `--json`, and the run
/// learns its baselines, never silently as if the record were fine or absent.
#[test]
fn a_state_record_that_does_not_read_is_said_and_the_run_learns_from_scratch() {
    use bearingd::config::Config;
    use bearingd::messages::{ChannelId, RawBlock};
    use bearingd::sinks::mcap::metadata::run_records;
    use bearingd::sinks::mcap::{LoggerConfig, McapLogger};
    let dir = scratch_dir("replay-bad-state");
    let config = Config::default_embedded().unwrap();
    let fs = config.sensors[0].sample_rate_hz;
    let origin = 1_700_000_000_000_000_000u64;
    let mut metadata = run_records(&config, origin, origin, &Default::default());
    let state = metadata
        .iter_mut()
        .find(|(name, _)| name == "bearingd.state")
        .expect("a bearingd.state record");
    state.1.insert("baselines_json".into(), "[[\"cut".into());
    let logger_config = LoggerConfig {
        metadata,
        ..LoggerConfig::new(dir.join("log"))
    };
    let mut logger = McapLogger::create(logger_config, origin).unwrap();
    let block = (fs / 10.0) as u64;
    for k in 0..20u64 {
        let raw = PipelineMessage::Raw(RawBlock {
            channel: ChannelId {
                sensor: config.sensors[0].id.clone(),
                axis: config.sensors[0].axes[0].clone(),
            },
            first_sample: k * block,
            sample_rate_hz: fs,
            scale_g_per_count: 1e-4,
            counts: vec![0; block as usize],
        });
        let at = origin + k * 100_000_000;
        logger.log(&raw, at, at).unwrap();
    }
    logger.finish().unwrap();
    let (summary, stderr) = replay_json(&mcap_files(&dir.join("log")), &dir.join("out"), &[]);
    assert_eq!(summary["settings_from"], "log", "{summary}");
    assert_eq!(summary["samples"], 20 * block, "{summary}");
    assert_eq!(
        summary["runs"][0]["baselines_from"], "unreadable_record",
        "{summary}"
    );
    assert!(
        stderr.contains("bearingd.state record does not read")
            && stderr.contains("learning its baselines from scratch"),
        "{stderr}"
    );
}
