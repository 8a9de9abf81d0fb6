//! Hostile neighbours of the alert service (issue 32, items 1 and 2): what others may leave at
//! the iceoryx2 root's path, and other processes on the service itself. The real `bearingd`
//! binary runs as a second process on a root the test planted: it must refuse it with the fix,
//! before any log file exists (a refused start used to leave an empty log behind, one per
//! restart), and never follow a link there. A forger (`tests/python/forge_alert.py`, a
//! process of the same user) can neither publish beside the daemon nor hold the service
//! before it; `bearingd alerts` and the Python example refuse a root of another user.

use super::hostile_files::{config, run_daemon};
use crate::cli::stderr as stderr_of;
use bearingd_testdata::{iox_root, mcap_files, scratch_dir};
use std::os::unix::fs::{symlink, PermissionsExt};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

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
    let Some(other) = other_uid() else {
        return;
    };
    let dir = scratch_dir("hostile-root-foreign");
    let (config, shared, root) = root_made_by(other, "0777", &dir, "hrf");
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

/// A config in `dir` whose iceoryx2 root `<shared>/r` user `other` made first, with `mode`
/// (`mkdir -m`); returns (config, shared, root).
fn root_made_by(other: u32, mode: &str, dir: &Path, tag: &str) -> (PathBuf, PathBuf, PathBuf) {
    let config = config(dir, tag);
    let configured = iox_root(env!("CARGO_TARGET_TMPDIR"), tag);
    let shared = sticky_dir_of_two_users(tag);
    let root = shared.join("r");
    let made = as_user(other, "mkdir")
        .args(["-m", mode])
        .arg(&root)
        .status()
        .expect("run setpriv (util-linux)");
    assert!(
        made.success(),
        "uid {other} could not create {}",
        root.display()
    );
    let text = std::fs::read_to_string(&config).unwrap().replace(
        &format!("\"{}\"", configured.display()),
        &format!("\"{}\"", root.display()),
    );
    std::fs::write(&config, text).unwrap();
    (config, shared, root)
}

/// A fresh directory directly in /dev/shm, mode 1777 as /dev/shm itself: both users may make
/// entries in it (the tests' own iox roots may sit in a 0700 directory of the test's user,
/// which the other user cannot enter).
fn sticky_dir_of_two_users(tag: &str) -> PathBuf {
    let dir = PathBuf::from(format!("/dev/shm/bd-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir(&dir).unwrap();
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o1777)).unwrap();
    dir
}

/// The uid to act as another user (`$BEARINGD_TEST_OTHER_UID`, default 61032, no passwd
/// entry needed), when this test runs as root; else `None` (said), or a failure under CI=true.
pub(super) fn other_uid() -> Option<u32> {
    if !is_root() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "this test needs root (setpriv to another uid); run the suite as root"
        );
        eprintln!("skipped: not root, cannot act as another user");
        return None;
    }
    Some(
        std::env::var("BEARINGD_TEST_OTHER_UID")
            .ok()
            .and_then(|u| u.parse().ok())
            .unwrap_or(61032),
    )
}

/// `program` run as `uid` (and its gid, no supplementary groups) through setpriv.
pub(super) fn as_user(uid: u32, program: impl AsRef<std::ffi::OsStr>) -> Command {
    let mut command = Command::new("setpriv");
    command
        .args([&format!("--reuid={uid}"), &format!("--regid={uid}")])
        .args(["--clear-groups", "--"])
        .arg(program);
    command
}

fn is_root() -> bool {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1))
        == Some("0")
}

/// The forger, `tests/python/forge_alert.py`, on `root` (the .venv's Python with iceoryx2).
fn forger(root: &Path) -> Option<Command> {
    let python = bearingd_testdata::python_iceoryx2()?;
    let mut command = Command::new(python);
    command
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/python/forge_alert.py"))
        .arg("--root")
        .arg(root);
    Some(command)
}

/// The daemon of `config` in real time for up to `seconds`, once its alert service exists.
fn live_daemon(config: &Path, data: &Path, root: &Path, seconds: &str) -> Child {
    let mut daemon = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["run", "--quiet", "--duration", seconds, "--config"])
        .arg(config)
        .arg("--data-dir")
        .arg(data)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let services = root.join("services");
    let start = Instant::now();
    while std::fs::read_dir(&services).map_or(0, |d| d.count()) < 2 {
        if let Ok(Some(status)) = daemon.try_wait() {
            let out = daemon.wait_with_output().unwrap();
            panic!("daemon ended ({status}): {}", stderr_of(&out));
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no alert service"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    daemon
}

fn stop(daemon: Child) -> std::process::Output {
    let _ = Command::new("kill")
        .args(["-TERM", &daemon.id().to_string()])
        .status();
    daemon.wait_with_output().unwrap()
}

/// `bearingd alerts --json` of `config` for `seconds`.
fn alerts_json(config: &Path, seconds: &str) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["alerts", "--json", "--timeout", seconds, "--config"])
        .arg(config)
        .output()
        .unwrap()
}

/// A process of the daemon's own user tries to publish a forged inner-race alarm (and a
/// forged huge sequence number, and a forged "cleared") while the daemon runs: iceoryx2
/// refuses it a publisher (the service has one, the daemon's), and `bearingd alerts` shows
/// nothing of it. Before issue 32 the service took two publishers and the forgery was shown.
#[test]
fn a_forger_of_the_daemons_user_cannot_publish_beside_it() {
    let dir = scratch_dir("hostile-forger");
    let config = config(&dir, "hfg");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hfg");
    let Some(_) = forger(&root) else {
        return;
    };
    let daemon = live_daemon(&config, &dir.join("data"), &root, "60");
    let forgeries: [&[&str]; 3] = [
        &["--sequence", "1", "--state", "raised"],
        &["--sequence", "1000000000", "--state", "raised"],
        &["--sequence", "2", "--state", "cleared", "--severity", "ok"],
    ];
    let mut results = Vec::new();
    for args in forgeries {
        let out = forger(&root)
            .unwrap()
            .args(["--publish", "--hold", "3", "--run-id", "1"])
            .args(args)
            .output()
            .unwrap();
        results.push(out);
    }
    let seen = alerts_json(&config, "2");
    let out = stop(daemon);
    assert!(out.status.success(), "daemon: {}", stderr_of(&out));
    for (args, result) in forgeries.iter().zip(&results) {
        let text = String::from_utf8_lossy(&result.stdout);
        assert_eq!(
            result.status.code(),
            Some(3),
            "forger {args:?} was not refused: {text} {}",
            stderr_of(result)
        );
        assert!(text.contains("refused"), "{text}");
    }
    let text = String::from_utf8_lossy(&seen.stdout);
    assert!(!text.contains("forged") && !text.contains("lost"), "{text}");
}

/// A live process of the same user that made the service first, of another shape: the daemon
/// refuses to start, naming its pid and program and the fix; once it is killed (`kill -9`,
/// nothing cleaned), the daemon removes the dead node and starts.
#[test]
fn a_service_held_by_a_live_forger_is_refused_naming_it_and_cleaned_once_it_died() {
    let dir = scratch_dir("hostile-holder");
    let config = config(&dir, "hho");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hho");
    let Some(mut holder) = forger(&root) else {
        return;
    };
    std::fs::create_dir_all(&root).unwrap();
    std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o700)).unwrap();
    let mut holder = holder
        .args(["--create", "--shape", "bad", "--hold", "60"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut ready = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(holder.stdout.as_mut().unwrap()),
        &mut ready,
    )
    .unwrap();
    assert_eq!(ready.trim(), "ready");
    let pid = holder.id().to_string();
    refused_twice(
        &config,
        &dir.join("data"),
        &[
            &format!("pid {pid} (python3"),
            "another shape",
            "outputs.alerts_service",
        ],
    );
    holder.kill().unwrap();
    holder.wait().unwrap();
    let out = run_daemon(&config, &dir.join("data"), "022");
    let err = stderr_of(&out);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("pid {pid}")),
        "the dead node is not said: {err}"
    );
}

/// Root's `bearingd alerts` facing a root another user made (0700, as a daemon of that user
/// would): it refuses with the `runuser` fix, and never becomes that user (it used to setuid to
/// the owner of the directory). The Python example refuses it too.
#[test]
fn roots_subscribers_refuse_another_users_root_and_never_switch_to_it() {
    let Some(other) = other_uid() else {
        return;
    };
    let dir = scratch_dir("hostile-root-sub");
    let (config, shared, root) = root_made_by(other, "0700", &dir, "hrs");
    let out = alerts_json(&config, "3");
    let err = stderr_of(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(&format!("uid {other}")), "{err}");
    assert!(err.contains("runuser -u"), "{err}");
    assert!(!err.contains("running as uid"), "{err}");
    if let Some(python) = bearingd_testdata::python_iceoryx2() {
        let out = Command::new(python)
            .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/alerts_subscriber.py"))
            .arg("--root")
            .arg(&root)
            .args(["--timeout", "3"])
            .output()
            .unwrap();
        let err = stderr_of(&out);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(&format!("uid {other}")), "{err}");
    }
    std::fs::remove_dir_all(&shared).unwrap();
}

/// Guard (worked before issue 32 and must still work): the daemon killed (`kill -9`) and
/// restarted while `bearingd alerts` stays connected. The connected subscriber keeps the
/// service alive, so the new daemon removes the dead node, reopens its own previous service
/// (same user, same shape) and says so; the subscriber's checks accept the new publisher.
#[test]
fn a_daemon_killed_and_restarted_under_a_connected_subscriber_reopens_its_service() {
    let dir = scratch_dir("hostile-restart");
    let config = config(&dir, "hre");
    let root = iox_root(env!("CARGO_TARGET_TMPDIR"), "hre");
    let data = dir.join("data");
    let mut first = live_daemon(&config, &data, &root, "60");
    let subscriber = Command::new(env!("CARGO_BIN_EXE_bearingd"))
        .args(["alerts", "--json", "--timeout", "10", "--config"])
        .arg(&config)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs(2));
    first.kill().unwrap();
    first.wait().unwrap();
    let second = live_daemon(&config, &data, &root, "60");
    std::thread::sleep(Duration::from_secs(3));
    let out = stop(second);
    let err = stderr_of(&out);
    let seen = subscriber.wait_with_output().unwrap();
    let seen_err = stderr_of(&seen);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("reopened our previous run's service"), "{err}");
    assert!(
        err.contains("removed the stale resources of a dead"),
        "{err}"
    );
    assert!(
        !seen_err.contains("not to be trusted"),
        "the subscriber refused the restarted daemon: {seen_err}"
    );
    assert_eq!(seen.status.code(), Some(0), "{seen_err}");
}
