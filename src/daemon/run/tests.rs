//! Unit tests of `bearingd run`'s wiring: a whole run in process, what refuses a start, the data
//! directories' locks and the threads' names and panics.

use super::*;
use crate::config::parse;
use crate::daemon::events::{ignore_events, kept_events};
use std::time::Instant;

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
fn a_run_of_one_simulated_sensor_stops_at_its_duration_and_sums_up_its_channel() {
    let scratch = Scratch::new("duration");
    let config = sim_config(scratch.path());
    let mcap_dir = config.outputs.mcap_dir.clone();
    let (events, said) = kept_events();
    let options = RunOptions {
        duration_s: Some(2.0),
        realtime: false,
        status_lines: false,
    };
    // The shutdown never comes: only the duration can end the run.
    let summary = run_blocking(config, options, events, std::future::pending()).unwrap();

    assert_eq!(summary.channels.len(), 1, "{:?}", summary.channels);
    let channel = &summary.channels[0];
    assert_eq!(channel.channel.to_string(), "unit/radial");
    // Whole blocks of 0.1 s: the duration, and less than one block more.
    assert!(
        (2.0..2.1).contains(&channel.seconds),
        "sample time {} s for a 2 s run",
        channel.seconds
    );
    assert!(
        channel.samples >= 2 * 25_600 && channel.samples < 2 * 25_600 + 2_560,
        "{} samples",
        channel.samples
    );
    assert_eq!((channel.gaps, channel.missing_samples), (0, 0));
    assert!(!channel.sensor_lost);
    assert!(summary.messages > 0, "nothing reached the sinks");
    assert_eq!(summary.alerts_failed, 0);
    assert_eq!(summary.alerts_published, 0, "no alert service in this plan");
    assert!(
        summary.flags.is_empty(),
        "a healthy bearing: {:?}",
        summary.flags
    );

    // The log it wrote.
    let logs: Vec<String> = entries(&mcap_dir)
        .into_iter()
        .filter(|name| name.ends_with(".mcap"))
        .collect();
    assert_eq!(logs.len(), 1, "{:?}", entries(&mcap_dir));
    let said = said.lock().unwrap().join("\n");
    assert!(
        said.contains("NoState"),
        "a first start has no state: {said}"
    );
    assert!(said.contains("LoggingTo"), "{said}");
}

#[test]
fn a_restart_in_the_same_directories_starts_from_the_state_saved_at_the_stop() {
    let scratch = Scratch::new("restart");
    let config = sim_config(scratch.path());
    let (mcap_dir, state_dir) = (
        config.outputs.mcap_dir.clone(),
        config.outputs.state_dir.clone(),
    );
    let options = RunOptions {
        duration_s: Some(1.0),
        ..RunOptions::default()
    };
    let (first_events, first_said) = kept_events();
    run_blocking(
        config.clone(),
        options.clone(),
        first_events,
        std::future::pending(),
    )
    .unwrap();
    assert!(
        entries(&state_dir).contains(&"baselines.json".to_owned()),
        "saved at the stop: {:?}",
        entries(&state_dir)
    );

    // The first run released its locks: the second starts, and starts from the saved state.
    let (events, said) = kept_events();
    run_blocking(config, options, events, std::future::pending()).unwrap();
    let said = said.lock().unwrap().join("\n");
    assert!(said.contains("StateLoaded"), "{said}");
    assert!(!said.contains("NoState"), "{said}");
    assert!(!said.contains("StaleLockTakenOver"), "a clean stop: {said}");
    let first_said = first_said.lock().unwrap();
    assert!(
        !first_said.iter().any(|line| line.starts_with("State(")),
        "no state problem: {first_said:?}"
    );
    let logs = entries(&mcap_dir)
        .into_iter()
        .filter(|name| name.ends_with(".mcap"))
        .count();
    assert_eq!(logs, 2, "one log per run: {:?}", entries(&mcap_dir));
}

#[test]
fn a_shutdown_stops_a_run_of_a_simulated_sensor_in_real_time() {
    let scratch = Scratch::new("shutdown");
    let config = sim_config(scratch.path());
    let options = RunOptions {
        duration_s: None,
        realtime: true,
        status_lines: false,
    };
    let started = Instant::now();
    let shutdown = async { tokio::time::sleep(Duration::from_millis(500)).await };
    let summary = run_blocking(config, options, ignore_events(), shutdown).unwrap();
    let took = started.elapsed();
    assert!(
        took < Duration::from_secs(3),
        "the run took {took:?} to stop"
    );
    let channel = &summary.channels[0];
    // Paced at real time: about the half second it ran, not as fast as the analysis goes.
    assert!(
        channel.seconds > 0.0 && channel.seconds <= took.as_secs_f64() + 0.2,
        "{} s of samples in {took:?}",
        channel.seconds
    );
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
