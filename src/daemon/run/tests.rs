//! Unit tests of `bearingd run`'s wiring: a whole run in process, what refuses a start, the data
//! directories' locks and the threads' names and panics.

use super::*;
use crate::config::parse;
use crate::daemon::events::ignore_events;
use std::sync::Mutex;

/// A directory of its own under the system's temporary directory, removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new(test: &str) -> Scratch {
        Scratch(bearingd_testdata::scratch_dir(&format!("run-{test}")))
    }

    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// One simulated sensor without a fault, its log, state and iceoryx2 root under `dir`.
fn sim_config(dir: &Path) -> Config {
    let text = r#"
[[sensors]]
id = "unit"
transport = "sim"
sample_rate_hz = 25600
bearing = "skf-6205-2rs"

[sensors.speed]
rpm = 1772

[sensors.sim]
fault = "none"
"#;
    let mut config = parse(text, "run unit test").unwrap();
    config.outputs.mcap_dir = dir.join("mcap");
    config.outputs.state_dir = dir.join("state");
    // Set after parsing: the config refuses a root under /tmp (systemd's PrivateTmp=), which
    // is where these tests' directories are.
    config.outputs.iceoryx2_root = dir.join("iox");
    config
}

/// The log and nothing else: no alert service, no fleet bridge.
fn log_only() -> SinkPlan {
    SinkPlan {
        alerts: false,
        fleet: false,
        extra: Vec::new(),
    }
}

/// Events that keep what they were told, one `Debug` line each.
fn kept_events() -> (Events, Arc<Mutex<Vec<String>>>) {
    let kept = Arc::new(Mutex::new(Vec::new()));
    let events: Events = {
        let kept = kept.clone();
        Arc::new(move |event| kept.lock().unwrap().push(format!("{event:?}")))
    };
    (events, kept)
}

/// A run of these tests that has not returned by then never will: a failure, not a hang.
const RUN_TIMEOUT: Duration = Duration::from_secs(30);

/// Drives `run` on a current-thread runtime, as far as its result.
fn run_blocking(
    config: Config,
    options: RunOptions,
    events: Events,
    shutdown: impl std::future::Future<Output = ()>,
) -> Result<RunSummary, RunError> {
    let running = run(config, options, log_only(), events, shutdown);
    tokio::runtime::Builder::new_current_thread()
        .enable_time()
        .build()
        .unwrap()
        .block_on(async { tokio::time::timeout(RUN_TIMEOUT, running).await })
        .unwrap_or_else(|_| panic!("run did not return within {RUN_TIMEOUT:?}"))
}

/// The names of the entries of `dir` (none when it does not exist).
fn entries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir).map_or_else(
        |_| Vec::new(),
        |entries| {
            entries
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        },
    )
}

fn set_mode(dir: &Path, mode: u32) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(dir, std::fs::Permissions::from_mode(mode)).unwrap();
}

#[test]
fn a_world_writable_log_directory_refuses_the_start_and_nothing_is_written_there() {
    let scratch = Scratch::new("open-mcap");
    let config = sim_config(scratch.path());
    let mcap_dir = config.outputs.mcap_dir.clone();
    std::fs::create_dir(&mcap_dir).unwrap();
    set_mode(&mcap_dir, 0o777);
    let options = RunOptions {
        duration_s: Some(1.0),
        ..RunOptions::default()
    };
    let refused = run_blocking(config, options, ignore_events(), std::future::pending());

    let error = refused.expect_err("a start with a world-writable log directory");
    assert!(
        matches!(
            &error,
            RunError::UnsafeDir(crate::fsafe::UnsafeDir::WorldWritable { path, .. }) if *path == mcap_dir
        ),
        "{error:?}"
    );
    let message = error.to_string();
    assert!(
        message.contains(&mcap_dir.display().to_string()) && message.contains("chmod o-w"),
        "{message}"
    );
    assert!(
        entries(&mcap_dir).is_empty(),
        "no lock file, no log: {:?}",
        entries(&mcap_dir)
    );
}

#[test]
fn a_world_writable_state_directory_refuses_the_start_before_any_lock_or_log() {
    let scratch = Scratch::new("open-state");
    let config = sim_config(scratch.path());
    let (mcap_dir, state_dir) = (
        config.outputs.mcap_dir.clone(),
        config.outputs.state_dir.clone(),
    );
    std::fs::create_dir(&state_dir).unwrap();
    set_mode(&state_dir, 0o777);
    let refused = run_blocking(
        config,
        RunOptions::default(),
        ignore_events(),
        std::future::pending(),
    );

    let error = refused.expect_err("a start with a world-writable state directory");
    assert!(matches!(&error, RunError::UnsafeDir(_)), "{error:?}");
    assert!(
        error.to_string().contains(&state_dir.display().to_string()),
        "{error}"
    );
    assert!(entries(&state_dir).is_empty(), "{:?}", entries(&state_dir));
    assert!(entries(&mcap_dir).is_empty(), "{:?}", entries(&mcap_dir));
}

#[test]
fn one_directory_for_the_log_and_the_state_is_locked_once() {
    let scratch = Scratch::new("one-dir");
    let mut config = sim_config(scratch.path());
    let data = scratch.path().join("data");
    config.outputs.mcap_dir = data.clone();
    config.outputs.state_dir = data.clone();
    let locks = lock_data_dirs(&config, &ignore_events()).unwrap();
    assert_eq!(locks.len(), 1, "one lock for one directory");
    assert_eq!(locks[0].path().parent(), Some(data.as_path()));
}

#[test]
fn a_second_owner_of_the_data_directories_is_refused_while_the_first_holds_them() {
    let scratch = Scratch::new("locked");
    let config = sim_config(scratch.path());
    let (events, said) = kept_events();
    let first = lock_data_dirs(&config, &events).unwrap();
    assert_eq!(first.len(), 2, "the log's and the state's");

    let error = lock_data_dirs(&config, &events).expect_err("a second owner");
    let RunError::Locked(LockError::Held { dir, holder }) = &error else {
        panic!("{error:?}")
    };
    assert_eq!(dir, &config.outputs.mcap_dir);
    assert!(
        holder.contains(&format!("pid={}", std::process::id())),
        "{holder}"
    );
    assert!(
        error.to_string().contains("in use by another bearingd"),
        "{error}"
    );

    // Released by a clean stop: the next start takes them without calling them stale.
    drop(first);
    let again = lock_data_dirs(&config, &events).unwrap();
    assert_eq!(again.len(), 2);
    let said = said.lock().unwrap().join("\n");
    assert!(!said.contains("StaleLockTakenOver"), "{said}");
}

#[test]
fn a_daemon_thread_is_named_and_its_panic_becomes_an_error_naming_it() {
    let thread = spawn("analysis", || {
        std::thread::current().name().map(str::to_owned)
    })
    .unwrap();
    assert_eq!(
        join("analysis", thread).unwrap().as_deref(),
        Some("bearingd-analysis")
    );

    let thread = spawn("sink", || -> u64 {
        panic!("a sink thread's panic (expected by this test)")
    })
    .unwrap();
    let error = join("sink", thread).expect_err("a panicked thread");
    assert!(
        matches!(error, RunError::ThreadPanicked { what: "sink" }),
        "{error:?}"
    );
    assert_eq!(
        error.to_string(),
        "the sink thread panicked (its message is in the log above)"
    );
}
