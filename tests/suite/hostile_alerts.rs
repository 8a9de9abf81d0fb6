//! Hostile neighbours of the alert service (issue 32, item 2): what others may leave at the
//! iceoryx2 root's path. The real `bearingd` binary runs as a second process on a root the
//! test planted: it must refuse it with the fix, before any log file exists (a refused start
//! used to leave an empty log behind, one per restart), and never follow a link there.

use super::hostile_files::{config, run_daemon};
use crate::cli::stderr as stderr_of;
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

/// Another user (uid 61032, `$BEARINGD_TEST_OTHER_UID` to change it) creates the root first,
/// mode 0777, in a sticky directory both may write (as /dev/shm is): the daemon refuses it,
/// naming the owner and the fix, and leaves no log. Needs root to act as the other user.
#[test]
fn a_root_another_user_made_first_is_refused_naming_its_owner() {
    if !is_root() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "this test needs root (setpriv to another uid); run the suite as root"
        );
        eprintln!("skipped: not root, cannot act as another user");
        return;
    }
    let other: u32 = std::env::var("BEARINGD_TEST_OTHER_UID")
        .ok()
        .and_then(|u| u.parse().ok())
        .unwrap_or(61032);
    let dir = scratch_dir("hostile-root-foreign");
    let config = config(&dir, "hrf");
    let shared = iox_root(env!("CARGO_TARGET_TMPDIR"), "hrf");
    let _ = std::fs::remove_dir_all(&shared);
    std::fs::create_dir_all(&shared).unwrap();
    std::fs::set_permissions(&shared, std::fs::Permissions::from_mode(0o1777)).unwrap();
    let root = shared.join("r");
    let made = std::process::Command::new("setpriv")
        .args([&format!("--reuid={other}"), &format!("--regid={other}")])
        .args(["--clear-groups", "--", "mkdir", "-m", "0777"])
        .arg(&root)
        .status()
        .expect("run setpriv (util-linux)");
    assert!(
        made.success(),
        "uid {other} could not create {}",
        root.display()
    );
    let text = std::fs::read_to_string(&config).unwrap().replace(
        &format!("\"{}\"", shared.display()),
        &format!("\"{}\"", root.display()),
    );
    std::fs::write(&config, text).unwrap();
    let root_text = root.display().to_string();
    refused_twice(
        &config,
        &dir.join("data"),
        &[
            &root_text,
            &format!("owned by uid {other}"),
            &format!("rm -r {root_text} as root"),
        ],
    );
    assert_eq!(
        std::fs::read_dir(&root).unwrap().count(),
        0,
        "iceoryx2 used it"
    );
    std::fs::remove_dir_all(&shared).unwrap();
}

fn is_root() -> bool {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1))
        == Some("0")
}
