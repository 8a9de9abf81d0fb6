//! Hostile neighbours (issue 32, items 3 and 4): names planted where the daemon writes, and
//! modes that must not follow the umask. Each test plants a real symbolic link to a "victim"
//! file of its own with known content, runs the real `bearingd` binary as a second process,
//! and checks that the victim is untouched and that what the daemon says names the path.

use crate::cli::{bearingd, stderr as stderr_of};
use bearingd_testdata::{iox_root, mcap_files, scratch_dir};
use std::os::unix::fs::{symlink, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const VICTIM_TEXT: &str = "victim: nobody may write, truncate or print this\n";

/// A file of the test's, mode 0600, that no bearingd may change.
fn victim(dir: &Path) -> PathBuf {
    let path = dir.join("victim");
    std::fs::write(&path, VICTIM_TEXT).unwrap();
    std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
    path
}

fn assert_untouched(victim: &Path) {
    assert_eq!(std::fs::read_to_string(victim).unwrap(), VICTIM_TEXT);
    let mode = std::fs::metadata(victim).unwrap().permissions().mode();
    assert_eq!(mode & 0o777, 0o600, "the victim's mode changed");
}

fn mode_of(path: &Path) -> u32 {
    std::fs::symlink_metadata(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .permissions()
        .mode()
        & 0o777
}

/// The default config with an iceoryx2 root of the test's own, in `dir/config.toml`.
pub(super) fn config(dir: &Path, tag: &str) -> PathBuf {
    let out = bearingd(&["config", "default"]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), tag);
    let text = String::from_utf8(out.stdout).unwrap().replace(
        "\"/run/bearingd/iceoryx2\"",
        &format!("\"{}\"", root.display()),
    );
    assert!(text.contains(&root.display().to_string()));
    let path = dir.join("config.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// `bearingd run` of `config` on `data`, 2 s of simulated signal as fast as it goes, under
/// `umask` (the shell sets it, then execs the binary).
pub(super) fn run_daemon(config: &Path, data: &Path, umask: &str) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!("umask {umask}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_bearingd"))
        .args(["run", "--config", config.to_str().unwrap(), "--data-dir"])
        .arg(data)
        .args(["--fast", "--quiet", "--duration", "2"])
        .output()
        .expect("run bearingd under sh")
}

/// The bytes of an unfinished log (a finished one cut at three quarters, as a `kill -9`
/// leaves it), made by a run of its own under `dir`.
fn unfinished_log_bytes(dir: &Path, config: &Path) -> Vec<u8> {
    let data = dir.join("source-run");
    let out = run_daemon(config, &data, "022");
    assert!(out.status.success(), "{}", stderr_of(&out));
    let logs = mcap_files(&data.join("mcap"));
    assert_eq!(logs.len(), 1, "{logs:?}");
    let mut bytes = std::fs::read(&logs[0]).unwrap();
    bytes.truncate(bytes.len() * 3 / 4);
    bytes
}

#[test]
fn a_link_named_like_the_lock_is_refused_and_its_target_neither_truncated_nor_printed() {
    let dir = scratch_dir("hostile-lock");
    let victim = victim(&dir);
    let config = config(&dir, "hl");
    for sub in ["state", "mcap"] {
        let data = dir.join(format!("data-{sub}"));
        std::fs::create_dir_all(data.join(sub)).unwrap();
        let link = data.join(sub).join("bearingd.lock");
        symlink(&victim, &link).unwrap();
        let out = run_daemon(&config, &data, "022");
        let err = stderr_of(&out);
        assert!(
            !out.status.success(),
            "started through a planted lock link: {err}"
        );
        assert!(
            err.contains(&link.display().to_string()) && err.contains("symbolic link"),
            "{err}"
        );
        assert!(
            !err.contains("victim:"),
            "the victim's content was printed: {err}"
        );
        assert!(!String::from_utf8_lossy(&out.stdout).contains("victim:"));
        assert_untouched(&victim);
    }

    // `replay --out` locks its directory too.
    let data = dir.join("data-ok");
    let out = run_daemon(&config, &data, "022");
    assert!(out.status.success(), "{}", stderr_of(&out));
    let logs = mcap_files(&data.join("mcap"));
    let replay_out = dir.join("replay-out");
    std::fs::create_dir_all(&replay_out).unwrap();
    let link = replay_out.join("bearingd.lock");
    symlink(&victim, &link).unwrap();
    let mut args = vec!["replay", "--quiet", "--out", replay_out.to_str().unwrap()];
    args.extend(logs.iter().map(|l| l.to_str().unwrap()));
    let out = bearingd(&args);
    let err = stderr_of(&out);
    assert!(
        !out.status.success(),
        "replayed through a planted lock link: {err}"
    );
    assert!(
        err.contains(&link.display().to_string()) && !err.contains("victim:"),
        "{err}"
    );
    assert_untouched(&victim);
}

#[test]
fn a_link_at_the_baselines_temporary_is_replaced_not_written_through() {
    let dir = scratch_dir("hostile-state");
    let victim = victim(&dir);
    let config = config(&dir, "hs");
    let data = dir.join("data");
    std::fs::create_dir_all(data.join("state")).unwrap();
    let link = data.join("state/baselines.json.new");
    symlink(&victim, &link).unwrap();
    let out = run_daemon(&config, &data, "022");
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert_untouched(&victim);
    // The save went to a file of its own, renamed into place; the planted name is gone.
    let saved = data.join("state/baselines.json");
    assert!(std::fs::symlink_metadata(&saved).unwrap().is_file());
    assert!(std::fs::read_to_string(&saved).unwrap().contains('{'));
    assert!(
        std::fs::symlink_metadata(&link).is_err(),
        "{} is left",
        link.display()
    );
}

#[test]
fn import_does_not_write_its_settings_through_a_link() {
    let dir = scratch_dir("hostile-import");
    let victim = victim(&dir);
    let record = dir.join("outer.wav");
    let made = bearingd(&[
        "simulate",
        "--fault",
        "outer",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
        "--duration",
        "2s",
        "--out",
        record.to_str().unwrap(),
    ]);
    assert!(made.status.success(), "{}", stderr_of(&made));
    let out_dir = dir.join("imported");
    std::fs::create_dir_all(&out_dir).unwrap();
    let link = out_dir.join("replay.toml");
    symlink(&victim, &link).unwrap();
    let out = bearingd(&[
        "import",
        record.to_str().unwrap(),
        "--out",
        out_dir.to_str().unwrap(),
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
    ]);
    assert!(out.status.success(), "{}", stderr_of(&out));
    assert_untouched(&victim);
    let written = std::fs::symlink_metadata(&link).unwrap();
    assert!(written.is_file(), "replay.toml is still a link");
    assert!(std::fs::read_to_string(&link)
        .unwrap()
        .contains("[[sensors]]"));
    assert_eq!(
        mode_of(&link) & 0o007,
        0,
        "replay.toml is readable by others"
    );
}

#[test]
fn recovery_and_retention_leave_a_log_named_link_alone_and_say_so() {
    let dir = scratch_dir("hostile-recover");
    let config = config(&dir, "hr");
    // The victim is an unfinished log the test owns, readable by its owner only: read
    // through the link, recovery would copy its content into the log directory.
    let victim = dir.join("private.mcap");
    std::fs::write(&victim, unfinished_log_bytes(&dir, &config)).unwrap();
    std::fs::set_permissions(&victim, std::fs::Permissions::from_mode(0o600)).unwrap();
    let before = std::fs::read(&victim).unwrap();
    let data = dir.join("data");
    std::fs::create_dir_all(data.join("mcap")).unwrap();
    let link = data.join("mcap/bearingd-20200101T000000Z-000000.mcap");
    symlink(&victim, &link).unwrap();
    let out = run_daemon(&config, &data, "022");
    let err = stderr_of(&out);
    assert!(out.status.success(), "{err}");
    assert_eq!(
        std::fs::read(&victim).unwrap(),
        before,
        "the victim changed"
    );
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink(),
        "the link was replaced by a recovered copy"
    );
    let said = |what: &str| {
        err.lines()
            .any(|l| l.contains(what) && l.contains(&link.display().to_string()))
    };
    assert!(said("recovery left alone"), "{err}");
    assert!(said("retention left alone"), "{err}");
    assert!(err.contains("symbolic link"), "{err}");
    assert!(!data.join("mcap/quarantine").exists());
}

#[test]
fn under_umask_000_directories_are_0750_and_files_0640_and_a_recovered_copy_never_wider() {
    let dir = scratch_dir("hostile-umask");
    let config = config(&dir, "hu");
    let data = dir.join("data");
    let out = run_daemon(&config, &data, "000");
    assert!(out.status.success(), "{}", stderr_of(&out));
    for made in [&data, &data.join("state"), &data.join("mcap")] {
        assert_eq!(mode_of(made), 0o750, "{}", made.display());
    }
    let logs = mcap_files(&data.join("mcap"));
    assert_eq!(logs.len(), 1, "{logs:?}");
    for made in [
        &logs[0],
        &data.join("state/baselines.json"),
        &data.join("state/bearingd.lock"),
        &data.join("mcap/bearingd.lock"),
    ] {
        assert_eq!(mode_of(made), 0o640, "{}", made.display());
    }

    // Unfinished logs of modes 0666 and 0600, recovered at the next start under umask 000:
    // 0640 (never wider) and 0600 (kept).
    let unfinished = unfinished_log_bytes(&dir, &config);
    let wide = data.join("mcap/bearingd-20200101T000000Z-000000.mcap");
    let narrow = data.join("mcap/bearingd-20200101T000000Z-000001.mcap");
    for (path, mode) in [(&wide, 0o666), (&narrow, 0o600)] {
        std::fs::write(path, &unfinished).unwrap();
        std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode)).unwrap();
    }
    let out = run_daemon(&config, &data, "000");
    let err = stderr_of(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("recovered {}", wide.display())),
        "{err}"
    );
    assert!(
        err.contains(&format!("recovered {}", narrow.display())),
        "{err}"
    );
    assert_eq!(mode_of(&wide), 0o640);
    assert_eq!(mode_of(&narrow), 0o600);
}

#[test]
fn a_data_directory_others_can_write_is_refused_with_the_fix() {
    let dir = scratch_dir("hostile-modes");
    let config = config(&dir, "hm");
    let data = dir.join("data");
    std::fs::create_dir_all(data.join("mcap")).unwrap();
    for (open, other) in [
        (data.clone(), data.join("mcap")),
        (data.join("mcap"), data.clone()),
    ] {
        std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
        std::fs::set_permissions(&other, std::fs::Permissions::from_mode(0o750)).unwrap();
        let out = run_daemon(&config, &data, "022");
        let err = stderr_of(&out);
        assert!(
            !out.status.success(),
            "started in a world-writable {}",
            open.display()
        );
        assert!(
            err.contains(&format!("chmod o-w {}", open.display())) && err.contains("0777"),
            "{err}"
        );
        assert!(
            mcap_files(&data.join("mcap")).is_empty(),
            "a log was opened"
        );
    }
}
