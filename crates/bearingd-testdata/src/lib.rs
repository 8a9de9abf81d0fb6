//! Test helpers shared by bearingd's unit and integration tests: a dev-dependency only, so none
//! of it compiles into the daemon.
//!
//! The real data sets live outside the repository (`../shared/data`, never committed), so a test
//! that needs one must say loudly when it is missing, and must fail on CI where a silent skip
//! would hide that nothing was tested.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The directory of one shared data set (`cwru`, `femto`, `ims`): under `$BEARINGD_DATA_DIR`
/// if set, else `<repository>/../shared/data`.
///
/// When it is missing: with `CI=true` this panics (the test fails) naming the data set and
/// where it was looked for; otherwise it prints a loud notice (past the test harness's capture) and returns `None` so the test
/// can return early.
pub fn shared_data_dir(kind: &str) -> Option<PathBuf> {
    let (base, source) = match std::env::var_os("BEARINGD_DATA_DIR") {
        Some(dir) => (PathBuf::from(dir), "$BEARINGD_DATA_DIR"),
        None => (
            repo_root().join("../shared/data"),
            "the default <repository>/../shared/data",
        ),
    };
    let dir = base.join(kind);
    if dir.is_dir() {
        return Some(dir);
    }
    let message = format!(
        "data set '{kind}' is missing: looked for {} (from {source}); set BEARINGD_DATA_DIR to the directory that holds cwru/, femto/ and ims/",
        dir.display()
    );
    let ci = std::env::var("CI").is_ok_and(|v| v.eq_ignore_ascii_case("true") || v == "1");
    if ci {
        panic!("{message}");
    }
    // Written to the stderr handle directly: the test harness captures eprintln! output of
    // passing tests, and this notice must be seen.
    let _ = writeln!(
        std::io::stderr(),
        "\n**********\nSKIPPING: {message}\n**********\n"
    );
    None
}

/// The root of the bearingd repository (this crate lives in `crates/bearingd-testdata`).
pub fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh, empty scratch directory under the system temp dir, unique per process and call.
///
/// A test's directory outlives it, so that a failure can be looked into; the first call of
/// each test process removes those of test processes that have ended ([`remove_stale_scratch`]),
/// so runs do not pile up in the temp dir (a full `cargo test --workspace` leaves about 0.5 GB,
/// copies of the binaries included).
///
/// # Panics
/// When the directory cannot be created (tests only).
pub fn scratch_dir(test: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    static STALE_REMOVED: std::sync::Once = std::sync::Once::new();
    STALE_REMOVED.call_once(|| {
        remove_stale_scratch(&std::env::temp_dir(), process_alive);
    });
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("bearingd-{test}-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    // `create_dir`, not `_all`: the temp dir is shared, and a directory (or a link to one) that
    // someone else put at this name after the removal must fail the test, not be written into.
    std::fs::create_dir(&dir)
        .unwrap_or_else(|e| panic!("cannot create scratch dir {}: {e}", dir.display()));
    dir
}

/// Removes the scratch directories in `temp` ([`scratch_dir`]'s `bearingd-<test>-<pid>-<n>`)
/// that this user owns and whose process `alive` says has ended. The temp dir is shared: a
/// link is never followed (the entry's own type; `remove_dir_all` unlinks a link that replaced
/// it), and another user's directory of that name is left alone, also when the tests run as
/// root. Returns how many were removed.
pub fn remove_stale_scratch(temp: &Path, alive: impl Fn(u32) -> bool) -> usize {
    use std::os::unix::fs::MetadataExt;
    let Ok(entries) = std::fs::read_dir(temp) else {
        return 0;
    };
    // This process's user: the owner of its /proc entry (Linux, as `process_alive`).
    let Ok(me) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return 0;
    };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(scratch_pid) else {
            continue;
        };
        // `DirEntry::metadata` does not follow a link.
        let mine = entry
            .metadata()
            .is_ok_and(|m| m.file_type().is_dir() && m.uid() == me);
        if mine && !alive(pid) && std::fs::remove_dir_all(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The process id in a scratch directory's name `bearingd-<test>-<pid>-<n>`.
fn scratch_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix("bearingd-")?;
    let mut fields = rest.rsplitn(3, '-');
    let n = fields.next()?;
    let pid = fields.next()?;
    let test = fields.next()?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    (digits(n) && !test.is_empty()).then_some(())?;
    pid.parse().ok().filter(|_| digits(pid))
}

/// Whether process `pid` is running (Linux: its /proc entry exists).
fn process_alive(pid: u32) -> bool {
    Path::new("/proc").join(pid.to_string()).exists()
}

/// An iceoryx2 root for a test, unique per process and `tag`: below `target_tmp` (pass
/// `env!("CARGO_TARGET_TMPDIR")`), or in `/dev/shm/bearingd-tests-<uid>` (this user's, made
/// `0700` here) when the checkout itself is under /tmp or /var/tmp, or so deep that the root
/// would be too long. (why) The config refuses a root under /tmp (systemd's PrivateTmp= would
/// hide it from subscribers) and one longer than 56 bytes (iceoryx2's Unix socket paths below
/// it must fit in 108), and CI must pass from a clone in any directory. The daemon refuses a
/// root another user owns or could write in, so the shared fallback is per user and private.
/// Keep `tag` short.
///
/// # Panics
/// When the fallback directory cannot be made this user's private directory (tests only).
pub fn iox_root(target_tmp: &str, tag: &str) -> PathBuf {
    let name = format!("{tag}-{}", std::process::id());
    let below_target = Path::new(target_tmp).join(&name);
    let under_tmp = ["/tmp", "/var/tmp"]
        .iter()
        .any(|t| below_target.starts_with(t));
    if under_tmp || below_target.as_os_str().len() > 50 {
        private_shm_dir().join(name)
    } else {
        below_target
    }
}

/// `/dev/shm/bearingd-tests-<effective uid>`, created `0700`; an existing one must be a
/// directory of this user (not a link), and is set to `0700`.
fn private_shm_dir() -> PathBuf {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let uid: u32 = status
        .lines()
        .find_map(|l| l.strip_prefix("Uid:"))
        .and_then(|ids| ids.split_whitespace().nth(1))
        .and_then(|euid| euid.parse().ok())
        .unwrap_or_else(|| panic!("cannot read the effective uid from /proc/self/status"));
    let dir = PathBuf::from(format!("/dev/shm/bearingd-tests-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let meta = std::fs::symlink_metadata(&dir)
        .unwrap_or_else(|e| panic!("cannot create {}: {e}", dir.display()));
    assert!(
        meta.is_dir() && meta.uid() == uid,
        "{} is not a directory of uid {uid} (a link, a file or another user's): remove it",
        dir.display()
    );
    std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700))
        .unwrap_or_else(|e| panic!("cannot chmod 0700 {}: {e}", dir.display()));
    dir
}

/// The `.mcap` files directly in `dir`, sorted by name (empty if it cannot be read).
pub fn mcap_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| {
            entries
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "mcap"))
                .collect()
        })
        .unwrap_or_default();
    files.sort();
    files
}

/// The rows of a data set's `manifest.csv`, each as column name → value.
///
/// # Panics
/// When the manifest cannot be read (tests only).
pub fn read_manifest(dir: &Path) -> Vec<std::collections::HashMap<String, String>> {
    let path = dir.join("manifest.csv");
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

/// The project's Python (`.venv/bin/python`) with the MCAP reader packages, for the
/// independent check of our files; `None` (said on stderr) outside CI when it is missing.
///
/// # Panics
/// Under `CI=true` when it is missing (tests only).
pub fn python_mcap() -> Option<PathBuf> {
    venv_python(
        "import mcap, mcap_protobuf, google.protobuf",
        "the Python MCAP reader (mcap, mcap-protobuf-support, protobuf)",
    )
}

/// The project's Python with the `iceoryx2` package, for the Python alert subscriber.
///
/// # Panics
/// Under `CI=true` when it is missing (tests only).
pub fn python_iceoryx2() -> Option<PathBuf> {
    venv_python("import iceoryx2", "the Python iceoryx2 package")
}

/// The project's Python with scipy, whose `scipy.io.savemat` writes the MATLAB fixtures.
///
/// # Panics
/// Under `CI=true` when it is missing (tests only).
pub fn python_scipy() -> Option<PathBuf> {
    venv_python(
        "import scipy.io, numpy",
        "scipy (scipy.io.savemat writes the MATLAB fixtures)",
    )
}

/// The project's Python with `paho-mqtt` and `protobuf`, for the Sparkplug B host of the fleet
/// bridge's tests (`tests/python/sparkplug_subscriber.py`).
///
/// # Panics
/// Under `CI=true` when it is missing (tests only).
pub fn python_sparkplug() -> Option<PathBuf> {
    venv_python(
        "import paho.mqtt.client, google.protobuf",
        "the Python MQTT client and protobuf (paho-mqtt, protobuf)",
    )
}

/// The project's Python, whose standard `pty` module runs a command under a pseudo-terminal
/// (the progress bars' tests).
///
/// # Panics
/// Under `CI=true` when it is missing (tests only).
pub fn python_pty() -> Option<PathBuf> {
    venv_python("import pty", "Python's pty module")
}

fn venv_python(imports: &str, what: &str) -> Option<PathBuf> {
    let py = repo_root().join(".venv/bin/python");
    let ci = std::env::var("CI").is_ok_and(|v| v == "true");
    let problem = if !py.exists() {
        Some(format!("{} does not exist", py.display()))
    } else {
        let out = std::process::Command::new(&py)
            .args(["-c", imports])
            .output()
            .expect("run python");
        (!out.status.success()).then(|| String::from_utf8_lossy(&out.stderr).into_owned())
    };
    match problem {
        None => Some(py),
        Some(p) if ci => panic!(
            "{what} missing ({p}); create it with `python3 -m venv .venv && \
             .venv/bin/pip install -r scripts/requirements-ci.txt`"
        ),
        Some(p) => {
            eprintln!("skipping the Python check: {what} missing: {p}");
            None
        }
    }
}

/// Runs `tests/python/check_mcap.py` on `file`; returns its JSON summary.
///
/// # Panics
/// When the check fails (tests only).
pub fn check_mcap_with_python(
    py: &Path,
    file: &Path,
    expected: Option<&Path>,
) -> serde_json::Value {
    let script = repo_root().join("tests/python/check_mcap.py");
    let mut cmd = std::process::Command::new(py);
    cmd.arg(script).arg(file);
    if let Some(e) = expected {
        cmd.arg(e);
    }
    let out = cmd.output().expect("run check_mcap.py");
    assert!(
        out.status.success(),
        "check_mcap.py failed on {}:\n{}\n{}",
        file.display(),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("summary JSON")
}

/// Runs `tests/python/log_topics.py` on `file`: its messages in log-time order as Python's
/// strict reader sees them (`topic`, `log_time`, `publish_time`, and `json` for the low-rate
/// JSON topics).
///
/// # Panics
/// When the file does not read strictly (tests only).
pub fn log_topics_with_python(py: &Path, file: &Path) -> Vec<serde_json::Value> {
    let script = repo_root().join("tests/python/log_topics.py");
    let out = std::process::Command::new(py)
        .arg(script)
        .arg(file)
        .output()
        .expect("run log_topics.py");
    assert!(
        out.status.success(),
        "log_topics.py failed on {}:\n{}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    summary["messages"].as_array().cloned().unwrap_or_default()
}

/// Writes `samples` to `path` as a one-column CSV, one value per line (a record a user might
/// have, in g).
pub fn write_csv<T: std::fmt::Display>(path: &Path, samples: impl IntoIterator<Item = T>) {
    let text: String = samples.into_iter().map(|x| format!("{x}\n")).collect();
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}

/// `n` samples at `fs_hz` of a sine of peak `amplitude_g` at `f_hz`.
pub fn sine_g(amplitude_g: f64, f_hz: f64, fs_hz: f64, n: usize) -> impl Iterator<Item = f64> {
    (0..n).map(move |i| amplitude_g * (std::f64::consts::TAU * f_hz * i as f64 / fs_hz).sin())
}

/// A deterministic pseudo-random byte stream (xorshift), for files that are not logs.
pub fn noise(len: usize, mut seed: u64) -> Vec<u8> {
    (0..len)
        .map(|_| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed as u8
        })
        .collect()
}

/// The binary `name` of the workspace beside `exe` (a test's own `env!("CARGO_BIN_EXE_...")`):
/// a test of one package cannot ask cargo for another package's binary. A missing one fails the
/// test, naming the command that builds it (each binary is its package's name).
pub fn binary_beside(exe: &str, name: &str) -> PathBuf {
    let path = Path::new(exe).with_file_name(name);
    assert!(
        path.is_file(),
        "{} is missing: build it first (`cargo build --release -p {name}`)",
        path.display()
    );
    path
}

/// Runs `program` (a binary of the workspace, e.g. `env!("CARGO_BIN_EXE_bearingd")`) with
/// `args` and returns what it did. A lab command (`simulate`, `train`, `analyze --plot`, ...)
/// that `bearingd` could not hand over because `bearingd-lab` is not built beside it fails the
/// test here, saying how to build it: `cargo test -p bearingd` alone does not build the lab.
pub fn run_binary(program: &str, args: &[&str]) -> std::process::Output {
    let out = std::process::Command::new(program)
        .args(args)
        .output()
        .unwrap_or_else(|error| panic!("cannot run {program}: {error}"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("is a lab command: install bearingd-lab"),
        "`bearingd {}` runs in bearingd-lab, which is not built beside {program}: run `cargo build --release -p bearingd-lab` first ({stderr})",
        args.join(" ")
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scratch_name_gives_its_process_and_nothing_else_does() {
        assert_eq!(scratch_pid("bearingd-alerts-cli-11924-0"), Some(11924));
        assert_eq!(scratch_pid("bearingd-trend-7-12"), Some(7));
        for other in [
            "bearingd-tests-0",
            "bearingd--5-1",
            "bearingd-x-5-",
            "bearingd-x-y-1",
            "bearingd-x-5-1a",
            "ci-check",
            "bearingd",
        ] {
            assert_eq!(scratch_pid(other), None, "{other}");
        }
    }

    #[test]
    fn only_the_directories_of_ended_processes_are_removed() {
        let temp = scratch_dir("stale-scratch");
        for name in [
            "bearingd-done-100-0",
            "bearingd-done-too-100-3",
            "bearingd-running-200-0",
            "other-100-0",
        ] {
            std::fs::create_dir_all(temp.join(name).join("inner")).expect("make a dir");
        }
        std::fs::write(temp.join("bearingd-file-100-1"), b"not a dir").expect("write a file");
        // A link named like an ended process's directory is not a directory: it and its
        // target stay.
        let target = temp.join("other-100-0");
        std::os::unix::fs::symlink(&target, temp.join("bearingd-link-100-2")).expect("make a link");
        let removed = remove_stale_scratch(&temp, |pid| pid == 200);
        assert_eq!(removed, 2);
        assert!(target.join("inner").is_dir(), "a link's target was removed");
        let mut left: Vec<String> = std::fs::read_dir(&temp)
            .expect("read the temp dir")
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(
            left,
            [
                "bearingd-file-100-1",
                "bearingd-link-100-2",
                "bearingd-running-200-0",
                "other-100-0"
            ]
        );
        assert_eq!(remove_stale_scratch(&temp.join("missing"), |_| false), 0);
        let _ = std::fs::remove_dir_all(&temp);
    }
}
