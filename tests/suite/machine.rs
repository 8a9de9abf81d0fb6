//! Machine faults (unbalance, misalignment, looseness) end to end: the channel monitor raises
//! the simulated fault's own flag and no other, a healthy machine or a bearing fault raises
//! none, spectra too coarse for half orders are not judged, and `analyze` names the fault in
//! its JSON (`machine_faults`) and says nothing on the developer records.

use bearingd::analysis::detectors::DetectorSettings;
use bearingd::analysis::flags::FlagSettings;
use bearingd::analysis::iso::SeveritySettings;
use bearingd::analysis::monitor::{ChannelMonitor, MonitorEvent, MonitorSettings};
use bearingd::analysis::speed::SpeedMode;
use bearingd::analysis::AnalysisSettings;
use bearingd::machine_fault::{MachineFault, MachineFaultKind};
use bearingd::messages::detect::machine::{MachineFlagMessage, MachineMessage};
use bearingd::messages::detect::Emitted;
use bearingd::messages::{DetectorMessage, FlagLevel};
use bearingd::twin::{Nuisance, SimulatedFault, SimulationParams, Simulator};

const SCALE: f64 = 0.000_488;
const FS: f64 = 25_600.0;

fn settings(window_s: f64) -> MonitorSettings {
    MonitorSettings {
        fs_hz: FS,
        analysis: AnalysisSettings {
            window_s,
            ..AnalysisSettings::default()
        },
        band_period_samples: (20.0 * FS) as u64,
        band_phase_samples: 0,
        window_stagger: (0, 1),
        band_history_samples: (10.0 * FS) as usize,
        flags: FlagSettings {
            watch_score: 10.0,
            alarm_score: 15.0,
            clear_ratio: 0.8,
            on_delay_samples: (5.0 * FS) as u64,
            off_delay_samples: (30.0 * FS) as u64,
        },
        baseline_windows: 20,
        sigma: 3.0,
        clip_count: 32_767,
        flat_line_samples: FS as u64,
        speed: SpeedMode::Fixed,
        detectors: DetectorSettings {
            severity: Some(SeveritySettings::default()),
            machine_faults: Some(Default::default()),
        },
        trend: bearingd::analysis::monitor::TrendSettings::default(),
    }
}

/// A machine in fair condition (the simulator's typical nuisance), with `fault` in the bearing
/// and `machine` at shaft orders.
fn record(
    fault: SimulatedFault,
    machine: Option<MachineFault>,
    seconds: f64,
) -> (Vec<i16>, SimulationParams) {
    let params = SimulationParams {
        fs_hz: FS,
        nuisance: Nuisance {
            machine_fault: machine,
            ..Nuisance::typical()
        },
        ..SimulationParams::example(fault)
    };
    let g = Simulator::record(params.clone(), seconds);
    let counts = g
        .iter()
        .map(|&x| (f64::from(x) / SCALE).round().clamp(-32_768.0, 32_767.0) as i16)
        .collect();
    (counts, params)
}

/// The machine detector's readings and flag changes over a record.
fn monitor(
    counts: &[i16],
    params: &SimulationParams,
    window_s: f64,
) -> (Vec<MachineMessage>, Vec<MachineFlagMessage>) {
    let mut monitor = ChannelMonitor::new(settings(window_s), params.frequencies(), None);
    let (mut readings, mut changes) = (Vec::new(), Vec::new());
    for (i, block) in counts.chunks(2_560).enumerate() {
        monitor.push_counts((i * 2_560) as u64, block, SCALE, &mut |e| {
            if let MonitorEvent::Detector(DetectorMessage::Machine(m)) = e {
                match m {
                    Emitted::Reading(r) => readings.push(r),
                    Emitted::Flag(f) => changes.push(f),
                }
            }
        });
    }
    let mut levels = Vec::new();
    monitor.detector_flags(&mut |flag, level| levels.push((flag.name, level)));
    for change in &changes {
        assert!(
            levels.iter().any(|(name, _)| *name == change.kind.name()),
            "{levels:?}"
        );
    }
    (readings, changes)
}

#[test]
fn each_simulated_machine_fault_raises_its_own_flag_and_no_other() {
    for kind in MachineFaultKind::ALL {
        // 3.5 mm/s at 1×: zone C of a group-2 machine on a rigid foundation (2.8–4.5 mm/s).
        let machine = MachineFault {
            kind,
            velocity_mm_s: 3.5,
        };
        let (counts, params) = record(SimulatedFault::None, Some(machine), 20.0);
        let (readings, changes) = monitor(&counts, &params, 1.0);
        assert!(readings.len() >= 3, "{}: {readings:?}", kind.name());
        let named: Vec<_> = readings.iter().filter_map(|r| r.fault).collect();
        assert!(
            !named.is_empty() && named.iter().all(|k| *k == kind),
            "{}: readings name {named:?}",
            kind.name()
        );
        let raised: Vec<_> = changes
            .iter()
            .filter(|c| c.from == FlagLevel::Ok)
            .map(|c| (c.kind, c.to))
            .collect();
        assert!(
            raised.first().is_some_and(|(k, _)| *k == kind)
                && raised.iter().all(|(k, _)| *k == kind),
            "{}: flags raised {raised:?}",
            kind.name()
        );
        // Raised after the on-delay (5 s), not before.
        assert!(changes[0].end_sample >= (5.0 * FS) as u64, "{changes:?}");
    }
}

#[test]
fn a_healthy_machine_and_bearing_faults_raise_no_machine_flag() {
    for fault in SimulatedFault::ALL {
        let (counts, params) = record(fault, None, 20.0);
        let (readings, changes) = monitor(&counts, &params, 1.0);
        assert!(readings.len() >= 3, "{}: {readings:?}", fault.name());
        assert!(changes.is_empty(), "{}: {changes:?}", fault.name());
        assert!(
            readings.iter().all(|r| r.fault.is_none()),
            "{}: {readings:?}",
            fault.name()
        );
    }
}

#[test]
fn spectra_too_coarse_for_half_orders_are_not_judged() {
    // 0.05 s windows: 20 Hz bins, where a half order of 29.5 Hz spans less than a bin.
    let machine = MachineFault {
        kind: MachineFaultKind::Looseness,
        velocity_mm_s: 6.0,
    };
    let (counts, params) = record(SimulatedFault::None, Some(machine), 10.0);
    let (readings, changes) = monitor(&counts, &params, 0.05);
    assert!(readings.is_empty() && changes.is_empty(), "{readings:?}");
}

/// The daemon on a simulated node with 0.1 g of imbalance (3.74 mm/s at 1×, zone C) and the
/// machine-fault detector on: it raises `unbalance` (alert code 6) to watch after the
/// on-delay, logs `/machine` and `/machine_flags` (read back by Python `mcap`), publishes the
/// alert to a Python iceoryx2 subscriber, and a replay of its log raises the same flag at the
/// same sample.
#[test]
fn the_daemon_raises_logs_publishes_and_replays_an_unbalance() {
    let (Some(py_mcap), Some(py_iox)) = (
        bearingd_testdata::python_mcap(),
        bearingd_testdata::python_iceoryx2(),
    ) else {
        return;
    };
    let dir = bearingd_testdata::scratch_dir("machine-daemon");
    let config = crate::severity::imbalance_config(&dir, 0.1, "im", "[detectors.machine_faults]");
    let root = bearingd::config::load(&config)
        .unwrap()
        .outputs
        .iceoryx2_root;
    // The subscriber first: it waits for the daemon to create the service. Two alerts: the
    // velocity zone flag and the unbalance both rise in zone C. The daemon in real time (see
    // `spawn_python_subscriber`).
    let subscriber = crate::alerts::spawn_python_subscriber(&py_iox, &root, 2);
    let stdout = crate::severity::run_ok(&[
        "run",
        "--config",
        config.to_str().unwrap(),
        "--duration",
        "30",
        "--quiet",
    ]);
    let flag_line = stdout
        .lines()
        .find(|l| l.starts_with("FLAG motor-de/radial: unbalance ok -> watch"))
        .unwrap_or_else(|| panic!("no unbalance flag raised:\n{stdout}"));
    for other in ["misalignment", "looseness"] {
        assert!(!stdout.contains(&format!(": {other} ")), "{stdout}");
    }
    assert!(stdout.contains("machine=unbalance("), "{stdout}");

    let live = bearingd_testdata::mcap_files(&dir.join("mcap"));
    let log = crate::severity::velocity_log(&py_mcap, &live);
    assert_eq!(
        log["schemas"]["/machine/motor-de/radial"]["name"],
        "bearingd.Machine"
    );
    assert_eq!(
        log["schemas"]["/machine_flags/motor-de/radial"]["name"],
        "bearingd.MachineFlag"
    );
    let readings = log["machine"].as_array().unwrap();
    assert!(readings.len() >= 5, "{}", readings.len());
    for r in readings {
        assert_eq!(r["fault"], "unbalance", "{r}");
        let v1 = r["orders_mm_s"][0].as_f64().unwrap();
        assert!((v1 - 3.74).abs() < 0.2, "{r}");
    }
    let flags = machine_flags(&log);
    assert_eq!(flags.len(), 1, "{flags:?}");
    assert_eq!(
        (flags[0].0.as_str(), flags[0].2.as_str()),
        ("unbalance", "watch")
    );
    assert!(
        flag_line.ends_with(&format!(" {}", flags[0].3)),
        "{flag_line} vs {flags:?}"
    );

    let received = subscriber.wait_with_output().unwrap();
    let text = String::from_utf8_lossy(&received.stdout);
    assert!(
        received.status.success(),
        "Python subscriber failed:\n{text}\n{}",
        String::from_utf8_lossy(&received.stderr)
    );
    // The subscriber prints Python's JSON, where a detector's alert has `NaN` for its fault
    // frequency: not JSON, so read as null.
    let alerts: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(&l.replace("NaN", "null")).expect(l))
        .collect();
    let unbalance = alerts
        .iter()
        .find(|a| a["fault"] == "unbalance")
        .unwrap_or_else(|| panic!("no unbalance alert:\n{text}"));
    assert_eq!(unbalance["state"], "raised", "{unbalance}");
    assert_eq!(unbalance["severity"], "watch", "{unbalance}");
    assert_eq!(unbalance["end_sample"], flags[0].3, "{unbalance}");
    let score = unbalance["score"].as_f64().unwrap();
    assert!((score - 3.74).abs() < 0.2, "{unbalance}");

    let replay_dir = dir.join("replay");
    crate::severity::run_ok(&[
        "replay",
        live[0].to_str().unwrap(),
        "--config",
        config.to_str().unwrap(),
        "--out",
        replay_dir.to_str().unwrap(),
        "--quiet",
    ]);
    let replayed =
        crate::severity::velocity_log(&py_mcap, &bearingd_testdata::mcap_files(&replay_dir));
    assert_eq!(machine_flags(&replayed), flags);
}

/// (kind, from, to, end_sample) of every machine flag change in a log.
fn machine_flags(log: &serde_json::Value) -> Vec<(String, String, String, u64)> {
    log["machine_flags"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let text = |key: &str| f[key].as_str().unwrap().to_string();
            (
                text("kind"),
                text("from"),
                text("to"),
                f["end_sample"].as_u64().unwrap(),
            )
        })
        .collect()
}

/// `bearingd simulate` (the lab) makes a record with each machine fault; `bearingd analyze`
/// names it under `machine_faults` in its JSON and its text, and names none on the same
/// machine without it.
#[test]
fn analyze_names_each_simulated_machine_fault_in_its_json_and_none_without() {
    let dir = bearingd_testdata::scratch_dir("machine-analyze");
    let run = crate::severity::run_ok;
    for kind in [
        None,
        Some("unbalance"),
        Some("misalignment"),
        Some("looseness"),
    ] {
        let csv = dir.join(format!("{}.csv", kind.unwrap_or("healthy")));
        let csv = csv.to_str().unwrap();
        let mut simulate = vec![
            "simulate",
            "--fault",
            "none",
            "--nuisance",
            "--fs",
            "25600",
            "--duration",
            "10s",
            "--noise",
            "0.05",
            "--out",
            csv,
        ];
        if let Some(kind) = kind {
            simulate.extend(["--machine-fault", kind, "--machine-fault-velocity", "4"]);
        }
        run(&simulate);
        let analyze = [
            "analyze",
            csv,
            "--fs",
            "25600",
            "--rpm",
            "1772",
            "--bearing",
            "skf-6205-2rs",
        ];
        let json: serde_json::Value =
            serde_json::from_str(&run(&[&analyze[..], &["--format", "json"]].concat()))
                .expect("JSON");
        let found = json["machine_faults"].as_array().expect("machine_faults");
        let kinds: Vec<&str> = found.iter().map(|f| f["kind"].as_str().unwrap()).collect();
        assert_eq!(kinds, kind.into_iter().collect::<Vec<_>>(), "{found:?}");
        let text = run(&analyze);
        match kind {
            Some(kind) => assert!(text.contains(&format!("machine fault: {kind} (")), "{text}"),
            None => assert!(!text.contains("machine fault:"), "{text}"),
        }
    }
}

/// A record too short to resolve half orders is not judged: `machine_faults` is null (not an
/// empty list, which would say "none found") and the text says why.
#[test]
fn analyze_says_a_record_too_short_for_half_orders_is_not_judged() {
    let dir = bearingd_testdata::scratch_dir("machine-short");
    let csv = dir.join("short.csv");
    let csv = csv.to_str().unwrap();
    let run = crate::severity::run_ok;
    run(&[
        "simulate",
        "--fault",
        "none",
        "--fs",
        "25600",
        "--duration",
        "0.2s",
        "--out",
        csv,
    ]);
    let analyze = [
        "analyze",
        csv,
        "--fs",
        "25600",
        "--rpm",
        "1772",
        "--bearing",
        "skf-6205-2rs",
    ];
    let json: serde_json::Value =
        serde_json::from_str(&run(&[&analyze[..], &["--format", "json"]].concat())).expect("JSON");
    assert!(
        json["machine_faults"].is_null(),
        "{}",
        json["machine_faults"]
    );
    let text = run(&analyze);
    assert!(
        text.contains("machine faults: not judged, a half order (14.77 Hz) spans"),
        "{text}"
    );
}
