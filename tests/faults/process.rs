//! The daemon as a process among others: a second daemon on the same data directory, the
//! lock of one killed with `kill -9`, baselines that survive a kill, the signal a kill costs,
//! and a replay of a file that is not a log.

use super::{
    bearingd, config_file, now_ns, python_metadata, raw_blocks, short_run, start_daemon, stderr_of,
    terminate, wait_for_log,
};
use bearingd::mcap_log::read_messages;
use bearingd::messages::PipelineMessage;
use bearingd_testdata::{check_mcap_with_python, mcap_files, noise, python_mcap, scratch_dir};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn a_second_daemon_on_the_same_data_dir_exits_2_naming_the_first_and_touches_nothing() {
    let dir = scratch_dir("faults-two");
    let data = dir.join("data");
    let mut first = start_daemon(&data);
    let open = wait_for_log(&data, 1);

    let second = short_run(&data);
    let stderr = stderr_of(&second);
    assert_eq!(second.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!("pid={}", first.id())) && stderr.contains("in use by another"),
        "{stderr}"
    );
    assert!(!stderr.contains("recovered"), "{stderr}");
    assert_eq!(mcap_files(&data.join("mcap")), vec![open.clone()]);

    // The first daemon goes on logging to its file and finishes it cleanly.
    let before = std::fs::metadata(&open).unwrap().len();
    wait_for_log(&data, before + 1);
    terminate(&mut first);
    let out = first.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert!(raw_blocks(std::slice::from_ref(&open)) > 0);
    if let Some(py) = python_mcap() {
        check_mcap_with_python(&py, &open, None);
    }
    // A clean stop releases the lock: the next start says nothing about a previous owner.
    let next = short_run(&data);
    assert!(next.status.success(), "{}", stderr_of(&next));
    assert!(
        !stderr_of(&next).contains("taken over"),
        "{}",
        stderr_of(&next)
    );
}

#[test]
fn the_lock_of_a_daemon_killed_with_sigkill_is_taken_over_and_said() {
    let dir = scratch_dir("faults-stale");
    let data = dir.join("data");
    let mut killed = start_daemon(&data);
    wait_for_log(&data, 1);
    let pid = killed.id();
    killed.kill().unwrap(); // SIGKILL
    killed.wait().unwrap();
    let lock = std::fs::read_to_string(data.join("mcap/bearingd.lock")).unwrap();
    assert!(lock.contains(&format!("pid={pid} ")), "{lock}");

    let out = short_run(&data);
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("taken over") && stderr.contains(&format!("pid={pid} ")),
        "{stderr}"
    );
}

#[test]
fn baselines_are_saved_on_a_period_so_a_kill_9_keeps_them_and_the_restart_says_what_it_loaded() {
    let dir = scratch_dir("faults-state");
    let data = dir.join("data");
    let root = format!("/dev/shm/bearingd-faults-{}", std::process::id());
    let config = config_file(&dir, |text| {
        let text = text
            .replace(
                "state_save_interval_s = 60.0",
                "state_save_interval_s = 0.2",
            )
            .replace("\"/run/bearingd/iceoryx2\"", &format!("\"{root}\""));
        assert!(text.contains("state_save_interval_s = 0.2"));
        text
    });
    let args = |duration: &'static str| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_bearingd"));
        cmd.args(["run", "--config", config.to_str().unwrap()])
            .args(["--data-dir", data.to_str().unwrap()])
            .args(["--fast", "--quiet", "--duration", duration]);
        cmd
    };
    let mut child = args("100000")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let saved = data.join("state/baselines.json");
    let deadline = Instant::now() + Duration::from_secs(120);
    while !std::fs::read_to_string(&saved).is_ok_and(|t| t.contains("motor-de")) {
        assert!(
            Instant::now() < deadline,
            "no baselines saved in {} while running",
            saved.display()
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    child.kill().unwrap(); // SIGKILL: no stop, no save at the end
    let killed = child.wait_with_output().unwrap();
    let stderr = stderr_of(&killed);
    assert!(
        stderr.contains("no saved health baselines") && stderr.contains("--data-dir overrides"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&saved).unwrap();
    let list: serde_json::Value = serde_json::from_str(&text).expect("a whole JSON file");
    assert!(!list.as_array().unwrap().is_empty());
    // --data-dir was honoured with --config: the logs are there too.
    assert!(!mcap_files(&data.join("mcap")).is_empty());

    let out = args("1").output().unwrap();
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("loaded the health baselines of 1 channel(s)")
            && stderr.contains(saved.to_str().unwrap()),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&root);
}

/// Seconds of signal the embedded default's log holds in `file`, contiguous from sample 0
/// (asserted), and the log-time origin the file names.
fn logged_signal(py: &Path, file: &Path) -> (f64, u64) {
    let mut next = 0u64;
    let mut rate = 0.0;
    for m in read_messages(&[file]) {
        if let PipelineMessage::Raw(b) = m.unwrap().message {
            assert_eq!(
                b.first_sample,
                next,
                "{}: a hole in the raw samples",
                file.display()
            );
            next += b.counts.len() as u64;
            rate = b.sample_rate_hz;
        }
    }
    let read = python_metadata(py, file);
    let origin = read["metadata"]["bearingd.run"][0]["log_time_origin_ns"]
        .as_str()
        .unwrap()
        .parse()
        .unwrap();
    (next as f64 / rate.max(1.0), origin)
}

/// `kill -9` of a real-time daemon at 20 seeded random moments: each time the restart
/// recovers the file, Python's strict reader reads it, its raw samples are contiguous from
/// the start, and the signal lost (from the last recovered sample to the kill) is at most the
/// last unflushed second plus the block in flight. Prints the losses for docs/OPERATIONS.md.
#[test]
fn kill_9_at_20_random_moments_loses_at_most_the_last_unflushed_second() {
    let Some(py) = python_mcap() else { return };
    const SEEDS: u64 = 20;
    let dir = scratch_dir("faults-kill9");
    let losses: Vec<(u64, f64, f64)> = std::thread::scope(|scope| {
        let workers: Vec<_> = (0..4u64)
            .map(|worker| {
                let (dir, py) = (&dir, &py);
                scope.spawn(move || {
                    let mut out = Vec::new();
                    for seed in (worker..SEEDS).step_by(4) {
                        let data = dir.join(format!("seed-{seed}"));
                        let mut child = start_daemon(&data);
                        wait_for_log(&data, 1);
                        // 0.2 to 3.2 s after the first flush reached the disk.
                        let wait_ms = 200
                            + noise(2, seed + 1)
                                .iter()
                                .fold(0u64, |a, &b| a * 256 + u64::from(b))
                                % 3000;
                        std::thread::sleep(Duration::from_millis(wait_ms));
                        child.kill().unwrap();
                        let killed_at = now_ns();
                        child.wait().unwrap();
                        let files = mcap_files(&data.join("mcap"));
                        assert_eq!(files.len(), 1, "{files:?}");
                        let out_run = short_run(&data);
                        assert!(out_run.status.success(), "{}", stderr_of(&out_run));
                        check_mcap_with_python(py, &files[0], None);
                        let (seconds, origin) = logged_signal(py, &files[0]);
                        let lived = (killed_at - origin) as f64 / 1e9;
                        out.push((seed, lived, lived - seconds));
                    }
                    out
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|w| w.join().unwrap())
            .collect()
    });
    assert_eq!(losses.len() as u64, SEEDS);
    let worst = losses.iter().map(|l| l.2).fold(0.0, f64::max);
    let mean = losses.iter().map(|l| l.2).sum::<f64>() / SEEDS as f64;
    eprintln!(
        "kill -9 at {SEEDS} moments: signal lost mean {mean:.2} s, worst {worst:.2} s; (seed, s logged before the kill, s lost): {losses:.2?}"
    );
    assert!(
        worst <= 2.0,
        "lost up to {worst:.2} s of signal: {losses:.2?}"
    );
}

#[test]
fn replay_of_a_file_that_is_not_mcap_exits_2_naming_it() {
    let dir = scratch_dir("faults-replay-junk");
    for (name, bytes) in [
        ("junk.mcap", noise(4096, 7)),
        ("short.mcap", b"MCAP".to_vec()),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let out = bearingd(&[
            "replay",
            path.to_str().unwrap(),
            "--out",
            dir.join("out").to_str().unwrap(),
            "--quiet",
        ]);
        let stderr = stderr_of(&out);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains(name) && stderr.contains("not an MCAP log"),
            "{stderr}"
        );
    }
}
