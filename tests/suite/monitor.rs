//! The streaming analysis of one channel: a simulated bearing that develops an outer-race fault
//! raises exactly that flag, after the onset, and the same samples cut into other blocks give
//! exactly the same events at the same samples.

use bearingd::analysis::flags::FlagSettings;
use bearingd::analysis::monitor::{ChannelMonitor, MonitorEvent, MonitorSettings};
use bearingd::analysis::speed::SpeedMode;
use bearingd::analysis::AnalysisSettings;
use bearingd::messages::detect::Emitted;
use bearingd::messages::{DetectorMessage, FlagLevel, HealthKind, HealthStage};
use bearingd::twin::{SimulatedFault, SimulationParams, Simulator};

const SCALE: f64 = 0.000_488;

fn settings(fs: f64) -> MonitorSettings {
    MonitorSettings {
        fs_hz: fs,
        analysis: AnalysisSettings::default(),
        band_period_samples: (20.0 * fs) as u64,
        band_phase_samples: 0,
        window_stagger: (0, 1),
        band_history_samples: (10.0 * fs) as usize,
        flags: FlagSettings {
            watch_score: 10.0,
            alarm_score: 15.0,
            clear_ratio: 0.8,
            on_delay_samples: (5.0 * fs) as u64,
            off_delay_samples: (30.0 * fs) as u64,
        },
        baseline_windows: 20,
        sigma: 3.0,
        clip_count: 32_767,
        flat_line_samples: fs as u64,
        speed: SpeedMode::Fixed,
        // The velocity severity runs too: its readings must not depend on block sizes either.
        detectors: bearingd::analysis::detectors::DetectorSettings::default()
            .with_severity(bearingd::analysis::iso::SeveritySettings::default()),
        trend: bearingd::analysis::monitor::TrendSettings::default(),
    }
}

fn counts(seconds: f64, onset_s: f64) -> (Vec<i16>, SimulationParams) {
    let params = SimulationParams {
        onset_s,
        ramp_s: 10.0,
        noise_g: 0.2,
        ..SimulationParams::example(SimulatedFault::OuterRace)
    };
    let g = Simulator::record(params.clone(), seconds);
    (
        g.iter()
            .map(|&x| (f64::from(x) / SCALE).round().clamp(-32_768.0, 32_767.0) as i16)
            .collect(),
        params,
    )
}

/// Events as comparable text lines.
fn run(counts: &[i16], params: &SimulationParams, block: usize) -> Vec<String> {
    let monitor = ChannelMonitor::new(settings(params.fs_hz), params.frequencies(), None);
    run_monitor(monitor, counts, block, &[])
}

/// Events as text lines; `speeds` (sample, shaft Hz) are given before the first block, each
/// waiting for its sample (only one may wait: pass them in order, one per call at the block
/// that reaches the previous one).
fn run_monitor(
    mut monitor: ChannelMonitor,
    counts: &[i16],
    block: usize,
    speeds: &[(u64, Option<f64>)],
) -> Vec<String> {
    let mut events = Vec::new();
    let mut at = 0;
    let mut speeds = speeds.iter().peekable();
    for chunk in counts.chunks(block) {
        // Hand over the next speed change in the block that reaches its sample.
        if let Some(&&(sample, hz)) = speeds.peek() {
            if sample < (at + chunk.len()) as u64 {
                monitor.set_speed_at(sample, hz, &mut |e| describe(e, &mut events));
                speeds.next();
            }
        }
        monitor.push_counts(at as u64, chunk, SCALE, &mut |e| describe(e, &mut events));
        at += chunk.len();
    }
    events
}

/// A monitor event as a comparable text line (windows are left out).
fn describe(event: MonitorEvent, events: &mut Vec<String>) {
    match event {
        MonitorEvent::Flag {
            fault,
            change,
            score,
            ..
        } => events.push(format!(
            "flag {} {:?}->{:?} at {} score {score:.3}",
            fault.name(),
            change.from,
            change.to,
            change.at_sample
        )),
        MonitorEvent::Stage(change) => {
            events.push(format!("stage {:?} at {}", change.to, change.at_sample))
        }
        MonitorEvent::Trend { point, stage } => events.push(format!(
            "trend {:.6} g {stage:?} at {}",
            point.rms, point.end_sample
        )),
        MonitorEvent::Bands {
            at_sample, bands, ..
        } => events.push(format!("bands at {at_sample}: {bands:?}")),
        MonitorEvent::Sensor {
            condition,
            active,
            at_sample,
        } => events.push(format!(
            "sensor {} {active} at {at_sample}",
            HealthKind::from(condition).name()
        )),
        MonitorEvent::Gap { at_sample, missing } => {
            events.push(format!("gap {missing} at {at_sample}"))
        }
        MonitorEvent::Speed {
            at_sample,
            shaft_hz,
            ..
        } => events.push(format!("speed {shaft_hz:?} at {at_sample}")),
        MonitorEvent::Detector(DetectorMessage::Velocity(Emitted::Reading(r))) => {
            events.push(format!(
                "velocity {:.6} mm/s zone {} flag {} at {}",
                r.rms_mm_s, r.zone, r.flag, r.end_sample
            ))
        }
        MonitorEvent::Detector(DetectorMessage::Velocity(Emitted::Flag(f))) => events.push(
            format!("velocity flag {:?}->{:?} at {}", f.from, f.to, f.end_sample),
        ),
        MonitorEvent::Detector(other) => events.push(format!("{other:?}")),
        MonitorEvent::Window(_) => {}
    }
}

#[test]
fn a_developing_outer_race_fault_raises_its_flag_after_onset_and_nothing_else() {
    let (counts, params) = counts(100.0, 30.0);
    let events = run(&counts, &params, 1_000);
    let onset_sample = (30.0 * params.fs_hz) as u64;
    let flags: Vec<&String> = events.iter().filter(|e| e.starts_with("flag")).collect();
    assert!(!flags.is_empty(), "no flag raised: {events:#?}");
    for flag in &flags {
        assert!(
            flag.starts_with("flag outer_race"),
            "a flag other than outer race: {flag}\n{events:#?}"
        );
        let at: u64 = flag
            .split(" at ")
            .nth(1)
            .unwrap()
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(at > onset_sample, "flag before the onset: {flag}");
    }
    assert!(flags.iter().any(|f| f.contains("->Alarm")), "{flags:#?}");
    assert!(
        events
            .iter()
            .any(|e| e == &format!("stage {:?} at {}", HealthStage::Healthy, 0))
            || events.iter().any(|e| e.starts_with("stage Healthy"))
    );
    assert!(
        events.iter().any(|e| e.starts_with("stage Degrading")),
        "{events:#?}"
    );
}

#[test]
fn a_flag_follows_the_verdict_of_its_evidence_and_carries_its_runner_up() {
    let (counts, params) = counts(100.0, 30.0);
    let mut monitor = ChannelMonitor::new(settings(params.fs_hz), params.frequencies(), None);
    // The verdict of every band selection, by the sample it is used at; every flag change.
    let mut verdicts = std::collections::BTreeMap::new();
    let mut flags = Vec::new();
    let mut watch = |event: MonitorEvent| match event {
        MonitorEvent::Bands {
            at_sample,
            evidence: Some(evidence),
            ..
        } => {
            verdicts.insert(at_sample, *evidence);
        }
        MonitorEvent::Flag {
            fault,
            change,
            runner_up,
            score,
            ..
        } => flags.push((change, fault, runner_up, score)),
        _ => {}
    };
    for (k, chunk) in counts.chunks(2_560).enumerate() {
        monitor.push_counts((k * 2_560) as u64, chunk, SCALE, &mut watch);
    }
    monitor.finish(&mut watch);
    assert!(!flags.is_empty(), "no flag raised");
    for (change, fault, runner_up, score) in flags {
        let evidence = verdicts
            .get(&change.at_sample)
            .unwrap_or_else(|| panic!("flag at {} without a verdict there", change.at_sample));
        let own = evidence.scores[fault.index()].score;
        assert_eq!(score, own, "flag at {}", change.at_sample);
        assert_eq!(runner_up, evidence.runner_up(fault));
        let named = evidence.verdict.faults().contains(&fault);
        if change.to > change.from {
            assert!(named, "a flag rises for a fault its verdict names");
            assert!(runner_up < own, "a rising flag's fault leads its verdict");
        } else {
            assert!(!named, "a flag falls when its verdict stops naming it");
        }
    }
}

#[test]
fn the_same_samples_in_other_blocks_give_the_same_events() {
    let (counts, params) = counts(70.0, 20.0);
    let reference = run(&counts, &params, 4_096);
    assert!(
        reference.iter().any(|e| e.starts_with("flag")),
        "{reference:#?}"
    );
    for block in [1_000, 333, 12_000] {
        assert_eq!(
            run(&counts, &params, block),
            reference,
            "block size {block}"
        );
    }
}

#[test]
fn gaps_are_reported_and_never_bridged_and_a_flat_line_is_seen() {
    let (mut counts, params) = counts(30.0, 100.0);
    let fs = params.fs_hz as usize;
    counts[12 * fs..14 * fs].fill(123);
    let mut monitor = ChannelMonitor::new(settings(params.fs_hz), params.frequencies(), None);
    let mut gaps = Vec::new();
    let mut flat = Vec::new();
    let mut last_end = 0;
    monitor.push_counts(0, &counts[..10 * fs], SCALE, &mut |_| {});
    // 0.5 s lost.
    monitor.push_counts(
        (10 * fs + fs / 2) as u64,
        &counts[10 * fs + fs / 2..],
        SCALE,
        &mut |event| match event {
            MonitorEvent::Gap { at_sample, missing } => gaps.push((at_sample, missing)),
            MonitorEvent::Sensor {
                active, at_sample, ..
            } => flat.push((active, at_sample)),
            MonitorEvent::Window(w) => last_end = w.end_sample,
            _ => {}
        },
    );
    assert_eq!(gaps, vec![((10 * fs) as u64, (fs / 2) as u64)]);
    assert!(last_end > (14 * fs) as u64, "windows go on after the gap");
    assert_eq!(flat.len(), 2, "{flat:?}");
    assert!(flat[0].0 && !flat[1].0);
    assert_eq!(flat[1].1, (14 * fs) as u64);
    assert_eq!(monitor.flag_levels(), [FlagLevel::Ok; 4]);
}

/// A channel whose speed comes from speed frames and has no nominal speed scores nothing, and
/// selects no band, until the first usable speed; then it selects its bands at once and raises
/// the outer-race flag. A speed above the maximum or "not available" makes it wait again (its
/// flag holds). The same speeds in other block sizes give the same events at the same samples.
#[test]
fn a_given_speed_takes_effect_at_its_sample_and_without_one_nothing_is_scored() {
    let (counts, params) = counts(70.0, 0.0);
    let fs = params.fs_hz;
    let shaft = params.rpm / 60.0;
    let mode = SpeedMode::Given {
        known_at_start: false,
        max_shaft_hz: shaft * 1.5,
    };
    let monitor = || {
        let mut s = settings(fs);
        s.speed = mode;
        // Started at the highest speed, for sizing; unknown until told.
        ChannelMonitor::new(s, params.bearing.fault_frequencies(shaft * 1.5), None)
    };
    let at = |seconds: f64| (seconds * fs) as u64;
    let speeds = [
        (at(15.0), Some(shaft)),
        (at(50.0), Some(shaft * 2.0)),
        (at(55.0), None),
        (at(60.0), Some(shaft)),
    ];
    let reference = run_monitor(monitor(), &counts, 4_096, &speeds);
    let first_bands = reference
        .iter()
        .position(|e| e.starts_with("bands"))
        .expect("bands selected");
    assert!(
        reference[first_bands].starts_with(&format!("bands at {}", at(15.0))),
        "{reference:#?}"
    );
    assert!(
        reference[..first_bands]
            .iter()
            .all(|e| !e.starts_with("flag")),
        "{reference:#?}"
    );
    let flags: Vec<&String> = reference.iter().filter(|e| e.starts_with("flag")).collect();
    assert!(
        flags.iter().any(|f| f.starts_with("flag outer_race Ok->")),
        "{reference:#?}"
    );
    assert!(
        flags.iter().all(|f| f.starts_with("flag outer_race")),
        "{flags:#?}"
    );
    // No flag change while the speed is unusable (50..60 s): flags hold.
    let unusable = reference
        .iter()
        .skip_while(|e| !e.starts_with(&format!("speed None at {}", at(50.0))))
        .take_while(|e| !e.starts_with(&format!("speed Some({shaft}) at {}", at(60.0))))
        .filter(|e| e.starts_with("flag"))
        .count();
    assert_eq!(unusable, 0, "{reference:#?}");
    assert!(reference.contains(&format!("speed None at {}", at(55.0))));
    for block in [1_000, 12_000] {
        assert_eq!(
            run_monitor(monitor(), &counts, block, &speeds),
            reference,
            "block size {block}"
        );
    }
}

/// An estimating channel (nominal speed 3 % off) estimates the speed at its first band
/// selection, before any score, and then raises the outer-race flag as with the true speed.
#[test]
fn an_estimating_channel_finds_the_speed_before_it_scores() {
    let (counts, params) = counts(40.0, 0.0);
    let fs = params.fs_hz;
    let shaft = params.rpm / 60.0;
    let mut s = settings(fs);
    s.speed = SpeedMode::Estimate(bearingd::analysis::speed::SpeedSearch {
        nominal_hz: shaft * 1.03,
        range: 0.05,
    });
    let monitor = ChannelMonitor::new(s, params.bearing.fault_frequencies(shaft * 1.03), None);
    let events = run_monitor(monitor, &counts, 4_096, &[]);
    let first_speed = events
        .iter()
        .position(|e| e.starts_with("speed"))
        .expect("an estimate");
    let estimated: f64 = events[first_speed]
        .trim_start_matches("speed Some(")
        .split(')')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (estimated / shaft - 1.0).abs() < 0.005,
        "{estimated} Hz for {shaft} Hz"
    );
    assert!(events[first_speed + 1].starts_with("bands"), "{events:#?}");
    assert!(
        events[..first_speed].iter().all(|e| !e.starts_with("flag")),
        "{events:#?}"
    );
    assert!(
        events.iter().any(|e| e.starts_with("flag outer_race Ok->")),
        "{events:#?}"
    );
    assert!(
        events
            .iter()
            .filter(|e| e.starts_with("flag"))
            .all(|e| e.starts_with("flag outer_race")),
        "{events:#?}"
    );
}

/// The sample positions of a monitor's band selections.
fn band_selections(
    settings: MonitorSettings,
    counts: &[i16],
    params: &SimulationParams,
) -> Vec<u64> {
    let monitor = ChannelMonitor::new(settings, params.frequencies(), None);
    let mut at = Vec::new();
    let mut start = 0u64;
    let mut monitor = monitor;
    for chunk in counts.chunks(4096) {
        monitor.push_counts(start, chunk, SCALE, &mut |e| {
            if let MonitorEvent::Bands { at_sample, .. } = e {
                at.push(at_sample);
            }
        });
        start += chunk.len() as u64;
    }
    at
}

#[test]
fn a_band_phase_staggers_the_selections_after_the_first() {
    let (counts, params) = counts(75.0, 0.0);
    let fs = params.fs_hz;
    let plain = band_selections(settings(fs), &counts, &params);
    let phase = (5.0 * fs) as u64;
    let staggered = band_selections(
        MonitorSettings {
            band_phase_samples: phase,
            window_stagger: (0, 1),
            ..settings(fs)
        },
        &counts,
        &params,
    );
    let history = (10.0 * fs) as u64;
    let period = (20.0 * fs) as u64;
    // Both select as soon as the history is full, then every period; the staggered one's
    // later selections sit `phase` later.
    assert_eq!(
        plain[..3],
        [history, history + period, history + 2 * period]
    );
    assert_eq!(
        staggered[..3],
        [
            history,
            history + period + phase,
            history + 2 * period + phase
        ]
    );
}

/// Issue 16 item 4 in the streaming path: a machine whose 100 Hz vibration steps from zone A
/// (0.55 mm/s) into zone C (4.41 mm/s, group 2 rigid: C from 2.8) and back. The zone flag
/// rises to watch once the velocity has stayed in zone C for the on-delay, and falls once it
/// has stayed below clear_ratio × 2.8 mm/s for the off-delay, exactly once each.
#[test]
fn the_velocity_zone_flag_rises_and_falls_with_the_fault_flags_hysteresis() {
    let fs = 12_000.0;
    let sine = |amplitude_g: f64, seconds: f64, from: usize| -> Vec<i16> {
        (from..from + (seconds * fs) as usize)
            .map(|n| {
                let g = amplitude_g * (std::f64::consts::TAU * 100.0 * n as f64 / fs).sin();
                (g / SCALE).round() as i16
            })
            .collect()
    };
    let mut counts = sine(0.05, 20.0, 0);
    counts.extend(sine(0.4, 30.0, counts.len()));
    counts.extend(sine(0.05, 60.0, counts.len()));
    let freqs = SimulationParams::example(SimulatedFault::None).frequencies();
    let mut monitor = ChannelMonitor::new(settings(fs), freqs, None);
    let (mut readings, mut changes) = (Vec::new(), Vec::new());
    for (i, block) in counts.chunks(1_000).enumerate() {
        monitor.push_counts((i * 1_000) as u64, block, SCALE, &mut |e| match e {
            MonitorEvent::Detector(DetectorMessage::Velocity(Emitted::Reading(r))) => {
                readings.push(r)
            }
            MonitorEvent::Detector(DetectorMessage::Velocity(Emitted::Flag(f))) => {
                assert_eq!((f.watch_mm_s, f.alarm_mm_s), (2.8, 4.5));
                changes.push(f)
            }
            _ => {}
        });
    }
    let (on_delay, off_delay) = ((5.0 * fs) as u64, (30.0 * fs) as u64);
    let first_in_c = readings.iter().find(|r| r.rms_mm_s >= 2.8).unwrap();
    let raise = readings
        .iter()
        .find(|r| r.end_sample >= first_in_c.end_sample + on_delay)
        .unwrap();
    let first_clear = readings
        .iter()
        .find(|r| r.end_sample > raise.end_sample && r.rms_mm_s < 0.8 * 2.8)
        .unwrap();
    let fall = readings
        .iter()
        .find(|r| r.end_sample >= first_clear.end_sample + off_delay)
        .unwrap();
    let got: Vec<_> = changes
        .iter()
        .map(|c| (c.from, c.to, c.end_sample))
        .collect();
    assert_eq!(
        got,
        [
            (FlagLevel::Ok, FlagLevel::Watch, raise.end_sample),
            (FlagLevel::Watch, FlagLevel::Ok, fall.end_sample)
        ]
    );
    // The steady parts read the analytic velocity, a·g₀/(2πf)/√2.
    let analytic = |a: f64| a * 9.806_65 / (std::f64::consts::TAU * 100.0) / 2f64.sqrt() * 1e3;
    let at = |seconds: f64| {
        readings
            .iter()
            .find(|r| r.end_sample as f64 >= seconds * fs)
            .unwrap()
            .rms_mm_s
    };
    for (seconds, a) in [(15.0, 0.05), (45.0, 0.4), (105.0, 0.05)] {
        let want = analytic(a);
        assert!(
            (at(seconds) - want).abs() / want < 0.01,
            "{seconds} s: {} vs {want} mm/s",
            at(seconds)
        );
    }
}

/// Issue 12 item 4: the k-th of n channels ends its windows (envelope and velocity) k/n of a
/// hop later than a lone channel does, so the daemon's channels do not all close a window on
/// the same block; the windows themselves stay one hop apart.
#[test]
fn a_window_stagger_moves_every_window_end_by_its_share_of_the_hop() {
    let (counts, params) = counts(12.0, 0.0);
    let fs = params.fs_hz;
    let ends = |stagger: (usize, usize)| {
        let mut monitor = ChannelMonitor::new(
            MonitorSettings {
                window_stagger: stagger,
                ..settings(fs)
            },
            params.frequencies(),
            None,
        );
        let (mut windows, mut velocity) = (Vec::new(), Vec::new());
        for (i, block) in counts.chunks(1_000).enumerate() {
            monitor.push_counts((i * 1_000) as u64, block, SCALE, &mut |e| match e {
                MonitorEvent::Window(w) => windows.push(w.end_sample),
                MonitorEvent::Detector(DetectorMessage::Velocity(Emitted::Reading(r))) => {
                    velocity.push(r.end_sample)
                }
                _ => {}
            });
        }
        (windows, velocity)
    };
    let (lone, lone_velocity) = ends((0, 1));
    let (third, third_velocity) = ends((1, 3));
    assert!(
        lone.len() > 10 && lone_velocity.len() > 5,
        "{lone:?} {lone_velocity:?}"
    );
    // The staggered channel closes every window the lone one does, but the last one may fall
    // after the record's end.
    assert!(third.len() + 1 >= lone.len(), "{lone:?} vs {third:?}");
    assert!(third_velocity.len() + 1 >= lone_velocity.len());
    let hop = lone[1] - lone[0];
    let velocity_hop = lone_velocity[1] - lone_velocity[0];
    assert!(lone.windows(2).all(|w| w[1] - w[0] == hop));
    for (a, b) in lone.iter().zip(&third) {
        assert_eq!(b - a, hop / 3, "envelope windows: {lone:?} vs {third:?}");
    }
    for (a, b) in lone_velocity.iter().zip(&third_velocity) {
        assert_eq!(
            b - a,
            velocity_hop / 3,
            "velocity: {lone_velocity:?} vs {third_velocity:?}"
        );
    }
}

/// A band selection's result used while the newest window's band work still waits (the daemon
/// spreads that work over the hop): the flags it decides come out right after its bands event,
/// so their alerts do not wait for that work; the window's report follows, with its own end
/// sample (before the flag's). The selections run on the daemon's band worker.
#[test]
fn a_selections_flags_come_before_the_report_of_a_window_still_waiting_for_its_bands() {
    let (counts, params) = counts(30.0, 0.0);
    // Each band selection's result used `delay` samples after it started; every flag, window
    // report and bands event in order, with its sample.
    let worker = bearingd::pipeline::bands::BandWorker::start(1).expect("the band worker starts");
    let run = |delay: u64| {
        let mut monitor = ChannelMonitor::new(settings(params.fs_hz), params.frequencies(), None)
            .with_band_selector(Box::new(worker.selector()), delay, 0);
        let mut events = Vec::new();
        for (k, chunk) in counts.chunks(2_560).enumerate() {
            monitor.push_counts((k * 2_560) as u64, chunk, SCALE, &mut |e| match e {
                MonitorEvent::Flag { change, .. } => events.push(("flag", change.at_sample)),
                MonitorEvent::Window(w) => events.push(("window", w.end_sample)),
                MonitorEvent::Bands { at_sample, .. } => events.push(("bands", at_sample)),
                _ => {}
            });
        }
        events
    };
    // Where the first selection starts, and the first window end after it: a result used
    // one sample after that end finds the window's band work still to be done.
    let first = run(1);
    let started = first
        .iter()
        .find(|&&(kind, _)| kind == "bands")
        .map(|&(_, at)| at - 1)
        .expect("a band selection");
    let (_, window_end) = *first
        .iter()
        .find(|&&(kind, end)| kind == "window" && end > started)
        .expect("a window after it");
    let events = run(window_end - started + 1);
    let at = window_end + 1;
    let flag = events
        .iter()
        .position(|&event| event == ("flag", at))
        .unwrap_or_else(|| panic!("no flag raised at {at}: {events:?}"));
    assert_eq!(
        flag.checked_sub(1).map(|before| events[before]),
        Some(("bands", at)),
        "the selection's bands event, then its flags: {events:?}"
    );
    let next_window = events[flag..].iter().find(|&&(kind, _)| kind == "window");
    assert_eq!(
        next_window,
        Some(&("window", window_end)),
        "after the flag, the report of the window that waited: {events:?}"
    );
}
