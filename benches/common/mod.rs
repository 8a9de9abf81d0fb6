//! What the latency benches share (`alert_latency`, `block_cost`): reading their knobs from the
//! environment, percentiles, and the simulated-sensor config whose flags chatter, so that both
//! measure the same analysis on the same inputs.
#![allow(dead_code)] // each bench uses its own subset

use std::fmt::Write as _;

/// The environment variable `name` as a number, or `default` when unset or not a number.
pub fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `p50 … ms, p99 … ms, p999 … ms` of ascending `sorted` (in ms), with `decimals` decimals.
pub fn spread_ms(sorted: &[f64], decimals: usize) -> String {
    let [p50, p99, p999] = [50.0, 99.0, 99.9].map(|p| percentile(sorted, p));
    format!("p50 {p50:.decimals$} ms, p99 {p99:.decimals$} ms, p999 {p999:.decimals$} ms")
}

/// The nearest-rank percentile `p` (0–100) of ascending `sorted`; NaN when empty.
pub fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Config that makes the flags chatter: one window per average, thresholds at the middle of the
/// outer-race scores, no delays and almost no hysteresis. Since the fault flags follow band
/// selections (once per `band_period_s`), what chatters is the per-window ISO zone flag, with
/// [`CHATTERING_IMBALANCE_G`]: about 40 % of the windows raise or clear an alert. Everything
/// else is the default config's.
pub const CHATTERING_THRESHOLDS: &str = "[analysis]\naverages = 1\n\n[thresholds]\n\
     watch_score = 60.0\nalarm_score = 90.0\nclear_ratio = 0.999\non_delay_s = 0\noff_delay_s = 0\n";

/// An imbalance whose 1× velocity sits at the ISO zone B/C boundary of the default machine
/// group (2.8 mm/s; 0.1 g gives 3.74 mm/s): with one window per average the zone flag flips on
/// about 40 % of the windows (25 changes in 60 s of one sensor with an outer-race fault,
/// measured 2026-11-27).
pub const CHATTERING_IMBALANCE_G: f64 = 0.075;

/// The simulator's default imbalance (`[sensors.sim] imbalance_g`): zone B, no velocity flag.
pub const DEFAULT_IMBALANCE_G: f64 = 0.05;

/// `sensors` simulated SKF 6205 sensors at `rate_hz` and 1772 rpm with seeds 1, 2, …; sensor
/// j's outer race fails at `onset_s(j)`; `imbalance_g` of once-per-revolution tone.
pub fn simulated_sensors(
    sensors: usize,
    rate_hz: usize,
    onset_s: impl Fn(usize) -> f64,
    imbalance_g: f64,
) -> String {
    let mut text = String::new();
    for j in 0..sensors {
        let _ = write!(
            text,
            "\n[[sensors]]\nid = \"s{j:02}\"\ntransport = \"sim\"\nsample_rate_hz = {rate_hz}\n\
             bearing = \"skf-6205-2rs\"\n[sensors.speed]\nsource = \"fixed\"\nrpm = 1772\n\
             [sensors.sim]\nfault = \"outer\"\nonset_s = {onset:?}\nseverity = 1.5\nseed = {seed}\n\
             imbalance_g = {imbalance_g:?}\n",
            onset = onset_s(j),
            seed = j + 1
        );
    }
    text
}

/// The machine's own jitter, the floor under any latency tail measured on it: a fixed amount of
/// arithmetic (calibrated to take about `work_us` here, the size of one window's analysis),
/// done `rounds` times, each after a 2 ms sleep as the analysis thread sleeps between blocks.
/// Returns the durations in ms, ascending. On a virtual machine the p99 of this alone can be
/// several times its median (a host that takes the CPU away is not visible from inside).
pub fn host_jitter_ms(work_us: f64, rounds: usize) -> Vec<f64> {
    fn spin(iterations: u64) -> f64 {
        let mut acc = 0.0f64;
        for k in 0..iterations {
            acc = std::hint::black_box(acc + k as f64 * 1e-9);
        }
        acc
    }
    let timed = |iterations: u64| {
        let started = std::time::Instant::now();
        std::hint::black_box(spin(iterations));
        started.elapsed().as_secs_f64() * 1e3
    };
    // Iterations per µs: the fastest of a few calibration runs (the least disturbed).
    let probe = 200_000u64;
    let fastest_ms = (0..20).map(|_| timed(probe)).fold(f64::INFINITY, f64::min);
    let iterations = (probe as f64 * work_us / (fastest_ms * 1e3)).max(1.0) as u64;
    let mut durations: Vec<f64> = (0..rounds)
        .map(|_| {
            std::thread::sleep(std::time::Duration::from_millis(2));
            timed(iterations)
        })
        .collect();
    durations.sort_by(f64::total_cmp);
    durations
}

/// The machine's own wake-up latency, the other floor under an alert's latency: the subscriber
/// sleeps in the kernel between alerts, and the publisher's notification has to wake it. Here
/// another process (this bench started again with [`WAKE_RECEIVER`]) sleeps on a Unix datagram
/// socket, as iceoryx2's event does on Linux, and is sent the wall-clock time `rounds` times,
/// `idle_ms` apart; it takes its receipt time minus the sent time. Returns the latencies in ms,
/// ascending. An idle CPU halts (on a VM the host must then reschedule the vCPU) or enters a
/// C-state; leaving it is what this measures, and what `outputs.cpu_wakeup_latency_us` caps.
/// `dir` holds the socket: a directory of this bench's own (the target dir's), emptied first.
pub fn wake_up_ms(dir: &std::path::Path, idle_ms: u64, rounds: usize) -> Vec<f64> {
    use std::os::unix::net::UnixDatagram;
    use std::process::{Command, Stdio};
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).expect("a scratch dir for the wake-up socket");
    let socket = dir.join("wake.sock");
    let receiver = Command::new(std::env::current_exe().expect("this bench's path"))
        .arg(WAKE_RECEIVER)
        .arg(&socket)
        .arg(rounds.to_string())
        .stdout(Stdio::piped())
        .spawn()
        .expect("start the wake-up receiver");
    let sender = UnixDatagram::unbound().expect("a Unix datagram socket");
    let started = std::time::Instant::now();
    while !socket.exists() {
        assert!(
            started.elapsed() < std::time::Duration::from_secs(10),
            "the wake-up receiver never bound {}",
            socket.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    for _ in 0..rounds {
        std::thread::sleep(std::time::Duration::from_millis(idle_ms));
        let sent = bearingd::clock::wall_clock_now_ns().to_le_bytes();
        sender
            .send_to(&sent, &socket)
            .expect("send to the wake-up receiver");
    }
    let output = receiver
        .wait_with_output()
        .expect("the wake-up receiver's latencies");
    let _ = std::fs::remove_dir_all(dir);
    let mut latencies: Vec<f64> = String::from_utf8_lossy(&output.stdout)
        .lines()
        .filter_map(|line| line.parse::<f64>().ok())
        .map(|ns| ns / 1e6)
        .collect();
    assert_eq!(
        latencies.len(),
        rounds,
        "the wake-up receiver reported {} of {rounds} wake-ups ({})",
        latencies.len(),
        output.status
    );
    latencies.sort_by(f64::total_cmp);
    latencies
}

/// The argument that makes a bench the receiver of [`wake_up_ms`]: `WAKE_RECEIVER socket rounds`.
pub const WAKE_RECEIVER: &str = "--wake-receiver";

/// The receiving end of [`wake_up_ms`], when this process was started with [`WAKE_RECEIVER`]:
/// binds the socket, takes `rounds` datagrams and prints each one's latency in ns, a line each.
/// Returns whether it was that receiver (the bench then has nothing else to do).
pub fn run_wake_receiver() -> bool {
    let args: Vec<String> = std::env::args().collect();
    let Some(at) = args.iter().position(|a| a == WAKE_RECEIVER) else {
        return false;
    };
    let (socket, rounds) = match (args.get(at + 1), args.get(at + 2).map(|r| r.parse())) {
        (Some(socket), Some(Ok(rounds))) => (socket, rounds),
        _ => panic!("{WAKE_RECEIVER} needs a socket path and a whole number of rounds"),
    };
    let receiver = std::os::unix::net::UnixDatagram::bind(socket).expect("bind the wake-up socket");
    // Ends, rather than waiting forever, if the sending bench has gone.
    receiver
        .set_read_timeout(Some(std::time::Duration::from_secs(10)))
        .expect("a read timeout on the wake-up socket");
    let mut sent = [0u8; 8];
    for _ in 0..rounds {
        if receiver.recv(&mut sent).is_err() {
            break;
        }
        let now = bearingd::clock::wall_clock_now_ns();
        println!("{}", now.saturating_sub(u64::from_le_bytes(sent)));
    }
    true
}
