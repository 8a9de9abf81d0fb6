//! Hostile and broken files named like logs, read by the real `bearingd` under an address-space
//! limit (issue 32 item 6): a record whose string declares 4 GiB inside 60 bytes, a top-level
//! record declaring 4 GiB, the MCAP magic followed by random bytes, and a valid log cut in the
//! middle of a chunk. `analyze` and `replay` must refuse the first three with an error naming
//! the file (exit 2, never an abort), read the cut log as far as it is valid, and the daemon's
//! start-up recovery must quarantine them, leave no `.recovering` copy and release its lock.

use crate::cli::stderr as stderr_of;
use bearingd::mcap_log::read_raw_blocks;
use bearingd_testdata::{iox_root, mcap_files, noise, scratch_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Address-space limit of every child, in KiB (`ulimit -v`): 2 GB, half of what the 4 GiB
/// declared lengths would need, far above what reading any of these files needs.
const ADDRESS_SPACE_KIB: &str = "2000000";

/// `bearingd args...` under [`ADDRESS_SPACE_KIB`]; asserts it exited (no abort, no signal).
fn bearingd_limited(args: &[&str]) -> Output {
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {ADDRESS_SPACE_KIB}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_bearingd"))
        .args(args)
        .output()
        .expect("run bearingd under sh");
    assert!(
        out.status.code().is_some(),
        "bearingd {args:?} was killed by a signal ({:?}): {}",
        out.status,
        stderr_of(&out)
    );
    out
}

/// An MCAP record: opcode, the declared length (u64 LE), the body.
fn record(opcode: u8, declared_len: u64, body: &[u8]) -> Vec<u8> {
    let mut out = vec![opcode];
    out.extend(declared_len.to_le_bytes());
    out.extend_from_slice(body);
    out
}

fn string(s: &str) -> Vec<u8> {
    let mut out = (s.len() as u32).to_le_bytes().to_vec();
    out.extend_from_slice(s.as_bytes());
    out
}

/// The magic and a well-formed header record: what every hostile file starts with.
fn mcap_start() -> Vec<u8> {
    let mut header = string("");
    header.extend(string("hostile"));
    let mut out = mcap::MAGIC.to_vec();
    out.extend(record(0x01, header.len() as u64, &header));
    out
}

/// (file name, bytes) of the three files from which nothing may be read.
fn hostile_files() -> Vec<(&'static str, Vec<u8>)> {
    // A metadata record of 27 bytes whose map holds one key declaring 4 GiB - 1: the map's own
    // length fits, the key's does not (the mcap crate reserved the key's length before reading).
    let mut metadata = string("bearingd.run");
    let mut map = u32::MAX.to_le_bytes().to_vec();
    map.extend_from_slice(b"abc");
    metadata.extend((map.len() as u32).to_le_bytes());
    metadata.extend(map);
    let mut string_4gib = mcap_start();
    string_4gib.extend(record(0x0C, metadata.len() as u64, &metadata));

    let mut record_4gib = mcap_start();
    record_4gib.extend(record(0x0C, 4 << 30, &[0u8; 64]));

    let mut random = mcap::MAGIC.to_vec();
    random.extend(noise(100_000, 7));
    vec![
        ("bearingd-20200101T000000Z-000001.mcap", string_4gib),
        ("bearingd-20200101T000000Z-000002.mcap", record_4gib),
        ("bearingd-20200101T000000Z-000003.mcap", random),
    ]
}

/// The embedded default with an iceoryx2 root of its own (`tag`), written to `dir`; the
/// config's path and the root (to remove after the run).
fn config_with_own_iox_root(dir: &Path, tag: &str) -> (PathBuf, PathBuf) {
    let config = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["config", "default"])
        .output()
        .unwrap();
    assert!(config.status.success());
    let iox = iox_root(env!("CARGO_TARGET_TMPDIR"), tag);
    std::fs::create_dir_all(&iox).unwrap();
    let text = String::from_utf8(config.stdout).unwrap().replace(
        "\"/run/bearingd/iceoryx2\"",
        &format!("\"{}\"", iox.display()),
    );
    assert!(text.contains(&iox.display().to_string()));
    let path = dir.join("config.toml");
    std::fs::write(&path, text).unwrap();
    (path, iox)
}

/// `bearingd run --fast` of `config` on `data` for `seconds` of signal, under the limit.
fn fast_run(config: &Path, data: &Path, seconds: &str) -> Output {
    bearingd_limited(&[
        "run",
        "--config",
        config.to_str().unwrap(),
        "--data-dir",
        data.to_str().unwrap(),
        "--fast",
        "--quiet",
        "--duration",
        seconds,
    ])
}

/// A finished log of six seconds of the embedded default (several chunks).
fn valid_log(dir: &Path, config: &Path) -> PathBuf {
    let data = dir.join("source");
    let out = fast_run(config, &data, "6");
    assert!(out.status.success(), "{}", stderr_of(&out));
    let files = mcap_files(&data.join("mcap"));
    assert_eq!(files.len(), 1, "{files:?}");
    files[0].clone()
}

/// `log`'s first half, written to `to`: cut in the middle of a chunk.
fn cut_in_half(log: &Path, to: &Path) {
    let bytes = std::fs::read(log).unwrap();
    std::fs::write(to, &bytes[..bytes.len() / 2]).unwrap();
}

fn raw_block_count(file: &Path) -> usize {
    read_raw_blocks(&[file]).filter(Result::is_ok).count()
}

/// The number N of "replayed N blocks" in a replay's output.
fn replayed_blocks(out: &Output) -> usize {
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr_of(out));
    let after = text
        .split("replayed ")
        .nth(1)
        .unwrap_or_else(|| panic!("no 'replayed N blocks' in: {text}"));
    after.split(' ').next().unwrap().parse().unwrap()
}

#[test]
fn analyze_and_replay_refuse_hostile_logs_naming_them_and_read_a_cut_log_as_far_as_it_is_valid() {
    let dir = scratch_dir("hostile-read");
    for (name, bytes) in hostile_files() {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let analyzed = bearingd_limited(&["analyze", path.to_str().unwrap()]);
        let stderr = stderr_of(&analyzed);
        assert_eq!(analyzed.status.code(), Some(2), "analyze {name}: {stderr}");
        assert!(
            stderr.contains(name) && stderr.contains("no message could be read"),
            "analyze {name}: {stderr}"
        );
        let out = dir.join(format!("replay-{name}"));
        let replayed = bearingd_limited(&[
            "replay",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ]);
        let stderr = stderr_of(&replayed);
        assert_eq!(replayed.status.code(), Some(2), "replay {name}: {stderr}");
        assert!(
            stderr.contains(name)
                && stderr.contains("no message could be read")
                && stderr.contains("not a bearingd log or is truncated"),
            "replay {name}: {stderr}"
        );
    }

    let (config, iox) = config_with_own_iox_root(&dir, "hl");
    let log = valid_log(&dir, &config);
    let cut = dir.join("cut.mcap");
    cut_in_half(&log, &cut);
    let whole = raw_block_count(&log);
    let readable = raw_block_count(&cut);
    assert!(
        readable > 0 && readable < whole,
        "{readable} of {whole} raw blocks readable in the cut log"
    );
    let analyzed = bearingd_limited(&["analyze", cut.to_str().unwrap()]);
    assert!(analyzed.status.success(), "{}", stderr_of(&analyzed));
    let report = String::from_utf8_lossy(&analyzed.stdout);
    assert!(
        report.contains("warning: the log is unfinished"),
        "{report}"
    );
    let replayed = bearingd_limited(&[
        "replay",
        cut.to_str().unwrap(),
        "--out",
        dir.join("replay-cut").to_str().unwrap(),
    ]);
    let _ = std::fs::remove_dir_all(&iox);
    assert!(replayed.status.success(), "{}", stderr_of(&replayed));
    assert_eq!(replayed_blocks(&replayed), readable);
}

#[test]
fn start_up_recovery_quarantines_hostile_logs_leaves_no_copy_or_lock_and_recovers_a_cut_log() {
    let dir = scratch_dir("hostile-recover");
    let (config, iox) = config_with_own_iox_root(&dir, "hr");
    let log = valid_log(&dir, &config);
    let data = dir.join("data");
    let logs = data.join("mcap");
    std::fs::create_dir_all(&logs).unwrap();
    let hostile = hostile_files();
    for (name, bytes) in &hostile {
        std::fs::write(logs.join(name), bytes).unwrap();
    }
    let cut = logs.join("bearingd-20200101T000000Z-000004.mcap");
    cut_in_half(&log, &cut);
    let readable = raw_block_count(&cut);
    assert!(readable > 0);

    let out = fast_run(&config, &data, "1");
    let stderr = stderr_of(&out);
    assert!(out.status.success(), "{stderr}");
    for (name, bytes) in &hostile {
        assert!(!logs.join(name).exists(), "{name} is still among the logs");
        let kept = std::fs::read(logs.join("quarantine").join(name)).unwrap();
        assert_eq!(&kept, bytes, "{name} was changed in quarantine");
        assert!(
            stderr.contains(name) && stderr.contains("could not be recovered"),
            "{name}: {stderr}"
        );
    }
    assert!(
        stderr.contains(&format!("recovered {}", cut.display())),
        "{stderr}"
    );
    // The recovered file holds every block that was readable, and reads back finished.
    assert_eq!(raw_block_count(&cut), readable);
    let leftovers: Vec<_> = std::fs::read_dir(&logs)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".recovering"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    // A clean stop empties the lock: the next start finds no previous owner.
    let lock = std::fs::read_to_string(logs.join("bearingd.lock")).unwrap();
    assert!(lock.is_empty(), "lock left: {lock}");

    // The next start meets none of them again.
    let again = fast_run(&config, &data, "1");
    let _ = std::fs::remove_dir_all(&iox);
    let stderr = stderr_of(&again);
    assert!(again.status.success(), "{stderr}");
    assert!(
        !stderr.contains("recovered") && !stderr.contains("taken over"),
        "{stderr}"
    );
}
