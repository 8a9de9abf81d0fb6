//! Alert latency (issue 6 target, reported in docs/ALERTS.md and docs/PERFORMANCE.md): from the
//! end of the window that raises an alert to a subscriber's receipt, p50 and p99.
//!
//! What is measured: the daemon (`bearingd run`, a separate process, real time) runs
//! `BENCH_SENSORS` simulated sensors at `BENCH_RATE` Hz whose outer races fail one after the
//! other; this process subscribes to the alert service and, for each alert, takes its receipt
//! time minus the alert's `wall_time_ns`: the moment the daemon's source completed the block
//! that completed the deciding window. Both clocks are the same machine's `CLOCK_REALTIME`.
//! So the latency covers the wait in the analysis queue (behind other channels' blocks and
//! band selections), the analysis of that block, the flag decision, the alert queue, iceoryx2
//! and the subscriber's wake-up; it does not cover the sensor's own block length (0.1 s of
//! samples) or the transport before the daemon.
//!
//! Run: `cargo bench --bench alert_latency` (about `BENCH_ROUNDS` × 75 s).
//!
//! It also prints the machine's own jitter first ([`common::host_jitter_ms`]: a fixed 0.3 ms of
//! arithmetic after a 2 ms sleep, 5,000 times), the floor under any tail measured here: on a
//! virtual machine whose host takes the CPU away now and then, that alone has a p99 several
//! times its median, and an alert's p99 cannot be read without it. And the machine's wake-up
//! ([`common::wake_up_ms`]: another process asleep for 50 ms woken through a socket, 400 times,
//! before the daemon starts): every alert wakes the subscriber, so that latency is in every alert's,
//! whatever the daemon does.
//!
//! `BENCH_WINDOWS=N` (issue 12, "p99 < 1 ms over 10,000 windows"): one round instead, long
//! enough for N analysis windows over all sensors, every sensor faulty from the start and the
//! flags made to chatter (one window per average, thresholds at the middle of the scores, no
//! delays, almost no hysteresis, and an imbalance at the ISO zone B/C boundary so that the
//! per-window `iso_zone` flag flips; the fault flags follow band selections and change at most
//! once per band period), so that about 40 % of the windows raise or clear an alert:
//! thousands of alerts, enough for p99 and p999 of a window's alert. The bearing-fault flags'
//! alerts (about 5 % of them, decided where a band selection's result is used) get a line of
//! their own: the overall percentiles are the per-window flags'. Only the thresholds, the
//! averaging and the imbalance differ from the default config; the analysis, band selections
//! and twin re-fits are the default's. `BENCH_BEARINGD=path` runs another build of the daemon (a before/after
//! comparison on the same machine load). `BENCH_CPU_WAKEUP_US=N` sets the daemon's
//! `outputs.cpu_wakeup_latency_us` (the CPUs' wake-up latency capped while it runs; left out by
//! default, as in the default config); `BENCH_CPU_AWAKE=0` (or `1`) sets
//! `outputs.cpu_awake_during_analysis = false` (`true`): idle CPUs woken for each block's
//! analysis or not; left out by default, as in the default config (on). Both need write access to `/dev/cpu_dma_latency`:
//! the summary line says when this user has none (the daemon then runs without them).
//! The daemon runs with the systemd unit's `GLIBC_TUNABLES` (its heap in huge pages,
//! `bearingd::daemon::heap_pages`), as installed; `BENCH_HEAP_TUNABLES=0` leaves the bench's
//! environment as it is (4 KiB pages unless it sets them), for a before/after comparison.
//!
//! A line says how the alerts came per input ([`InputGroups`]): alone, or several from
//! one input, and how far apart; one per round, the daemon's own part of the latency
//! (`alerts_in_service` of its summary: its input's arrival to the alert in shared memory,
//! before the subscriber is woken), so a run on any machine tells the daemon's time from the
//! machine's wake-up.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use bearingd::clock::wall_clock_now_ns;
use bearingd::iox::IoxSettings;
use bearingd::messages::FaultKind;
use bearingd::sinks::alerts::payload::fault_code;
use bearingd::sinks::alerts::service::{AlertServiceSettings, AlertSubscriber, Received};
use common::{
    env_or, host_jitter_ms, percentile, simulated_sensors, spread_ms, wake_up_ms,
    CHATTERING_IMBALANCE_G, CHATTERING_THRESHOLDS, DEFAULT_IMBALANCE_G,
};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// What the daemon asks of the CPUs' wake-up latency (docs/DAEMON.md).
#[derive(Clone, Copy)]
struct CpuRequests {
    /// `outputs.cpu_wakeup_latency_us`.
    cap_us: Option<u32>,
    /// `outputs.cpu_awake_during_analysis`; `None`: left out (the daemon's default, on; a
    /// build from before the key, given with `BENCH_BEARINGD`, would refuse it).
    awake: Option<bool>,
}

/// `sensors` simulated sensors; sensor j's outer race fails at 2 + 2.5 j s, or at 0 with
/// `chatter` (then the flags chatter: see the module doc).
fn write_config(
    dir: &Path,
    iox: &Path,
    (sensors, rate): (usize, usize),
    chatter: bool,
    cpu: CpuRequests,
) -> PathBuf {
    let mut text = String::new();
    if chatter {
        text.push_str(CHATTERING_THRESHOLDS);
    }
    let imbalance_g = if chatter {
        CHATTERING_IMBALANCE_G
    } else {
        DEFAULT_IMBALANCE_G
    };
    let onset_s = |j: usize| if chatter { 0.0 } else { 2.0 + 2.5 * j as f64 };
    text += &simulated_sensors(sensors, rate, onset_s, imbalance_g);
    let _ = write!(
        text,
        r#"
[outputs]
state_dir = "{state}"
mcap_dir = "{mcap}"
iceoryx2_root = "{iox}"
"#,
        state = dir.join("state").display(),
        mcap = dir.join("mcap").display(),
        iox = iox.display()
    );
    if let Some(us) = cpu.cap_us {
        let _ = writeln!(text, "cpu_wakeup_latency_us = {us}");
    }
    if let Some(awake) = cpu.awake {
        let _ = writeln!(text, "cpu_awake_during_analysis = {awake}");
    }
    let path = dir.join("bench.toml");
    std::fs::write(&path, text).expect("write the bench config");
    path
}

/// The CPU requests of the run as its summary line says them.
fn cpu_requests(cpu: CpuRequests, writable: bool, device: &str) -> String {
    if !writable && (cpu.awake != Some(false) || cpu.cap_us.is_some()) {
        return format!("CPUs at the kernel's idle policy ({device} not writable by this user)");
    }
    let mut said = Vec::new();
    if let Some(us) = cpu.cap_us {
        said.push(format!("CPU wake-up capped at {us} µs"));
    }
    said.push(
        match cpu.awake {
            Some(true) => "CPUs awake during analysis",
            Some(false) => "CPUs not kept awake during analysis",
            None => "cpu_awake_during_analysis left to the daemon's default",
        }
        .to_string(),
    );
    said.join(", ")
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo test --benches` asks for a list; nothing to run quickly here
    }
    if common::run_wake_receiver() {
        return;
    }
    let sensors = env_or("BENCH_SENSORS", 16);
    let rate = env_or("BENCH_RATE", 25_600);
    let windows = env_or("BENCH_WINDOWS", 0);
    let chatter = windows > 0;
    let cpu = CpuRequests {
        cap_us: std::env::var("BENCH_CPU_WAKEUP_US").ok().map(|v| {
            v.parse()
                .expect("BENCH_CPU_WAKEUP_US: a whole number of µs")
        }),
        awake: std::env::var("BENCH_CPU_AWAKE").ok().map(|v| v != "0"),
    };
    // Whether the daemon (this user) can make either request: if not, it says so and runs
    // without, and this run measures the kernel's idle policy.
    let device = bearingd::daemon::cpu_latency::CPU_LATENCY_DEVICE;
    let writable = std::fs::OpenOptions::new().write(true).open(device).is_ok();
    let rounds = if chatter {
        1
    } else {
        env_or("BENCH_ROUNDS", 4)
    };
    // Windows hop by half a second (1 s windows, overlap 0.5); none before the first band
    // selection at 10 s, plus a few seconds of slack.
    let duration_s = if chatter {
        12.0 + (windows as f64 / sensors as f64 * 0.5).ceil()
    } else {
        20.0 + 2.5 * sensors as f64 + 20.0
    };
    // The floor under the tail: the same machine's jitter on a fixed 0.3 ms of work.
    let jitter = host_jitter_ms(300.0, 5_000);
    let host = format!(
        "host jitter, a fixed 0.3 ms of work after a 2 ms sleep, 5,000 times: {}",
        spread_ms(&jitter, 2)
    );
    // The other floor: how long this machine takes to wake a process asleep in the kernel, as
    // the subscriber is between alerts.
    let wake_dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("alert-latency-wake-up");
    let wake = format!(
        "wake-up, another process asleep on a Unix datagram socket for 50 ms, woken 400 times: {}",
        spread_ms(&wake_up_ms(&wake_dir, 50, 400), 3)
    );
    let daemon_path = std::env::var("BENCH_BEARINGD")
        .unwrap_or_else(|_| env!("CARGO_BIN_EXE_bearingd").to_string());
    let heap_tunables = (std::env::var("BENCH_HEAP_TUNABLES").as_deref() != Ok("0"))
        .then_some(bearingd::daemon::heap_pages::HEAP_TUNABLES);
    let mut latencies_ms = Vec::new();
    // The alerts of the bearing-fault flags alone: each follows a band selection's verdict,
    // the path of the alerts a maintenance engineer acts on (the rest are per-window flags).
    let mut fault_latencies_ms = Vec::new();
    let mut lost = 0u64;
    let mut inputs = InputGroups::default();
    let mut in_service = Vec::new();
    for round in 0..rounds {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("alert-latency-{round}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("bench dir");
        let iox = dir.join("iox");
        let config = write_config(&dir, &iox, (sensors, rate), chatter, cpu);
        let prefix = format!("bdbench{}_", std::process::id());
        let daemon_out = dir.join("daemon.ndjson");
        let mut daemon = Command::new(&daemon_path)
            .args([
                "run",
                "--quiet",
                "--format",
                "json",
                "--duration",
                &duration_s.to_string(),
                "--config",
            ])
            .arg(&config)
            .env("BEARINGD_IOX_PREFIX", &prefix)
            .envs(heap_tunables.map(|value| ("GLIBC_TUNABLES", value)))
            .stdout(std::fs::File::create(&daemon_out).expect("daemon output file"))
            .spawn()
            .expect("start bearingd");
        let settings = AlertServiceSettings {
            service: "bearingd/alerts".into(),
            iox: IoxSettings {
                prefix: Some(prefix),
                root_path: Some(iox.display().to_string()),
            },
        };
        let started = Instant::now();
        let mut subscriber = loop {
            match AlertSubscriber::open(&settings, bearingd::fsafe::effective_uid()) {
                Ok(s) => break s,
                Err(e) if started.elapsed() > Duration::from_secs(30) => {
                    panic!("the daemon's alert service never appeared: {e}")
                }
                Err(_) => std::thread::sleep(Duration::from_millis(50)),
            }
        };
        subscriber
            .take_history(Duration::from_millis(200))
            .expect("the daemon's alert service passes the owner checks");
        let mut round_alerts = 0;
        while started.elapsed().as_secs_f64() < duration_s + 5.0 {
            match subscriber
                .next(Duration::from_millis(500))
                .expect("the daemon's alert service passes the owner checks")
            {
                Some(Received::Alert(alert)) => {
                    let latency_ms = (wall_clock_now_ns() as f64 - alert.wall_time_ns as f64) / 1e6;
                    latencies_ms.push(latency_ms);
                    inputs.add(alert.wall_time_ns, latency_ms);
                    if FaultKind::ALL
                        .iter()
                        .any(|&kind| fault_code(kind) == alert.fault)
                    {
                        fault_latencies_ms.push(latency_ms);
                    }
                    round_alerts += 1;
                }
                Some(Received::Lost { first, last, .. }) => lost += last - first + 1,
                Some(Received::Untrusted { sequence, .. }) => {
                    panic!("untrusted alert #{sequence} from the daemon")
                }
                Some(Received::NewRun { .. }) | None => {}
            }
            if let Ok(Some(_)) = daemon.try_wait() {
                break;
            }
        }
        let _ = daemon.wait();
        eprintln!("round {round}: {round_alerts} alerts");
        in_service.push(daemon_in_service(&daemon_out));
    }
    assert!(!latencies_ms.is_empty(), "no alert arrived");
    latencies_ms.sort_by(f64::total_cmp);
    println!(
        "alert latency, {sensors} sensors at {rate} Hz, {rounds} round(s){}, {}, heap {}: {} alerts ({lost} lost), \
         p50 {:.2} ms, p99 {:.2} ms, p999 {:.2} ms, max {:.2} ms, min {:.2} ms",
        if chatter {
            format!(", {duration_s} s = {windows}+ windows, chattering flags")
        } else {
            String::new()
        },
        cpu_requests(cpu, writable, device),
        match heap_tunables {
            Some(_) => "with the unit's GLIBC_TUNABLES",
            None => "as the bench's environment gives it",
        },
        latencies_ms.len(),
        percentile(&latencies_ms, 50.0),
        percentile(&latencies_ms, 99.0),
        percentile(&latencies_ms, 99.9),
        latencies_ms.last().unwrap(),
        latencies_ms[0]
    );
    fault_latencies_ms.sort_by(f64::total_cmp);
    println!(
        "of them, bearing-fault flags (band selections' verdicts): {} alerts, p50 {:.2} ms, \
         p90 {:.2} ms, p99 {:.2} ms, max {:.2} ms",
        fault_latencies_ms.len(),
        percentile(&fault_latencies_ms, 50.0),
        percentile(&fault_latencies_ms, 90.0),
        percentile(&fault_latencies_ms, 99.0),
        fault_latencies_ms.last().copied().unwrap_or(f64::NAN),
    );
    println!("{}", inputs.summary());
    for (round, spread) in in_service.iter().enumerate() {
        println!("round {round}, the daemon's own part: {spread}");
    }
    println!("{host}");
    println!("{wake}");
}

/// The daemon's own part of its alerts' latency, from its summary (`run --format json`, last
/// line): how long after its input arrived each alert was in the service, before the
/// subscriber's wake-up. The rest of an alert's latency is that wake-up, this machine's.
fn daemon_in_service(out: &Path) -> String {
    let text = std::fs::read_to_string(out).expect("the daemon's output");
    let summary: serde_json::Value = text
        .lines()
        .rev()
        .find_map(|line| {
            serde_json::from_str::<serde_json::Value>(line)
                .ok()
                .filter(|v| v["type"] == "summary")
        })
        .unwrap_or_else(|| panic!("no summary line in {}", out.display()));
    let d = &summary["alerts_in_service"];
    let ms = |key: &str| d[key].as_f64().map_or(f64::NAN, |us| us / 1e3);
    format!(
        "{} alerts in the service p50 {:.2} ms, p90 {:.2} ms, p99 {:.2} ms, max {:.2} ms \
         after their input arrived (receipt adds the subscriber's wake-up)",
        d["alerts"],
        ms("p50_us"),
        ms("p90_us"),
        ms("p99_us"),
        ms("max_us")
    )
}

/// How the alerts came per input (the alerts of one input carry its arrival stamp): alone, or
/// several together, and how long a later alert of an input came after the one before it (the
/// cost of one more alert while the subscriber is awake). It says whether one wake-up per
/// input instead of per alert could shorten the tail (it cannot when nearly all come alone).
#[derive(Default)]
struct InputGroups {
    /// The current input's stamp and its last alert's latency.
    last: Option<(u64, f64)>,
    /// Alerts per input, for inputs with at least one.
    sizes: Vec<usize>,
    /// A later alert of an input: its latency minus the previous alert's, in ms.
    later_gaps_ms: Vec<f64>,
}

impl InputGroups {
    fn add(&mut self, arrived_ns: u64, latency_ms: f64) {
        match self.last {
            Some((stamp, before_ms)) if stamp == arrived_ns => {
                self.later_gaps_ms.push(latency_ms - before_ms);
                if let Some(size) = self.sizes.last_mut() {
                    *size += 1;
                }
            }
            _ => self.sizes.push(1),
        }
        self.last = Some((arrived_ns, latency_ms));
    }

    fn summary(&mut self) -> String {
        let alone = self.sizes.iter().filter(|&&n| n == 1).count();
        let together: usize = self.sizes.iter().filter(|&&n| n > 1).sum();
        let inputs = self.sizes.iter().filter(|&&n| n > 1).count();
        let largest = self.sizes.iter().copied().max().unwrap_or(0);
        self.later_gaps_ms.sort_by(f64::total_cmp);
        let gaps = if self.later_gaps_ms.is_empty() {
            String::new()
        } else {
            format!(
                "; a later alert of an input came p50 {:.1} µs, max {:.1} µs after the one before",
                percentile(&self.later_gaps_ms, 50.0) * 1e3,
                self.later_gaps_ms.last().unwrap() * 1e3
            )
        };
        format!(
            "alerts per input: {alone} alone, {together} in {inputs} inputs of 2 to {largest}{gaps}"
        )
    }
}
