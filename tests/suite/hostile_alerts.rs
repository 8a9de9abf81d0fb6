//! Hostile neighbours of the alert service (issue 32, item 2): what others may leave at the
//! iceoryx2 root's path. The real `bearingd` binary runs as a second process on a root the
//! test planted: it must refuse it with the fix, before any log file exists (a refused start
//! used to leave an empty log behind, one per restart), and never follow a link there.

use super::hostile_files::{config, run_daemon, stderr_of};
use bearingd_testdata::{iox_root, mcap_files, scratch_dir};
use std::os::unix::fs::{symlink, PermissionsExt};
use std::path::Path;

/// Runs the daemon twice (a restart loop) on `data` and checks each start is refused with exit
/// 2, an error containing every one of `expected`, and no log left.
fn refused_twice(config: &Path, data: &Path, expected: &[&str]) {
    for start in 1..=2 {
        let out = run_daemon(config, data, "022");
        let err = stderr_of(&out);
        assert_eq!(out.status.code(), Some(2), "start {start}: {err}");
        for needle in expected {
            assert!(
                err.contains(needle),
                "start {start}: no {needle:?} in: {err}"
            );
        }
        let logs = mcap_files(&data.join("mcap"));
        assert!(logs.is_empty(), "start {start} left logs: {logs:?}");
    }
}

#[test]
fn a_link_at_the_iox_root_is_refused_and_not_followed_and_no_log_is_left() {
    let dir = scratch_dir("hostile-root-link");
    let config = config(&dir, "hrl");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hrl");
    let victim = dir.join("victim-dir");
    std::fs::create_dir_all(&victim).unwrap();
    let _ = std::fs::remove_dir_all(&root);
    symlink(&victim, &root).unwrap();
    let root_text = root.display().to_string();
    refused_twice(
        &config,
        &dir.join("data"),
        &[&root_text, "symbolic link", &format!("rm {root_text}")],
    );
    assert_eq!(
        std::fs::read_dir(&victim).unwrap().count(),
        0,
        "iceoryx2 wrote into the link's target"
    );
    std::fs::remove_file(&root).unwrap();
}

#[test]
fn a_root_others_can_write_or_a_file_at_its_path_is_refused_with_the_fix() {
    let dir = scratch_dir("hostile-root-open");
    let config = config(&dir, "hro");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hro");
    let root_text = root.display().to_string();
    let _ = std::fs::remove_dir_all(&root);
    let _ = std::fs::remove_file(&root);
    std::fs::create_dir_all(&root).unwrap();
    std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o777)).unwrap();
    refused_twice(
        &config,
        &dir.join("data"),
        &[&root_text, "0777", "rm -r", "outputs.iceoryx2_root"],
    );
    std::fs::remove_dir_all(&root).unwrap();
    std::fs::write(&root, "not a directory").unwrap();
    refused_twice(
        &config,
        &dir.join("data"),
        &[&root_text, "not a directory", "outputs.iceoryx2_root"],
    );
    std::fs::remove_file(&root).unwrap();
}

#[test]
fn the_daemons_own_0750_root_is_tightened_to_0700_and_the_run_goes_on() {
    let dir = scratch_dir("hostile-root-own");
    let config = config(&dir, "hrw");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hrw");
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o750)).unwrap();
    let data = dir.join("data");
    let out = run_daemon(&config, &data, "022");
    let err = stderr_of(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("was mode 0750: now 0700"), "{err}");
    let mode = std::fs::metadata(&root).unwrap().permissions().mode() & 0o7777;
    assert_eq!(mode, 0o700);
    assert_eq!(mcap_files(&data.join("mcap")).len(), 1);
    let _ = std::fs::remove_dir_all(&root);
}
